"""Support search on the pooled integral form, reduced to R factors.

A data set's integral-form design of one equation (:mod:`fitting.derivatives.integral_form`: detrended double integrals
of the 35 library columns per window, pooled over runs) is reduced to the R factor of the QR decomposition
of each run's ``[X b]`` (36 x 36).  A least squares on any support, its standard errors, the residual sum of
squares and a K-fold cross-validation over runs are then exact and cost microseconds, so whole elimination
paths and stepwise searches are cheap.

* :func:`select_support`: backward elimination until Holm's rule declares every term significant, then
  stepwise additions, swaps and two-for-one merges (:func:`_stepwise`).
* :func:`prune_heldout`: the elimination continued from a support down to the forced terms, keeping the
  support with the smallest held-out error.
* :func:`heldout_inflation`: how far a support's held-out misfit exceeds its in-sample residual, in units of what
  white noise explains (a sign of model error that spare terms cannot hide).
* :func:`numerov_columns`: the prefilter that makes the trapezoid double integral fourth-order accurate.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np
from numpy.typing import NDArray

from cubedimer.folds import run_folds
from cubedimer.terms import is_velocity_free
from ..derivatives.integral_form import detrend_windows, integral_columns, window_starts
from ..model import TERMS
from ..multiple_testing import holm_all_significant, holm_backward_elimination, holm_z_threshold

__all__ = ["ReducedDesign", "reduced_design", "run_weights", "numerov_columns", "fit_support", "fit_on_runs", "heldout_rms", "heldout_inflation",
           "select_support", "prune_heldout"]

@dataclass(frozen=True)
class ReducedDesign:
    """One equation's design over all runs, reduced to R factors of ``[X b]``."""

    per_run: list[NDArray[np.float64]]   # R factor of every run's [X b]
    rows: NDArray[np.int64]              # frames per run
    windows: NDArray[np.int64]           # windows per run
    total: NDArray[np.float64]           # R factor of all runs

    @property
    def dof(self) -> int:
        """Frames less the two integration constants (offset and slope) of every window."""
        return int(self.rows.sum() - 2 * self.windows.sum())


def _r_factor(blocks: Sequence[NDArray]) -> NDArray[np.float64]:
    return np.linalg.qr(np.vstack(blocks), mode="r")


def numerov_columns(f: NDArray) -> NDArray[np.float64]:
    """Library columns (n, ...) prefiltered so that the trapezoid double integral of
    :func:`fitting.derivatives.integral_form.integral_columns` is fourth-order accurate.

    Twice the trapezoid rule gives ``x[k+1] - 2 x[k] + x[k-1] = dt^2 (f[k-1] + 2 f[k] + f[k+1]) / 4``;
    Numerov's relation ``dt^2 (f[k-1] + 10 f[k] + f[k+1]) / 12`` is exact to O(dt^6).  Replacing f by
    ``g = (-f[k-1] + 8 f[k] - f[k+1]) / 6`` makes the two agree to O((omega dt)^4) (the straight lines
    that differ are removed by the detrending).  Without it the double integral is (omega dt)^2 / 6
    too large at angular frequency omega: 0.14 % at 22 Hz and 1500 fps, measured as a y-stiffness
    bias of 7.6 oracle standard errors on 12 runs; a model whose frequency is that far off drifts in
    phase over a state-estimation segment.  The first and last frames are left unchanged.
    """
    f = np.asarray(f, float)
    g = f.copy()
    g[1:-1] = (8.0 * f[1:-1] - f[:-2] - f[2:]) / 6.0
    return g


_VELOCITY_FREE = np.array([is_velocity_free(t) for t in TERMS])


