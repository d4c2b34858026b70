"""Model discovery on the integral form with model-based column states (the default selection).

Method
------
1. **Integral form, pooled over runs** (:mod:`fitting.integral_form`): per window of 0.75 of the
   coordinate's dominant period, the measured position minus its straight line is regressed on the
   detrended double integrals of the 35 library columns.  The residual is the white tracking noise,
   so least squares is efficient and its standard errors are honest.
2. **Selection** on each equation, in three steps.  (a) Backward elimination from the full library,
   dropping the least significant term (velocity terms first while one is below the Bonferroni level),
   until Holm's rule (:func:`fitting.multiple_testing.holm_reject`, family-wise ``alpha`` over the
   library terms that are not forced in) declares every remaining term significant.  (b) Stepwise
   additions and swaps that keep every term significant (:func:`_stepwise`): elimination alone decides
   between nearly collinear terms by the accident of the full fit.  (c) Held-out pruning: the elimination
   continues from there down to the forced terms, and the support with the smallest held-out error
   (K-fold over runs) on that path is kept, so a term must also improve the prediction of runs it was not
   fitted on.  The damping terms (ydot in yddot, thetadot in thetaddot) are always kept.
3. **Errors in the variables.**  The first pass evaluates the columns at raw y, smoothed ydot and theta
   smoothed over half a hinge period (:func:`fitting.integral_form.column_states`); such columns lose
   weak velocity terms and bias others (measured: 5.5 oracle standard errors on the y coupling of the
   hinge).  Every later pass evaluates them at the raw positions and the velocities of the selected
   model's own trajectories, fitted segment by segment to the data
   (:func:`fitting.model_states.model_states`), and selects again from the full library.  Raw positions
   cost nothing (their white noise averages out in the double integral), while model positions feed the
   model's own errors back into the columns (measured: the passes then drifted by ~2 standard errors per
   pass and collected spurious theta terms in yddot).  The columns are prefiltered
   (:func:`numerov_columns`) so that the double integral is fourth-order accurate; the model's
   frequencies are then unbiased, which the segment fits need.  The passes stop when the support is
   unchanged and no coefficient moved by more than ``tolerance`` standard errors; a support that
   returns to an earlier one, or still changes after ``selection_passes``, is frozen.
4. **Trade-off.**  Every support met on the elimination paths, with its held-out error (fit on the other
   runs; root-mean-square misfit of the held-out runs' detrended positions per degree of freedom),
   forms the Pareto front of number of terms against held-out error (:attr:`DiscoveryResult.pareto`).

Everything after the column evaluation works on the R factor of the QR decomposition of each run's
design ``[X b]`` (35 + 1 columns), so a least squares on any support, the whole elimination path and
the cross-validation cost microseconds each.
"""
from __future__ import annotations

import logging
import time
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Sequence

import numpy as np
from numpy.typing import NDArray

from cubedimer.terms import EQUATION_NAMES, evaluate_library, is_velocity_free
from .integral_form import column_states, detrend_windows, integral_columns, integral_window, window_starts
from .model import TERMS, PolynomialModel, damping_mask
from .model_states import SegmentConfig, model_states, segment_length
from .multiple_testing import holm_reject, holm_z_threshold

if TYPE_CHECKING:
    from cubedimer.dataset import Run
    from .derivatives import Derivatives

__all__ = ["DiscoveryConfig", "PathPoint", "IterationLog", "DiscoveryResult", "discover_model", "METHOD"]

log = logging.getLogger(__name__)

#: One-line description of the method (written next to the result).
METHOD = ("pooled integral form (windows of 0.75 of the coordinate's dominant period), backward elimination from the "
          "35-term library until Holm's rule at family-wise alpha declares every remaining term significant (damping "
          "terms always kept), repeated with the columns evaluated at the selected model's trajectories fitted segment "
          "by segment to the data until the support and coefficients converge")


