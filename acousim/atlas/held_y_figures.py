"""Figures of the held-y attractor map (:mod:`acousim.atlas.held_y`): the class map and the 2 f_y line over (r, A)."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from cubedimer.atomic import save_figure

__all__ = ["CELL_KINDS", "cell_kind", "write_held_y_figures"]

#: What a cell shows, in the order of precedence, and its colour.
CELL_KINDS = {"both phase classes": "tab:purple", "in phase": "tab:blue", "anti-phase": "tab:red",
              "other lock": "tab:green", "folded": "black", "not locked or at rest": "tab:orange"}


def cell_kind(row: dict) -> str:
    """The class of a cell of :func:`acousim.atlas.held_y.cell_summary`: both phase classes populated, else the
    largest outcome among in phase, anti-phase, other locks (quadrature, p:q), folded and not locked."""
    if row["two_phase_classes"]:
        return "both phase classes"
    counts = {"in phase": row["in_phase"], "anti-phase": row["anti_phase"],
              "other lock": row["quadrature"] + row["ratio_locked"], "folded": row["folded"],
              "not locked or at rest": row["independent"] + row["at_rest"]}
    return max(counts, key=lambda k: counts[k])


def write_held_y_figures(config, rows: list[dict], out: str | Path) -> list[Path]:
    """``held_y_classes.png`` (each cell's kind at (r = f_theta / f_y, A), one panel per pressure; a ring marks a
    cell with a third long-lived class) and ``held_y_2fy.png`` (the largest 2 f_y share of the runs locked at f_y,
    same axes; a black edge marks >= 5 %); returns the paths."""
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D

    out = Path(out)
    pressures = list(config.pressures_pa)
    paths = []
    fig, axes = plt.subplots(1, len(pressures), figsize=(4.2 * len(pressures) + 1.6, 3.8), squeeze=False)
    for ax, p in zip(axes[0], pressures):
        mine = [r for r in rows if r["pressure_pa"] == p]
        for r in mine:
            ax.scatter(r["r"], r["amplitude_m"] * 1e6, s=42, color=CELL_KINDS[cell_kind(r)], edgecolors="0.4",
                       linewidth=0.4, zorder=2)
            if r["third_class"]:
                ax.scatter(r["r"], r["amplitude_m"] * 1e6, s=120, facecolors="none", edgecolors="k", linewidth=0.8,
                           zorder=3)
        ax.axvline(1.0, color="0.7", lw=0.8, zorder=1)
        ax.set_xlabel("r = f_theta / f_y (linear, about the equilibrium)")
        ax.set_title(f"p0 = {p / 1e3:g} kPa", fontsize=9)
    axes[0][0].set_ylabel("held y amplitude A [um]")
    handles = [Line2D([], [], marker="o", ls="", color=c, label=k) for k, c in CELL_KINDS.items()]
    handles.append(Line2D([], [], marker="o", ls="", mfc="none", mec="k", ms=9, label="third long-lived class"))
    axes[0][-1].legend(handles=handles, fontsize=7, loc="upper left", bbox_to_anchor=(1.02, 1.0))
    fig.tight_layout()
    paths.append(save_figure(fig, out / "held_y_classes.png"))

    fig, axes = plt.subplots(1, len(pressures), figsize=(4.2 * len(pressures) + 1.2, 3.8), squeeze=False)
    sc = None
    for ax, p in zip(axes[0], pressures):
        mine = [r for r in rows if r["pressure_pa"] == p and np.isfinite(r["max_share_2fy_locked"])]
        if mine:
            share = np.array([r["max_share_2fy_locked"] for r in mine])
            sc = ax.scatter([r["r"] for r in mine], [r["amplitude_m"] * 1e6 for r in mine], c=np.log10(share * 100),
                            cmap="viridis", vmin=-1, vmax=1.5, s=42,
                            edgecolors=["k" if v >= 0.05 else "none" for v in share], linewidth=1.0)
        ax.axvline(1.0, color="0.7", lw=0.8)
        ax.set_xlabel("r = f_theta / f_y")
        ax.set_title(f"p0 = {p / 1e3:g} kPa: theta's 2 f_y line (locked at f_y)", fontsize=9)
    axes[0][0].set_ylabel("held y amplitude A [um]")
    if sc is not None:
        fig.colorbar(sc, ax=axes[0].tolist(), label="log10 (2 f_y / f_y line, %)")
    paths.append(save_figure(fig, out / "held_y_2fy.png"))
    return paths