def reduced_design(positions: Sequence[NDArray], library: Sequence[NDArray], dts: Sequence[float],
                   windows: Sequence[int], trims: Sequence[int], cache: dict | None = None,
                   weights: Sequence[float] | None = None) -> ReducedDesign:
    """R factors of the integral-form design of one equation.  ``cache`` (run index -> ((trim, window), columns))
    keeps the integrated velocity-free columns between passes whose position states are the same (raw) data.
    ``weights`` (one per run, :func:`run_weights`) multiply each run's rows: weighted least squares for runs of
    different tracking noise."""
    rs, rows, wins = [], [], []
    for i, (x, f, dt, w, tr) in enumerate(zip(positions, library, dts, windows, trims)):
        starts = window_starts(len(x), int(w), int(tr))
        if starts.size == 0:
            continue
        X = np.empty((starts.size * int(w), f.shape[1]))
        hit = cache is not None and i in cache and cache[i][0] == (tr, int(w))
        cols = ~_VELOCITY_FREE if hit else np.ones(f.shape[1], bool)
        X[:, cols] = integral_columns(numerov_columns(f[:, cols]), dt, starts, int(w))
        if hit:
            X[:, _VELOCITY_FREE] = cache[i][1]
        elif cache is not None:
            cache[i] = ((tr, int(w)), X[:, _VELOCITY_FREE].copy())
        b = detrend_windows(x, starts, int(w))
        rs.append(_r_factor([np.column_stack([X, b])]) * (1.0 if weights is None else float(weights[i])))
        rows.append(X.shape[0])
        wins.append(starts.size)
    if not rs:
        raise ValueError("no run is long enough for one integral-form window")
    return ReducedDesign(rs, np.array(rows), np.array(wins), _r_factor(rs))


def run_weights(noise: Sequence[float | None]) -> NDArray[np.float64] | None:
    """Per run, the weight of its rows in the pooled least squares: ``sigma_ref / sigma_run`` with ``sigma_ref`` the
    RMS of the runs' noises, so that every run's weighted residual has the one standard deviation sigma_ref (white
    noise of different levels: weighted least squares is then the efficient estimator and its standard errors are
    honest).  None (every run weighs alike) unless every run states a positive finite noise, or when all state the
    same."""
    s = np.array([np.nan if v is None else float(v) for v in noise])
    if s.size == 0 or not np.all(np.isfinite(s) & (s > 0)) or np.all(s == s[0]):
        return None
    return np.sqrt(np.mean(s ** 2)) / s


def _lstsq(R: NDArray, cols: Sequence[int], covariance: bool = True) -> tuple[NDArray, NDArray | None, float]:
    """Coefficients, unscaled covariance (X_S^T X_S)^-1 (None unless ``covariance``) and residual sum of squares
    on the columns ``cols``."""
    A = R[:, cols]
    scale = np.maximum(np.linalg.norm(A, axis=0), 1e-300)
    As = A / scale
    c, *_ = np.linalg.lstsq(As, R[:, -1], rcond=None)
    r = R[:, -1] - As @ c
    cov = np.linalg.pinv(As.T @ As) / np.outer(scale, scale) if covariance else None
    return c / scale, cov, float(r @ r)


def fit_support(d: ReducedDesign, cols: Sequence[int]) -> tuple[NDArray, NDArray, float]:
    """Coefficients, standard errors and residual std on ``cols`` (dof: frames - 2 per window - terms)."""
    cols = list(cols)
    if not cols:
        dof = max(d.dof, 1)
        return np.zeros(0), np.zeros(0), float(np.sqrt(d.total[:, -1] @ d.total[:, -1] / dof))
    c, cov, rss = _lstsq(d.total, cols)
    dof = max(d.dof - len(cols), 1)
    s2 = rss / dof
    return c, np.sqrt(np.clip(np.diag(cov), 0.0, None) * s2), float(np.sqrt(s2))


def fit_on_runs(d: ReducedDesign, runs: Sequence[int], cols: Sequence[int]) -> NDArray[np.float64]:
    """Least-squares coefficients on ``cols`` from the runs ``runs`` alone (a fold's training runs)."""
    cols = list(cols)
    if not cols:
        return np.zeros(0)
    return _lstsq(_r_factor([d.per_run[r] for r in runs]), cols, covariance=False)[0]


def heldout_rms(d: ReducedDesign, paths: Sequence[Sequence[int]], n_folds: int) -> list[float]:
    """Held-out RMS misfit per degree of freedom of every support in ``paths`` (K-fold over runs): the runs' sums of
    :func:`heldout_per_run`, added fold by fold."""
    R = len(d.per_run)
    if R < 2:
        return [float("nan")] * len(paths)
    err = heldout_per_run(d, paths, n_folds)
    order = [r for _, test in run_folds(R, n_folds) for r in test]
    dof = max(float(d.dof), 1.0)
    return [float(np.sqrt(sum(float(e[r]) for r in order) / dof)) for e in err]


