"""Figures of a twin data set's exact states: time series and spectra, phase portraits, Poincare
section and map, and the distribution of the y-theta phase; runs are coloured by their attractor
class (:func:`cubedimer.attractors.classify_trajectory`).

The caller chooses the matplotlib backend (the command-line tools and the Makefile set
``MPLBACKEND=Agg``).
"""
from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from cubedimer.atomic import save_figure
from cubedimer.attractors import CLASS_COLORS, classify_trajectory, section_phase
from cubedimer.poincare import poincare_section
from cubedimer.spectra import amplitude_spectrum

from ..dynamics.effects import EffectSet

__all__ = ["write_twin_figures"]

#: classes in the order their representative runs are shown
_SHOWN = ("locked-in-phase", "locked-anti-phase", "locked-p:q", "independent", "locked-quadrature", "theta-at-rest")


@dataclass(frozen=True)
class _TwinStates:
    """A twin data set's exact states and what every figure shows of them."""

    t: np.ndarray
    names: list[str]
    states: list[np.ndarray]
    dt: float
    locks: list
    reps: list[int]
    title: str


def _load_states(data_dir: Path) -> _TwinStates:
    """``truth_states.npz`` and ``truth.json`` of ``data_dir``, each run classified, up to three representative
    runs (the first of each class in the order of :data:`_SHOWN`)."""
    npz = np.load(data_dir / "truth_states.npz")
    truth = json.loads((data_dir / "truth.json").read_text())
    t = npz["t"]
    names = sorted(k for k in npz.files if k != "t")
    states = [npz[k] for k in names]
    locks = [classify_trajectory(t, x) for x in states]
    reps = []
    for lab in _SHOWN:
        idx = [i for i, l in enumerate(locks) if l.label == lab]
        if idx:
            reps.append(idx[0])
    return _TwinStates(t=t, names=names, states=states, dt=float(t[1] - t[0]), locks=locks, reps=reps[:3],
                       title=f"acousim twin: {EffectSet.from_dict(truth['effects']).describe()}")


def _timeseries_figure(s: _TwinStates):
    """Time series (y and theta, with the last 0.15 s normalised) and amplitude spectra of the representative runs."""
    import matplotlib.pyplot as plt

    t, states, locks, names, dt, reps = s.t, s.states, s.locks, s.names, s.dt, s.reps
    fig, axes = plt.subplots(len(reps), 2, figsize=(12, 3.0 * len(reps)), squeeze=False)
    for row, i in enumerate(reps):
        x, lab = states[i], locks[i]
        ax = axes[row, 0]
        ax.plot(t, x[:, 0] * 1e6, color="k", lw=0.6, label="y [um]")
        ax.set_ylabel("y [um]")
        ax2 = ax.twinx()
        ax2.plot(t, x[:, 2], color=CLASS_COLORS[lab.label], lw=0.6, label="theta")
        ax2.set_ylabel("theta")
        ax.set_title(f"{names[i]}: {lab.label} (phase {np.degrees(lab.section_phase):.0f} deg)", fontsize=9)
        ax.set_xlabel("t [s] (field back on at 0)")
        ins = ax.inset_axes([0.62, 0.6, 0.36, 0.38])
        sel = t > t[-1] - 0.15
        ins.plot(t[sel], x[sel, 0] / np.max(np.abs(x[sel, 0])), "k", lw=0.8)
        ins.plot(t[sel], (x[sel, 2] - x[sel, 2].mean()) / np.max(np.abs(x[sel, 2] - x[sel, 2].mean())),
                 color=CLASS_COLORS[lab.label], lw=0.8)
        ins.set_xticks([]), ins.set_yticks([])
        ax = axes[row, 1]
        h = len(t) // 2
        f, ay = amplitude_spectrum(x[h:, 0], dt)
        _, at = amplitude_spectrum(x[h:, 2], dt)
        ax.semilogy(f, ay / ay.max(), "k", lw=0.7, label="y")
        ax.semilogy(f, at / at.max(), color=CLASS_COLORS[lab.label], lw=0.7, label="theta")
        fy = f[np.argmax(ay)]
        for m in (1, 2, 3):
            ax.axvline(m * fy, color="0.7", lw=0.5, ls="--")
        ax.set_xlim(0, 80)
        ax.set_ylim(1e-5, 2)
        ax.set_xlabel("f [Hz] (second half of the run; dashed: 1, 2, 3 x f_y)")
        ax.set_ylabel("amplitude / max")
        ax.legend(fontsize=8, loc="upper right")
    return fig


