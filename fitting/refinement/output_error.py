"""Output-error refinement: the coefficients whose trajectories best follow the measured runs over several periods.

Why
---
Under model error (a truth that the cubic library cannot represent) no least-squares estimate of the
coefficients is efficient, and each weights the misfit differently: the integral form
(:mod:`fitting.derivatives.integral_form`) weights the slow part of the residual, a least squares on differentiated data
the fast part.  Neither is the coefficient set that predicts the motion best, and the long-time error, the
quantity a user compares against experiment, differs between them by up to a factor of two.

Method
------
Each run is cut into segments of ``periods`` periods of its slower dominant frequency, overlapping by half
(:func:`fitting.refinement.model_states.segment_layout`; at most ``max_segments`` in all, evenly spread).  The parameters
are the coefficients of the given support and the initial state of every segment (4 per segment); the objective
is the misfit of the simulated y and theta to the measured ones, each in units of its tracking noise, summed over
all frames of all segments: the maximum-likelihood fit for white tracking noise when the model is exact, and the
best predictor over the segment length when it is not.  It is minimised by Levenberg-Marquardt from the start
coefficients with the segment states first fitted alone (Gauss-Newton); the Jacobian is a forward difference
with every perturbed trajectory integrated in one compiled call per chunk of segments
(:func:`fitting.integrate.integrate_batch`), and the segment states are eliminated from the normal equations by
their Schur complement, so a step costs one solve of the size of the support.  Fitting the segment states removes
the error of smoothed initial states, which otherwise dominates a trajectory misfit.  A segment whose trajectory
leaves ten times the run's range at the start coefficients, or whose misfit there is above ``outlier_factor`` (5)
times the median segment's, is left out: where the motion is chaotic (a double pendulum at large swings) a few
diverged segments would otherwise decide the coefficients.

Pruning and additions
---------------------
A support selected by held-out prediction under model error keeps terms whose only use is to absorb a little of the
model error in the acceleration; along a trajectory they do nothing.  And it misses terms whose share of the
acceleration is small but whose effect accumulates along a trajectory: a nonlinear damping (``y^2*ydot`` in a van
der Pol oscillator) decides the amplitude after a few periods.  So after the refinement the support is changed by
the output error itself, in three steps.

1. Pruning: terms are tried for removal one at a time, the weakest first (smallest RMS contribution to its
   equation's acceleration over the state estimates given); a term goes when the support without it, refined again over
   the same segments, has a squared misfit within ``support_tolerance`` (3 %) of the model-error part of the full
   support's, ``misfit**2 - 1`` in noise units: the tolerance of the held-out selection
   (:func:`fitting.selection.support_search.select_heldout`), on the quantity a long-time prediction needs.  Pruning stops at
   the ``support_rejections``-th (2nd) term that must stay.  Terms the caller forces (``forced``) are never tried.
2. Additions: a score test ranks every absent term of the library by the drop of the squared misfit that adding it
   would give to first order, the support's coefficients and the segment states re-optimised with it
   (Gauss-Newton on the forward-difference Jacobian of all 70 coefficients, the states eliminated by their Schur
   complement: one Jacobian for all candidates).  The best is added, and the support refined, when its refitted
   misfit drops by more than ``support_tolerance`` of the model-error part, the same rule read the other way; and
   only when the drop is beyond what the noise explains (a chi-square test at a family-wise 1 % over the
   candidates).  Terms are added only while the misfit exceeds ``addition_misfit`` (1.05, the discovery's model-error
   factor) times the noise.  The additions stop at the ``support_rejections``-th candidate that fails
   (``additions=False``: no additions, pruning alone).  An added term's standard error is the output error's own
   (Gauss-Newton, scaled by the misfit squared).
3. After an addition, pruning again from the grown support: a term the added one makes redundant goes.

A user's practical threshold (``misfit_tolerance``, the discovery's ``--heldout-tolerance``) widens both rules on the
whole RMS misfit: a term also goes when the misfit without it is within that fraction of the full support's, and an
addition must lower it by more than that fraction.
"""
from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import Sequence

import numpy as np
from numpy.typing import NDArray
from scipy.stats import chi2