def heldout_inflation(design: ReducedDesign, support: Sequence[int], n_folds: int) -> float:
    """How far the held-out misfit (K-fold over runs) of ``support`` exceeds its in-sample residual, in units of what
    white noise explains: ``(heldout^2 / residual^2 - 1) * dof / terms`` with the residual per degree of freedom
    (:func:`fitting.selection.support_search.fit_support`) and ``dof`` the design's frames less two per window.  Of order 1
    when the residual is white noise; large when the support's terms fit model error that differs between runs
    (runs of other amplitudes).  NaN with fewer than two runs."""
    support = list(support)
    held = heldout_rms(design, [support], n_folds)[0]
    resid = fit_support(design, support)[2]
    dof = float(design.dof)
    if not (np.isfinite(held) and resid > 0):
        return float("nan")
    return float(((held / resid) ** 2 - 1.0) * dof / max(len(support), 1))


def heldout_per_run(d: ReducedDesign, paths: Sequence[Sequence[int]], n_folds: int) -> NDArray[np.float64]:
    """Held-out sum of squared misfits of every run (n_paths, R) for every support in ``paths`` (K-fold over runs,
    the folds of :func:`heldout_rms`)."""
    R = len(d.per_run)
    split = run_folds(R, n_folds)
    folds = [test for _, test in split]
    train = [_r_factor([d.per_run[r] for r in tr]) for tr, _ in split]
    out = np.zeros((len(paths), R))
    for i, cols in enumerate(paths):
        for fold, Rt in zip(folds, train):
            c = _lstsq(Rt, cols, covariance=False)[0] if len(cols) else np.zeros(0)
            for r in fold:
                res = d.per_run[r][:, list(cols)] @ c - d.per_run[r][:, -1]
                out[i, r] = float(res @ res)
    return out


def select_heldout(d: ReducedDesign, forced: NDArray[np.bool_], alpha: float = 0.01, velocity_first: bool = True,
                   n_folds: int = 5, se_rule: float = 1.0, tolerance: float = 0.0,
                   noise: float | None = None,
                   rms_tolerance: float = 0.0) -> tuple[list[int], list[list[int]], list[float]]:
    """Selection by held-out prediction over runs, for data whose residual is model error rather than noise.

    Backward elimination from the full library (least |z| first, velocity terms first while one is below the
    Bonferroni level) down to the forced terms; on that path the smallest support whose held-out error (K-fold over
    runs) exceeds the path's smallest by at most ``se_rule`` standard errors of the difference, the standard error
    from the paired per-run differences (the one-standard-error rule of cross-validation, paired over runs), or by
    at most ``tolerance`` (the mean over runs of each run's relative excess of held-out sum of squares), whichever
    is larger: an excess that small is the same held-out error even where its standard error is smaller.  Given the
    white ``noise`` (residual standard deviation units), the tolerance is taken as a share of the model error alone,
    ``tolerance * (1 - noise^2 / heldout^2)`` at the best support: the noise's part of the misfit no model reduces.
    A support whose held-out RMS error is within the relative ``rms_tolerance`` of the path's smallest counts as the
    same too (the user's practical threshold, as in :func:`prune_heldout`; 0: no such allowance).
    Returns the support, the path and the path's held-out RMS errors (as :func:`heldout_rms`)."""
    n_lib = d.total.shape[1] - 1
    path = [keep for keep, _ in _eliminate(d, range(n_lib), forced, alpha, velocity_first)]
    err = heldout_per_run(d, path, n_folds)
    dof = float(d.dof)
    held = [float(np.sqrt(e / max(dof, 1.0))) for e in err.sum(axis=1)]
    R = err.shape[1]
    if R < 2 or not np.all(np.isfinite(err)):
        return path[0], path, held
    total = err.sum(axis=1)
    best = int(np.argmin(total))
    rel = err / err[best] - 1.0  # each run's relative increase over the best support
    mean, se = rel.mean(axis=1), rel.std(axis=1, ddof=1) / np.sqrt(R)
    if noise is not None:  # the tolerance is a share of the model error, the part of the misfit a model can reduce
        tolerance *= max(0.0, 1.0 - (noise / held[best]) ** 2) if held[best] > 0 else 0.0
    limit = min(held) * (1.0 + rms_tolerance) if rms_tolerance > 0 else -np.inf
    chosen = max(i for i in range(len(path)) if mean[i] <= max(se_rule * se[i], tolerance) or held[i] <= limit)
    return path[chosen], path, held


