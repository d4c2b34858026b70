"""Long-time refinement of model coefficients with nlopt's gradient-free optimisers.

The free parameters are the coefficients of the model's active terms in scaled variables
(:class:`~fitting.model.Scales`), so they are all O(1)..O(1e-3) and one trust region fits
all.  The objective is the mean over the given runs of the loss of
:mod:`fitting.refinement.losses`, each run simulated from its own (smoothed) initial state with the
compiled RK4 integrator of :mod:`fitting.integrate` (batched over runs).  BOBYQA (a bounded
quadratic-model trust-region method) is the default: on smooth 10-20-D problems it needs far
fewer evaluations than Nelder-Mead or Subplex (DEPENDENCY_NOTES.md).  Bounds are
``c0 +- max(rel_bound |c0|, abs_bound)`` per coefficient.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Sequence

import numpy as np
from numpy.typing import NDArray

from cubedimer.config_checks import check_choice, check_non_negative, check_positive, check_that, check_whole
from ..derivatives.savitzky_golay import Derivatives
from ..integrate import integrate_batch
from ..model import EXPONENTS, PolynomialModel, Scales
from .losses import LossTerms, LossWeights, Reference, loss_terms, make_reference

__all__ = ["RefineConfig", "JOINT_REFINE", "RefineResult", "Objective", "scaled_reference", "refine", "default_substeps",
           "significant_digits", "START_DIGITS"]


#: The nlopt local derivative-free algorithms :class:`RefineConfig` accepts.
REFINE_ALGORITHMS = ("LN_BOBYQA", "LN_SBPLX", "LN_NELDERMEAD", "LN_COBYLA")


@dataclass(frozen=True)
class RefineConfig:
    """Optimiser settings.

    Parameters
    ----------
    algorithm : str
        nlopt local derivative-free algorithm name (``LN_BOBYQA``, ``LN_SBPLX``,
        ``LN_NELDERMEAD``, ``LN_COBYLA``).
    max_evals : int
        Objective evaluations (per optimisation).
    rel_bound, abs_bound : float
        Box half-width around the start: ``max(rel_bound |c0|, abs_bound)`` (scaled units).
    initial_step : float
        Initial step as a fraction of the box half-width.
    xtol_rel, ftol_rel : float
        nlopt stopping tolerances.
    h_omega : float
        RK4 step times the fastest linear angular frequency of the start model.
    horizons : tuple of float
        Continuation in the time horizon: the optimisation runs in stages on the first
        ``h * duration`` of every run, each stage starting from the previous optimum, with the
        evaluations split equally.  A 3 % frequency error makes the crossing-by-crossing loss
        over 66 periods wrap around two full phase cycles (many local minima); over the first
        quarter of the run it is a single basin.
    weights : LossWeights
    """

    algorithm: str = "LN_BOBYQA"
    max_evals: int = 600
    rel_bound: float = 0.5
    abs_bound: float = 0.02
    initial_step: float = 0.1
    xtol_rel: float = 1e-7
    ftol_rel: float = 1e-9
    h_omega: float = 0.05
    horizons: tuple[float, ...] = (0.25, 0.5, 1.0)
    weights: LossWeights = field(default_factory=LossWeights)

    def __post_init__(self) -> None:
        check_choice(self, "algorithm", REFINE_ALGORITHMS)
        check_whole(self, "max_evals")
        for name in ("rel_bound", "abs_bound", "initial_step", "h_omega"):
            check_positive(self, name)
        for name in ("xtol_rel", "ftol_rel"):
            check_non_negative(self, name)
        h = self.horizons
        check_that(self, isinstance(h, tuple) and len(h) > 0 and all(isinstance(x, (int, float)) and 0 < x <= 1 for x in h)
                   and list(h) == sorted(h), f"horizons must be an increasing tuple of fractions in (0, 1], got {h!r}")


#: A joint re-optimisation on all runs: of the minimal model (``FitConfig.joint``) and of a variant before it is
#: compared with it (:func:`fitting.compare.compare_models`); a tighter box than a per-run refinement's.
JOINT_REFINE = RefineConfig(max_evals=600, rel_bound=0.3, abs_bound=0.005)


@dataclass(frozen=True, eq=False)
class RefineResult:
    """Outcome of one refinement.

    Attributes
    ----------
    model : PolynomialModel
        Refined model (SI).
    start : PolynomialModel
        Starting model (SI).
    loss_start, loss_end : LossTerms
        Mean loss terms over the runs at the start and at the optimum.
    per_run_start, per_run_end : list of LossTerms
    history : ndarray
        Objective value of every evaluation, in order (the optimisation trajectory; the
        horizon stages follow each other).
    n_evals : int
    status : int
        nlopt return code (positive: success, 5 = max evaluations reached).
    """

    model: PolynomialModel
    start: PolynomialModel
    loss_start: LossTerms
    loss_end: LossTerms
    per_run_start: list[LossTerms]
    per_run_end: list[LossTerms]
    history: NDArray[np.float64]
    n_evals: int
    status: int


def scaled_reference(d: Derivatives, scales: Scales, horizon: float = 1.0) -> Reference:
    """Reference of one run's interior (edge frames dropped) in scaled variables.

    ``horizon`` < 1 keeps only that fraction of the interior (from its start).
    """
    n = d.t.size - 2 * d.trim
    s = slice(d.trim, d.trim + max(16, int(round(horizon * n))))
    return make_reference((d.t[s] - d.t[s][0]) / scales.time, d.state[s] / scales.state)


def _mean_terms(terms: Sequence[LossTerms]) -> LossTerms:
    return LossTerms(*(float(np.mean([getattr(t, k) for t in terms])) for k in
                       ("shape", "poincare", "frequency", "total")),
                     blown_up=any(t.blown_up for t in terms))


class Objective:
    """Mean loss over runs as a function of the scaled coefficients of the active terms.

    Parameters
    ----------
    refs : list of Reference
        Runs (scaled variables).
    mask : ndarray of bool (2, 35)
        Active terms.
    substeps : int
        RK4 steps per frame.
    weights : LossWeights
    """

    def __init__(self, refs: Sequence[Reference], mask: NDArray[np.bool_], substeps: int,
                 weights: LossWeights = LossWeights()):
        self.refs = list(refs)
        self.mask = np.asarray(mask, bool)
        self.substeps = int(substeps)
        self.weights = weights
        self.x0s = np.array([r.x0 for r in self.refs])
        self.dts = np.array([r.dt for r in self.refs])
        self.ns = np.array([r.n for r in self.refs], dtype=np.int64)
        self.bounds = np.array([weights.bound * r.norm for r in self.refs])
        self.cols = np.flatnonzero(self.mask.any(axis=0))  # integrate only the active monomials
        self.exps = np.ascontiguousarray(EXPONENTS[self.cols])
        self.history: list[float] = []

    def coef(self, x: NDArray) -> NDArray[np.float64]:
        c = np.zeros(self.mask.shape)
        c[self.mask] = x
        return c

    def per_run(self, coef_scaled: NDArray) -> list[LossTerms]:
        c = np.ascontiguousarray(np.asarray(coef_scaled)[:, self.cols])
        traj, nv = integrate_batch(c, self.exps, self.x0s, self.dts, self.ns,
                                   self.substeps, self.bounds)
        return [loss_terms(traj[i, : r.n], int(nv[i]), r, self.weights) for i, r in enumerate(self.refs)]

    def __call__(self, x: NDArray, grad: NDArray | None = None) -> float:
        val = float(np.mean([t.total for t in self.per_run(self.coef(np.asarray(x)))]))
        if not np.isfinite(val):  # defensive: the loss is finite by construction
            val = 2.0 * self.weights.penalty
        self.history.append(val)
        return val


def default_substeps(coef_scaled: NDArray, dt_scaled: float, h_omega: float) -> int:
    """RK4 steps per frame from the fastest linear frequency of a scaled model (at least 1)."""
    from ..model import TERMS

    om = np.sqrt(max(1.0, -coef_scaled[0, TERMS.index("y")], -coef_scaled[1, TERMS.index("theta")]))
    return max(1, int(np.ceil(dt_scaled * om / h_omega)))


#: significant digits of the refinement's start and box (:func:`significant_digits`)
START_DIGITS = 9


def significant_digits(x: NDArray, digits: int = START_DIGITS) -> NDArray[np.float64]:
    """``x`` rounded to ``digits`` significant decimal digits, element by element (zeros stay zero)."""
    x = np.asarray(x, float)
    nz = (x != 0) & np.isfinite(x)
    e = np.floor(np.log10(np.abs(np.where(nz, x, 1.0))))
    scale = 10.0 ** (digits - 1 - e)
    return np.where(nz, np.round(x * scale) / scale, x)


def refine(start: PolynomialModel, derivs: Sequence[Derivatives], scales: Scales,
           config: RefineConfig = RefineConfig(), mask: NDArray[np.bool_] | None = None,
           half_width: NDArray[np.float64] | None = None) -> RefineResult:
    """Minimise the mean long-time loss over ``derivs`` starting from ``start``.

    Parameters
    ----------
    start : PolynomialModel
        Start (SI), e.g. the regression model C0.
    derivs : list of Derivatives
        Runs (one for a per-run refinement, all for the joint one).
    scales : Scales
    config : RefineConfig
    mask : ndarray of bool (2, 35), optional
        Terms to optimise (default: the start's support); other terms are zero.
    half_width : ndarray (2, 35), optional
        Box half-width per coefficient in scaled units (e.g. a few standard errors); default
        ``max(rel_bound |c0|, abs_bound)``.
    """
    import nlopt

    refs = [scaled_reference(d, scales) for d in derivs]
    mask = start.support if mask is None else np.asarray(mask, bool)
    # the start and the box to START_DIGITS significant digits in the data's own scaled units: the optimiser's path
    # on the non-smooth loss turns a 1e-10 change of its start into 0.5 standard errors, so without this the unit
    # a data set is written in (whose conversion changes the last bits) would change the result (docs/fitting.md,
    # "Units and time scale")
    c0 = significant_digits(np.where(mask, scales.to_scaled(start.coef), 0.0))
    sub = default_substeps(c0, refs[0].dt, config.h_omega)
    obj = Objective(refs, mask, sub, config.weights)
    x0 = c0[mask]
    per_start = obj.per_run(c0)
    if x0.size == 0:
        lt = _mean_terms(per_start)
        return RefineResult(start, start, lt, lt, per_start, per_start, np.array([lt.total]), 1, 0)
    if half_width is None:
        half = np.maximum(config.rel_bound * np.abs(x0), config.abs_bound)
    else:
        half = significant_digits(np.asarray(half_width, float)[mask])
        if not np.all(half > 0):
            raise ValueError("half_width must be positive on every optimised term")
    x = x0.copy()
    history: list[float] = []
    status = 0
    horizons = sorted(set(config.horizons) | {1.0})
    for k, h in enumerate(horizons):
        stage = obj if h >= 1.0 else Objective([scaled_reference(d, scales, h) for d in derivs], mask, sub,
                                                config.weights)
        opt = nlopt.opt(getattr(nlopt, config.algorithm), x0.size)
        opt.set_lower_bounds(x0 - half)
        opt.set_upper_bounds(x0 + half)
        opt.set_initial_step(config.initial_step * half)
        opt.set_min_objective(stage)
        opt.set_maxeval(max(2 * x0.size + 2, int(config.max_evals) // len(horizons)))
        opt.set_xtol_rel(config.xtol_rel)
        opt.set_ftol_rel(config.ftol_rel)
        try:
            try:
                x = opt.optimize(x)
            except nlopt.invalid_argument:
                # BOBYQA rejects a start that lies closer to a bound than its initial step (but not on it): a
                # later stage starting near the box's edge retries with the step cut to the room left
                room = np.minimum(x - (x0 - half), (x0 + half) - x)
                step = config.initial_step * half
                opt.set_initial_step(np.where((room > 0) & (room < step), 0.5 * room, step))
                x = opt.optimize(x)
            status = int(opt.last_optimize_result())
        except (nlopt.RoundoffLimited, nlopt.invalid_argument, RuntimeError, ValueError):  # keep the previous point
            status = -4
        history += stage.history
    best = obj.coef(x)
    per_end = obj.per_run(best)
    # never return something worse than the start (e.g. after a roundoff failure)
    if np.mean([t.total for t in per_end]) > np.mean([t.total for t in per_start]):
        best, per_end = c0, per_start
    return RefineResult(model=PolynomialModel(scales.to_si(best)), start=start,
                        loss_start=_mean_terms(per_start), loss_end=_mean_terms(per_end),
                        per_run_start=per_start, per_run_end=per_end,
                        history=np.asarray(history), n_evals=len(history), status=status)
