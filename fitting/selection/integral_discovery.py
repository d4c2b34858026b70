"""Model discovery on the integral form with model-based column states (the default selection).

Method
------
1. **Integral form, pooled over runs** (:mod:`fitting.derivatives.integral_form`): per window of 0.75 of the
   coordinate's dominant period, the measured position minus its straight line is regressed on the
   detrended double integrals of the 35 library columns.  The residual is the white tracking noise,
   so least squares is efficient and its standard errors are honest.  From the second pass on, a window is
   at most ``natural_periods`` (0.875) periods of the equation's natural frequency (:func:`natural_windows`):
   a hinge driven at f_y near f_theta = 2 f_y moves at half its natural frequency, and longer windows let
   the raw positions' noise in the stiffness column into the residual.
2. **Selection** on each equation, in three steps.  (a) Backward elimination from the full library,
   dropping the least significant term (velocity terms first while one is below the Bonferroni level),
   until Holm's rule (:func:`fitting.multiple_testing.holm_reject`, family-wise ``alpha`` over the
   library terms that are not forced in) declares every remaining term significant.  (b) Stepwise
   additions, swaps and merges that keep every term significant
   (:func:`fitting.selection.support_search.select_support`): elimination alone decides
   between nearly collinear terms by the accident of the full fit.  (c) Held-out pruning: the elimination
   continues from there down to the forced terms, and the support with the smallest held-out error
   (K-fold over runs) on that path is kept, so a term must also improve the prediction of runs it was not
   fitted on.  The damping terms (ydot in yddot, thetadot in thetaddot) are always kept.  Under model error
   (``model_error_factor``, ``model_error_inflation``) the equation is selected by held-out prediction instead.
3. **Errors in the variables.**  The first pass evaluates the columns at raw y, smoothed ydot and theta
   smoothed over half a hinge period (:func:`fitting.derivatives.integral_form.column_states`), which loses weak velocity
   terms and biases others (5.5 oracle standard errors on the hinge's y coupling).  Every later pass evaluates
   them at the raw positions (whose white noise averages out in the double integral) and the velocities of the
   selected model's own trajectories fitted segment by segment to the data
   (:func:`fitting.refinement.model_states.model_states`), and selects again from the full library.  The columns are
   prefiltered (:func:`fitting.selection.support_search.numerov_columns`) so that the double integral is fourth-order
   accurate and the model's frequencies unbiased.  The passes stop when the support is unchanged and no
   coefficient moved by more than ``tolerance`` standard errors; a support that returns to an earlier one, or
   still changes after ``selection_passes``, is frozen.
4. **Trade-off.**  Every support met on the elimination paths, with its held-out error (fit on the other
   runs; root-mean-square misfit of the held-out runs' detrended positions per degree of freedom),
   forms the Pareto front of number of terms against held-out error (:attr:`DiscoveryResult.pareto`).
5. **Output error under model error.**  No least squares is efficient then; the coefficients are refined so that
   the model's trajectories follow the runs over segments of several periods, what a long-time prediction needs;
   the terms a trajectory does not need are pruned and those it needs added (:mod:`fitting.refinement.output_error`).
   The segments start from the last pass's model-based states, not from the smoothed ones: on a double pendulum at
   12 % truncation (4 runs) this lowers the held-out long-time error from the first state from 6.7 to 4.3 %.

Everything after the column evaluation works on the R factor of each run's design ``[X b]`` (35 + 1 columns),
so a least squares on any support, a whole elimination path and the cross-validation cost microseconds each.
"""
from __future__ import annotations

import logging
import time
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Sequence

import numpy as np
from numpy.typing import NDArray

from cubedimer.executor import single_blas_thread
from cubedimer.terms import EQUATION_NAMES, evaluate_library
from ..derivatives.integral_form import integral_form_states, integral_window, natural_windows
from ..model import TERMS, PolynomialModel, damping_mask
from ..refinement.model_states import model_states, segment_length
from ..refinement.output_error import OutputErrorFit, refine_output_error
from .discovery_config import FEW_RUNS_MODE, KNEE_TOLERANCE, METHOD, MODEL_ERROR_MODE, DiscoveryConfig
from .estimate_choice import EstimateChoice, acceleration_fit, chosen_coefficients, state_estimate_starts
from .front import (ACCELERATIONS, ALONG_HORIZON_PERIODS, Front, HeldOutRun, capped_support, long_time_front,
                    refined_front)
