"""Figures of a fit and of a comparison (matplotlib, Agg backend, written atomically as PNG).

* ``zscores.png``: bar chart of every term's z-score per equation, threshold line, selected terms highlighted (methods
  with across-run statistics, :class:`fitting.results.EnsembleExtras`);
* ``pareto.png``: the discovery's Pareto front;
* ``front.png``: the discovery's front of model size against the held-out long-time error from the first state and
  along the runs, with error bars over folds;
* ``coefficients.png``: per-run refined coefficients (SI, normalised by the final value) of the selected terms;
* ``optimisation.png``: loss against evaluation for every per-run refinement and the joint one;
* ``phase_portraits.png`` / ``poincare.png``: data vs minimal model for up to four runs.
"""
from __future__ import annotations

import os
from pathlib import Path
import numpy as np

from cubedimer.atomic import atomic_save
from cubedimer.terms import EQUATION_NAMES
from ..compare import Comparison
from ..method_names import get_method
from ..model import TERMS
from ..results import EnsembleExtras, FitResult, RunFit
from ..selection.discovery_config import KNEE_TOLERANCE
from ..selection.integral_discovery import DiscoveryResult

__all__ = ["plot_fit", "plot_comparison"]


def _plt():
    import matplotlib.pyplot as plt

    return plt


def _save(fig, path: Path) -> None:
    atomic_save(path, lambda tmp: fig.savefig(tmp, dpi=110, bbox_inches="tight", format="png"))
    _plt().close(fig)


def plot_fit(res: FitResult, out_dir: str | os.PathLike, n_runs: int = 4) -> list[Path]:
    """Write the fit figures to ``out_dir``; returns their paths."""
    plt = _plt()
    out = Path(out_dir)
    paths = []
    if isinstance(res.extras, EnsembleExtras):  # a method with across-run statistics
        paths.append(_plot_zscores(res, res.extras.stats, out / "zscores.png"))
    discovery = getattr(res.extras, "discovery", None)  # a method with a discovery path (DiscoveryExtras)
    if isinstance(discovery, DiscoveryResult):
        paths.append(_plot_pareto(discovery, out / "pareto.png"))
        if discovery.front is not None:
            paths.append(_plot_front(discovery, out / "front.png"))
    # coefficient distributions
    sel = [(q, j) for q in range(2) for j in range(len(TERMS)) if res.mask[q, j]]
    fig, ax = plt.subplots(figsize=(max(6, 0.7 * len(sel)), 4))
    c = np.array([f.model.coef for f in res.run_fits])
    for k, (q, j) in enumerate(sel):
        ref = res.model.coef[q, j] if res.model.coef[q, j] != 0 else 1.0
        ax.plot(np.full(c.shape[0], k) + np.linspace(-0.15, 0.15, c.shape[0]), c[:, q, j] / ref, "o", ms=3, alpha=0.7)
    ax.axhline(1.0, color="k", lw=0.8)
    ax.set_xticks(range(len(sel)), [f"{EQUATION_NAMES[q][:-3]}: {TERMS[j]}" for q, j in sel], rotation=60, ha="right")
    ax.set_ylabel("per-run refined / final coefficient")
    ax.set_title("coefficient distributions over runs (selected terms)")
    paths.append(out / "coefficients.png")
    _save(fig, paths[-1])
    # optimisation trajectory
    fig, ax = plt.subplots(figsize=(7, 4))
    for f in res.run_fits:
        if not isinstance(f, RunFit):  # per-run results without an optimisation (the discovery's least squares)
            continue
        ax.plot(np.minimum.accumulate(f.history), color="tab:gray", lw=0.6, alpha=0.6)
    ax.plot(np.minimum.accumulate(res.joint.history), color="tab:red", lw=1.5, label="joint (minimal model)")
    ax.set_yscale("log")
    ax.set_xlabel("objective evaluation")
    ax.set_ylabel("best loss so far")
    ax.legend()
    ax.set_title("optimisation trajectories (gray: per-run refinements)")
    paths.append(out / "optimisation.png")
    _save(fig, paths[-1])
    # phase portraits and Poincare maps
    from cubedimer.poincare import poincare_section
    from ..refinement.long_time import scaled_reference

    runs = res.runs[:n_runs]
    fig1, ax1 = plt.subplots(2, len(runs), figsize=(3.2 * len(runs), 6), squeeze=False)
    fig2, ax2 = plt.subplots(1, len(runs), figsize=(3.2 * len(runs), 3.2), squeeze=False)
    for k, p in enumerate(runs):
        ref = scaled_reference(p.derivs, res.scales)
        t = ref.t * res.scales.time
        data = ref.state * res.scales.state
        sim, nv = res.model.simulate(data[0], t)
        for row, (i, j, lab) in enumerate([(0, 1, ("y [um]", "ydot [mm/s]")), (2, 3, ("theta", "thetadot [1/s]"))]):
            sc = (1e6, 1e3) if row == 0 else (1.0, 1.0)
            ax1[row, k].plot(data[:, i] * sc[0], data[:, j] * sc[1], lw=0.4, color="k", label="data")
            ax1[row, k].plot(sim[:nv, i] * sc[0], sim[:nv, j] * sc[1], lw=0.4, color="tab:red", alpha=0.8, label="model")
            ax1[row, k].set_xlabel(lab[0])
            ax1[row, k].set_ylabel(lab[1])
        ax1[0, k].set_title(p.run.name)
        sd, ss = poincare_section(t, data), poincare_section(t[:nv], sim[:nv])
        ax2[0, k].plot(sd.theta, sd.thetadot, "o", ms=3, color="k", label="data")
        ax2[0, k].plot(ss.theta, ss.thetadot, "x", ms=3, color="tab:red", label="model")
        ax2[0, k].set_xlabel("theta at y = 0, ydot < 0")
        ax2[0, k].set_ylabel("thetadot [1/s]")
        ax2[0, k].set_title(p.run.name)
    ax1[0, 0].legend(fontsize=7)
    ax2[0, 0].legend(fontsize=7)
    paths += [out / "phase_portraits.png", out / "poincare.png"]
    _save(fig1, paths[-2])
    _save(fig2, paths[-1])
    return paths


