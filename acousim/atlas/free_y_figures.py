"""The figure of the free-y attractor map (:mod:`acousim.atlas.free_y`): what each cell's periodic orbits are, over
(r = f_theta / f_y, detuning), one panel per cavity Q."""
from __future__ import annotations

from pathlib import Path

from cubedimer.atomic import save_figure

__all__ = ["CELL_KINDS", "cell_kind", "write_free_y_figure"]

#: What a cell shows, in the order of precedence, and its (marker, colour).
CELL_KINDS = {"stable in phase and anti-phase": ("o", "tab:purple"), "stable in phase": ("o", "tab:blue"),
              "stable anti-phase": ("o", "tab:red"), "stable, other class": ("o", "tab:green"),
              "unstable orbits only": ("o", "none"), "no orbit: escaped or folded": ("x", "black"),
              "no orbit: rest": (".", "tab:gray"), "no orbit found: still drifting": ("^", "tab:orange")}


def cell_kind(row: dict) -> str:
    """The kind of a cell of :func:`acousim.atlas.free_y.cell_summary` (:data:`CELL_KINDS`)."""
    inp, anti = row["stable_in_phase"], row["stable_anti_phase"]
    if inp and anti:
        return "stable in phase and anti-phase"
    if inp or anti:
        return "stable in phase" if inp else "stable anti-phase"
    if row["stable_other"]:
        return "stable, other class"
    if row["orbits"]:
        return "unstable orbits only"
    lost = row["escaped"] + row["folded"]
    if lost >= max(row["rest"], row["not_converged"]):
        return "no orbit: escaped or folded"
    return "no orbit: rest" if row["rest"] >= row["not_converged"] else "no orbit found: still drifting"


def write_free_y_figure(config, rows: list[dict], path: str | Path) -> Path:
    """``free_y_map.png`` from the cells' summaries (:func:`acousim.atlas.free_y.cell_summary`): each cell's kind at
    (r, x), one panel per Q; the number beside a cell is its largest non-trivial |mu| (the least stable orbit's), a
    shaded band the linear theory's unstable detunings."""
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D

    qs = list(config.quality_factors)
    fig, axes = plt.subplots(1, len(qs), figsize=(4.4 * len(qs) + 2.4, 4.0), squeeze=False, sharey=True)
    for ax, q in zip(axes[0], qs):
        mine = [r for r in rows if r["quality_factor"] == q]
        for r in mine:
            m, c = CELL_KINDS[cell_kind(r)]
            if m in ("x", "."):  # unfilled markers take one colour
                ax.scatter(r["r"], r["detuning"], marker=m, s=60, color=c, linewidth=0.8, zorder=3)
            else:
                ax.scatter(r["r"], r["detuning"], marker=m, s=60, facecolors=c, edgecolors="k" if c == "none" else c,
                           linewidth=0.8, zorder=3)
            if r["orbits"]:
                ax.annotate(f"{r['max_max_multiplier']:.3f}", (r["r"], r["detuning"]), fontsize=6,
                            xytext=(4, 3), textcoords="offset points")
        for r in mine:
            if r["band_low"] == r["band_low"]:  # not NaN
                ax.plot([r["r"]] * 2, [r["band_low"], r["band_high"]], color="0.85", lw=6, zorder=1,
                        solid_capstyle="butt")
        ax.set_xlabel("r = f_theta / f_y (linear, about the equilibrium)")
        ax.set_title(f"Q = {q:g}, A_cav = {config.area_m2 * 1e6:.0f} mm^2, p0 = {config.pressure_pa / 1e3:g} kPa",
                     fontsize=9)
        ax.set_ylim(min(config.detunings) - 0.5, max(config.detunings) + 0.5)
    axes[0][0].set_ylabel("detuning x = (f_c - f_d) / (f / 2Q)")
    handles = [Line2D([], [], marker=m, ls="", color=c if c != "none" else "k", mfc=c, label=k)
               for k, (m, c) in CELL_KINDS.items()]
    handles.append(Line2D([], [], color="0.85", lw=6, label="linear unstable band of x"))
    axes[0][-1].legend(handles=handles, fontsize=7, loc="upper left", bbox_to_anchor=(1.02, 1.0))
    fig.tight_layout()
    return save_figure(fig, path)