def _abs_z(d: ReducedDesign, cols: Sequence[int]) -> NDArray[np.float64]:
    c, se, _ = fit_support(d, cols)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.nan_to_num(np.abs(c / se), nan=0.0)


def _rss(d: ReducedDesign, cols: Sequence[int]) -> float:
    return _lstsq(d.total, list(cols), covariance=False)[2] if len(cols) else float(d.total[:, -1] @ d.total[:, -1])


def _eliminate(d: ReducedDesign, cols: Sequence[int], forced: NDArray[np.bool_], alpha: float, velocity_first: bool):
    """Backward elimination from ``cols`` down to the forced terms (:func:`fitting.multiple_testing.holm_backward_elimination`):
    yields (support, |z|) before every step; with ``velocity_first`` velocity terms go first while one of them is
    below the Bonferroni level."""
    n_hyp = max(int(forced.size - forced.sum()), 1)
    velocity_z = holm_z_threshold(alpha, n_hyp, 1) if velocity_first else -np.inf
    for keep, absz, _ in holm_backward_elimination(lambda k: (_abs_z(d, k), None), cols, ~_VELOCITY_FREE, ~forced,
                                                   velocity_z):
        yield keep, absz


def _holm_ok(absz: NDArray, free: NDArray[np.bool_], alpha: float, n_hyp: int) -> bool:
    """Holm's rule over ``n_hyp`` hypotheses declares every free term significant."""
    return holm_all_significant(absz[free], alpha, n_hyp)


def select_support(d: ReducedDesign, forced: NDArray[np.bool_], alpha: float = 0.01, velocity_first: bool = True,
                   stepwise: bool = True, velocity_price: float | None = None) -> tuple[list[int], list[list[int]]]:
    """Backward elimination from the full library until Holm's rule declares every free term significant, then
    stepwise additions and swaps (:func:`_stepwise`); returns the selection and the elimination path."""
    n_lib = d.total.shape[1] - 1
    n_hyp = int(n_lib - forced.sum())
    path: list[list[int]] = []
    cols: list[int] = []
    for keep, absz in _eliminate(d, range(n_lib), forced, alpha, velocity_first):
        path.append(keep)
        cols = keep
        if _holm_ok(absz, ~forced[keep], alpha, n_hyp):
            break
    if stepwise:
        cols = _stepwise(d, cols, forced, alpha, n_hyp, velocity_price)
    return cols, path


def prune_heldout(d: ReducedDesign, cols: list[int], forced: NDArray[np.bool_], alpha: float = 0.01,
                  velocity_first: bool = True, n_folds: int = 5,
                  tolerance: float = 0.0) -> tuple[list[int], list[list[int]], list[float]]:
    """Continue the elimination from the significant support ``cols`` down to the forced terms and keep the
    smallest support whose held-out error is within the relative ``tolerance`` of the smallest on that path."""
    path = [keep for keep, _ in _eliminate(d, cols, forced, alpha, velocity_first)]
    held = heldout_rms(d, path, n_folds)
    if not np.all(np.isfinite(held)):
        return cols, path, held
    limit = min(held) * (1.0 + tolerance)
    best = max(i for i, h in enumerate(held) if h <= limit)
    return path[best], path, held