def _plot_zscores(res: FitResult, stats, path: Path) -> Path:
    """Every term's z-score across runs per equation, the selected terms in red, the paper's threshold dashed."""
    plt = _plt()
    fig, axes = plt.subplots(2, 1, figsize=(13, 6.5), sharex=True)
    thr = res.config.method.ensemble.z_threshold
    for q, ax in enumerate(axes):
        z = np.minimum(stats.zscore[q], 1e3)
        ax.bar(range(len(TERMS)), z, color=np.where(res.mask[q], "tab:red", "tab:gray"))
        ax.axhline(thr, color="k", ls="--", lw=1)
        ax.set_yscale("symlog", linthresh=1)
        ax.set_ylabel(f"z-score ({EQUATION_NAMES[q]})")
    axes[1].set_xticks(range(len(TERMS)), TERMS, rotation=90)
    rule = get_method(res.method).describe(res).selected_by  # the method's (or its selection rule's) words
    axes[0].set_title(f"term z-scores (mean / std) across runs; red: selected {rule}; dashed: the paper's z = {thr:g}")
    _save(fig, path)
    return path


def _plot_pareto(disc, path: Path) -> Path:
    """Held-out error against the number of terms per equation (the discovery's elimination paths)."""
    plt = _plt()
    fig, axes = plt.subplots(1, 2, figsize=(11, 4))
    for ax, eq in zip(axes, EQUATION_NAMES):
        pts = [p for p in disc.pareto[eq] if np.isfinite(p.heldout_rms)]
        if not pts:
            ax.set_axis_off()
            continue
        best = min(p.heldout_rms for p in pts)
        n = np.array([p.n_terms for p in pts])
        excess = np.array([100.0 * (p.heldout_rms / best - 1.0) for p in pts])
        ax.plot(n, excess, "o", color="tab:gray", ms=4, label="supports on the elimination paths")
        sel = [k for k, p in enumerate(pts) if p.selected]
        ax.plot(n[sel], excess[sel], "o", color="tab:red", ms=8, label="selected")
        ax.axhline(100 * KNEE_TOLERANCE, color="tab:blue", ls=":", lw=0.8)
        knee = disc.knee().get(eq)
        if knee is not None:
            k = next(i for i, p in enumerate(pts) if p.terms == knee)
            ax.plot(n[k], excess[k], "s", mfc="none", mec="tab:blue", ms=11, mew=1.5,
                    label=f"knee: smallest within {100 * KNEE_TOLERANCE:g} % of the best")
        ax.set_yscale("symlog", linthresh=0.01)
        ax.set_xlabel("number of terms")
        ax.set_ylabel("held-out RMS error above the smallest [%]")
        ax.set_title(f"{eq}: Pareto front (5-fold over runs)")
        ax.legend(fontsize=7)
    _save(fig, path)
    return path


