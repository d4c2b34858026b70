"""Baselines against the default discovery on the sparse-truth data sets, and the detection curve.

Two modes, both on the data sets of :mod:`benchmarks.bench_discovery` (same generator, same seeds):

* ``--baselines``: on each data set, pysindy STLSQ on the Savitzky-Golay accelerations with the cubic
  library, pysindy's ``EnsembleOptimizer`` (bagged STLSQ), pysindy's weak form (``WeakPDELibrary`` on the
  first-order state), the paper's pipeline (``FitConfig.for_method("paper")``, one worker process) and ours
  (:func:`fitting.selection.integral_discovery.discover_model`).  Per method and data set: missing true terms, spurious
  terms, median and max relative coefficient error on the true terms found, wall time.
* ``--detection-curve``: the ``paper``, ``weak8`` and ``weak20`` truths at 6, 8, 12, 20 and 30 runs (other
  settings of each case); every true term's oracle z (:mod:`fitting.uncertainty.oracle`) and whether ours and STLSQ
  selected it; the fraction found per oracle-z bin and run count, and the spurious terms, optionally
  plotted (``--figure PATH``).

The pysindy settings are fixed once for every data set (:data:`STLSQ_THRESHOLD`, :data:`STLSQ_ALPHA`,
:data:`WEAK_WINDOW_S`, :data:`WEAK_WINDOWS_PER_RUN`; the thresholds are those of
:class:`fitting.selection.sparse_regression.RegressionConfig`, dimensionless in the scaled variables).

Run ``python -m benchmarks.bench_baselines --baselines --detection-curve [--cases paper signs stiff]
[--seeds 101 102] [--paper-seeds 101] [--curve-seeds 101 102 103 104]
[--figure docs/figures/detection_curve.png]``.
``main()`` with no options runs both at the default sizes without writing a figure (the
``python -m benchmarks`` runner's contract: it returns the markdown report).
"""
from __future__ import annotations

import argparse
import dataclasses
import sys
import time
import warnings
from dataclasses import dataclass
from typing import Callable, Sequence

import numpy as np
from numpy.typing import NDArray

from benchmarks.bench_discovery import CASES, Case, make_data, oracle

#: STLSQ threshold and ridge alpha of every pysindy baseline (scaled variables; RegressionConfig's defaults)
STLSQ_THRESHOLD = 0.003
STLSQ_ALPHA = 0.3
#: weak form: half-width of the test-function windows [s] (the discovery's 25-ms window) and windows per run
WEAK_WINDOW_S = 0.025
WEAK_WINDOWS_PER_RUN = 200
#: EnsembleOptimizer: bagged models and inclusion probability for a term to be kept
ENSEMBLE_MODELS = 50
ENSEMBLE_INCLUSION = 0.5
#: run counts and oracle-z bin edges of the detection curve
CURVE_RUNS = (6, 8, 12, 20, 30)
Z_BINS = (0.0, 2.0, 5.0, 10.0, 20.0, np.inf)


@dataclass(frozen=True)
class TermScore:
    """Support and coefficient errors of a fitted (2, 35) coefficient array against the truth.

    Attributes
    ----------
    missing : tuple of str
        True terms not selected (``equation:term``).
    spurious : tuple of str
        Selected terms that are not in the truth.
    rel_errors : ndarray
        |fitted / true - 1| of the true terms that were selected.
    """

    missing: tuple[str, ...]
    spurious: tuple[str, ...]
    rel_errors: NDArray[np.float64]

    @property
    def median_error(self) -> float:
        """Median relative error on the true terms found (NaN if none)."""
        return float(np.median(self.rel_errors)) if self.rel_errors.size else float("nan")

    @property
    def max_error(self) -> float:
        """Largest relative error on the true terms found (NaN if none)."""
        return float(np.max(self.rel_errors)) if self.rel_errors.size else float("nan")