def _phase_portraits_figure(s: _TwinStates):
    """(theta, thetadot, y) of the representative runs and (theta, thetadot) of all runs over the last second."""
    import matplotlib.pyplot as plt

    t, states, locks, reps = s.t, s.states, s.locks, s.reps
    fig = plt.figure(figsize=(12, 5))
    ax3 = fig.add_subplot(1, 2, 1, projection="3d")
    ax = fig.add_subplot(1, 2, 2)
    last = t > t[-1] - 1.0
    for i, (x, lab) in enumerate(zip(states, locks)):
        c = CLASS_COLORS[lab.label]
        if i in reps:
            ax3.plot(x[last, 2], x[last, 3], x[last, 0] * 1e6, color=c, lw=0.5)
        ax.plot(x[last, 2], x[last, 3], color=c, lw=0.3, alpha=0.6)
    ax3.set_xlabel("theta"), ax3.set_ylabel("thetadot [1/s]"), ax3.set_zlabel("y [um]")
    ax3.set_title("(theta, thetadot, y), last second, representative runs", fontsize=9)
    ax.set_xlabel("theta"), ax.set_ylabel("thetadot [1/s]")
    ax.set_title("(theta, thetadot), last second, all runs (colour: class)", fontsize=9)
    for lab, c in CLASS_COLORS.items():
        ax.plot([], [], color=c, label=f"{lab} ({sum(l.label == lab for l in locks)})")
    ax.legend(fontsize=8)
    return fig


def _poincare_figure(s: _TwinStates):
    """The Poincare section y = 0, ydot < 0 of every run and its map theta_k -> theta_k+1."""
    import matplotlib.pyplot as plt

    t, states, locks = s.t, s.states, s.locks
    fig, axes = plt.subplots(1, 2, figsize=(12, 5))
    for x, lab in zip(states, locks):
        sec = poincare_section(t, x)
        c = CLASS_COLORS[lab.label]
        late = sec.times > t[-1] / 2
        axes[0].plot(sec.theta[~late], sec.thetadot[~late], ".", color=c, ms=1.5, alpha=0.3)
        axes[0].plot(sec.theta[late], sec.thetadot[late], ".", color=c, ms=3)
        axes[1].plot(sec.theta[:-1], sec.theta[1:], ".", color=c, ms=2, alpha=0.6)
    lim = max(1e-3, max(np.max(np.abs(x[:, 2])) for x in states))
    axes[1].plot([-lim, lim], [-lim, lim], "k:", lw=0.6)
    axes[0].set_xlabel("theta at y = 0, ydot < 0"), axes[0].set_ylabel("thetadot [1/s]")
    axes[0].set_title("Poincare section (faint: first half, bold: second half)", fontsize=9)
    axes[1].set_xlabel("theta_k"), axes[1].set_ylabel("theta_k+1")
    axes[1].set_title("Poincare map of theta", fontsize=9)
    for lab, c in CLASS_COLORS.items():
        axes[0].plot([], [], ".", color=c, label=lab)
    axes[0].legend(fontsize=8)
    return fig


def _phase_hist_figure(s: _TwinStates):
    """The y-theta phase per run (second half) and per 0.5 s window."""
    import matplotlib.pyplot as plt

    t, states, locks, dt = s.t, s.states, s.locks, s.dt
    fig, axes = plt.subplots(1, 2, figsize=(12, 4))
    bins = np.linspace(-180, 180, 37)
    per_run = [np.degrees(l.section_phase) for l in locks if np.isfinite(l.section_phase)]
    axes[0].hist(per_run, bins=bins, color="0.4")
    axes[0].set_xlabel("phase of theta relative to y at f_y [deg] (second half of each run)")
    axes[0].set_ylabel("runs")
    win = int(round(0.5 / dt))
    rows = []
    for x in states:
        for k0 in range(0, len(t) - win + 1, win):
            phase, _ = section_phase(t[k0:k0 + win], x[k0:k0 + win])
            if np.isfinite(phase):
                rows.append((k0 * dt, np.degrees(phase)))
    rows = np.array(rows) if rows else np.zeros((0, 2))
    if len(rows):
        sc = axes[1].scatter(rows[:, 1], rows[:, 0], c=rows[:, 0], s=6, cmap="viridis")
        fig.colorbar(sc, ax=axes[1], label="window start [s]")
    axes[1].set_xlabel("phase per 0.5 s window [deg]"), axes[1].set_ylabel("window start [s]")
    axes[1].set_xlim(-180, 180)
    return fig


#: The figures in the order they are written: file name (after the prefix) and the function drawing it.
_FIGURES = (("timeseries.png", _timeseries_figure), ("phase_portraits.png", _phase_portraits_figure),
            ("poincare.png", _poincare_figure), ("phase_hist.png", _phase_hist_figure))


def write_twin_figures(data_dir: str | os.PathLike, fig_dir: str | os.PathLike, prefix: str = "twin_") -> list[Path]:
    """Figures of a twin data set's exact states (``truth_states.npz``) into ``fig_dir``.

    ``{prefix}timeseries.png`` (time series and amplitude spectra of representative runs),
    ``{prefix}phase_portraits.png`` ((theta, thetadot, y) portraits), ``{prefix}poincare.png`` (the
    section y = 0, ydot < 0 and its map theta_k -> theta_k+1) and ``{prefix}phase_hist.png`` (the
    y-theta phase difference per run and per 0.5 s window).  Returns the paths written.
    """
    data_dir, fig_dir = Path(data_dir), Path(fig_dir)
    states = _load_states(data_dir)
    fig_dir.mkdir(parents=True, exist_ok=True)
    out = []
    for name, draw in _FIGURES:
        fig = draw(states)
        fig.suptitle(states.title, fontsize=9)
        fig.tight_layout()
        out.append(fig_dir / f"{prefix}{name}")
        save_figure(fig, out[-1], dpi=110)
    return out
