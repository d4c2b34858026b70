"""Figures of the model-vs-simulation report (matplotlib).  Every axis is labelled with units."""
from __future__ import annotations

from pathlib import Path
from typing import Sequence

import numpy as np

__all__ = ["data_figures", "phase_space_figures", "restoring_overlay_figure", "timeseries_overlay_figure"]

UM = 1e6


def _plt():
    import matplotlib.pyplot as plt

    return plt


def _save(fig, path: Path) -> Path:
    from cubedimer.atomic import save_figure

    return save_figure(fig, path, dpi=120)


from cubedimer.attractors import CLASS_COLORS


def data_figures(prepared: Sequence, out: Path) -> list[tuple[Path, str]]:
    """Time series, spectra, phase-difference distribution and attractor classes of the runs."""
    from cubedimer.spectra import amplitude_spectrum

    plt = _plt()
    figs = []
    # time series of one run per class
    by_class: dict[str, list] = {}
    for p in prepared:
        by_class.setdefault(p.attractor.label, []).append(p)
    reps = [v[0] for v in by_class.values()][:3]
    fig, axes = plt.subplots(len(reps), 1, figsize=(8, 2.2 * len(reps)), squeeze=False, constrained_layout=True)
    for ax, p in zip(axes[:, 0], reps):
        t, y, th = p.run.t, p.run.y, p.run.theta
        ax.plot(t, y * UM, color="k", lw=0.5)
        ax.set_ylabel(r"$y$ [$\mu$m]")
        ax2 = ax.twinx()
        ax2.plot(t, th, color=CLASS_COLORS.get(p.attractor.label, "tab:green"), lw=0.5)
        ax2.set_ylabel(r"$\theta$", color=CLASS_COLORS.get(p.attractor.label, "tab:green"))
        ax.set_title(f"{p.run.name}: {p.attractor.label} (phase {np.degrees(p.attractor.phase):.0f} deg)", fontsize=9)
        ax.set_xlabel("t [s]")
    figs.append((_save(fig, out / "data_timeseries.png"),
                 "Time series of one run per attractor class: y (black, left axis) and theta (colour, right axis)."))
    # spectra
    fig, axes = plt.subplots(1, 2, figsize=(9, 3.2), constrained_layout=True)
    for p in prepared:
        c = CLASS_COLORS.get(p.attractor.label, "tab:green")
        for ax, x in zip(axes, (p.run.y, p.run.theta)):
            f, a = amplitude_spectrum(x - x.mean(), p.run.dt)
            ax.semilogy(f, a / max(a.max(), 1e-300), color=c, lw=0.5, alpha=0.6)
    fy = np.median([p.f_y for p in prepared])
    for ax, lab in zip(axes, ("y", r"$\theta$")):
        for h in (1, 2, 3):
            ax.axvline(h * fy, color="0.6", ls=":", lw=0.8)
        ax.set_xlim(0, 4 * fy)
        ax.set_ylim(1e-4, 1.5)
        ax.set_xlabel("frequency [Hz] (dotted: 1, 2, 3 x f_y)")
        ax.set_ylabel(f"amplitude of {lab} / max")
    axes[0].set_title("spectra of y (colour: attractor class)", fontsize=9)
    axes[1].set_title(r"spectra of $\theta$", fontsize=9)
    figs.append((_save(fig, out / "data_spectra.png"),
                 "Amplitude spectra of every run, normalised; dotted lines at the harmonics of the median y frequency."))
    # phase difference and classes
    fig, axes = plt.subplots(1, 2, figsize=(9, 3.2), constrained_layout=True)
    ph = np.degrees([p.attractor.phase for p in prepared])
    axes[0].hist(ph, bins=np.linspace(-180, 180, 37), color="0.3")
    axes[0].set_xlabel(r"phase of $\theta$ relative to y at f_y [deg]")
    axes[0].set_ylabel("runs")
    labels = list(by_class)
    axes[1].bar(range(len(labels)), [len(by_class[l]) for l in labels], color=[CLASS_COLORS.get(l, "tab:green") for l in labels])
    axes[1].set_xticks(range(len(labels)), [l.replace("-", "\n", 1) for l in labels], fontsize=8)
    axes[1].set_ylabel("runs")
    axes[1].set_title("attractor classes", fontsize=9)
    figs.append((_save(fig, out / "data_phase_classes.png"),
                 "Distribution of the y-theta phase difference across runs and the attractor classes (amplitude and phase relation)."))
    return figs