def score_terms(true_coef: NDArray[np.float64], coef: NDArray[np.float64]) -> TermScore:
    """Missing and spurious terms and the relative errors of the true terms found.

    Parameters
    ----------
    true_coef, coef : ndarray (2, 35)
        True and fitted coefficients (rows yddot, thetaddot; columns :data:`fitting.model.TERMS`); a term is
        selected when its coefficient is non-zero.

    Returns
    -------
    TermScore
    """
    from cubedimer.terms import coefficient_label

    true, sel = np.asarray(true_coef) != 0, np.asarray(coef) != 0
    missing = tuple(coefficient_label(q, j) for q, j in zip(*np.nonzero(true & ~sel)))
    spurious = tuple(coefficient_label(q, j) for q, j in zip(*np.nonzero(sel & ~true)))
    found = true & sel
    rel = np.abs(np.asarray(coef)[found] / np.asarray(true_coef)[found] - 1.0)
    return TermScore(missing, spurious, rel)


def weak_sindy(derivs: Sequence, scales) -> NDArray[np.float64]:
    """pysindy's weak form (``WeakPDELibrary``, cubic polynomial library with a constant) on the smoothed
    first-order state (y, ydot, theta, thetadot) of every run, STLSQ at the fixed threshold.

    The weak left-hand side of the ydot and thetadot columns is -int phi' ydot and -int phi' thetadot, so
    the second and fourth equations are the yddot and thetaddot equations.

    Returns
    -------
    ndarray (2, 35)
        SI coefficients of [yddot, thetaddot].
    """
    import pysindy as ps

    from cubedimer.terms import STATE_NAMES
    from fitting.selection.sparse_regression import pysindy_to_canonical

    X = [d.state / scales.state for d in derivs]
    t = (derivs[0].t - derivs[0].t[0]) / scales.time
    n = min(len(x) for x in X)
    X = [x[:n] for x in X]
    lib = ps.WeakPDELibrary(function_library=ps.PolynomialLibrary(degree=3, include_bias=True),
                            spatiotemporal_grid=t[:n], K=WEAK_WINDOWS_PER_RUN, H_xt=WEAK_WINDOW_S / scales.time,
                            p=4)
    model = ps.SINDy(optimizer=ps.STLSQ(threshold=STLSQ_THRESHOLD, alpha=STLSQ_ALPHA), feature_library=lib)
    np.random.seed(0)  # the window centres are drawn from numpy's global generator
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model.fit(X, t=t[1] - t[0], feature_names=list(STATE_NAMES))
    names = model.get_feature_names()
    coef = np.asarray(model.coefficients())[[1, 3]]
    return scales.to_si(pysindy_to_canonical(names, coef))


@dataclass(frozen=True)
class MethodResult:
    """One method on one data set."""

    method: str
    score: TermScore
    wall: float


def _timed(fn: Callable[[], NDArray[np.float64]]) -> tuple[NDArray[np.float64], float]:
    t0 = time.perf_counter()
    coef = fn()
    return coef, time.perf_counter() - t0


def run_baselines(case: Case, seed: int, paper: bool) -> list[MethodResult]:
    """Every method on one data set (the paper's pipeline only when ``paper``)."""
    from cubedimer.executor import ExecutorConfig
    from cubedimer.spectra import dominant_frequency
    from fitting.selection.integral_discovery import DiscoveryConfig, discover_model
    from fitting.config import FitConfig
    from fitting.fit import fit_runs, prepare_runs
    from fitting.selection.sparse_regression import (RegressionConfig, dataset_scales, fit_ensemble_regression,
                                                     fit_regression)

    truth, runs, derivs, _ = make_data(case, seed)
    scales = dataset_scales(derivs, [dominant_frequency(r.y, r.dt) for r in runs])
    plain = RegressionConfig(threshold=STLSQ_THRESHOLD, alpha=STLSQ_ALPHA, matched_filter=False)
    methods: dict[str, Callable[[], NDArray[np.float64]]] = {
        "pysindy STLSQ": lambda: fit_regression(derivs, scales, plain).coef,
        "pysindy EnsembleOptimizer": lambda: fit_ensemble_regression(
            derivs, scales, plain, n_models=ENSEMBLE_MODELS, inclusion=ENSEMBLE_INCLUSION, seed=seed)[0].coef,
        "pysindy WeakPDELibrary": lambda: weak_sindy(derivs, scales),
    }
    if paper:
        def paper_fit() -> NDArray[np.float64]:
            cfg = FitConfig.for_method("paper")
            prepared, sc = prepare_runs(runs, cfg)
            return fit_runs(prepared, sc, cfg, executor=ExecutorConfig(workers=1), cache_dir=None,
                            progress=False).model.coef

        methods["paper's pipeline"] = paper_fit
    methods["ours (discover_model)"] = lambda: discover_model(runs, derivs, DiscoveryConfig()).coef
    out = []
    for name, fn in methods.items():
        coef, wall = _timed(fn)
        out.append(MethodResult(name, score_terms(truth.coef, coef), wall))
        print(f"[baselines] {case.name} {seed} {name}: {len(out[-1].score.missing)} missing, "
              f"{len(out[-1].score.spurious)} spurious, {wall:.1f} s", file=sys.stderr, flush=True)
    return out