@dataclass(frozen=True)
class DiscoveryConfig:
    """Settings of :func:`discover_model`.

    Parameters
    ----------
    alpha : float
        Family-wise significance level of Holm's rule (per equation).
    window_periods : float
        Integral-form window in periods of the coordinate's dominant frequency
        (:func:`fitting.integral_form.integral_window`).
    window_bounds_s : (float, float)
        Its minimum and maximum [s].  The raw positions' noise in the columns, double integrated over a
        window W, grows like (omega W)^2 times the coordinate's stiffness; with the 30-ms minimum of the
        cross-check a 35-Hz hinge got windows of 1.05 periods and its damping came out 4 oracle standard
        errors off (1500 fps, 12 runs); at 0.75 periods (21 ms) within 2.
    segments : SegmentConfig
        The model-based state estimate.
    max_iterations : int
        Passes with model-based states after the first pass.
    tolerance : float
        Convergence: every coefficient changed by less than ``tolerance`` standard errors.
    velocity_first : bool
        Drop velocity terms first while one is below the Bonferroni level.
    keep_damping : bool
        Always keep ydot in yddot and thetadot in thetaddot.
    selection_passes : int
        Passes that may change the support; after them (or when the support returns to an earlier one) it is
        frozen and only the coefficients and states iterate.
    heldout_prune : bool
        After Holm's rule, continue the elimination and keep the support with the smallest held-out error.
    heldout_tolerance : float
        Keep the smallest support whose held-out RMS error is at most ``1 + heldout_tolerance`` times the
        smallest on that path (0: the minimum itself).
    n_folds : int
        Folds over runs of the held-out error (at most the number of runs).
    """

    alpha: float = 0.01
    window_periods: float = 0.75
    window_bounds_s: tuple[float, float] = (0.01, 0.5)
    segments: SegmentConfig = field(default_factory=SegmentConfig)
    max_iterations: int = 6
    tolerance: float = 0.5
    velocity_first: bool = True
    keep_damping: bool = True
    selection_passes: int = 3
    heldout_prune: bool = True
    heldout_tolerance: float = 0.0
    n_folds: int = 5
    raw_positions: bool = True
    stepwise: bool = True

    def __post_init__(self) -> None:
        if not 0 < self.alpha < 1:
            raise ValueError(f"alpha must lie in (0, 1), got {self.alpha}")
        if not self.window_periods > 0:
            raise ValueError(f"window_periods must be positive, got {self.window_periods}")
        if self.max_iterations < 0 or self.n_folds < 2:
            raise ValueError("max_iterations must be >= 0 and n_folds >= 2")
        if not (self.tolerance > 0 and 0 <= self.heldout_tolerance < 1):
            raise ValueError("tolerance must be positive and heldout_tolerance in [0, 1)")


@dataclass(frozen=True)
class PathPoint:
    """One support on an equation's elimination path.

    Attributes
    ----------
    terms : tuple of str
    residual_std : float
        In-sample residual standard deviation per degree of freedom [m or rad].
    heldout_rms : float
        Held-out root-mean-square misfit per degree of freedom (K-fold over runs) [m or rad]; NaN with
        fewer than two runs.
    selected : bool
        The support Holm's rule stopped at.
    """

    terms: tuple[str, ...]
    residual_std: float
    heldout_rms: float
    selected: bool = False

    @property
    def n_terms(self) -> int:
        return len(self.terms)

    def to_json(self) -> dict:
        return {"n_terms": self.n_terms, "terms": list(self.terms), "residual_std": self.residual_std,
                "heldout_rms": self.heldout_rms, "selected": self.selected}


@dataclass(frozen=True)
class IterationLog:
    """One pass: which states, how many terms, how far the coefficients moved."""

    iteration: int
    states: str
    n_terms: tuple[int, int]
    max_change_se: float
    residual_std: tuple[float, float]
    state_rms: tuple[float, float]
    failed_frames: int
    seconds: float

    def to_json(self) -> dict:
        return dict(self.__dict__)