from cubedimer.config_checks import check_non_negative, check_positive, check_whole
from cubedimer.terms import coefficient_label, coefficient_labels, evaluate_library
from ..model import PolynomialModel
from .segment_problem import (Segments, TrajectoryProblem, build_segments, fit_segment_states, lm_step,
                              reduced_normal)

__all__ = ["OutputErrorConfig", "OutputErrorFit", "refine_output_error"]

log = logging.getLogger(__name__)

#: family-wise false-alarm probability of the score test over the absent terms (an added term must beat the noise)
_ADDITION_LEVEL = 0.01


@dataclass(frozen=True)
class OutputErrorConfig:
    """Settings of :func:`refine_output_error`.

    Parameters
    ----------
    periods : float
        Segment length in periods of the run's slower dominant frequency: the horizon over which the
        trajectories are fitted.
    max_segments : int
        At most this many segments in all (evenly spread over the runs' segments).
    iterations : int
        Levenberg-Marquardt iterations at most.
    rtol : float
        Stop when an iteration lowers the misfit by less than this fraction.
    h_omega : float
        RK4 step times the model's fastest linear angular frequency.
    outlier_factor : float
        Segments whose RMS misfit at the start coefficients (states fitted) exceeds this many times the median
        segment's are left out: the model's trajectory has diverged from the motion there (a chaotic stretch, or a
        range the cubic cannot follow), and a sum of squares would be decided by them alone.
    support_tolerance : float or None
        A term is pruned when the refined squared misfit without it exceeds the full support's by at most this
        fraction of the full support's model-error part (``misfit**2 - 1``), and added when the refined squared
        misfit with it is lower by more than this fraction of the current model-error part; None: the support is
        kept as given.
    misfit_tolerance : float
        A practical threshold on top (the discovery passes its ``heldout_tolerance``, ``--heldout-tolerance``): a
        term is also pruned when the refined RMS misfit without it is within this fraction of the full support's,
        and an addition must lower the RMS misfit by more than this fraction.  0: none.
    support_rejections : int
        Pruning stops after this many terms were tried and kept, and the additions after this many were tried and
        not added.
    additions : bool
        Whether terms are added (False: pruning alone).
    addition_misfit : float
        Terms are added only while the misfit exceeds this many times the tracking noise (the discovery's
        ``model_error_factor``): below it the trajectories follow the runs to the noise, and an added term fits
        the noise's correlations between segments and the collinear leftovers of the others.
    max_terms : int or None
        Terms are added only to an equation with fewer terms than this (the discovery's ``max_terms``, ``fit
        --max-terms``): a cap on the model's size holds after the refinement too.  None: no cap.
    """

    periods: float = 5.0
    max_segments: int = 256
    iterations: int = 20
    rtol: float = 1e-6
    h_omega: float = 0.1
    outlier_factor: float = 5.0
    support_tolerance: float | None = 0.03
    misfit_tolerance: float = 0.0
    support_rejections: int = 2
    additions: bool = True
    addition_misfit: float = 1.05
    max_terms: int | None = None

    def __post_init__(self) -> None:
        for name in ("periods", "rtol", "h_omega", "outlier_factor", "addition_misfit"):
            check_positive(self, name)
        check_whole(self, "max_segments")
        check_whole(self, "iterations")
        check_whole(self, "support_rejections")
        if self.support_tolerance is not None:
            check_non_negative(self, "support_tolerance")
        check_non_negative(self, "misfit_tolerance")
        if self.max_terms is not None:
            check_whole(self, "max_terms")