def _pct(x: float) -> str:
    return "-" if not np.isfinite(x) else f"{100 * x:.1f} %"


def baselines_table(results: dict[tuple[str, int], list[MethodResult]]) -> list[str]:
    """Markdown: one row per data set and method, then one summary row per method."""
    lines = ["| data set | seed | method | missing true terms | spurious terms | median / max coefficient error "
             "(true terms found) | wall time [s] |", "|---|---|---|---|---|---|---|"]
    per_method: dict[str, list[MethodResult]] = {}
    for (case, seed), res in results.items():
        for r in res:
            per_method.setdefault(r.method, []).append(r)
            s = r.score
            miss = f"{len(s.missing)}" + (f" ({', '.join(s.missing)})" if s.missing else "")
            spur = f"{len(s.spurious)}" + (f" ({', '.join(s.spurious)})" if s.spurious else "")
            lines.append(f"| {case} | {seed} | {r.method} | {miss} | {spur} | {_pct(s.median_error)} / "
                         f"{_pct(s.max_error)} | {r.wall:.1f} |")
    lines += ["", "| method | data sets | missing (total) | spurious (total) | median of median errors | "
              "largest error | median wall time [s] |", "|---|---|---|---|---|---|---|"]
    for m, rs in per_method.items():
        med = np.nanmedian([r.score.median_error for r in rs])
        mx = np.nanmax([r.score.max_error for r in rs])
        lines.append(f"| {m} | {len(rs)} | {sum(len(r.score.missing) for r in rs)} | "
                     f"{sum(len(r.score.spurious) for r in rs)} | {_pct(med)} | {_pct(mx)} | "
                     f"{np.median([r.wall for r in rs]):.1f} |")
    return lines


@dataclass(frozen=True)
class Detection:
    """One true term on one data set of the detection curve."""

    case: str
    n_runs: int
    seed: int
    term: str
    oracle_z: float
    found: dict[str, bool]
    #: spurious terms each method selected on this term's data set
    spurious: dict[str, int]


def detection_data(base: Case, n_runs: int, seed: int) -> list[Detection]:
    """Oracle z of every true term of ``base`` at ``n_runs`` runs and whether ours and STLSQ selected it."""
    from cubedimer.spectra import dominant_frequency
    from cubedimer.terms import coefficient_label
    from fitting.selection.integral_discovery import DiscoveryConfig, discover_model
    from fitting.selection.sparse_regression import RegressionConfig, dataset_scales, fit_regression

    case = dataclasses.replace(base, n_runs=n_runs)
    truth, runs, derivs, exact = make_data(case, seed)
    se = oracle(truth, runs, exact, (case.noise_y, case.noise_theta))
    scales = dataset_scales(derivs, [dominant_frequency(r.y, r.dt) for r in runs])
    sel = {"ours": discover_model(runs, derivs, DiscoveryConfig()).mask,
           "STLSQ": fit_regression(derivs, scales, RegressionConfig(
               threshold=STLSQ_THRESHOLD, alpha=STLSQ_ALPHA, matched_filter=False)).support}
    spurious = {m: int((s & ~truth.support).sum()) for m, s in sel.items()}
    out = []
    for q, j in zip(*np.nonzero(truth.support)):
        out.append(Detection(base.name, n_runs, seed, coefficient_label(q, j),
                             float(abs(truth.coef[q, j]) / se[q, j]), {m: bool(s[q, j]) for m, s in sel.items()},
                             spurious))
    return out


