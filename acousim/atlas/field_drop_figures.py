"""Figures of the attractor atlas (:mod:`acousim.atlas.field_drops`): a basin map per dimer and the phase histogram.

The caller chooses the matplotlib backend (the command-line tools and the Makefile set ``MPLBACKEND=Agg``).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from cubedimer.atomic import save_figure
from cubedimer.attractors import CLASS_COLORS, LOCKED_AT_FY

__all__ = ["OUTCOME_COLORS", "write_atlas_figures"]

#: One colour per outcome (the classifier's colours, and two for the failures).
OUTCOME_COLORS = {"escaped": "white", "folded": "black", **CLASS_COLORS}


def write_atlas_figures(config, rows: list[dict], out: str | Path, outcomes: tuple[str, ...]) -> list[Path]:
    """``basin_<dimer>.png`` (outcome over drop duration x hinge angle, long-lived cells marked) per dimer and
    ``phase_histogram.png`` (the settled y-theta phase of the locked cells, per dimer); returns the paths.
    ``outcomes`` are the outcome names in colour-map order (``acousim.atlas.field_drops.OUTCOMES``)."""
    import matplotlib.pyplot as plt
    from matplotlib.colors import ListedColormap
    from matplotlib.patches import Patch

    out = Path(out)
    paths = []
    cmap = ListedColormap([OUTCOME_COLORS[o] for o in outcomes])
    t_ms = np.asarray(config.t_off) * 1e3
    th = np.asarray(config.theta_drop)
    for d, dimer in enumerate(config.dimers):
        grid = np.full((len(th), len(t_ms)), np.nan)
        mine = [r for r in rows if r["index"][0] == d]
        for r in mine:
            grid[r["index"][2], r["index"][1]] = outcomes.index(r["outcome"])
        fig, ax = plt.subplots(figsize=(6.4, 4.2))
        ax.pcolormesh(_edges(t_ms), _edges(th), grid, cmap=cmap, vmin=-0.5, vmax=len(outcomes) - 0.5,
                      edgecolors="0.7", linewidth=0.3)
        for r in mine:
            if r.get("long_lived"):
                ax.plot(r["t_off_s"] * 1e3, r["theta_drop"], marker="o", ms=3, color="white", mec="k", mew=0.4)
        ax.set_xlabel("drop duration t_off [ms]")
        ax.set_ylabel("hinge angle at the drop theta_drop")
        ax.set_title(f"{dimer.side * 1e6:.0f} um, g/s = {dimer.gap_ratio:g}, p0 = {config.pressure_amplitude_pa / 1e3:g} kPa"
                     " (dots: long-lived)", fontsize=9)
        present = [o for o in outcomes if any(r["outcome"] == o for r in mine)]
        ax.legend(handles=[Patch(facecolor=OUTCOME_COLORS[o], edgecolor="0.5", label=o) for o in present],
                  fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
        fig.tight_layout()
        paths.append(save_figure(fig, out / f"basin_{dimer.label}.png"))
    fig, ax = plt.subplots(figsize=(6.0, 3.6))
    bins = np.linspace(-180, 180, 37)
    for dimer in config.dimers:
        ph = [r["section_phase_deg"] for r in rows if r["dimer"] == dimer.label and r["outcome"] in LOCKED_AT_FY
              and r.get("section_phase_deg") is not None and np.isfinite(r["section_phase_deg"])]
        ax.hist(ph, bins=bins, histtype="step", lw=1.5, label=f"{dimer.label} ({len(ph)} locked)")
    ax.set_xlabel("settled phase of theta relative to y at f_y [deg]")
    ax.set_ylabel("runs")
    ax.set_xlim(-180, 180)
    ax.legend(fontsize=7)
    fig.tight_layout()
    paths.append(save_figure(fig, out / "phase_histogram.png"))
    return paths


def _edges(centres: np.ndarray) -> np.ndarray:
    """Cell edges around (sorted) grid centres."""
    c = np.asarray(centres, float)
    if c.size == 1:
        return np.array([c[0] - 0.5, c[0] + 0.5])
    mid = 0.5 * (c[1:] + c[:-1])
    return np.concatenate([[2 * c[0] - mid[0]], mid, [2 * c[-1] - mid[-1]]])
