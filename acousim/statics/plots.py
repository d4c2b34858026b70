"""Figures of a static sweep, in the style of the source paper's Fig. 2c-d.

* :func:`plot_restoring_force`: yddot versus y at a few bends (the vertical trap);
* :func:`plot_restoring_torque`: thetaddot versus theta at several heights y;
* :func:`plot_thetaddot_map`: heat map of thetaddot over (theta, y).

Each function returns the matplotlib Figure; :func:`save_sweep_figures` writes all three as PNG.
"""
from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from .sweep import SweepResult

__all__ = ["plot_restoring_force", "plot_restoring_torque", "plot_thetaddot_map", "save_sweep_figures", "model_label"]

UM = 1e6  # metres -> micrometres for axes


def _figure(figsize=(5.0, 3.8)):
    import matplotlib.pyplot as plt

    return plt.subplots(figsize=figsize, constrained_layout=True)


def model_label(sweep: SweepResult) -> str:
    """The force model a sweep was made with, for a title: the registry's label of ``settings["model"]`` (e.g.
    "Gor'kov model"), the recorded name itself when it is not a registered model."""
    from ..models import force_model_names, force_model_type

    name = str(sweep.settings.get("model", "unknown model"))
    return f"{force_model_type(name).label} model" if name in force_model_names() else name


def _nearest_indices(grid: np.ndarray, values) -> list[int]:
    return sorted({int(np.argmin(np.abs(grid - v))) for v in values})


def plot_restoring_force(sweep: SweepResult, thetas=(0.0, 0.5, 0.9), ax=None):
    """yddot [m/s^2] versus y [um] at the grid bends closest to ``thetas``."""
    fig, ax = _figure() if ax is None else (ax.figure, ax)
    for i in _nearest_indices(sweep.theta_grid, thetas):
        ax.plot(sweep.y_grid * UM, sweep["yddot"][i], label=rf"$\theta$ = {round(sweep.theta_grid[i], 2) + 0.0:.2f}")
    spread = np.ptp(sweep["yddot"], axis=0).max() / (np.ptp(sweep["yddot"]) or 1.0)
    if spread < 0.01:
        ax.text(0.03, 0.04, f"curves coincide: the bend changes $\\ddot y$ by < {100 * spread:.2g} %\n"
                "(a cube's second moment is isotropic)", transform=ax.transAxes, fontsize=7, color="0.3")
    ax.axhline(0, color="0.6", lw=0.8)
    ax.axvline(0, color="0.6", lw=0.8)
    ax.set_xlabel(r"$y$ = $Z_{com} - Z_{eq}$ [$\mu$m]")
    ax.set_ylabel(r"$\ddot y$ [m/s$^2$]")
    ax.set_title(f"Restoring force ({model_label(sweep)})")
    ax.legend(frameon=False)
    return fig


def plot_restoring_torque(sweep: SweepResult, ys=None, ax=None):
    """thetaddot [1/s^2] versus theta at several heights y (default: 5 across the grid)."""
    fig, ax = _figure() if ax is None else (ax.figure, ax)
    if ys is None:
        ys = np.linspace(sweep.y_grid.min(), sweep.y_grid.max(), 5)
    import matplotlib.pyplot as plt

    idx = _nearest_indices(sweep.y_grid, ys)
    colors = plt.cm.viridis(np.linspace(0, 1, len(idx)))
    for c, j in zip(colors, idx):
        ax.plot(sweep.theta_grid, sweep["thetaddot"][:, j], color=c, label=rf"$y$ = {sweep.y_grid[j] * UM:+.0f} $\mu$m")
    ax.axhline(0, color="0.6", lw=0.8)
    ax.axvline(0, color="0.6", lw=0.8)
    ax.set_xlabel(r"$\theta$ = $(\alpha - \beta)/\pi$")
    ax.set_ylabel(r"$\ddot\theta$ [1/s$^2$]")
    ax.set_title(f"Restoring torque on the hinge ({model_label(sweep)})")
    ax.legend(frameon=False, fontsize=8)
    return fig


def plot_thetaddot_map(sweep: SweepResult, ax=None):
    """Heat map of thetaddot [1/s^2] over (theta, y [um]) with a diverging colour scale."""
    fig, ax = _figure((5.4, 3.8)) if ax is None else (ax.figure, ax)
    val = sweep["thetaddot"].T
    lim = np.nanmax(np.abs(val)) or 1.0
    mesh = ax.pcolormesh(sweep.theta_grid, sweep.y_grid * UM, val, cmap="RdBu_r", vmin=-lim, vmax=lim, shading="auto")
    ax.contour(sweep.theta_grid, sweep.y_grid * UM, val, levels=9, colors="k", linewidths=0.4)
    fig.colorbar(mesh, ax=ax, label=r"$\ddot\theta$ [1/s$^2$]")
    ax.set_xlabel(r"$\theta$")
    ax.set_ylabel(r"$y$ [$\mu$m]")
    ax.set_title(r"$\ddot\theta(\theta, y)$ at zero velocity")
    return fig


def save_sweep_figures(sweep: SweepResult, out_dir: str | os.PathLike) -> list[Path]:
    """Write restoring_force.png, restoring_torque.png and thetaddot_map.png into ``out_dir``."""
    from cubedimer.atomic import save_figure

    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    paths = []
    for name, fn in (
        ("restoring_force.png", plot_restoring_force),
        ("restoring_torque.png", plot_restoring_torque),
        ("thetaddot_map.png", plot_thetaddot_map),
    ):
        paths.append(save_figure(fn(sweep), out_dir / name, dpi=150))
    return paths