def _plot_front(disc, path: Path) -> Path:
    """Held-out long-time error from the first state and along the runs (mean and standard error over folds) against
    the terms of both equations; the discovery's selection, the knee (one-standard-error rule) and the ``--max-terms`` pick marked."""
    from ..selection.front import ALONG_HORIZON_PERIODS

    plt = _plt()
    front = disc.front
    pts = [p for p in front.points if np.isfinite(p.error)]
    fig, ax = plt.subplots(figsize=(7, 4.2))
    n = np.array([sum(p.n_terms) for p in pts])
    err = np.array([100.0 * p.error for p in pts])
    se = np.array([100.0 * p.error_se if np.isfinite(p.error_se) else 0.0 for p in pts])
    ax.errorbar(n, err, yerr=se, fmt="o-", color="tab:gray", ms=4, capsize=2,
                label=f"from the first state ({front.n_folds}-fold over runs, +- 1 standard error)")
    along = [p for p in pts if np.isfinite(p.error_along)]
    if along:
        ax.errorbar([sum(p.n_terms) for p in along], [100.0 * p.error_along for p in along],
                    yerr=[100.0 * p.error_along_se if np.isfinite(p.error_along_se) else 0.0 for p in along],
                    fmt="^--", color="tab:orange", ms=4, capsize=2,
                    label=f"along the runs (restarted from the data every {ALONG_HORIZON_PERIODS:g} slow periods)")
    marks = [(front.selected, "o", "tab:red", "selected (the default)"),
             (front.knee, "s", "tab:blue", "knee: smallest within 1 standard error of the best")]
    if disc.max_terms is not None:
        fitted = {eq: tuple(t) for eq, t in disc.terms().items()}
        picked = next((p for p in pts if {eq: tuple(sorted(t)) for eq, t in p.terms.items()}
                       == {eq: tuple(sorted(t)) for eq, t in fitted.items()}), None)
        marks.append((picked, "D", "tab:green", f"--max-terms {disc.max_terms}"))
    for point, marker, colour, label in marks:
        if point is not None and np.isfinite(point.error):
            ax.plot(sum(point.n_terms), 100.0 * point.error, marker, mfc="none", mec=colour, ms=11, mew=1.5,
                    label=label)
    ax.set_yscale("log")
    ax.set_xlabel("terms (both equations)")
    ax.set_ylabel("held-out long-time error [% of the RMS motion]")
    ax.set_title("front: model size against held-out long-time error")
    ax.legend(fontsize=7)
    _save(fig, path)
    return path


def plot_comparison(cmp: Comparison, out_dir: str | os.PathLike) -> Path:
    """Per-run shape and Poincare errors of the variant against the reference model."""
    plt = _plt()
    fig, axes = plt.subplots(1, 2, figsize=(9, 4))
    for ax, key, test in ((axes[0], "shape", cmp.shape_test), (axes[1], "poincare", cmp.poincare_test)):
        r = [getattr(x, key) for x in cmp.reference_losses]
        v = [getattr(x, key) for x in cmp.variant_losses]
        ax.loglog(r, v, "o")
        lim = [min(r + v) * 0.8, max(r + v) * 1.25]
        ax.plot(lim, lim, "k--", lw=0.8)
        ax.set_xlabel(f"minimal model {key} error")
        ax.set_ylabel(f"variant {key} error")
        ax.set_title(f"Wilcoxon p(variant worse) = {test.p_greater:.2g}")
    path = Path(out_dir) / "compare.png"
    _save(fig, path)
    return path