@dataclass(frozen=True, eq=False)
class OutputErrorFit:
    """Result of :func:`refine_output_error`.

    Attributes
    ----------
    coef : ndarray (2, 35)
        Refined coefficients (SI), zero outside the (pruned) support.
    misfit_start, misfit : float
        Root-mean-square misfit of the segments' trajectories to y and theta, in units of the tracking noise
        (about 1 for an exact model), at the start coefficients (segment states fitted) and after the refinement
        and pruning.
    segments : int
        Segments fitted.
    segment_s : float
        Median segment length [s].
    iterations : int
        Levenberg-Marquardt iterations taken.
    dropped : int
        Segments left out because their trajectory left the run's range, or did not follow the motion
        (``outlier_factor``), at the start coefficients.
    misfit_support : float
        The misfit refined on the start support, before pruning (NaN when nothing was fitted).
    pruned : tuple of str
        The terms pruned, as ``equation:term`` (``thetaddot:ydot^2``), in the order they went.
    added : tuple of str
        The terms added, in the order they came.
    std_errors : ndarray (2, 35) or None
        Where terms were added: the Gauss-Newton standard errors of the final support's coefficients (SI), from
        the output error's normal matrix with the segment states eliminated, scaled by the misfit squared.
    """

    coef: NDArray[np.float64]
    misfit_start: float
    misfit: float
    segments: int
    segment_s: float
    iterations: int
    dropped: int = 0
    misfit_support: float = float("nan")
    pruned: tuple[str, ...] = ()
    added: tuple[str, ...] = ()
    std_errors: NDArray[np.float64] | None = None

    def merged_std_errors(self, start: NDArray) -> NDArray[np.float64]:
        """The standard errors ``start`` (2, 35) of the start support, with the output error's on added terms."""
        start = np.asarray(start, float)
        return start if self.std_errors is None else np.where(start != 0.0, start, self.std_errors)

    def to_json(self) -> dict:
        return {"misfit_start": self.misfit_start, "misfit": self.misfit, "segments": self.segments,
                "segment_s": self.segment_s, "iterations": self.iterations, "dropped": self.dropped,
                "misfit_support": self.misfit_support, "pruned": list(self.pruned), "added": list(self.added)}


def _followed(mean_square: NDArray, factor: float) -> NDArray[np.bool_]:
    """The segments whose trajectory stays in range and whose RMS misfit is at most ``factor`` times the median
    segment's."""
    finite = np.isfinite(mean_square)
    if not finite.any():
        return finite
    return finite & (mean_square <= factor**2 * np.median(mean_square[finite]))


def refine_output_error(model: PolynomialModel, dts: Sequence[float], ys: Sequence[NDArray],
                        thetas: Sequence[NDArray], states: Sequence[NDArray], slow_freqs: Sequence[float],
                        sigma: Sequence[float], config: OutputErrorConfig = OutputErrorConfig(),
                        forced: NDArray | None = None) -> OutputErrorFit:
    """Refine the model's coefficients on its support by the output error over segments, then prune the terms a
    trajectory does not need (module docstring).

    Parameters
    ----------
    model : PolynomialModel
        Start model (SI); its non-zero coefficients are the support.
    dts : per run frame interval [s]
    ys, thetas : per run measured y [m] and theta [-] at every frame (gaps filled)
    states : per run (n_i, 4) state estimates [y, ydot, theta, thetadot] (the segments' start states and ranges)
    slow_freqs : per run the slower dominant frequency [Hz]
    sigma : (float, float)
        Tracking noise of y [m] and theta [-] (the misfit's units).
    config : OutputErrorConfig
    forced : (2, 35) bool, optional
        Terms never pruned.

    Returns
    -------
    OutputErrorFit
        The start coefficients unchanged when no segment can be integrated.
    """
    coef = np.asarray(model.coef, float)
    segs = build_segments(dts, ys, thetas, states, slow_freqs, config)
    # noiseless or unmeasured noise: a floor of 1e-6 of each coordinate's RMS keeps the two weighted alike
    floor = 1e-6 * np.sqrt(np.nanmean(segs.data ** 2, axis=(0, 1)))
    sigma = np.asarray(sigma, float)
    sigma = np.where(np.isfinite(sigma) & (sigma > floor), sigma, floor)
    segment_s = float(np.median(segs.length * segs.dt))
    start = TrajectoryProblem(coef, segs, sigma, config.h_omega)
    x0, seg_cost = fit_segment_states(start, start.parameters(coef), segs.x0.copy())
    ok = _followed(seg_cost / (2.0 * segs.length), config.outlier_factor)
    dropped = int((~ok).sum())
    if not ok.any():
        log.info("output-error refinement: no segment is followed at the start coefficients; not refined")
        return OutputErrorFit(coef, float("nan"), float("nan"), 0, segment_s, 0, dropped)
    segs = segs.subset(ok)
    fit = _refine(coef, segs, sigma, x0[ok], config)
    out = OutputErrorFit(fit.coef, fit.misfit_start, fit.misfit, int(ok.sum()), segment_s, fit.iterations, dropped,
                         fit.misfit)
    log.info("output-error refinement: misfit %.4g -> %.4g noise units over %d segments of %.3g s (%d iterations)",
             out.misfit_start, out.misfit, out.segments, segment_s, out.iterations)
    if config.support_tolerance is None:
        return out
    return _select(out, fit.x0, segs, sigma, states, config, forced)