@dataclass(frozen=True, eq=False)
class DiscoveryResult:
    """Outcome of :func:`discover_model`.

    Attributes
    ----------
    mask : ndarray of bool (2, 35)
        Selected terms (rows yddot, thetaddot).
    coef : ndarray (2, 35)
        Least-squares coefficients on the selected support [SI]; zero elsewhere.
    std_errors : ndarray (2, 35)
        Their standard errors [SI]; zero outside the support.
    residual_std : ndarray (2,)
        Residual standard deviation of y [m] and theta [-] (compare with the tracking noise).
    window_s : ndarray (2,)
        Median integral-form window of each equation [s].
    pareto : dict
        ``{equation: tuple of PathPoint}``, from the full library to the forced terms.
    iterations : tuple of IterationLog
    converged : bool
    """

    mask: NDArray[np.bool_]
    coef: NDArray[np.float64]
    std_errors: NDArray[np.float64]
    residual_std: NDArray[np.float64]
    window_s: NDArray[np.float64]
    pareto: dict[str, tuple[PathPoint, ...]]
    iterations: tuple[IterationLog, ...]
    converged: bool

    @property
    def z(self) -> NDArray[np.float64]:
        """coefficient / standard error (0 outside the support)."""
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(self.mask, self.coef / np.where(self.mask, self.std_errors, 1.0), 0.0)

    @property
    def model(self) -> PolynomialModel:
        return PolynomialModel(self.coef)

    def terms(self) -> dict[str, list[str]]:
        return {eq: [t for t, m in zip(TERMS, self.mask[q]) if m] for q, eq in enumerate(EQUATION_NAMES)}

    def to_json(self) -> dict:
        """Selected terms with value, std_error and z per equation; the Pareto front; the iterations."""
        z = self.z
        return {"method": METHOD,
                **{eq: {"terms": {t: {"value": float(self.coef[q, j]), "std_error": float(self.std_errors[q, j]),
                                      "z": float(z[q, j])} for j, t in enumerate(TERMS) if self.mask[q, j]},
                        "residual_std": float(self.residual_std[q]), "window_s": float(self.window_s[q]),
                        "pareto": [p.to_json() for p in self.pareto[eq]]}
                   for q, eq in enumerate(EQUATION_NAMES)},
                "iterations": [it.to_json() for it in self.iterations], "converged": self.converged}


# ---- least squares on R factors ------------------------------------------------------------------------------
@dataclass(frozen=True)
class _Design:
    """One equation's design over all runs, reduced to R factors of ``[X b]``."""

    per_run: list[NDArray[np.float64]]   # R factor of every run's [X b]
    rows: NDArray[np.int64]              # frames per run
    windows: NDArray[np.int64]           # windows per run
    total: NDArray[np.float64]           # R factor of all runs


def _r_factor(blocks: Sequence[NDArray]) -> NDArray[np.float64]:
    return np.linalg.qr(np.vstack(blocks), mode="r")


def _single_thread():
    """One BLAS thread for the many small factorisations (on a shared 2-core machine a multi-threaded
    OpenBLAS made a 4500 x 36 QR 20 times slower); a no-op without threadpoolctl."""
    try:
        from threadpoolctl import threadpool_limits
    except ImportError:  # pragma: no cover - threadpoolctl comes with scikit-learn (pysindy)
        from contextlib import nullcontext
        return nullcontext()
    return threadpool_limits(1)


def numerov_columns(f: NDArray) -> NDArray[np.float64]:
    """Library columns (n, ...) prefiltered so that the trapezoid double integral of
    :func:`fitting.integral_form.integral_columns` is fourth-order accurate.

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


def _design(positions: Sequence[NDArray], library: Sequence[NDArray], dts: Sequence[float], windows: Sequence[int],
            trims: Sequence[int], cache: dict | None = None) -> _Design:
    """R factors of the integral-form design of one equation.  ``cache`` (run index -> (trim, columns)) keeps
    the integrated velocity-free columns between passes whose position states are the same (raw) data."""
    rs, rows, wins = [], [], []
    for i, (x, f, dt, w, tr) in enumerate(zip(positions, library, dts, windows, trims)):
        starts = window_starts(len(x), int(w), int(tr))
        if starts.size == 0:
            continue
        X = np.empty((starts.size * int(w), f.shape[1]))
        hit = cache is not None and i in cache and cache[i][0] == tr
        cols = ~_VELOCITY_FREE if hit else np.ones(f.shape[1], bool)
        X[:, cols] = integral_columns(numerov_columns(f[:, cols]), dt, starts, int(w))
        if hit:
            X[:, _VELOCITY_FREE] = cache[i][1]
        elif cache is not None:
            cache[i] = (tr, X[:, _VELOCITY_FREE].copy())
        b = detrend_windows(x, starts, int(w))
        rs.append(_r_factor([np.column_stack([X, b])]))
        rows.append(X.shape[0])
        wins.append(starts.size)
    if not rs:
        raise ValueError("no run is long enough for one integral-form window")
    return _Design(rs, np.array(rows), np.array(wins), _r_factor(rs))


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


def _fit(d: _Design, cols: Sequence[int]) -> tuple[NDArray, NDArray, float]:
    """Coefficients, standard errors and residual std on ``cols`` (dof: frames - 2 per window - terms)."""
    cols = list(cols)
    if not cols:
        dof = max(int(d.rows.sum() - 2 * d.windows.sum()), 1)
        return np.zeros(0), np.zeros(0), float(np.sqrt(d.total[:, -1] @ d.total[:, -1] / dof))
    c, cov, rss = _lstsq(d.total, cols)
    dof = max(int(d.rows.sum() - 2 * d.windows.sum() - len(cols)), 1)
    s2 = rss / dof
    return c, np.sqrt(np.clip(np.diag(cov), 0.0, None) * s2), float(np.sqrt(s2))


def _heldout(d: _Design, paths: Sequence[Sequence[int]], n_folds: int) -> list[float]:
    """Held-out RMS misfit per degree of freedom of every support in ``paths`` (K-fold over runs)."""
    R = len(d.per_run)
    if R < 2:
        return [float("nan")] * len(paths)
    k = min(n_folds, R)
    folds = [list(range(f, R, k)) for f in range(k)]
    train = [_r_factor([d.per_run[r] for r in range(R) if r not in fold]) for fold in folds]
    dof = float(d.rows.sum() - 2 * d.windows.sum())
    out = []
    for cols in paths:
        sse = 0.0
        for fold, Rt in zip(folds, train):
            c = _lstsq(Rt, cols, covariance=False)[0] if len(cols) else np.zeros(0)
            for r in fold:
                res = d.per_run[r][:, list(cols)] @ c - d.per_run[r][:, -1]
                sse += float(res @ res)
        out.append(float(np.sqrt(sse / max(dof, 1.0))))
    return out


def _abs_z(d: _Design, cols: Sequence[int]) -> NDArray[np.float64]:
    c, se, _ = _fit(d, cols)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.nan_to_num(np.abs(c / se), nan=0.0)


def _holm_ok(absz: NDArray, free: NDArray[np.bool_], alpha: float, n_hyp: int) -> bool:
    """Holm's rule over ``n_hyp`` hypotheses declares every free term significant."""
    from scipy.special import ndtr

    return n_hyp == 0 or bool(holm_reject(2.0 * ndtr(-absz[free]), alpha, n_hyp).all())