from .support_search import (fit_support, heldout_inflation, heldout_per_run, heldout_rms, prune_heldout, reduced_design,
                             run_weights, select_heldout, select_support)

if TYPE_CHECKING:
    from cubedimer.dataset import Run
    from ..derivatives.preparation import RunPreparation
    from ..derivatives.savitzky_golay import Derivatives

__all__ = ["DiscoveryConfig", "PathPoint", "IterationLog", "DiscoveryResult", "discover_model",
           "METHOD", "KNEE_TOLERANCE", "MODEL_ERROR_MODE", "FEW_RUNS_MODE"]

log = logging.getLogger(__name__)

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
    """One pass: which states, how many terms, how far the coefficients moved (in standard errors, over the equations
    selected by significance) and how far the held-out error of the selection moved (relative, over those under
    model error)."""

    iteration: int
    states: str
    n_terms: tuple[int, int]
    max_change_se: float
    residual_std: tuple[float, float]
    state_rms: tuple[float, float]
    failed_frames: int
    seconds: float
    heldout_change: float = float("nan")

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
        Their standard errors [SI] (an output-error addition's from the output error); zero outside the support.
    residual_std : ndarray (2,)
        Residual standard deviation of y [m] and theta [-] (compare with the tracking noise).
    window_s : ndarray (2,)
        Median integral-form window of each equation [s].
    pareto : dict
        ``{equation: tuple of PathPoint}``, from the full library to the forced terms.
    iterations : tuple of IterationLog
    converged : bool
    selection_modes : tuple of str
        Per equation, how the last pass selected: ``"significance"`` (Holm's rule and the held-out pruning) or
        ``"held-out (model error)"`` (``DiscoveryConfig.model_error_factor`` or ``model_error_inflation``).
    residual_to_noise : tuple of float
        Per equation, the residual standard deviation at the significance rule's support over the tracking noise.
    heldout_inflation : tuple of float
        Per equation, :func:`fitting.selection.support_search.heldout_inflation` at the significance rule's support (NaN with
        fewer than two runs).
    output_error : OutputErrorFit or None
    front : Front or None
        Model size against the held-out long-time error (:mod:`fitting.selection.front`); None with fewer than two runs.
    max_terms : int or None
        The cap on terms per equation that picked this model from the front (``DiscoveryConfig.max_terms``).
    estimate : EstimateChoice or None
        Under model error, which estimate gave the coefficients (:mod:`fitting.selection.estimate_choice`).
    """

    mask: NDArray[np.bool_]
    coef: NDArray[np.float64]
    std_errors: NDArray[np.float64]
    residual_std: NDArray[np.float64]
    window_s: NDArray[np.float64]
    pareto: dict[str, tuple[PathPoint, ...]]
    iterations: tuple[IterationLog, ...]
    converged: bool
    selection_modes: tuple[str, str] = ("significance", "significance")
    residual_to_noise: tuple[float, float] = (float("nan"), float("nan"))
    heldout_inflation: tuple[float, float] = (float("nan"), float("nan"))
    output_error: OutputErrorFit | None = None
    front: Front | None = None
    max_terms: int | None = None
    estimate: EstimateChoice | None = None

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

    def knee(self, tolerance: float = KNEE_TOLERANCE) -> dict[str, tuple[str, ...]]:
        """Per equation, the smallest support on the Pareto front whose held-out error is within ``tolerance`` (a
        fraction) of the front's best: the smaller model a practical threshold gives (``heldout_tolerance``).
        Empty for an equation whose front has no held-out errors (fewer than two runs)."""
        out = {}
        for eq in EQUATION_NAMES:
            front = [p for p in self.pareto[eq] if np.isfinite(p.heldout_rms)]
            if front:
                best = min(p.heldout_rms for p in front)
                out[eq] = min((p for p in front if p.heldout_rms <= best * (1.0 + tolerance)),
                              key=lambda p: p.n_terms).terms
        return out

    def to_json(self) -> dict:
        """Selected terms with value, std_error and z per equation; the Pareto front; its knee at
        :data:`KNEE_TOLERANCE`; the iterations."""
        z = self.z
        knee = self.knee()
        return {"method": METHOD,
                **{eq: {"terms": {t: {"value": float(self.coef[q, j]), "std_error": float(self.std_errors[q, j]),
                                      "z": float(z[q, j])} for j, t in enumerate(TERMS) if self.mask[q, j]},
                        "residual_std": float(self.residual_std[q]), "window_s": float(self.window_s[q]),
                        "pareto": [p.to_json() for p in self.pareto[eq]],
                        "selection": {"rule": self.selection_modes[q],
                                      "residual_to_noise": float(self.residual_to_noise[q]),
                                      "heldout_inflation": float(self.heldout_inflation[q])}}
                   for q, eq in enumerate(EQUATION_NAMES)},
                "knee": {"tolerance": KNEE_TOLERANCE, **{eq: list(t) for eq, t in knee.items()}},
                "iterations": [it.to_json() for it in self.iterations], "converged": self.converged,
                "output_error": self.output_error.to_json() if self.output_error is not None else None,
                "estimate": self.estimate.to_json() if self.estimate is not None else None,
                "front": ({**self.front.to_json(), "max_terms": self.max_terms} if self.front is not None else None)}


# ---- the discovery loop ----------------------------------------------------------------------------------------
def discover_model(runs: Sequence["Run"], derivs: Sequence["Derivatives"],
                   config: DiscoveryConfig = DiscoveryConfig(),
                   prepared: Sequence["RunPreparation | None"] | None = None,
                   refine_front: bool = False) -> DiscoveryResult:
    """Select and fit both equations on the integral form with model-based column states (module docstring).

    Parameters
    ----------
    runs : per run :class:`cubedimer.dataset.Run` (raw, gap-filled y [m] and theta [-] at every frame)
    derivs : per run :class:`fitting.derivatives.savitzky_golay.Derivatives` (the smoothed ydot of the first pass, its edges)
    config : DiscoveryConfig
    prepared : per run its :class:`fitting.derivatives.preparation.RunPreparation` (the frequencies and column states
        prepared once), optional: otherwise made from ``runs`` and ``derivs`` by the same rules
    refine_front : bool
        Refine every front point's coefficients by the output error on its supports
        (:func:`fitting.selection.front.refined_front`; one output-error fit per point: several times the fit's cost).

    Returns
    -------
    DiscoveryResult
    """
    with single_blas_thread():
        return _discover(runs, derivs, config, prepared, refine_front)


@dataclass(frozen=True, eq=False)
class _Setup:
    """What the passes read: positions, first states and edges, windows, segments, forced terms, noise, frequencies."""

    dts: list[float]
    ys: list[NDArray]
    ths: list[NDArray]
    first: list[NDArray]
    edges: list[int]
    windows: list[list[int]]
    seg_len: list[int]
    forced: NDArray
    noise: tuple[float, float]
    slow_freqs: list[float]
    weights: tuple[NDArray | None, NDArray | None] = (None, None)


@dataclass(frozen=True, eq=False)
class _Pass:
    """One selection-and-fit pass over both equations."""

    coef: NDArray
    se: NDArray
    res_std: NDArray
    designs: list
    fronts: list[tuple[list, list[float], list[int]]]
    modes: tuple[str, str]
    ratio: tuple[float, float]
    inflation: tuple[float, float]
    heldout: tuple[float, float] = (float("nan"), float("nan"))


def _setup(runs: Sequence["Run"], derivs: Sequence["Derivatives"], config: DiscoveryConfig,
           prepared: Sequence["RunPreparation | None"] | None = None) -> _Setup:
    """Step 1: the first pass's column states (smoothed) and each run's oscillation frequencies (those of the runs'
    preparations, :func:`fitting.derivatives.integral_form.integral_form_states`), the windows from them and the noise
    of the positions."""
    from cubedimer.noise import white_noise_std

    dts = [float(r.dt) for r in runs]
    ys = [np.asarray(r.y, float) for r in runs]
    ths = [np.asarray(r.theta, float) for r in runs]
    freqs, first, edges = integral_form_states(runs, derivs, prepared)
    windows = [[integral_window(dt, f[q], config.window_periods, bounds_periods=config.window_bounds_periods,
                                reference_hz=_reference_frequency(f)) for f, dt in zip(freqs, dts)] for q in range(2)]
    seg_len = [segment_length(dt, f[0], f[1], config.segments) for f, dt in zip(freqs, dts)]
    forced = damping_mask() if config.keep_damping else np.zeros((2, len(TERMS)), bool)
    # each run weighted by its own recorded tracking noise (Run.noise, meta.json's tracking.runs); the noise the
    # residual is compared with is then that of the weighted positions
    recorded = [getattr(r, "noise", None) for r in runs]
    weights = tuple(run_weights([None if n is None else n[q] for n in recorded]) for q in range(2))
    noise = tuple(white_noise_std(x if w is None else [wi * xi for wi, xi in zip(w, x)])
                  for x, w in zip((ys, ths), weights))
    return _Setup(dts, ys, ths, first, edges, windows, seg_len, forced, noise,
                  [min((v for v in f if v > 0), default=float("nan")) for f in freqs], weights)


def _reference_frequency(freqs: tuple[float, float]) -> float:
    """The frequency [Hz] whose periods bound a run's windows and segments: the first coordinate's dominant one, or
    the second's when the first does not oscillate (NaN when neither does)."""
    return next((float(f) for f in freqs if np.isfinite(f) and f > 0), float("nan"))


def _runs_disagree(design, chosen: Sequence[int], significant: Sequence[int], config: DiscoveryConfig) -> bool:
    """Whether the held-out selection ``chosen`` drops terms of the significance rule's support ``significant`` on
    the word of runs that disagree: some held-out run's misfit is higher without them by more than
    ``DiscoveryConfig.few_runs_excess`` (relative), with fewer runs than ``DiscoveryConfig.few_runs``.  Logged as a
    warning with more runs."""
    dropped = set(significant) - set(chosen)
    n_runs = len(design.per_run)
    if not dropped or n_runs < 2 or config.few_runs_excess is None:
        return False
    err = heldout_per_run(design, [list(chosen), list(significant)], config.n_folds)
    with np.errstate(divide="ignore", invalid="ignore"):
        excess = float(np.nanmax(err[0] / err[1] - 1.0))
    if not excess > config.few_runs_excess:
        return False
    if n_runs < config.few_runs:
        log.warning("held-out selection over %d runs drops %d terms of the significance rule's support while a held-out "
                    "run's misfit rises by %.0f %% without them: the runs disagree, the significance support is kept",
                    n_runs, len(dropped), 100 * excess)
        return True
    log.warning("held-out selection drops %d terms of the significance rule's support while a held-out run's misfit "
                "rises by %.0f %% without them", len(dropped), 100 * excess)
    return False


def _is_model_error(ratio: float, inflation: float, config: DiscoveryConfig) -> bool:
    """Either sign of model error (``model_error_factor``, ``model_error_inflation``)."""
    factor, limit = config.model_error_factor, config.model_error_inflation
    return (factor is not None and ratio > factor) or (limit is not None and bool(limit < inflation < np.inf))


def _select_equation(design, forced: NDArray, noise: float, config: DiscoveryConfig):
    """One equation's support: Holm's rule with stepwise swaps, then held-out pruning, or held-out selection when
    the residual shows model error.  Returns (support, path, held-out errors, mode, residual / noise, held-out
    inflation)."""
    sel, path = select_support(design, forced, config.alpha, config.velocity_first, config.stepwise,
                               config.velocity_price)
    ratio = fit_support(design, sel)[2] / noise if noise > 0 else float("inf")
    inflation = heldout_inflation(design, sel, config.n_folds)
    mode = "significance"
    held_a = [float("nan")] * len(path)
    if _is_model_error(ratio, inflation, config):
        mode = MODEL_ERROR_MODE
        significant = list(sel)
        sel, path, held = select_heldout(design, forced, config.alpha, config.velocity_first, config.n_folds,
                                         config.model_error_se, config.model_error_tolerance, noise,
                                         config.heldout_tolerance)
        if _runs_disagree(design, sel, significant, config):
            sel, mode = significant, FEW_RUNS_MODE
    elif config.heldout_prune:
        sel, path_b, held_b = prune_heldout(design, sel, forced, config.alpha, config.velocity_first, config.n_folds,
                                            config.heldout_tolerance)
        path, held = path + path_b, held_a + held_b
    else:
        held = held_a
    return sel, path, held, mode, ratio, inflation


def _one_pass(setup: _Setup, windows, states: Sequence[NDArray], trims: Sequence[int], caches: list[dict] | None,
              frozen: NDArray | None, config: DiscoveryConfig) -> _Pass:
    """Step 2: select (unless ``frozen``) and fit both equations with the columns at ``states``."""
    lib = [evaluate_library(s) for s in states]
    positions = (setup.ys, setup.ths)
    designs = [reduced_design(positions[q], lib, setup.dts, windows[q], trims, caches[q] if caches else None,
                              setup.weights[q]) for q in range(2)]
    coef, se, res_std, fronts = np.zeros((2, len(TERMS))), np.zeros((2, len(TERMS))), np.zeros(2), []
    modes, ratio, inflation = [], [], []
    for q in range(2):
        sel, path, held, mode, r, infl = _select_equation(designs[q], setup.forced[q], setup.noise[q], config)
        modes.append(mode)
        ratio.append(r)
        inflation.append(infl)
        if frozen is not None:
            sel = list(np.flatnonzero(frozen[q]))
        c, e, s = fit_support(designs[q], sel)
        coef[q, sel], se[q, sel], res_std[q] = c, e, s
        fronts.append((path, held, sel))
    held = tuple(heldout_rms(designs[q], [fronts[q][2]], config.n_folds)[0] for q in range(2))
    return _Pass(coef, se, res_std, designs, fronts, (modes[0], modes[1]), (ratio[0], ratio[1]),
                 (inflation[0], inflation[1]), held)


def _freeze(mask: NDArray, masks: list[NDArray], it: int, config: DiscoveryConfig) -> tuple[NDArray | None, str]:
    """Step 3's freezing of the support: a selection that returns to an earlier support (held-out errors within their
    noise) or keeps changing is frozen: the smaller of the last two supports, then only the coefficients iterate.
    Returns (frozen support or None, what to add to the pass's label)."""
    if it < 1:
        return None, ""
    if any(np.array_equal(mask, m) for m in masks[:-1]) and not np.array_equal(mask, masks[-1]):
        return min((masks[-1], mask), key=lambda m: int(m.sum())), ", support frozen (cycle)"
    if it >= config.selection_passes:
        return mask, ", support frozen"
    return None, ""


def _max_change(result: _Pass, mask: NDArray, prev: _Pass | None, config: DiscoveryConfig) -> tuple[float, float]:
    """Step 3's convergence measures since the previous pass: the largest change of a coefficient in standard errors
    over the equations selected by significance, and the largest relative change of the held-out RMS error of the
    selection over those under model error, where standard errors mean nothing (both inf when the support changed;
    0 where no equation is of that kind)."""
    if prev is None:
        return np.inf, np.inf
    prev_mask = prev.coef != 0.0
    if not np.array_equal(mask, prev_mask):
        return np.inf, np.inf
    model_error = np.array([m in (MODEL_ERROR_MODE, FEW_RUNS_MODE) for m in result.modes])
    with np.errstate(divide="ignore", invalid="ignore"):
        d = np.abs(result.coef - prev.coef) / np.maximum(result.se, prev.se)
        held = np.abs(np.subtract(result.heldout, prev.heldout)) / np.asarray(prev.heldout)
    se_rows = ~model_error[:, None] & mask
    change = float(np.nanmax(np.where(se_rows, d, 0.0)))
    held_change = float(np.nanmax(np.where(model_error, held, 0.0)))
    return change, (held_change if np.isfinite(held_change) or not model_error.any() else np.inf)


def _iterate(setup: _Setup, config: DiscoveryConfig) -> tuple[_Pass, list[list[int]], list[IterationLog], bool,
                                                               list[NDArray] | None]:
    """Step 3: passes with the columns at the smoothed states, then at the selected model's states fitted to the
    data, until the support and the coefficients converge.  Returns (last pass, windows, history, converged, the
    last model-based states (None after the first pass alone))."""
    dts, ys, ths, first, edges, windows = setup.dts, setup.ys, setup.ths, setup.first, setup.edges, setup.windows
    caches: list[dict] = [{}, {}]
    states, trims, label = first, edges, "smoothed"
    estimate = result = prev = frozen = None
    history: list[IterationLog] = []
    masks: list[NDArray] = []
    for it in range(config.max_iterations + 1):
        t0 = time.perf_counter()
        if it == 1 and config.natural_periods is not None:
            windows = natural_windows(result.coef, windows, dts, config.natural_periods)
        if it > 0:
            sigma = (float(result.res_std[0]), float(result.res_std[1]))
            estimate = model_states(PolynomialModel(result.coef), dts, ys, ths, first, setup.seg_len, sigma,
                                    config.segments, x0=estimate.x0 if estimate is not None else None)
            states = estimate.states
            if config.raw_positions:
                states = [np.column_stack([y, s[:, 1], th, s[:, 3]]) for y, th, s in zip(ys, ths, states)]
            trims = [edge if f.any() else 0 for f, edge in zip(estimate.failed, edges)]
            label = "model"
        result = _one_pass(setup, windows, states, trims, caches if it > 0 and config.raw_positions else None,
                           frozen, config)
        mask = result.coef != 0.0
        if frozen is None:
            frozen, note = _freeze(mask, masks, it, config)
            label += note
        masks.append(mask)
        change, held_change = _max_change(result, mask, prev, config)
        res_std = result.res_std
        history.append(IterationLog(
            iteration=it, states=label, n_terms=(int(mask[0].sum()), int(mask[1].sum())), max_change_se=change,
            heldout_change=held_change,
            residual_std=(float(res_std[0]), float(res_std[1])),
            state_rms=tuple(float(v) for v in (estimate.rms if estimate is not None else (np.nan, np.nan))),
            failed_frames=estimate.n_failed if estimate is not None else 0, seconds=time.perf_counter() - t0))
        log.info("discovery pass %d (%s states): %d + %d terms, max change %.3g SE, residual std (y, theta) %.3g, %.3g (SI)",
                 it, label, mask[0].sum(), mask[1].sum(), change, res_std[0], res_std[1])
        if change < config.tolerance and held_change < config.heldout_convergence:
            return result, windows, history, True, (estimate.states if estimate is not None else None)
        prev = result
    return result, windows, history, False, (estimate.states if estimate is not None else None)


def _pareto_fronts(result: _Pass, config: DiscoveryConfig) -> dict[str, tuple[PathPoint, ...]]:
    """Step 4: per equation, the distinct supports of the last pass's elimination path with their residual and
    held-out errors (computed where the path has none), the largest first."""
    pareto = {}
    for q, eq in enumerate(EQUATION_NAMES):
        path, held, sel = result.fronts[q]
        design = result.designs[q]
        missing = [i for i, h in enumerate(held) if not np.isfinite(h)]
        for i, h in zip(missing, heldout_rms(design, [path[i] for i in missing], config.n_folds)):
            held[i] = h
        seen, points = set(), []
        for cols, h in zip(path, held):
            key = tuple(sorted(cols))
            if key in seen:
                continue
            seen.add(key)
            points.append(PathPoint(tuple(TERMS[j] for j in key), fit_support(design, key)[2], h,
                                    selected=set(key) == set(sel)))
        pareto[eq] = tuple(sorted(points, key=lambda p: -p.n_terms))
    return pareto


def _discover(runs: Sequence["Run"], derivs: Sequence["Derivatives"], config: DiscoveryConfig,
              prepared: Sequence["RunPreparation | None"] | None = None, refine_front: bool = False) -> DiscoveryResult:
    """Steps 1-5: set up, iterate the passes, the output error under model error, the Pareto fronts, the result."""
    t_start = time.perf_counter()
    setup = _setup(runs, derivs, config, prepared)
    result, windows, history, converged, model_based = _iterate(setup, config)
    held_out = [HeldOutRun(dt, y[d.trim:], th[d.trim:], np.asarray(d.state[d.trim], float),
                           np.asarray(d.state[d.trim:], float), _horizon_frames(f, dt))
                for dt, y, th, d, f in zip(setup.dts, setup.ys, setup.ths, derivs, setup.slow_freqs)]
    front = long_time_front(result.designs, result.fronts, held_out, config.n_folds, alpha=config.alpha,
                            velocity_first=config.velocity_first)
    if config.max_terms is not None:
        result = _capped(result, config.max_terms, front)
    oe_states = model_based or [d.state for d in derivs]
    if refine_front and front is not None and config.output_error is not None:
        front = _refined_front(setup, front, held_out, oe_states, config)
    refined = _refine_output_error(setup, oe_states, result, config)
    coef, se = (result.coef, result.se) if refined is None else (refined.coef, refined.merged_std_errors(result.se))
    choice = None
    if refined is not None and (config.estimate_choice or (config.estimate_choice is None and config.max_terms)):
        coef, se, choice = chosen_coefficients(result.designs, held_out, setup.dts, setup.ys, setup.ths, oe_states,
                                               setup.slow_freqs, setup.noise, config.output_error, coef, se,
                                               config.n_folds, config.acceleration_window_periods)
    mask = coef != 0.0
    window_s = np.array([np.median([w * dt for w, dt in zip(windows[q], setup.dts)]) for q in range(2)])
    pareto = _pareto_fronts(result, config)
    log.info("discovery: %d terms in %.2f s (%sconverged)", mask.sum(), time.perf_counter() - t_start,
             "" if converged else "not ")
    for q, eq in enumerate(EQUATION_NAMES):
        if result.modes[q] != "significance":
            log.info("%s: residual %.3g times the tracking noise, held-out inflation %.3g (limits %s, %s): model "
                     "error; terms selected by held-out prediction over runs", eq, result.ratio[q], result.inflation[q],
                     config.model_error_factor, config.model_error_inflation)
    return DiscoveryResult(mask=mask, coef=coef, std_errors=np.where(mask, se, 0.0),
                           residual_std=result.res_std, window_s=window_s, pareto=pareto, iterations=tuple(history),
                           converged=converged, selection_modes=result.modes, residual_to_noise=result.ratio,
                           heldout_inflation=result.inflation, output_error=refined, front=front,
                           max_terms=config.max_terms, estimate=choice)


def _refined_front(setup: _Setup, front: Front, held_out: list[HeldOutRun], states: list[NDArray],
                   config: DiscoveryConfig) -> Front:
    """The front with every point's coefficients the best of the integral form, the output error (segment states
    ``states``) and the least squares of short-window accelerations by the prediction from the fitted runs' first
    state estimates (:func:`fitting.selection.front.refined_front`)."""
    oe_fixed = replace(config.output_error, support_tolerance=None, additions=False)
    everything = range(len(setup.ys))
    return refined_front(front, lambda c: refine_output_error(
        PolynomialModel(c), setup.dts, setup.ys, setup.ths, states, setup.slow_freqs, setup.noise, oe_fixed).coef,
        state_estimate_starts(held_out, states, setup.ys),
        {ACCELERATIONS: lambda c: acceleration_fit(setup.dts, setup.ys, setup.ths, c != 0, everything,
                                                   config.acceleration_window_periods)[0]})


def _horizon_frames(slow_freq: float, dt: float) -> int:
    """Frames of the front's horizon along a run (``ALONG_HORIZON_PERIODS`` slow periods; 0 without a frequency)."""
    return int(round(ALONG_HORIZON_PERIODS / (slow_freq * dt))) if np.isfinite(slow_freq) and slow_freq > 0 else 0


def _capped(result: _Pass, cap: int, front: Front | None = None) -> _Pass:
    """The last pass with each equation's support replaced by the front's point at ``cap`` terms (where the front
    ordered that cap by the held-out long-time error, :meth:`fitting.selection.front.Front.supports_at`; else
    :func:`fitting.selection.front.capped_support`), refitted on all runs."""
    coef, se, res_std, fronts = np.zeros_like(result.coef), np.zeros_like(result.se), result.res_std.copy(), []
    at_cap = front.supports_at(cap) if front is not None else None
    for q, (path, held, sel) in enumerate(result.fronts):
        cols = list(capped_support(path, held, sel, cap) if at_cap is None else at_cap[q])
        c, e, s = fit_support(result.designs[q], cols)
        coef[q, cols], se[q, cols], res_std[q] = c, e, s
        fronts.append((path, held, cols))
    return replace(result, coef=coef, se=se, res_std=res_std, fronts=fronts)


def _refine_output_error(setup: _Setup, states: list[NDArray], result: _Pass, config: DiscoveryConfig):
    """Step 5: under model error, the coefficients whose trajectories best follow the runs over several periods,
    from the segment states ``states`` (the last pass's model-based states: the smoothing filter's attenuation of the
    velocities starts the segments of a chaotic motion off its trajectory, and the segment-state fit then settles in
    another minimum or drops the segment as an outlier)."""
    if config.output_error is None or not {MODEL_ERROR_MODE, FEW_RUNS_MODE} & set(result.modes):
        return None
    oe = replace(config.output_error, misfit_tolerance=max(config.output_error.misfit_tolerance,
                                                           config.heldout_tolerance),  # the practical threshold
                 max_terms=config.max_terms)  # a cap holds after the additions
    return refine_output_error(PolynomialModel(result.coef), setup.dts, setup.ys, setup.ths, states,
                               setup.slow_freqs, setup.noise, oe, setup.forced)