@dataclass(frozen=True, eq=False)
class _Refined:
    coef: NDArray
    x0: NDArray
    misfit_start: float
    misfit: float
    iterations: int


def _refine(coef: NDArray, segs: Segments, sigma: NDArray, x0: NDArray, config: OutputErrorConfig) -> _Refined:
    """Levenberg-Marquardt on the support's coefficients and the segment states from (``coef``, ``x0``); every
    segment must stay in bounds at every accepted step (misfit inf when one leaves them at the start)."""
    problem = TrajectoryProblem(coef, segs, sigma, config.h_omega)
    p = problem.parameters(coef)
    n_obs = max(int(problem.valid.sum()) * 2, 1)
    cost, ok = problem.cost(p, x0)
    if not ok.all():
        return _Refined(coef, x0, np.inf, np.inf, 0)
    cost_start, lam, it = cost, 1e-3, 0
    for it in range(1, config.iterations + 1):
        normal = problem.normal_equations(p, x0)
        for _ in range(10):
            step_c, step_x = lm_step(normal, lam)
            trial_cost, trial_ok = problem.cost(p + step_c, x0 + step_x)
            if trial_ok.all() and trial_cost < cost:
                break
            lam *= 4.0
        else:
            break
        gain = (cost - trial_cost) / cost
        log.debug("output-error iteration %d: misfit %.6g -> %.6g, lambda %.3g", it, cost, trial_cost, lam)
        p, x0, cost, lam = p + step_c, x0 + step_x, trial_cost, max(lam / 3.0, 1e-9)
        if gain < config.rtol:
            break
    out = np.zeros_like(coef)
    out[:, problem.cols] = problem.matrix(p)
    return _Refined(out, x0, float(np.sqrt(cost_start / n_obs)), float(np.sqrt(cost / n_obs)), it)


def _contributions(coef: NDArray, library: NDArray, column_rms: NDArray) -> NDArray[np.float64]:
    """(2, 35) RMS of every term's contribution to its equation's acceleration over the states whose library
    columns are ``library`` (n, 35; their RMS ``column_rms``), relative to the RMS of that equation's modelled
    acceleration; zero outside the support."""
    acc_rms = np.sqrt(np.mean((library @ np.asarray(coef, float).T) ** 2, axis=0))
    return np.abs(coef) * column_rms[None] / np.maximum(acc_rms, 1e-300)[:, None]


def _prune(coef: NDArray, x0: NDArray, misfit: float, segs: Segments, sigma: NDArray, library: NDArray,
           config: OutputErrorConfig, frozen: NDArray) -> tuple[NDArray, NDArray, float, list[str]]:
    """Backward elimination by the refined output error over the same segments (module docstring, Pruning and
    additions): the pruned (coefficients, segment states, misfit, terms)."""
    limit = max(misfit ** 2 + config.support_tolerance * max(misfit ** 2 - 1.0, 0.0),
                (misfit * (1.0 + config.misfit_tolerance)) ** 2)
    frozen = frozen.copy()
    column_rms = np.sqrt(np.mean(library ** 2, axis=0))
    pruned, kept = [], 0
    while kept < config.support_rejections:
        weight = np.where((coef != 0) & ~frozen, _contributions(coef, library, column_rms), np.inf)
        weight[(coef != 0).sum(axis=1) <= 1] = np.inf  # an equation keeps at least one term
        q, j = np.unravel_index(np.argmin(weight), weight.shape)
        if not np.isfinite(weight[q, j]):
            break
        trial = coef.copy()
        trial[q, j] = 0.0
        cand = _refine(trial, segs, sigma, x0, config)
        name = coefficient_label(q, j)
        log.debug("output-error pruning: without %s misfit %.5g (limit %.5g)", name, cand.misfit, np.sqrt(limit))
        if cand.misfit ** 2 <= limit:
            coef, x0, misfit = cand.coef, cand.x0, cand.misfit
            pruned.append(name)
        else:
            frozen[q, j] = True
            kept += 1
    return coef, x0, misfit, pruned