def _bin_label(lo: float, hi: float) -> str:
    return f"< {hi:g}" if lo == 0 else (f">= {lo:g}" if not np.isfinite(hi) else f"{lo:g}-{hi:g}")


def detection_table(dets: Sequence[Detection], method: str) -> list[str]:
    """Markdown: true terms found / true terms per run count (rows) and oracle-z bin (columns), and the spurious
    terms over the data sets of each run count."""
    edges = list(zip(Z_BINS[:-1], Z_BINS[1:]))
    lines = ["| runs | " + " | ".join(f"oracle z {_bin_label(lo, hi)}" for lo, hi in edges)
             + " | all | spurious terms (total over data sets) |", "|---" * (len(edges) + 3) + "|"]
    for n in sorted({d.n_runs for d in dets}):
        cells = []
        for lo, hi in [*edges, (-np.inf, np.inf)]:
            sub = [d.found[method] for d in dets if d.n_runs == n and lo <= d.oracle_z < hi]
            cells.append(f"{sum(sub)} / {len(sub)}" if sub else "-")
        per_set = {(d.case, d.seed): d.spurious[method] for d in dets if d.n_runs == n}
        cells.append(f"{sum(per_set.values())} on {len(per_set)} data sets")
        lines.append(f"| {n} | " + " | ".join(cells) + " |")
    return lines


def term_z_table(dets: Sequence[Detection]) -> list[str]:
    """Markdown: each true term's oracle z (median over seeds) per run count, with how often each method found it
    (one truth: pass the detections of one case)."""
    runs = sorted({d.n_runs for d in dets})
    terms = list(dict.fromkeys(d.term for d in dets))
    methods = list(dets[0].found)
    lines = ["| term | " + " | ".join(f"{n} runs" for n in runs) + " |", "|---" * (len(runs) + 1) + "|"]
    for t in terms:
        cells = []
        for n in runs:
            sub = [d for d in dets if d.term == t and d.n_runs == n]
            found = ", ".join(f"{m} {sum(d.found[m] for d in sub)}/{len(sub)}" for m in methods)
            cells.append(f"z {np.median([d.oracle_z for d in sub]):.1f} ({found})")
        lines.append(f"| {t} | " + " | ".join(cells) + " |")
    return lines