def phase_space_figures(prepared: Sequence, model, out: Path) -> list[tuple[Path, str]]:
    """(theta, thetadot, y) portraits per class, data and minimal model, and Poincare-map convergence."""
    from cubedimer.poincare import poincare_section

    plt = _plt()
    by_class: dict[str, list] = {}
    for p in prepared:
        by_class.setdefault(p.attractor.label, []).append(p)
    reps = [(k, v[0]) for k, v in by_class.items()][:3]
    fig = plt.figure(figsize=(4.2 * len(reps), 4.0), constrained_layout=True)
    conv = []
    for i, (label, p) in enumerate(reps):
        ax = fig.add_subplot(1, len(reps), i + 1, projection="3d")
        st = p.derivs.state[p.derivs.trim: len(p.derivs.t) - p.derivs.trim]
        t = p.derivs.t[p.derivs.trim: len(p.derivs.t) - p.derivs.trim]
        sim, nv = model.simulate(st[0], t - t[0])
        ax.plot(st[:, 2], st[:, 3], st[:, 0] * UM, color="k", lw=0.3, label="data")
        ax.plot(sim[:nv, 2], sim[:nv, 3], sim[:nv, 0] * UM, color="tab:red", lw=0.3, alpha=0.7, label="minimal model")
        ax.set_xlabel(r"$\theta$")
        ax.set_ylabel(r"$\dot\theta$ [1/s]")
        ax.set_zlabel(r"$y$ [$\mu$m]")
        ax.set_title(f"{label} ({p.run.name})", fontsize=9)
        if i == 0:
            ax.legend(fontsize=7)
        conv.append((label, poincare_section(t, st), poincare_section(t[:nv], sim[:nv])))
    paths = [(_save(fig, out / "phase_portraits_3d.png"),
              "Phase portraits in (theta, thetadot, y) of one run per attractor class: data (black) and the minimal model "
              "integrated from the run's first state (red).")]
    fig, axes = plt.subplots(1, len(conv), figsize=(4.2 * len(conv), 3.2), squeeze=False, constrained_layout=True)
    for ax, (label, sd, ss) in zip(axes[0], conv):
        ax.plot(np.arange(len(sd.theta)), sd.theta, "o-", ms=2, lw=0.5, color="k", label="data")
        ax.plot(np.arange(len(ss.theta)), ss.theta, "x-", ms=2, lw=0.5, color="tab:red", label="model")
        ax.set_xlabel("crossing number k (y = 0, ydot < 0)")
        ax.set_ylabel(r"$\theta$ at the crossing")
        ax.set_title(label, fontsize=9)
    axes[0, 0].legend(fontsize=7)
    paths.append((_save(fig, out / "poincare_convergence.png"),
                  "Convergence of the Poincare map: theta at successive crossings of y = 0 (ydot < 0), data and model."))
    return paths