def _rss(d: _Design, cols: Sequence[int]) -> float:
    return _lstsq(d.total, list(cols), covariance=False)[2] if len(cols) else float(d.total[:, -1] @ d.total[:, -1])


def _eliminate(d: _Design, cols: Sequence[int], forced: NDArray[np.bool_], alpha: float, velocity_first: bool):
    """Backward elimination from ``cols`` down to the forced terms: yields (support, |z|) before every step.
    The least significant free term goes; with ``velocity_first`` velocity terms go first while one of them is
    below the Bonferroni level."""
    n_hyp = max(int(forced.size - forced.sum()), 1)
    keep = list(cols)
    while True:
        absz = _abs_z(d, keep)
        yield list(keep), absz
        free = ~forced[keep]
        if not free.any():
            return
        pool = np.flatnonzero(free)
        if velocity_first:
            weak_v = pool[~_VELOCITY_FREE[np.array(keep)[pool]] & (absz[pool] < holm_z_threshold(alpha, n_hyp, 1))]
            if weak_v.size:
                pool = weak_v
        keep.pop(int(pool[np.argmin(absz[pool])]))


def _select(d: _Design, forced: NDArray[np.bool_], config: DiscoveryConfig) -> tuple[list[int], list[list[int]]]:
    """Backward elimination from the full library until Holm's rule declares every free term significant, then
    stepwise additions and swaps (:func:`_stepwise`); returns the selection and the elimination path."""
    n_lib = d.total.shape[1] - 1
    n_hyp = int(n_lib - forced.sum())
    path: list[list[int]] = []
    cols: list[int] = []
    for keep, absz in _eliminate(d, range(n_lib), forced, config.alpha, config.velocity_first):
        path.append(keep)
        cols = keep
        if _holm_ok(absz, ~forced[keep], config.alpha, n_hyp):
            break
    if config.stepwise:
        cols = _stepwise(d, cols, forced, config.alpha, n_hyp)
    return cols, path


def _heldout_prune(d: _Design, cols: list[int], forced: NDArray[np.bool_],
                   config: DiscoveryConfig) -> tuple[list[int], list[list[int]], list[float]]:
    """Continue the elimination from the significant support ``cols`` down to the forced terms and keep the
    smallest support whose held-out error is within ``heldout_tolerance`` of the smallest on that path."""
    path = [keep for keep, _ in _eliminate(d, cols, forced, config.alpha, config.velocity_first)]
    held = _heldout(d, path, config.n_folds)
    if not np.all(np.isfinite(held)):
        return cols, path, held
    limit = min(held) * (1.0 + config.heldout_tolerance)
    best = max(i for i, h in enumerate(held) if h <= limit)
    return path[best], path, held