def plot_detection(dets: Sequence[Detection], path: str) -> None:
    """Fraction of true terms found against oracle z, one line per run count; one panel per method (ours,
    pysindy STLSQ).  Marker area is proportional to the number of true terms in the bin."""
    import matplotlib.pyplot as plt

    edges = list(zip(Z_BINS[:-1], Z_BINS[1:]))
    centres = np.arange(len(edges))
    runs = sorted({d.n_runs for d in dets})
    cmap = plt.get_cmap("viridis")
    fig, axes = plt.subplots(1, 2, figsize=(10, 4.2), sharey=True)
    for ax, (method, title) in zip(axes, (("ours", "ours (discover_model)"), ("STLSQ", "pysindy STLSQ"))):
        for k, n in enumerate(runs):
            frac, count = [], []
            for lo, hi in edges:
                sub = [d.found[method] for d in dets if d.n_runs == n and lo <= d.oracle_z < hi]
                frac.append(np.mean(sub) if sub else np.nan)
                count.append(len(sub))
            colour = cmap(k / max(len(runs) - 1, 1))
            x = centres + 0.06 * (k - (len(runs) - 1) / 2)  # a small offset so overlapping points stay visible
            ok = np.isfinite(frac)
            ax.plot(x[ok], np.asarray(frac)[ok], "-", color=colour, alpha=0.6, label=f"{n} runs")
            ax.scatter(x[ok], np.asarray(frac)[ok], s=12 + 3 * np.asarray(count)[ok], color=colour, zorder=3)
        ax.set_xticks(centres, [_bin_label(lo, hi) for lo, hi in edges])
        ax.set_xlabel("oracle z of the true term")
        ax.set_title(title, fontsize=10)
        ax.set_ylim(-0.05, 1.05)
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("fraction of true terms found")
    axes[0].legend(fontsize=8, loc="lower right")
    cases = ", ".join(dict.fromkeys(d.case for d in dets))
    fig.suptitle(f"Detection curve ({cases} truths; marker area ~ number of true terms in the bin)", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def _settings(case: Case) -> str:
    return (f"{case.name}: {case.n_runs} runs x {case.duration:g} s at {case.fps:g} fps, "
            f"noise {case.noise_y * 1e6:g} um / {case.noise_theta:g}")


def main(argv: list[str] | None = None) -> str:
    """Run the benchmark and return the markdown report.  ``argv`` None (the ``python -m benchmarks`` runner):
    both modes at a reduced size (seed 101, the paper's pipeline on the ``paper`` truth only, two curve seeds;
    about 4 minutes); the tables of docs/fitting.md come from the commands given there."""
    ap = argparse.ArgumentParser(prog="python -m benchmarks.bench_baselines", description=__doc__.splitlines()[0])
    ap.add_argument("--baselines", action="store_true", help="the baselines table")
    ap.add_argument("--detection-curve", action="store_true", help="the detection curve")
    ap.add_argument("--cases", nargs="*", default=["paper", "signs", "stiff"])
    ap.add_argument("--seeds", nargs="*", type=int, default=[101, 102])
    ap.add_argument("--paper-cases", nargs="*", default=None,
                    help="data sets (case names) on which the paper's pipeline runs (default: all; it is slow)")
    ap.add_argument("--paper-seeds", nargs="*", type=int, default=[101],
                    help="seeds on which the paper's pipeline runs (default 101; it takes 70-200 s per data set)")
    ap.add_argument("--curve-cases", nargs="*", default=["paper", "weak8", "weak20"],
                    help="truths of the detection curve (each at every --curve-runs, other settings of the case)")
    ap.add_argument("--curve-runs", nargs="*", type=int, default=list(CURVE_RUNS))
    ap.add_argument("--curve-seeds", nargs="*", type=int, default=[101, 102, 103, 104])
    ap.add_argument("--figure", default=None, help="write the detection curve to this PNG")
    if argv is None:
        argv = ["--seeds", "101", "--paper-cases", "paper", "--curve-seeds", "101", "102"]
    args = ap.parse_args(argv)
    both = not (args.baselines or args.detection_curve)
    lines: list[str] = []
    if args.baselines or both:
        t0 = time.perf_counter()
        results = {}
        for name in args.cases:
            for seed in args.seeds:
                paper = ((args.paper_cases is None or name in args.paper_cases)
                         and (args.paper_seeds is None or seed in args.paper_seeds))
                results[(name, seed)] = run_baselines(CASES[name], seed, paper)
        lines += ["## Baselines on the sparse-truth data sets", "",
                  "Data sets: " + "; ".join(_settings(CASES[n]) for n in args.cases) + f"; seeds {args.seeds}.", "",
                  *baselines_table(results), "", f"_baselines: {time.perf_counter() - t0:.0f} s wall._", ""]
    if args.detection_curve or both:
        t0 = time.perf_counter()
        dets: list[Detection] = []
        for name in args.curve_cases:
            for n in args.curve_runs:
                for seed in args.curve_seeds:
                    dets += detection_data(CASES[name], n, seed)
                    print(f"[curve] {name} {n} runs, seed {seed} done", file=sys.stderr, flush=True)
        lines += ["## Detection curve", "",
                  "Truths and settings (the run count replaced by each of "
                  f"{args.curve_runs}): " + "; ".join(_settings(CASES[n]) for n in args.curve_cases)
                  + f"; seeds {args.curve_seeds}.", "",
                  "Ours (`discover_model`), true terms found / true terms per oracle-z bin (all truths pooled):", "",
                  *detection_table(dets, "ours"), "", "pysindy STLSQ:", "", *detection_table(dets, "STLSQ"), ""]
        for name in args.curve_cases:
            lines += [f"Per term, `{name}` (median oracle z over seeds; found by each method / seeds):", "",
                      *term_z_table([d for d in dets if d.case == name]), ""]
        lines += [f"_detection curve: {time.perf_counter() - t0:.0f} s wall._", ""]
        if args.figure:
            plot_detection(dets, args.figure)
    return "\n".join(lines)


if __name__ == "__main__":
    print(main(sys.argv[1:]))