def _stepwise(d: ReducedDesign, cols: list[int], forced: NDArray[np.bool_], alpha: float, n_hyp: int,
              velocity_price: float | None = None) -> list[int]:
    """Improve a support found by backward elimination.

    Moves, in this order of preference: add the most significant outside term if every term stays
    significant (Holm); swap one free term for an outside one when that lowers the residual sum of squares;
    replace two free terms by one outside term when that raises the residual sum of squares by less than
    log(N) residual variances (N: degrees of freedom; the Bayesian information criterion's price of one
    parameter, for two non-nested supports).  Every move keeps all terms significant and never returns to a
    support met before; the search stops when no move applies.

    Why: backward elimination alone decides between two nearly collinear terms by which one the full
    library's fit happens to make less significant (measured: y*thetadot^2 with oracle z 7 lost to
    y*theta^2 on a nearly harmonic hinge); the swap compares the two supports directly.  Velocity terms earn
    their place: replacing a velocity-free term by a velocity term needs a drop of the residual sum of
    squares by more than z_alpha^2 residual variances (z_alpha = 2.58 at alpha = 0.01; a likelihood-ratio
    test at level alpha).  On harmonic y motion y^2*theta and ydot^2*theta are nearly collinear (measured
    drops of -5 to +2.4 residual variances between them, against +10 to +25 for y*thetadot^2 over
    y*theta^2), so this keeps the velocity-free term there.  The merge undoes a pair that stands in for one
    true term: y*theta^2 + ydot*theta*thetadot for y*thetadot^2 fitted 0.4 residual variances better on a
    35-Hz hinge and 8.0 on an 8-run set (z_alpha^2 = 6.6 would keep that pair; log(N) = 10.5 there), the
    best of the ~600 pairs the search tries.
    """
    from scipy.special import ndtri

    n_lib = d.total.shape[1] - 1
    velocity = ~_VELOCITY_FREE[:n_lib]
    z_alpha_sq = float(ndtri(1.0 - 0.5 * alpha)) ** 2
    tau = z_alpha_sq if velocity_price is None else float(velocity_price)
    tau_merge = max(z_alpha_sq, float(np.log(max(d.dof, 2))))
    cols = sorted(cols)
    visited = {tuple(cols)}

    def significant(trial: list[int]) -> bool:
        return tuple(trial) not in visited and _holm_ok(_abs_z(d, trial), ~forced[trial], alpha, n_hyp)

    def additions(outside: list[int], free: list[int], base: float, s2: float) -> list[list[int]]:
        """The most significant addition that keeps every term significant."""
        best = None
        for j in outside:
            trial = sorted(cols + [j])
            if tuple(trial) in visited:
                continue
            absz = _abs_z(d, trial)
            if _holm_ok(absz, ~forced[trial], alpha, n_hyp) and (best is None or absz[trial.index(j)] > best[0]):
                best = (absz[trial.index(j)], trial)
        return [best[1]] if best else []

    def swaps(outside: list[int], free: list[int], base: float, s2: float) -> list[list[int]]:
        """One-for-one swaps that lower the residual (a velocity term replacing a velocity-free one: by > tau)."""
        out = []
        for i in free:
            for j in outside:
                trial = sorted([k for k in cols if k != i] + [j])
                gain = (base - _rss(d, trial)) / s2
                if gain > (tau if velocity[j] and not velocity[i] else 0.0):
                    out.append((-gain, trial))
        return [t for _, t in sorted(out)]

    def merges(outside: list[int], free: list[int], base: float, s2: float) -> list[list[int]]:
        """Two-for-one replacements that cost less than ``tau_merge`` residual variances."""
        out = []
        for ia in range(len(free)):
            for ib in range(ia + 1, len(free)):
                rest = [k for k in cols if k not in (free[ia], free[ib])]
                for j in outside:
                    trial = sorted(rest + [j])
                    loss = (_rss(d, trial) - base) / s2
                    if loss < tau_merge:
                        out.append((loss, trial))
        return [t for _, t in sorted(out)]

    for _ in range(4 * n_lib):
        outside = [j for j in range(n_lib) if j not in cols]
        free = [i for i in cols if not forced[i]]
        base = _rss(d, cols)
        s2 = base / max(d.dof - len(cols), 1)
        moved = False
        for kind in (additions, swaps, merges):
            for trial in kind(outside, free, base, s2):
                if significant(trial):
                    cols = trial
                    visited.add(tuple(cols))
                    moved = True
                    break
            if moved:
                break
        if not moved:
            return cols
    return cols