def _stepwise(d: _Design, cols: list[int], forced: NDArray[np.bool_], alpha: float, n_hyp: int) -> list[int]:
    """Improve a support found by backward elimination.

    Add the most significant outside term if every term stays significant (Holm); else swap one free term for
    an outside one when that lowers the residual sum of squares and keeps every term significant; else replace
    two free terms by one outside term when that raises the residual sum of squares by less than log(N)
    residual variances (N: degrees of freedom; the Bayesian information criterion's price of one parameter,
    for two non-nested supports); never return to a support met before; stop when none applies.  Backward elimination alone decides between two nearly collinear terms by which one the
    full library's fit happens to make less significant (measured: y*thetadot^2 with oracle z 7 lost to
    y*theta^2 on a nearly harmonic hinge); the swap compares the two supports directly.  Velocity terms earn
    their place: replacing a velocity-free term by a velocity term needs a drop of the residual sum of squares
    by more than z_alpha^2 residual variances (z_alpha = 2.58 at alpha = 0.01; a likelihood-ratio test at level
    alpha).  On harmonic y motion y^2*theta and ydot^2*theta are nearly collinear (measured drops of -5 to +2.4
    residual variances between them, against +10 to +25 for y*thetadot^2 over y*theta^2), so this keeps the
    velocity-free term there.  The merge undoes a pair that stands in for one true term: y*theta^2 +
    ydot*theta*thetadot for y*thetadot^2 fitted 0.4 residual variances better on a 35-Hz hinge and 8.0 on an
    8-run set (z_alpha^2 = 6.6 would keep that pair; log(N) = 10.5 there), the best of ~600 pairs a search
    over two-for-one replacements tries.
    """
    from scipy.special import ndtri

    n_lib = d.total.shape[1] - 1
    velocity = ~_VELOCITY_FREE[:n_lib]
    tau = float(ndtri(1.0 - 0.5 * alpha)) ** 2
    tau_merge = max(tau, float(np.log(max(int(d.rows.sum() - 2 * d.windows.sum()), 2))))
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
        s2 = base / max(int(d.rows.sum() - 2 * d.windows.sum() - len(cols)), 1)
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


# ---- the discovery loop ----------------------------------------------------------------------------------------
def discover_model(runs: Sequence["Run"], derivs: Sequence["Derivatives"],
                   config: DiscoveryConfig = DiscoveryConfig()) -> DiscoveryResult:
    """Select and fit both equations on the integral form with model-based column states (module docstring).

    Parameters
    ----------
    runs : per run :class:`cubedimer.dataset.Run` (raw, gap-filled y [m] and theta [-] at every frame)
    derivs : per run :class:`fitting.derivatives.Derivatives` (the smoothed ydot of the first pass, its edges)
    config : DiscoveryConfig

    Returns
    -------
    DiscoveryResult
    """
    with _single_thread():
        return _discover(runs, derivs, config)