def restoring_overlay_figure(models: Sequence[tuple], prepared: Sequence, out: Path) -> tuple[Path, str]:
    """The paper's Fig. 2c-d: the simulations' restoring force and torque with the data's measured accelerations.

    ``models``: (curves, delta [m], label) per calibrated simulation, the first one the main model: its stored
    restoring curves (diagnosis.json ``model_comparison.simulations[i].curves``: ``y_m``, ``yddot`` at theta = 0;
    ``theta``, ``thetaddot`` at y = 0); the data's y is each simulation's y minus its delta (calibrated origin).  The axes are the data's: y from the data's
    origin, and the acceleration range of the data (a model curve may leave the plot; the caption says so).
    """
    plt = _plt()
    fig, axes = plt.subplots(1, 2, figsize=(10, 3.8), constrained_layout=True)
    states = np.concatenate([p.derivs.state for p in prepared])
    accel = np.concatenate([p.derivs.accel for p in prepared])
    pick = np.random.default_rng(0).choice(len(states), size=min(6000, len(states)), replace=False)
    st, ac = states[pick], accel[pick]
    delta0 = models[0][1]
    small = np.abs(st[:, 2]) < 0.1
    axes[0].plot(st[small, 0] * UM, ac[small, 0], ".", ms=1, color="0.6", label=r"data, $|\theta| < 0.1$")
    ymid = np.abs(st[:, 0] + delta0) < 30e-6
    axes[1].plot(st[ymid, 2], ac[ymid, 1], ".", ms=1, color="0.6", label=r"data, $|y| < 30\,\mu$m")
    colors = ("tab:blue", "tab:red", "tab:green")
    clipped = []
    for (curves, delta, label), color in zip(models, colors):
        axes[0].plot((np.asarray(curves["y_m"]) - delta) * UM, curves["yddot"], color=color, lw=2,
                     label=rf"{label}, $\theta = 0$")
        torque = np.asarray(curves["thetaddot"])
        axes[1].plot(curves["theta"], torque, color=color, lw=2, label=f"{label}, y = 0")
        lo, hi = np.quantile(ac[ymid, 1], [0.001, 0.999]) if ymid.any() else (-1.0, 1.0)
        if np.any(np.abs(torque) > 3 * max(abs(lo), abs(hi))):
            clipped.append(label)
    if ymid.any():
        lo, hi = np.quantile(ac[ymid, 1], [0.001, 0.999])
        pad = 0.5 * (hi - lo)
        axes[1].set_ylim(lo - pad, hi + pad)
    axes[0].set_xlabel(r"$y$ [$\mu$m] (data's origin)")
    axes[0].set_ylabel(r"$\ddot y$ [m/s$^2$]")
    axes[0].set_title("restoring force", fontsize=9)
    axes[0].legend(fontsize=7)
    axes[1].set_xlabel(r"$\theta$")
    axes[1].set_ylabel(r"$\ddot\theta$ [1/s$^2$]")
    axes[1].set_title("restoring torque on the hinge", fontsize=9)
    axes[1].legend(fontsize=7)
    names = " and ".join(f"the {label} model" for _, _, label in models)
    caption = (f"The paper's Fig. 2c-d for these data: the restoring force and torque of {names}, each at its calibrated "
               "pressure and origin, with the measured accelerations (grey dots, Savitzky-Golay estimates at the measured "
               "states); y is the data's own.")
    if clipped:
        caption += f" The torque axis shows the data's range: the {', '.join(clipped)} curve leaves it."
    return _save(fig, out / "restoring_overlay.png"), caption


def timeseries_overlay_figure(overlay: dict, fit_model, out: Path) -> tuple[Path, str]:
    """One run's y and theta against time: the data (smoothed), the fitted minimal model and the calibrated simulation
    with the identified effects, both started from the run's first state (diagnosis.json ``overlay``)."""
    plt = _plt()
    t = np.asarray(overlay["t_s"])
    data, sim = overlay["data"], overlay["simulation"]
    fitted, n_fit = fit_model.simulate(np.asarray(overlay["first_state"]), np.linspace(t[0], t[-1], len(t)))
    n_sim = int(sim.get("simulated_frames", len(t)))
    fig, axes = plt.subplots(2, 1, figsize=(9, 4.6), sharex=True, constrained_layout=True)
    for ax, key, col, scale, unit in ((axes[0], "y_m", 0, UM, r"$y$ [$\mu$m]"), (axes[1], "theta", 2, 1.0, r"$\theta$")):
        ax.plot(t, np.asarray(data[key]) * scale, color="k", lw=1.2, label="data (smoothed)")
        ax.plot(t[:n_fit], fitted[:n_fit, col] * scale, color="tab:red", lw=0.9, ls="--", label="fitted minimal model")
        ax.plot(t[:n_sim], np.asarray(sim[key])[:n_sim] * scale, color="tab:blue", lw=0.9,
                label="calibrated simulation with the identified effects")
        ax.set_ylabel(unit)
    axes[1].set_xlabel("t [s] from the run's first frame")
    axes[0].legend(fontsize=7, loc="upper right")
    effects = ", ".join(sim.get("effects") or {}) or "no effect"
    caption = (f"Run {overlay['run']}: the data (black) against the fitted minimal model (red, dashed) and the "
               f"calibrated simulation with {effects} (blue), both integrated from the run's first smoothed state; "
               "where a curve ends early, that model left the trap.")
    return _save(fig, out / "timeseries_overlay.png"), caption
