"""The accuracy/sparsity front of a discovery: model size against the held-out long-time error.

For every cap ``n`` on the number of terms per equation, each equation takes the largest support on its elimination
path with at most ``n`` terms (among supports of one size the one with the smallest integral-form held-out error):
up to the size of the discovery's own selection (its larger equation's) the smaller supports of the pruning paths
and the selection itself, above it the larger supports of the backward elimination from the full library.  That model is fitted on the training runs of each fold
(K-fold over runs, :func:`cubedimer.folds.run_folds`) and integrated from the first state of every held-out run; its
**long-time error** is the RMS of the trajectory's error over the RMS of the run's motion about its mean, averaged
over the two coordinates (:func:`long_time_error`), a dimensionless number that does not depend on the units of time
or of the coordinates.  Beside it, the **error along the runs** (:func:`long_time_error_along`): the same error over
horizons of ``ALONG_HORIZON_PERIODS`` (5) periods of the run's slower dominant frequency, restarting from the run's
state estimate at the start of every horizon, averaged over the horizons: the first state's error is decided by the
largest amplitudes of a decaying run, this one by the motion's whole range.  The front records, per point, the mean
over folds of each and its standard error (the spread of the fold means over sqrt(K)): under model error the error
bars say which sizes the data can tell apart.

**The order of the front.**  Below the selection's size each cap's model is the best, by the held-out error from
the first state over the first ``ALONG_HORIZON_PERIODS`` slow periods (mean over folds and coordinates; over a whole
decaying run a small model's phase error saturates near 100 % and ranks nothing), of: the selection's paths at that
cap (which keep the forced damping terms), the backward elimination without forced terms, forward selection on the
integral form (:func:`candidate_paths`), up to ``LONG_TIME_FORWARD_SIZE`` terms forward selection by that long-time
error itself (:func:`long_time_forward`), their per-equation mix, and the smaller caps' models
(:func:`ordered_supports`).  So the one- and two-term points are the restoring forces, not the damped oscillator.
Above the selection's size an enlargement that a smaller model predicts better is left out: its cap maps to that
model (``Front.cap_points``), and the front holds only the sizes that the held-out runs prefer.
:func:`refined_front` (``discover_model(..., refine_front=True)``) gives every point the estimate on its supports
that predicts the fitted runs from their first state estimates best: the integral form's least squares, the output
error's refinement (as the selected model's under model error) or the least squares of short-window accelerations.

The **knee** is the one-standard-error rule: the smallest model whose held-out long-time error is within one fold
standard error of the best point's.  It is recorded beside the discovery's own selection (which stays the default:
significance and integral-form held-out pruning, :mod:`fitting.selection.integral_discovery`); ``fit --max-terms N``
(``DiscoveryConfig.max_terms``) fits the point at cap N (:meth:`Front.supports_at`).
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Callable, Mapping, Sequence

import numpy as np
from numpy.typing import NDArray

from cubedimer.folds import run_folds
from cubedimer.terms import EQUATION_NAMES
from ..integrate import integrate_batch
from ..model import EXPONENTS, TERMS, PolynomialModel
from .support_search import ReducedDesign, _eliminate, fit_on_runs, heldout_rms

__all__ = ["FrontPoint", "Front", "HeldOutRun", "long_time_error", "long_time_error_along", "capped_support",
           "long_time_front", "held_out_fold_errors", "refined_front", "forward_path", "candidate_paths",
           "ordered_supports", "BLOW_UP_FACTOR", "ALONG_HORIZON_PERIODS", "OUTPUT_ERROR", "INTEGRAL_FORM",
           "ACCELERATIONS"]

#: A trajectory leaving this many times the run's largest |state| has blown up (its long-time error is infinite).
BLOW_UP_FACTOR = 10.0
#: The horizon of the error along the runs, in periods of the run's slower dominant frequency.
ALONG_HORIZON_PERIODS = 5.0
#: Up to this many terms per equation the front's ordering includes :func:`long_time_forward` (forward selection by
#: the long-time error itself, over the ``LONG_TIME_SHORTLIST`` best additions by the integral form's held-out error)
LONG_TIME_FORWARD_SIZE = 4
LONG_TIME_SHORTLIST = 4
#: the names of the estimates of a support's coefficients (:func:`refined_front`, :mod:`fitting.selection.estimate_choice`)
OUTPUT_ERROR, INTEGRAL_FORM, ACCELERATIONS = "output error", "integral form", "accelerations"


@dataclass(frozen=True)
class HeldOutRun:
    """What a held-out run's long-time error needs: its frame interval [s], measured positions from the first state
    on, and that first state [y, ydot, theta, thetadot] (SI); for the error along the run, the state estimates
    (n, 4) from the first state on and the horizon [frames] (0: no error along the run)."""

    dt: float
    y: NDArray[np.float64]
    theta: NDArray[np.float64]
    x0: NDArray[np.float64]
    states: NDArray[np.float64] | None = None
    horizon: int = 0


def long_time_error(model: PolynomialModel, run: HeldOutRun) -> float:
    """RMS error of ``model``'s trajectory from ``run.x0`` over the RMS of the run's motion about its mean, averaged
    over y and theta (dimensionless; inf when the trajectory blows up)."""
    data = np.column_stack([run.y, run.theta])
    err = _trajectory_error(model, run.x0, data, run.dt, np.max(np.abs(data), axis=0))
    signal = np.std(data, axis=0)
    return float(np.mean(err / np.where(signal > 0, signal, 1.0)))


def long_time_error_along(model: PolynomialModel, run: HeldOutRun) -> float:
    """The error of :func:`long_time_error` over horizons of ``run.horizon`` frames, restarting from the state
    estimate ``run.states`` at the start of every horizon (the last one ending at the run's end), RMS over the
    horizons and over the run's RMS motion about its mean, averaged over y and theta (dimensionless; inf when a
    trajectory blows up, NaN without states or horizon)."""
    starts, h = _starts_along(run)
    if not starts:
        return float("nan")
    data = np.column_stack([run.y, run.theta])
    reach = np.max(np.abs(data), axis=0)
    sq = np.array([_trajectory_error(model, run.states[i], data[i:i + h], run.dt, reach) ** 2 for i in starts])
    signal = np.std(data, axis=0)
    return float(np.mean(np.sqrt(np.mean(sq, axis=0)) / np.where(signal > 0, signal, 1.0)))


def _trajectory_error(model: PolynomialModel, x0: NDArray, data: NDArray, dt: float, reach: NDArray) -> NDArray:
    """RMS error (y, theta) of ``model``'s trajectory from ``x0`` against ``data`` (n, 2); inf on a blow-up beyond
    ``BLOW_UP_FACTOR`` times ``reach`` (or the start's positions)."""
    n = data.shape[0]
    reach = np.maximum(reach, np.abs(np.asarray(x0)[[0, 2]]))
    bound = BLOW_UP_FACTOR * np.array([reach[0], np.inf, reach[1], np.inf])  # the rates: bounded through the positions
    states, n_valid = model.simulate(x0, np.arange(n) * dt, bound=bound)
    if n_valid < n:
        return np.full(2, np.inf)
    return np.sqrt(np.mean((states[:, [0, 2]] - data) ** 2, axis=0))


def _starts_along(run: HeldOutRun) -> tuple[list[int], int]:
    """The first frames of the horizons of :func:`long_time_error_along` and the horizon [frames] (no horizons
    without states or horizon)."""
    if run.states is None or run.horizon < 2:
        return [], 0
    n = run.y.shape[0]
    h = min(int(run.horizon), n)
    starts = list(range(0, n - h + 1, h))
    if starts[-1] + h < n:
        starts.append(n - h)
    return starts, h


def held_out_fold_errors(models: Sequence[PolynomialModel], folds: Sequence[tuple], held_out: Sequence[HeldOutRun]
                         ) -> tuple[list[float], list[float]]:
    """Per fold, the mean over its held-out runs of :func:`long_time_error` and of :func:`long_time_error_along` of
    the fold's model (``models[k]`` for ``folds[k] = (train, test)``): the same numbers, with every trajectory of all
    folds integrated in two compiled calls (the runs from their first states, the horizons along the runs) instead
    of one call each."""
    runs = {r: _RunData(held_out[r]) for _, test in folds for r in test}
    first, along = [], []  # (model, run, start frame, frames, start from the state estimate)
    for k, (_, test) in enumerate(folds):
        for r in test:
            first.append((k, r, 0, runs[r].data.shape[0], False))
            starts, h = _starts_along(held_out[r])
            along.extend((k, r, i, h, True) for i in starts)
    err_first = dict(zip([job[:2] for job in first], _batch_errors(models, runs, first)))
    err_along: dict[tuple, list] = {}
    for job, err in zip(along, _batch_errors(models, runs, along)):
        err_along.setdefault(job[:2], []).append(err ** 2)
    fold_err, fold_along = [], []
    for k, (_, test) in enumerate(folds):
        errs, errs_along = [], []
        for r in test:
            errs.append(float(np.mean(err_first[k, r] / runs[r].scale)))
            sq = err_along.get((k, r))
            errs_along.append(float(np.mean(np.sqrt(np.mean(np.array(sq), axis=0)) / runs[r].scale)) if sq
                              else float("nan"))
        fold_err.append(float(np.mean(errs)))
        fold_along.append(float(np.mean(errs_along)))
    return fold_err, fold_along


class _RunData:
    """A held-out run's measured positions (n, 2), their largest |value| and the RMS motion about the mean (zero
    replaced by 1), as :func:`long_time_error` computes them."""

    def __init__(self, run: HeldOutRun):
        self.run = run
        self.data = np.column_stack([run.y, run.theta])
        self.reach = np.max(np.abs(self.data), axis=0)
        signal = np.std(self.data, axis=0)
        self.scale = np.where(signal > 0, signal, 1.0)


def _batch_errors(models: Sequence[PolynomialModel], runs: dict, jobs: list[tuple]) -> list:
    """:func:`_trajectory_error` of each job ``(model, run, start frame, frames, from the state estimate)`` (else
    from the run's first state ``x0``), all integrated in one compiled call; ``runs``: each run's :class:`_RunData`."""
    if not jobs:
        return []
    x0s = np.array([runs[r].run.states[i] if estimate else runs[r].run.x0 for _, r, i, _, estimate in jobs], float)
    reach = np.maximum(np.array([runs[job[1]].reach for job in jobs]), np.abs(x0s[:, [0, 2]]))
    bounds = BLOW_UP_FACTOR * np.column_stack([reach[:, 0], np.full(len(jobs), np.inf), reach[:, 1],
                                               np.full(len(jobs), np.inf)])
    ns = np.array([job[3] for job in jobs])
    dts = np.array([float(runs[r].run.dt) if n > 1 else 1.0 for _, r, _, n, _ in jobs])  # as PolynomialModel.simulate
    steps = np.array([models[k].default_substeps(dt) for (k, *_), dt in zip(jobs, dts)])
    traj, n_valid = integrate_batch(np.array([models[job[0]].coef for job in jobs]), EXPONENTS, x0s, dts, ns, steps,
                                    bounds)
    return [np.full(2, np.inf) if n_valid[b] < n else
            np.sqrt(np.mean((traj[b, :n][:, [0, 2]] - runs[r].data[i:i + n]) ** 2, axis=0))
            for b, (_, r, i, n, _) in enumerate(jobs)]


@dataclass(frozen=True)
class FrontPoint:
    """One model on the front.

    Attributes
    ----------
    max_terms : int
        The cap on terms per equation that gives this model.
    terms : dict
        ``{equation: tuple of term names}``.
    error, error_se : float
        Held-out long-time error from the first state (fraction; mean over folds) and its standard error over folds
        (NaN with one fold).
    fold_errors : tuple of float
    selected : bool
        The discovery's own selection.
    error_along, error_along_se : float
        Held-out error along the runs (:func:`long_time_error_along`; mean over folds) and its standard error (NaN
        where the held-out runs carry no state estimates).
    fold_errors_along : tuple of float
    coef : ndarray (2, 35) or None
        The point's coefficients fitted on all runs (integral-form least squares on its supports; SI), the model a
        user takes at this size without refitting (None where not computed).
    refined : bool
        ``coef`` is the output error's refinement on the point's supports (:func:`refined_front`).
    estimate : str
        The estimate ``coef`` is: ``INTEGRAL_FORM`` (the least squares above), or the one :func:`refined_front` kept.
    """

    max_terms: int
    terms: dict[str, tuple[str, ...]]
    error: float
    error_se: float
    fold_errors: tuple[float, ...]
    selected: bool = False
    error_along: float = float("nan")
    error_along_se: float = float("nan")
    fold_errors_along: tuple[float, ...] = ()
    coef: NDArray[np.float64] | None = field(default=None, compare=False, repr=False)
    refined: bool = False
    estimate: str = INTEGRAL_FORM

    @property
    def n_terms(self) -> tuple[int, int]:
        return tuple(len(self.terms[eq]) for eq in EQUATION_NAMES)

    def to_json(self) -> dict:
        return {"max_terms": self.max_terms, "n_terms": {eq: len(self.terms[eq]) for eq in EQUATION_NAMES},
                "terms": {eq: list(self.terms[eq]) for eq in EQUATION_NAMES}, "error": _num(self.error),
                "error_se": _num(self.error_se), "fold_errors": [_num(e) for e in self.fold_errors],
                "error_along": _num(self.error_along), "error_along_se": _num(self.error_along_se),
                "fold_errors_along": [_num(e) for e in self.fold_errors_along], "selected": self.selected,
                "refined": self.refined, "estimate": self.estimate,
                **({"coefficients": {eq: {TERMS[j]: float(self.coef[q, j]) for j in np.flatnonzero(self.coef[q])}
                                     for q, eq in enumerate(EQUATION_NAMES)}} if self.coef is not None else {})}


def _num(x: float) -> float | None:
    return float(x) if np.isfinite(x) else None


@dataclass(frozen=True)
class Front:
    """The front (module docstring): its points, smallest first, and the knee (one-standard-error rule)."""

    points: tuple[FrontPoint, ...]
    n_folds: int
    #: (cap, index into ``points``) for every cap evaluated; the caps below ``ordered_below`` were ordered by the
    #: held-out long-time error (:func:`ordered_supports`), the others follow the selection's elimination paths
    cap_points: tuple[tuple[int, int], ...] = ()
    ordered_below: int = 0

    def supports_at(self, cap: int) -> tuple[tuple[int, ...], ...] | None:
        """Per equation the column indices of the front's model at ``cap`` terms per equation where the front
        ordered that cap by the held-out long-time error (the point of the largest evaluated cap not above it); None
        at and above ``ordered_below`` (there the selection's own paths decide, :func:`capped_support`)."""
        if cap >= self.ordered_below or not self.cap_points:
            return None
        below = [i for c, i in self.cap_points if c <= cap] or [self.cap_points[0][1]]
        terms = self.points[below[-1]].terms
        return tuple(tuple(sorted(TERMS.index(t) for t in terms[eq])) for eq in EQUATION_NAMES)

    @property
    def knee(self) -> FrontPoint | None:
        """The smallest point within one fold standard error of the best held-out long-time error (None: no point
        has a finite error)."""
        finite = [p for p in self.points if np.isfinite(p.error)]
        if not finite:
            return None
        best = min(finite, key=lambda p: p.error)
        limit = best.error + (best.error_se if np.isfinite(best.error_se) else 0.0)
        return min((p for p in finite if p.error <= limit), key=lambda p: (sum(p.n_terms), p.error))

    @property
    def selected(self) -> FrontPoint | None:
        return next((p for p in self.points if p.selected), None)

    def to_json(self) -> dict:
        knee = self.knee
        return {"measure": "held-out long-time error: RMS trajectory error from each held-out run's first state over "
                           "the run's RMS motion, mean of y and theta; mean and standard error over folds",
                "measure_along": f"held-out error along the runs: the same over horizons of {ALONG_HORIZON_PERIODS:g} "
                                 "periods of the run's slower frequency, restarted from the run's state estimate at "
                                 "each horizon's start, RMS over the horizons",
                "n_folds": self.n_folds, "knee_rule": "smallest model within one fold standard error of the best",
                "knee_max_terms": knee.max_terms if knee is not None else None,
                "default": "the discovery's own selection (selected: true)",
                "ordering": f"below {self.ordered_below} terms per equation each cap's point is the best of "
                            "several candidate paths (the selection's elimination, the elimination without forced "
                            "terms, forward selection) by the held-out long-time error from the first state",
                "cap_points": {str(c): i for c, i in self.cap_points},
                "points": [p.to_json() for p in self.points]}


def capped_support(path: Sequence[Sequence[int]], held: Sequence[float], selected: Sequence[int],
                   cap: int, enlarge: bool = False) -> tuple[int, ...]:
    """The support of one equation at a cap of ``cap`` terms: the selection when it fits, else the largest support
    on the elimination ``path`` with at most ``cap`` terms (the smallest held-out error among equal sizes; the
    smallest support on the path when none fits).  With ``enlarge``, a cap above the selection's size takes the
    largest path support within it that is larger than the selection (the selection when there is none)."""
    sel = tuple(sorted(selected))
    cands = [(tuple(sorted(c)), h if np.isfinite(h) else np.inf) for c, h in zip(path, held)]
    if len(sel) <= cap:
        if not enlarge:
            return sel
        cands = [c for c in cands if len(sel) < len(c[0])]
        if not any(len(c[0]) <= cap for c in cands):
            return sel
    fit = [c for c in cands if len(c[0]) <= cap]
    if not fit:
        return min(cands, key=lambda c: len(c[0]))[0]
    size = max(len(c[0]) for c in fit)
    return min((c for c in fit if len(c[0]) == size), key=lambda c: c[1])[0]


def long_time_front(designs: Sequence[ReducedDesign], fronts: Sequence[tuple], held_out: Sequence[HeldOutRun],
                    n_folds: int, caps: Sequence[int] | None = None, ordered: bool = True, alpha: float = 0.01,
                    velocity_first: bool = True) -> Front | None:
    """The front (module docstring) of one discovery.

    Parameters
    ----------
    designs : per equation the reduced integral-form design (all runs)
    fronts : per equation ``(path, held-out errors, selected support)`` of the last pass
    held_out : per run (the designs' order) what its long-time error needs
    n_folds : folds over runs
    caps : caps to evaluate (default every size on the paths)
    ordered : below the selection's size, each cap's point is the best by the held-out long-time error of the
        candidate supports of :func:`ordered_supports` (else the selection's elimination paths alone)
    alpha, velocity_first : the elimination's settings (:func:`candidate_paths`)

    Returns
    -------
    Front, or None with fewer than two runs.
    """
    R = len(held_out)
    if R < 2:
        return None
    folds = run_folds(R, n_folds)
    if caps is None:
        caps = sorted({len(c) for path, _, sel in fronts for c in [*path, sel]})
    largest = max(len(sel) for _, _, sel in fronts)  # up to the selection's size caps shrink, above it they enlarge
    below = largest if ordered else 0
    paths = [candidate_paths(d, n_folds, below - 1, alpha, velocity_first) for d in designs] if below > 1 else []
    seen, points, cap_points, scored = {}, [], [], {}
    joint = long_time_forward(designs, folds, held_out, n_folds, min(below - 1, LONG_TIME_FORWARD_SIZE), scored)
    for cap in caps:
        supports = tuple(capped_support(path, held, sel, cap, enlarge=cap > largest) for path, held, sel in fronts)
        if cap < below:
            supports = ordered_supports(supports, cap, paths, designs, folds, held_out,
                                        (*seen, *(p for p in joint if max(map(len, p)) <= cap)), scored)
        elif ordered and cap > largest:  # an enlargement that a smaller model predicts better is not on the front
            supports = ordered_supports(supports, cap, [], designs, folds, held_out, tuple(seen), scored)
        if supports in seen:
            cap_points.append((int(cap), seen[supports]))
            continue
        seen[supports] = len(points)
        cap_points.append((int(cap), len(points)))
        models = fold_models(supports, designs, folds)
        fold_err, fold_along = held_out_fold_errors(models, folds, held_out)
        (mean, se), (along, along_se) = _fold_mean(fold_err), _fold_mean(fold_along)
        everything = range(R)
        coef = np.zeros((2, len(TERMS)))
        for q, cols in enumerate(supports):
            coef[q, list(cols)] = fit_on_runs(designs[q], everything, cols)
        points.append(FrontPoint(int(cap), {eq: tuple(TERMS[j] for j in s) for eq, s in zip(EQUATION_NAMES, supports)},
                                 mean, se, tuple(fold_err),
                                 selected=all(tuple(sorted(f[2])) == s for f, s in zip(fronts, supports)),
                                 error_along=along, error_along_se=along_se, fold_errors_along=tuple(fold_along),
                                 coef=coef))
    return Front(tuple(points), len(folds), tuple(cap_points), below)


def refined_front(front: Front, refine: Callable[[NDArray], NDArray], held_out: Sequence[HeldOutRun],
                  estimates: Mapping[str, Callable[[NDArray], NDArray]] | None = None) -> Front:
    """The front with every point's coefficients the estimate on its supports that predicts the fitted runs best.

    The candidates: the integral form's least squares (``FrontPoint.coef``), ``refine`` (coefficients (2, 35) ->
    coefficients on the same support, the output error's refinement the selected model gets under model error) and
    every ``estimates`` entry (name -> the same kind of map, e.g. the least squares of short-window accelerations,
    :func:`fitting.selection.estimate_choice.acceleration_fit`).  Each is scored by the error of its trajectories from
    the runs' first states ``held_out[r].x0`` over their first horizon (:func:`_first_state_errors` on all runs, mean
    of the two coordinates; give the state estimates' first states, not the smoothed ones, whose filter bias would
    decide the comparison); ties keep the earlier candidate, the least squares first.  ``FrontPoint.estimate`` names
    the one kept (``refined``: it is the output error's).  The points' held-out errors are those of the least squares.
    """
    everything = [(list(range(len(held_out))), list(range(len(held_out))))]
    named = {OUTPUT_ERROR: refine, **(estimates or {})}
    points = []
    for p in front.points:
        if p.coef is None:
            points.append(p)
            continue
        cands = {INTEGRAL_FORM: p.coef}
        for name, fit in named.items():
            try:
                cands[name] = np.where(p.coef != 0, fit(p.coef), 0.0)
            except (ValueError, FloatingPointError, np.linalg.LinAlgError):  # a failed estimate is not a candidate
                continue
        err = {k: float(np.mean(_model_first_state_errors([PolynomialModel(c)], everything, held_out)))
               for k, c in cands.items()}
        best = min(cands, key=lambda k: err[k] if np.isfinite(err[k]) else np.inf)
        points.append(p if best == INTEGRAL_FORM else
                      replace(p, coef=cands[best], refined=best == OUTPUT_ERROR, estimate=best))
    return replace(front, points=tuple(points))


def long_time_forward(designs: Sequence[ReducedDesign], folds: Sequence[tuple[list[int], list[int]]],
                      held_out: Sequence[HeldOutRun], n_folds: int, max_size: int, scored: dict | None = None,
                      shortlist: int = LONG_TIME_SHORTLIST) -> list[tuple[tuple[int, ...], ...]]:
    """Forward selection of both equations by the held-out long-time error from the first state: at every size
    (1 to ``max_size`` terms per equation), each equation in turn takes the one of its ``shortlist`` best additions
    by the integral form's held-out error (or none) whose model has the smallest long-time error (mean over
    ``folds`` and the two coordinates).  Returns the models (per equation the column indices), one per size."""
    scored = {} if scored is None else scored
    if max_size < 1:
        return []
    n_lib = designs[0].total.shape[1] - 1
    supports = [(), ()]
    out = []
    for _ in range(min(max_size, n_lib)):
        for q in range(2):
            trial = [list(supports[q]) + [j] for j in range(n_lib) if j not in supports[q]]
            held = np.nan_to_num(heldout_rms(designs[q], trial, n_folds), nan=np.inf)
            cands = [tuple(sorted(trial[i])) for i in np.argsort(held, kind="stable")[:shortlist]]
            other = supports[1 - q] or forward_path(designs[1 - q], n_folds, 1)[0]
            pairs = [(c, other) if q == 0 else (other, c) for c in ([supports[q]] if supports[q] else []) + cands]
            for p in pairs:
                if p not in scored:
                    scored[p] = _first_state_errors(p, designs, folds, held_out)
            supports[q] = min(pairs, key=lambda p: float(np.mean(scored[p])))[q]
        out.append(tuple(supports))
    return out


def forward_path(design: ReducedDesign, n_folds: int, max_size: int) -> list[tuple[int, ...]]:
    """Forward selection on the integral form: from no term, add the term whose support has the smallest held-out
    error (K-fold over runs, :func:`fitting.selection.support_search.heldout_rms`) until ``max_size`` terms; returns
    the supports of sizes 1 to ``max_size``.  No term is forced: the restoring force comes before the damping."""
    n_lib = design.total.shape[1] - 1
    cols: list[int] = []
    out = []
    for _ in range(min(max_size, n_lib)):
        trial = [cols + [j] for j in range(n_lib) if j not in cols]
        held = np.nan_to_num(heldout_rms(design, trial, n_folds), nan=np.inf)
        cols = trial[int(np.argmin(held))]
        out.append(tuple(sorted(cols)))
    return out


def candidate_paths(design: ReducedDesign, n_folds: int, max_size: int, alpha: float = 0.01,
                    velocity_first: bool = True) -> list[list[tuple[int, ...]]]:
    """One equation's candidate supports of at most ``max_size`` terms beside the selection's own paths: the
    backward elimination from the full library without forced terms (down to one term) and :func:`forward_path`."""
    if max_size < 1:
        return []
    n_lib = design.total.shape[1] - 1
    free = np.zeros(n_lib, bool)
    elim = [tuple(sorted(k)) for k, _ in _eliminate(design, range(n_lib), free, alpha, velocity_first)
            if 1 <= len(k) <= max_size]
    return [elim, forward_path(design, n_folds, max_size)]


def ordered_supports(supports: tuple[tuple[int, ...], ...], cap: int, paths: Sequence[list[list[tuple[int, ...]]]],
                     designs: Sequence[ReducedDesign], folds: Sequence[tuple[list[int], list[int]]],
                     held_out: Sequence[HeldOutRun], earlier: Sequence[tuple[tuple[int, ...], ...]] = (),
                     scored: dict | None = None) -> tuple[tuple[int, ...], ...]:
    """The model of at most ``cap`` terms per equation with the smallest held-out long-time error from the first
    state (mean over ``folds``) among: ``supports`` (the selection's paths at this cap), every candidate path's
    largest support within the cap (the same path for both equations, :func:`candidate_paths`), their mix that takes
    for each equation the candidate best on its own coordinate, and the ``earlier`` (smaller caps') models.  Ties
    keep the earlier entry, ``supports`` first.  ``scored`` (supports -> per-coordinate errors) keeps the scores
    between calls."""
    scored = {} if scored is None else scored

    def score(c):
        if c not in scored:
            scored[c] = _first_state_errors(c, designs, folds, held_out)
        return scored[c]

    def within(path):
        fit = [c for c in path if len(c) <= cap]
        return max(fit, key=len) if fit else None

    cands = [supports]
    for k in range(min((len(p) for p in paths), default=0)):
        pair = tuple(within(paths[q][k]) for q in range(len(designs)))
        if all(c is not None for c in pair) and pair not in cands:
            cands.append(pair)
    scores = [score(c) for c in cands]
    if len(cands) > 1:  # each equation's support from the candidate that predicts its own coordinate best
        mix = tuple(cands[int(np.argmin([s[q] for s in scores]))][q] for q in range(len(designs)))
        if mix not in cands:
            cands.append(mix)
            scores.append(score(mix))
    cands += [e for e in earlier if e not in cands]
    scores += [score(c) for c in cands[len(scores):]]
    return cands[int(np.argmin([float(np.mean(s)) for s in scores]))]



def fold_models(supports, designs, folds) -> list:
    """The model on ``supports`` (per equation, column indices) fitted on each fold's training runs by least squares on
    the integral-form ``designs``, one :class:`PolynomialModel` per fold."""
    models = []
    for train, _ in folds:
        coef = np.zeros((2, len(TERMS)))
        for q, cols in enumerate(supports):
            coef[q, list(cols)] = fit_on_runs(designs[q], train, cols)
        models.append(PolynomialModel(coef))
    return models

def _first_state_errors(supports: tuple[tuple[int, ...], ...], designs: Sequence[ReducedDesign],
                        folds: Sequence[tuple[list[int], list[int]]], held_out: Sequence[HeldOutRun]) -> NDArray:
    """Per coordinate (y, theta) the held-out error from the first state over the first horizon of the error along
    the runs (``HeldOutRun.horizon``, ``ALONG_HORIZON_PERIODS`` slow periods; the whole run without one) of the model
    on ``supports`` (fitted on each fold's training runs), over the RMS motion in that horizon, mean over the folds of
    the mean over their held-out runs (inf on a blow-up).  The ordering's score: over a whole decaying run a small
    model's phase error saturates the error near 100 %, and the ranking of small models is noise."""
    return _model_first_state_errors(fold_models(supports, designs, folds), folds, held_out)


def _model_first_state_errors(models: Sequence[PolynomialModel], folds: Sequence[tuple[list[int], list[int]]],
                              held_out: Sequence[HeldOutRun]) -> NDArray:
    """Per coordinate the error of :func:`_first_state_errors` of the fold models ``models[k]`` on the held-out runs
    of ``folds[k]``, every trajectory integrated in one compiled call (:func:`_batch_errors`)."""
    runs = {r: _RunData(held_out[r]) for _, test in folds for r in test}
    size = {r: (held_out[r].horizon if held_out[r].horizon >= 2 else runs[r].data.shape[0]) for r in runs}
    size = {r: min(n, runs[r].data.shape[0]) for r, n in size.items()}
    jobs = [(k, r, 0, size[r], False) for k, (_, test) in enumerate(folds) for r in test]
    errs = iter(_batch_errors(models, runs, jobs))
    out = []
    for _, test in folds:
        per_run = []
        for r in test:
            signal = np.std(runs[r].data[:size[r]], axis=0)
            per_run.append(next(errs) / np.where(signal > 0, signal, 1.0))
        out.append(np.mean(per_run, axis=0))
    return np.mean(out, axis=0)


def _fold_mean(fold_err: Sequence[float]) -> tuple[float, float]:
    """Mean over folds (inf when a fold blew up, NaN when undefined) and its standard error (NaN with one fold)."""
    err = np.asarray(fold_err, float)
    if np.isnan(err).any():
        return float("nan"), float("nan")
    mean = float(np.mean(err)) if np.all(np.isfinite(err)) else float("inf")
    se = float(np.std(err, ddof=1) / np.sqrt(err.size)) if err.size > 1 and np.isfinite(mean) else float("nan")
    return mean, se