def _standard_errors(coef: NDArray, x0: NDArray, segs: Segments, sigma: NDArray,
                     config: OutputErrorConfig) -> NDArray[np.float64]:
    """(2, 35) Gauss-Newton standard errors of the support's coefficients, the segment states eliminated: the
    inverse normal matrix scaled by the misfit squared (a residual that is partly model error) and by 2 (the
    half-overlapping segments count every frame twice); zero outside the support."""
    problem = TrajectoryProblem(coef, segs, sigma, config.h_omega)
    p = problem.parameters(coef)
    a, _ = reduced_normal(problem.normal_equations(p, x0))
    cost, _ = problem.cost(p, x0)
    n_obs = max(int(problem.valid.sum()) * 2, 1)
    # equilibrated first: the coefficients' units span ten decades (y^2*theta ~1e10 against 1 ~1e3 in SI), and a
    # pseudo-inverse of the raw matrix would cut the large-variance directions as round-off
    d = np.sqrt(np.maximum(np.diag(a), 1e-300))
    var = np.diag(np.linalg.pinv(a / np.outer(d, d))) / d ** 2 * 2.0 * cost / max(n_obs - p.size, 1)
    out = np.zeros(coef.shape)
    out[:, problem.cols] = problem.matrix(np.sqrt(np.maximum(var, 0.0)))
    return out


def _addition_gains(coef: NDArray, x0: NDArray, segs: Segments, sigma: NDArray, library: NDArray,
                    config: OutputErrorConfig) -> tuple[NDArray, NDArray]:
    """Score test of every absent term: (2, 35) the drop of the squared misfit (noise units) that adding it and
    refitting the support and segment states would give to first order (Gauss-Newton, the other coefficients
    and the states re-optimised), and the coefficient it would take; -inf and 0 on the support."""
    support = coef != 0
    problem = TrajectoryProblem(coef, segs, sigma, config.h_omega, mask=np.ones_like(support))
    p = problem.parameters(coef)
    on = support[:, problem.cols][problem.mask[:, problem.cols]]
    # an absent term's step moves its equation's acceleration by 1e-6 of its RMS over the state estimates
    acc_rms = np.sqrt(np.mean((library @ coef.T) ** 2, axis=0))
    column_rms = np.sqrt(np.mean(library ** 2, axis=0))
    q_of, j_of = problem.where[:, 0], problem.cols[problem.where[:, 1]]
    usable = column_rms[j_of] > 0
    step = 1e-6 * acc_rms[q_of] / np.where(usable, column_rms[j_of], 1.0)
    dp = np.where(on, 1e-6 * np.maximum(np.abs(p), 1e-300), np.maximum(step, 1e-300))
    a, g = reduced_normal(problem.normal_equations(p, x0, dp=dp))
    d = np.sqrt(np.maximum(np.diag(a), 1e-300))  # equilibrated (see _standard_errors); undone in delta
    a, g = a / np.outer(d, d), g / d
    off = ~on
    proj = np.linalg.lstsq(a[np.ix_(on, on)], a[np.ix_(on, off)], rcond=None)[0]  # (n_on, n_off)
    curv = np.diag(a)[off] - np.einsum("ij,ij->j", a[np.ix_(on, off)], proj)
    score = g[off] - proj.T @ g[on]
    n_obs = max(int(problem.valid.sum()) * 2, 1)
    # a term the noise alone could explain is never a candidate: its drop of the sum of squares must pass a
    # chi-square test at a family-wise level of 1 % over the candidates, doubled since the half-overlapping
    # segments count every frame twice
    floor = 2.0 * chi2.isf(_ADDITION_LEVEL / max(int(off.sum()), 1), 1)
    ok = usable[off] & (curv > 0) & (score ** 2 > floor * np.maximum(curv, 0.0))
    gain, delta = np.full(coef.shape, -np.inf), np.zeros(coef.shape)
    gain[q_of[off][ok], j_of[off][ok]] = score[ok] ** 2 / curv[ok] / n_obs
    delta[q_of[off][ok], j_of[off][ok]] = -score[ok] / (curv[ok] * d[off][ok])
    return gain, delta