def _discover(runs: Sequence["Run"], derivs: Sequence["Derivatives"], config: DiscoveryConfig) -> DiscoveryResult:
    from cubedimer.spectra import dominant_frequency

    t_start = time.perf_counter()
    dts = [float(r.dt) for r in runs]
    ys = [np.asarray(r.y, float) for r in runs]
    ths = [np.asarray(r.theta, float) for r in runs]
    freqs = [(dominant_frequency(y, dt), dominant_frequency(th, dt)) for y, th, dt in zip(ys, ths, dts)]
    first, edges = [], []
    for r, d, dt, (f_y, f_theta) in zip(runs, derivs, dts, freqs):
        st, edge = column_states(dt, r.y, r.theta, d.state[:, 1], f_y, f_theta, int(d.trim))
        first.append(st)
        edges.append(edge)
    windows = [[integral_window(dt, f[q], config.window_periods, config.window_bounds_s) for f, dt in zip(freqs, dts)]
               for q in range(2)]
    window_s = np.array([np.median([w * dt for w, dt in zip(windows[q], dts)]) for q in range(2)])
    seg_len = [segment_length(dt, f[0], f[1], config.segments) for f, dt in zip(freqs, dts)]
    forced = damping_mask() if config.keep_damping else np.zeros((2, len(TERMS)), bool)
    positions = (ys, ths)

    caches: list[dict] = [{}, {}]

    def one_pass(states: Sequence[NDArray], trims: Sequence[int], cached: bool, frozen: NDArray | None):
        lib = [evaluate_library(s) for s in states]
        designs = [_design(positions[q], lib, dts, windows[q], trims, caches[q] if cached else None) for q in range(2)]
        coef, se, res_std, fronts = np.zeros((2, len(TERMS))), np.zeros((2, len(TERMS))), np.zeros(2), []
        for q in range(2):
            sel, path = _select(designs[q], forced[q], config)
            held_a = [float("nan")] * len(path)
            if config.heldout_prune:
                sel, path_b, held_b = _heldout_prune(designs[q], sel, forced[q], config)
                path, held = path + path_b, held_a + held_b
            else:
                held = held_a
            if frozen is not None:
                sel = list(np.flatnonzero(frozen[q]))
            c, e, s = _fit(designs[q], sel)
            coef[q, sel], se[q, sel], res_std[q] = c, e, s
            fronts.append((path, held, sel))
        return coef, se, res_std, designs, fronts

    states, trims, label = first, edges, "smoothed"
    estimate = None
    history: list[IterationLog] = []
    prev = None
    converged = False
    frozen: NDArray | None = None
    masks: list[NDArray] = []
    for it in range(config.max_iterations + 1):
        t0 = time.perf_counter()
        if it > 0:
            sigma = (float(res_std[0]), float(res_std[1]))
            estimate = model_states(PolynomialModel(coef), dts, ys, ths, first, seg_len, sigma, config.segments,
                                    x0=estimate.x0 if estimate is not None else None)
            states = estimate.states
            if config.raw_positions:
                states = [np.column_stack([y, s[:, 1], th, s[:, 3]]) for y, th, s in zip(ys, ths, states)]
            trims = [edge if f.any() else 0 for f, edge in zip(estimate.failed, edges)]
            label = "model"
        coef, se, res_std, designs, fronts = one_pass(states, trims, it > 0 and config.raw_positions, frozen)
        mask = coef != 0.0
        if frozen is None and it >= 1:
            # a selection that returns to an earlier support (held-out errors within their noise) or keeps
            # changing is frozen: the smaller of the last two supports, then only the coefficients iterate
            if any(np.array_equal(mask, m) for m in masks[:-1]) and not np.array_equal(mask, masks[-1]):
                frozen = min((masks[-1], mask), key=lambda m: int(m.sum()))
                label += ", support frozen (cycle)"
            elif it >= config.selection_passes:
                frozen = mask
                label += ", support frozen"
        masks.append(mask)
        change = np.inf
        if prev is not None:
            with np.errstate(divide="ignore", invalid="ignore"):
                d = np.abs(coef - prev[0]) / np.maximum(se, prev[1])
            change = float(np.nanmax(np.where(mask | prev[2], d, 0.0)))
            if not np.array_equal(mask, prev[2]):
                change = np.inf
        history.append(IterationLog(
            iteration=it, states=label, n_terms=(int(mask[0].sum()), int(mask[1].sum())), max_change_se=change,
            residual_std=(float(res_std[0]), float(res_std[1])),
            state_rms=tuple(float(v) for v in (estimate.rms if estimate is not None else (np.nan, np.nan))),
            failed_frames=estimate.n_failed if estimate is not None else 0, seconds=time.perf_counter() - t0))
        log.info("discovery pass %d (%s states): %d + %d terms, max change %.3g SE, residual std %.3g m, %.3g",
                 it, label, mask[0].sum(), mask[1].sum(), change, res_std[0], res_std[1])
        if change < config.tolerance:
            converged = True
            break
        prev = (coef, se, mask)
    pareto = {}
    for q, eq in enumerate(EQUATION_NAMES):
        path, held, sel = fronts[q]
        missing = [i for i, h in enumerate(held) if not np.isfinite(h)]
        for i, h in zip(missing, _heldout(designs[q], [path[i] for i in missing], config.n_folds)):
            held[i] = h
        seen, points = set(), []
        for cols, h in zip(path, held):
            key = tuple(sorted(cols))
            if key in seen:
                continue
            seen.add(key)
            points.append(PathPoint(tuple(TERMS[j] for j in key), _fit(designs[q], key)[2], h,
                                    selected=set(key) == set(sel)))
        pareto[eq] = tuple(sorted(points, key=lambda p: -p.n_terms))
    log.info("discovery: %d terms in %.2f s (%s)", int(mask.sum()), time.perf_counter() - t_start,
             "converged" if converged else "not converged")
    return DiscoveryResult(mask=mask, coef=coef, std_errors=se, residual_std=res_std, window_s=window_s,
                           pareto=pareto, iterations=tuple(history), converged=converged)