def _add(coef: NDArray, x0: NDArray, misfit: float, segs: Segments, sigma: NDArray, library: NDArray,
         config: OutputErrorConfig) -> tuple[NDArray, NDArray, float, list[str]]:
    """Forward selection by the refined output error (module docstring, Pruning and additions): the absent term of
    the largest score is added when, refitted, it lowers the squared misfit by more than ``support_tolerance`` of the
    model-error part; the grown (coefficients, segment states, misfit, terms)."""
    added, tried, rejected = [], np.zeros(coef.shape, bool), 0
    while rejected < config.support_rejections and misfit > config.addition_misfit:
        need = max(config.support_tolerance * max(misfit ** 2 - 1.0, 0.0),
                   misfit ** 2 * (1.0 - (1.0 + config.misfit_tolerance) ** -2))
        gain, delta = _addition_gains(coef, x0, segs, sigma, library, config)
        gain[tried] = -np.inf
        if config.max_terms is not None:
            gain[(coef != 0).sum(axis=1) >= config.max_terms] = -np.inf  # the cap holds
        q, j = np.unravel_index(np.argmax(gain), gain.shape)
        if not gain[q, j] > need:
            break
        trial = coef.copy()
        trial[q, j] = delta[q, j]
        cand = _refine(trial, segs, sigma, x0, config)
        name = coefficient_label(q, j)
        log.debug("output-error addition: with %s misfit %.5g -> %.5g (predicted %.5g, needed %.5g)", name, misfit,
                  cand.misfit, np.sqrt(max(misfit ** 2 - gain[q, j], 0.0)), np.sqrt(max(misfit ** 2 - need, 0.0)))
        if cand.misfit ** 2 <= misfit ** 2 - need:
            coef, x0, misfit = cand.coef, cand.x0, cand.misfit
            added.append(name)
        else:
            tried[q, j] = True
            rejected += 1
    return coef, x0, misfit, added


def _select(fit: OutputErrorFit, x0: NDArray, segs: Segments, sigma: NDArray, states: Sequence[NDArray],
            config: OutputErrorConfig, forced: NDArray | None) -> OutputErrorFit:
    """Prune, add the terms the trajectories need, and prune again after an addition (module docstring)."""
    frozen = np.zeros(fit.coef.shape, bool) if forced is None else np.asarray(forced, bool)
    library = evaluate_library(np.vstack(states))  # the state estimates' columns, once for every candidate
    coef, x0, misfit, pruned = _prune(fit.coef, x0, fit.misfit, segs, sigma, library, config, frozen)
    coef, x0, misfit, added = _add(coef, x0, misfit, segs, sigma, library, config) if config.additions else (
        coef, x0, misfit, [])
    if added:
        coef, x0, misfit, again = _prune(coef, x0, misfit, segs, sigma, library, config,
                                         frozen | np.isin(coefficient_labels(), added))
        pruned += again
    if pruned or added:
        log.info("output-error support: %d terms removed (%s), %d added (%s), misfit %.4g -> %.4g noise units",
                 len(pruned), ", ".join(pruned), len(added), ", ".join(added), fit.misfit, misfit)
    se = _standard_errors(coef, x0, segs, sigma, config) if added else None
    return OutputErrorFit(coef, fit.misfit_start, misfit, fit.segments, fit.segment_s, fit.iterations, fit.dropped,
                          fit.misfit, tuple(pruned), tuple(added), se)

