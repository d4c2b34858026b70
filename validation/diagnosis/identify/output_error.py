"""The velocity coupling judged on the runs' whole trajectories (output error), beside the air's damping law.

Why
---
The integral form of the theta equation sees the coupling's slow part in windows of 0.75 hinge periods.  A
damping-like forcing at the hinge's own frequency accumulates in the amplitude over many periods, which such windows
do not see: on twin data sets with the air's damping and a coupling at the blind strengths, the integral form's
standard errors were SE(c5) = 400 1/m and SE(c6) = 7.9e5 1/m^2, the whole trajectories' (the Cramer-Rao bound of an
output-error fit) four times smaller (docs/diagnosis.md, Known limitations).  The held-out test of the greedy rounds
missed half the couplings drawn beside the air's damping.

Method
------
Every run is simulated from its first smoothed state with the twin's equations of motion
(:class:`acousim.DimerDynamics`, the diagnosis's force model at the calibrated pressure) and compared with every
recorded frame of y and theta, each residual in units of the run's tracking noise (white: the residual of a model that
explains the data is the noise itself).  The model holds the effects named before (their parameters fitted again
from the held-out rounds' values: a parameter left at an integral-form estimate leaves a trajectory misfit that the
coupling would absorb), linear damping replaced by a damping law with its two rates free, the pressure (a
pressure 0.02 % off shifts the trap's phase by several noise units over a run), a y offset, and each run's initial state (4 free
numbers per run).  Two damping laws are tried, the air's (:func:`acousim.dynamics.effects.air_damping_for`: the
dimer's own computed shape of the hinge damping, ``S(theta)``, the one implementation the twin uses) and linear
damping; the one with the smaller misfit is the null model.  The velocity coupling's c5 and c6 are then added and the
whole model refitted (Gauss-Newton, forward-difference sensitivities, all runs' simulations in one compiled batch).
Both fits are converged maxima of the likelihood: each runs until a step lowers its misfit by less than
:data:`CONVERGED_CHI2` (a step the linearised model predicts to lower it less, :func:`_predicted_drop`, is taken
without the Jacobian at its end), and the null is refitted from the coupled fit's point with the coupling removed (then the coupled
fit from the null's new point) until neither improves (:func:`_converged_pair`).  Otherwise the coupled fit, which
starts where the null stopped, completes the null's unfinished descent and the test counts it as the coupling's gain:
on the paper-like preset (whose 12 runs of 4 s resolve c5 to 0.04 1/m) that named couplings of c5 = 0.1-3 1/m.  The
statistic is the smaller of the likelihood ratio and the Wald statistic of (c5, c6) at the coupled fit: the two agree
where both fits are converged in one basin, and a ratio the coupling's size in standard errors does not back is a null
left in another basin (:func:`_wald`).

Cost: a Jacobian is ``k + 4`` simulations of every run (k shared parameters, 4 initial-state components) beside the
run's own; a trial step simulates only the runs (its Jacobian is made where the step is taken), a refit's
difference steps start at the previous fit's standard errors, and the last step (predicted and found to lower the
misfit by less than the threshold) is taken without the Jacobian at its end: the fit's covariance is that of the
point before, within a fraction of a standard error.

The candidate is judged in noise units: the drop of the misfit, ``Delta chi^2 = chi^2_null - chi^2_coupled`` (a
likelihood ratio for white Gaussian noise; divided by the coupled model's misfit per frame where that exceeds 1, so
that a model error the noise does not hold widens the unit alike), against the chi-square law with 2 degrees of
freedom at ``alpha``, and only where the coupled model explains the data to their noise (misfit per frame at most
:data:`MAX_MISFIT_PER_FRAME`): elsewhere the held-out rounds decide alone, and only where the coupling changes the hinge's damping by at least
:data:`MIN_MODULATION_FRACTION` of its rate (a practical size: a smaller state-dependent damping is within what no
damping law is known to, and long runs resolve it statistically from the simulation's own model error).  The sign-flip test of the per-run drops is reported beside it but does not decide: the drops
are in-sample, never negative in sum, so their signs are not symmetric under the null, and with 10 runs a weak
coupling that half the runs barely excite (little hinge motion) failed it at chi-square p = 2e-4 and 2e-11 on the
tuning sets.  The misfit per frame of the null model is reported too (1 when the model explains the data to its
noise).  Where the test names the coupling, its c5 and c6 are the trajectories' estimates, with the Gauss-Newton
standard errors (:attr:`OutputErrorTest.std_errors`).
"""
from __future__ import annotations

import logging
from dataclasses import dataclass, field
from typing import Sequence

import numpy as np
from numpy.typing import NDArray

from .statistics import sign_flip_pvalue

__all__ = ["TrajectoryFit", "OutputErrorTest", "RunTrajectories", "TrajectoryResiduals", "first_difference_steps",
           "shared_parameter_names",
           "run_trajectories", "fit_trajectories",
           "velocity_coupling_output_error", "damping_modulation"]

logger = logging.getLogger(__name__)

#: Forward-difference steps of the shared parameters (gamma_y, gamma_theta [1/s], c5 [1/m], c6 [1/m^2]) and of the
#: initial state (y [m], ydot [m/s], theta, thetadot [1/s]): each changes the trajectories by about a noise unit.  After
#: each Gauss-Newton step a shared parameter's step shrinks to its standard error where that is smaller: on data as
#: informative as the paper-like preset's (12 runs of 4 s of large, weakly damped motion) the first steps were 10-400
#: standard errors (the pressure's, pair scattering's kappa), whose curvature slowed the descent to a crawl.
SHARED_STEPS = {"pressure_pa": 0.01, "gamma_y": 0.01, "gamma_theta": 0.01, "c5": 50.0, "c6": 5e4}
STATE_STEPS = np.array([2e-7, 2e-5, 2e-4, 2e-3])
#: A frame whose residual exceeds this many noise units is left out (a tracking glitch or a diverged trial).
OUTLIER_NOISE_UNITS = 50.0
#: The coupled model must explain the data to their noise: a misfit per frame above this leaves a model error whose
#: structure the chi-square does not describe (tuning sets: 0.98-1.02 where the model is right, 24 coupling-free sets
#: 0.984-1.020: the per-run noise estimates' 1-2 %; paper-like preset, converged fits: 0.996-1.007).
MAX_MISFIT_PER_FRAME = 1.05
#: A Gauss-Newton step that lowers the misfit by less than this many noise units ends a fit (converged).  The test
#: compares two fitted maxima of the likelihood, so each must be converged to well within its threshold, chi-square(2)
#: at alpha = 0.01, 9.2 units: an unconverged null whose remaining descent the coupled fit (started from it) completes
#: is counted as the coupling's gain.  On the paper-like preset (seeds 802 and 805) three steps left the null 3,000 and
#: 200 units above its minimum, which the coupled fit reached with c5 = 2.8 and 0.12 1/m: both were named.
CONVERGED_CHI2 = 0.5
#: Rounds of refitting each model from the other's optimum (the null from the coupled fit's point with c5 = c6 = 0,
#: the coupled from the null's), until neither lowers its misfit by more than :data:`CONVERGED_CHI2`.
ALTERNATIONS = 3
#: A practical size: the coupling is named only where it changes the hinge's damping by at least this fraction of the
#: hinge's fitted damping rate gamma_theta, measured as the rms over the recorded frames of its damping-rate modulation
#: ``(c5 thetadot + c6 ydot) y`` [1/s] along the coupled fit (:func:`damping_modulation`).  No damping law is known
#: to that accuracy (the air's, docs/damping.md: about 10 %; its Oseen correction is amplitude-dependent), so a
#: state-dependent damping below 1 % of the rate is not a separate effect the data need, however long the runs that
#: resolve it statistically: on the paper-like preset (seed 804, 12 runs of 4 s, no coupling) a converged fit named
#: c5 = -0.26 +- 0.09 1/m (chi-square p = 2.5e-4) whose modulation is 1.3e-3 1/s, 0.09 % of gamma_theta = 1.5 1/s;
#: the couplings the blind study draws modulate the damping by 0.2-2.7 1/s, 17-220 % of its gamma_theta (1.2 1/s).
MIN_MODULATION_FRACTION = 0.01


@dataclass(frozen=True, eq=False)
class RunTrajectories:
    """The recorded frames the output-error fit compares with, from each run's first smoothed state on."""

    dt: float  #: frame interval [s]
    positions: list[NDArray[np.float64]]  #: per run (m_i, 2) measured [y, theta] from the first state's frame on
    noise_sd: NDArray[np.float64]  #: (R, 2) tracking noise of y [m] and theta
    starts: NDArray[np.float64]  #: (R, 4) first smoothed states [y, ydot, theta, thetadot]

    @property
    def frames(self) -> int:
        """The longest run's frames."""
        return max(len(p) for p in self.positions)


def run_trajectories(recorded_runs: Sequence) -> RunTrajectories | None:
    """:class:`RunTrajectories` of the diagnosis's recorded runs
    (:class:`~validation.diagnosis.prepare.runs.RunAccelerations` with integral data); None when a run has none."""
    positions, noise, starts = [], [], []
    dt = None
    for r in recorded_runs:
        integral = r.integral
        if integral is None:
            return None
        dt = integral.dt
        # the integral data start later than the smoothed states (their column edge): start at their first frame
        j = int(np.argmin(np.abs(np.asarray(r.t, float) - integral.t0)))
        if abs(float(r.t[j]) - integral.t0) > 0.5 * dt or len(integral.positions) < 10:
            return None
        positions.append(np.asarray(integral.positions, float))
        noise.append(np.sqrt(np.maximum(np.asarray(integral.noise_var, float), 1e-30)))
        starts.append(np.asarray(r.state[j], float))
    return RunTrajectories(float(dt), positions, np.array(noise), np.array(starts))


@dataclass(frozen=True)
class TrajectoryFit:
    """An output-error fit: the shared parameters, their standard errors (the Gauss-Newton covariance in noise
    units), the misfit and each run's."""

    damping_law: str  #: "air_damping" or "linear_damping"
    params: dict[str, float]  #: gamma_y, gamma_theta [1/s], y_offset [m], and c5, c6 when fitted
    std_errors: dict[str, float]
    chi2: float  #: sum of squared residuals in noise units
    frames: int  #: residuals compared (y and theta frames)
    per_run_chi2: tuple[float, ...]
    starts: NDArray[np.float64] = field(repr=False)
    #: the Gauss-Newton covariance of (c5, c6) in noise units (None without the coupling)
    coupling_cov: NDArray[np.float64] | None = field(default=None, repr=False)
    #: the Gauss-Newton covariance of the shared parameters, in the order of :attr:`shared_names` (the runs' initial
    #: states and the y offset marginalised; None where the normal equations were singular)
    shared_cov: NDArray[np.float64] | None = field(default=None, repr=False)
    shared_names: tuple[str, ...] = ()

    def correlation(self, a: str, b: str) -> float:
        """The Gauss-Newton correlation of shared parameters ``a`` and ``b`` (NaN where not fitted)."""
        if self.shared_cov is None or a not in self.shared_names or b not in self.shared_names:
            return float("nan")
        i, j = self.shared_names.index(a), self.shared_names.index(b)
        c = self.shared_cov
        return float(c[i, j] / np.sqrt(abs(c[i, i] * c[j, j]))) if c[i, i] * c[j, j] != 0 else float("nan")

    @property
    def chi2_per_frame(self) -> float:
        """The misfit per compared frame (1 for a model that explains the data to its noise)."""
        return self.chi2 / max(self.frames, 1)


def _effects(law: str, shape: dict, others: dict, names: Sequence[str], p: NDArray) -> dict:
    values = dict(zip(names, p))  # the pressure (first) is not an effect's
    rates = {"gamma_y": values["gamma_y"], "gamma_theta": values["gamma_theta"]}
    out = {k: {q: values[f"{k}.{q}"] for q in v} for k, v in others.items()}
    out[law] = {**shape, **rates} if law == "air_damping" else rates
    if "c5" in values:
        out["velocity_coupling"] = {"c5": values["c5"], "c6": values["c6"]}
    return out


def _simulate_states(surrogate, pressure: float, effects: dict, starts: NDArray, dt: float,
                     frames: int) -> NDArray:
    """(B, frames, 4) simulated states [y, ydot, theta, thetadot] at the pressure amplitude ``pressure`` [Pa] (NaN
    where a trajectory stopped, or everywhere for a trial outside the effects' physics)."""
    from acousim import DimerDynamics, EffectSet

    states = np.array(starts, float)
    states[:, 2] = np.clip(states[:, 2], -0.999, 0.999)
    try:
        dynamics = DimerDynamics(surrogate.with_pressure(pressure), EffectSet.from_dict(effects))
    except ValueError:  # a trial outside the effects' physics (a negative rate) or a pressure that cannot levitate
        return np.full((len(states), frames, 4), np.nan)
    out, _, _ = dynamics.integrate_batch(states, dt * (frames - 1), dt, max_step=dt)
    return out[:, :frames]


def _simulate(surrogate, pressure: float, effects: dict, starts: NDArray, dt: float, frames: int) -> NDArray:
    """(B, frames, 2) simulated [y, theta] (:func:`_simulate_states`)."""
    return _simulate_states(surrogate, pressure, effects, starts, dt, frames)[..., [0, 2]]


def _step(name: str, value: float) -> float:
    """The forward-difference step of a shared parameter: :data:`SHARED_STEPS`, or 1e-3 of another effect's value
    (1e-6 where it is zero)."""
    return SHARED_STEPS[name] if name in SHARED_STEPS else max(1e-3 * abs(value), 1e-6)


def _predicted_drop(jtr: NDArray, step: NDArray, steps: NDArray, cov: NDArray, p: NDArray) -> float:
    """The misfit drop the Gauss-Newton step ``step`` predicts, ``jtr . step`` [noise units] (exact for a model linear
    in its parameters), where the Jacobian is that of the quadratic regime: every shared difference step within two
    standard errors (:func:`_shrunk`); infinite otherwise (a step larger than that can mis-state the gradient).  A step
    predicted and found to lower the misfit by less than :data:`CONVERGED_CHI2` is the fit's last: it is taken, and
    the Jacobian at its end (k + 4 simulations of every run) is not made."""
    if np.any(steps > 2.0 * _shrunk(np.full_like(steps, np.inf), cov, p)):
        return float("inf")
    return float(jtr @ step)


def _shrunk(steps: NDArray, cov: NDArray, p: NDArray) -> NDArray:
    """Difference steps of the shared parameters no larger than their standard errors (the Jacobian of the quadratic
    regime), never below 1e-9 of the value."""
    k = len(steps)
    return np.minimum(steps, np.maximum(np.sqrt(np.abs(np.diag(cov)[:k])), 1e-9 * np.abs(p) + 1e-12))


@dataclass(frozen=True, eq=False)
class TrajectoryResiduals:
    """The runs' residuals in noise units at a point of the fit (shared parameters ``p`` in the order of ``names``,
    the y offset, the initial states ``x0``), and their normal equations by forward differences."""

    data: RunTrajectories
    surrogate: object
    law: str
    shape: dict
    others: dict
    names: list[str]
    target: NDArray[np.float64]  #: (R, frames, 2) recorded [y, theta], NaN past a run's end
    scale: NDArray[np.float64]  #: (R, 1, 2) tracking noise

    def simulate(self, p: NDArray, x0: NDArray) -> NDArray:
        """(B, frames, 2) simulated [y, theta] from the initial states ``x0`` with shared parameters ``p``."""
        effects = _effects(self.law, self.shape, self.others, self.names, p)
        return _simulate(self.surrogate, p[0], effects, x0, self.data.dt, self.data.frames)

    def misfit(self, p: NDArray, offset: float, x0: NDArray) -> tuple[float, NDArray, tuple]:
        """Misfit (each frame's squared residual capped at OUTLIER_NOISE_UNITS^2, so that a trial that loses frames
        is not rewarded for it), per run, and what the normal equations need (the simulated frames, the residuals
        kept) at (p, offset, x0): one simulation of the runs, all a trial step needs until it is accepted."""
        base = self.simulate(p, x0)
        resid = (self.target - base - np.array([offset, 0.0])) / self.scale
        keep = np.isfinite(resid) & (np.abs(np.nan_to_num(resid, nan=np.inf)) < OUTLIER_NOISE_UNITS)
        capped = np.where(keep, resid ** 2, np.where(np.isfinite(self.target), OUTLIER_NOISE_UNITS ** 2, 0.0))
        per_run = np.sum(capped, axis=(1, 2))
        return float(per_run.sum()), per_run, (base, keep, np.where(keep, resid, 0.0))

    def normal_equations(self, p: NDArray, x0: NDArray, at: tuple, steps: NDArray) -> tuple[NDArray, NDArray]:
        """J^T J and J^T r at (p, x0) by forward differences (``steps`` of the shared parameters,
        :data:`STATE_STEPS` of the initial states) from the simulated frames ``at`` (:meth:`misfit`'s)."""
        base, keep, r = at
        R, n, k = len(x0), self.data.frames, len(p)
        size = k + 1 + 4 * R
        moved = self.simulate(p, np.concatenate([x0 + STATE_STEPS[j] * np.eye(4)[j] for j in range(4)]))
        sims = [self.simulate(p + steps[j] * np.eye(k)[j], x0) for j in range(k)]
        jtj, jtr = np.zeros((size, size)), np.zeros(size)
        scale = self.scale
        for i in range(R):
            cols = np.zeros((n, 2, size))
            for j in range(k):
                cols[:, :, j] = (sims[j][i] - base[i]) / steps[j] / scale[i]
            cols[:, 0, k] = 1.0 / scale[i, 0, 0]
            for j in range(4):
                cols[:, :, k + 1 + 4 * i + j] = (moved[j * R + i] - base[i]) / STATE_STEPS[j] / scale[i]
            a = np.nan_to_num(cols[keep[i]])
            jtj += a.T @ a
            jtr += a.T @ r[i][keep[i]]
        return jtj, jtr


def _inverse(jtj: NDArray) -> NDArray | None:
    """The Gauss-Newton covariance (J^T J)^-1 in noise units; None where singular."""
    try:
        return np.linalg.inv(jtj + 1e-12 * np.diag(np.diag(jtj)))
    except np.linalg.LinAlgError:
        return None


def shared_parameter_names(others: dict, with_coupling: bool) -> list[str]:
    """The fit's shared parameters, in its order: the pressure, the damping's two rates, the other named effects'
    parameters (``"effect.parameter"``, ``others``: effect -> parameters) and, ``with_coupling``, c5 and c6."""
    own = [f"{k}.{q}" for k, v in others.items() for q in v]
    return ["pressure_pa", "gamma_y", "gamma_theta"] + own + (["c5", "c6"] if with_coupling else [])


def first_difference_steps(names: Sequence[str], p: NDArray, scales: dict[str, float] | None) -> NDArray:
    """The first difference steps of the shared parameters: :func:`_step`, no larger than ``scales`` (standard
    errors by name) where given."""
    steps = np.array([_step(nm, v) for nm, v in zip(names, p)])
    known = np.array([(scales or {}).get(nm, np.inf) for nm in names], float)
    return np.where(np.isfinite(known) & (known > 0), np.minimum(steps, np.maximum(known, 1e-9 * np.abs(p) + 1e-12)),
                    steps)


def fit_trajectories(data: RunTrajectories, surrogate, law: str, shape: dict, others: dict, start: dict,
                     with_coupling: bool, iterations: int = 10, starts: NDArray | None = None,
                     scales: dict[str, float] | None = None) -> TrajectoryFit:
    """Gauss-Newton output-error fit of the shared rates (and c5, c6 with ``with_coupling``), a y offset and each
    run's initial state (module docstring).

    Parameters
    ----------
    data : RunTrajectories
    surrogate : acousim force model (its pressure is set from ``start["pressure_pa"]``, fitted)
    law : "air_damping" (rates free, ``shape`` its dimensionless parameters) or "linear_damping"
    shape : the air damping's sway_ratio, wedge_ratio, gap_ratio (unused for linear damping)
    others : the other effects named before, {name: params}: their parameters are fitted too (named
        ``"effect.parameter"``), from these values
    start : starting pressure_pa [Pa], gamma_y, gamma_theta (and c5, c6; the other effects' parameters by name)
    with_coupling : fit the velocity coupling's c5, c6
    iterations : at most this many Gauss-Newton steps; the fit stops earlier where a step lowers the misfit by
        less than :data:`CONVERGED_CHI2`
    starts : starting initial states (R, 4); default the first smoothed states
    scales : standard errors of shared parameters by name (a previous fit's, :attr:`TrajectoryFit.std_errors`): their
        first difference steps are no larger (:func:`first_difference_steps`), so that the Jacobian of a fit started at or near
        an optimum is that of the quadratic regime from the start and its last step is recognised
        (:func:`_predicted_drop`)
    """
    names = shared_parameter_names(others, with_coupling)
    values = {**{f"{k}.{q}": x for k, v in others.items() for q, x in v.items()}, **start}
    p = np.array([float(values.get(n, 0.0)) for n in names])
    offset = float(start.get("y_offset", 0.0))
    x0 = np.array(data.starts if starts is None else starts, float)
    R, k = len(data.positions), len(names)
    target = np.full((R, data.frames, 2), np.nan)
    for i, pos in enumerate(data.positions):
        target[i, :len(pos)] = pos
    res = TrajectoryResiduals(data, surrogate, law, shape, others, names, target, data.noise_sd[:, None, :])
    steps = first_difference_steps(names, p, scales)
    size = k + 1 + 4 * R
    frames = int(np.isfinite(target).sum())

    def evaluate(p, offset, x0):
        """:meth:`TrajectoryResiduals.misfit`, per run, and the normal equations at (p, offset, x0)."""
        chi2, per_run, at = res.misfit(p, offset, x0)
        return (chi2, per_run, *res.normal_equations(p, x0, at, steps))

    chi2, per_run, jtj, jtr = evaluate(p, offset, x0)
    cov = _inverse(jtj)
    for _ in range(iterations):
        if cov is None:
            break
        step = cov @ jtr
        last = _predicted_drop(jtr, step, steps, cov, p) < CONVERGED_CHI2  # predicted to be the last step
        for _halving in range(4):  # a step that raises the misfit is halved (the model is not linear in c5, c6)
            trial = (p + step[:k], offset + step[k], x0 + step[k + 1:].reshape(R, 4))
            tried = res.misfit(*trial)  # the Jacobian only where the step is taken, and not after the last
            if tried[0] <= chi2:
                got = None if last and chi2 - tried[0] < CONVERGED_CHI2 else (
                    tried[0], tried[1], *res.normal_equations(trial[0], trial[2], tried[2], steps))
                break
            step = 0.5 * step
        else:  # no descent along this Jacobian: once more with steps of a standard error, if that shrinks them
            smaller = _shrunk(steps, cov, p)
            if np.all(smaller > 0.5 * steps):
                break
            steps = smaller
            chi2, per_run, jtj, jtr = evaluate(p, offset, x0)
            cov = _inverse(jtj)
            continue
        if got is None:  # converged as predicted: the covariance of the point before, a fraction of an error away
            (p, offset, x0), chi2, per_run = trial, tried[0], tried[1]
            break
        drop = chi2 - got[0]
        (p, offset, x0), (chi2, per_run, jtj, jtr) = trial, got
        cov = _inverse(jtj)
        if cov is not None:
            steps = _shrunk(steps, cov, p)
        if drop < CONVERGED_CHI2:  # converged: a further step would change the test's statistic by less
            break
    se = np.sqrt(np.abs(np.diag(cov))) if cov is not None else np.full(size, np.nan)
    params = {**dict(zip(names, map(float, p))), "y_offset": offset}
    errors = {**dict(zip(names, map(float, se[:k]))), "y_offset": float(se[k])}
    cc = cov[k - 2:k, k - 2:k] if with_coupling and cov is not None else None  # c5, c6 are the last shared names
    shared = cov[:k, :k].copy() if cov is not None else None
    return TrajectoryFit(law, params, errors, chi2, frames, tuple(map(float, per_run)), x0, cc, shared, tuple(names))


@dataclass(frozen=True)
class OutputErrorTest:
    """The velocity coupling's output-error test (module docstring)."""

    null: TrajectoryFit  #: the better damping law without the coupling
    coupled: TrajectoryFit  #: the same law with c5, c6
    other_law_chi2: float  #: the misfit of the other damping law (without the coupling)
    statistic: float  #: chi^2_null - chi^2_coupled [noise units]
    p_value: float  #: chi-square (2 degrees of freedom) tail of ``statistic``
    sign_flip_p: float  #: sign-flip test of the per-run drops
    alpha: float
    significant: bool
    likelihood_ratio: float = float("nan")  #: chi^2_null - chi^2_coupled, in the same (widened) noise units
    wald: float = float("nan")  #: c^T C^-1 c of (c5, c6) at the coupled fit, in the same units
    #: rms damping-rate modulation (c5 thetadot + c6 ydot) y of the coupled fit over the recorded frames [1/s]
    modulation: float = float("nan")
    #: the hinge's damping rate gamma_theta at the coupled fit [1/s]
    gamma_theta: float = float("nan")

    @property
    def params(self) -> dict[str, float]:
        """The output-error estimates of c5 [1/m] and c6 [1/m^2]."""
        return {k: self.coupled.params[k] for k in ("c5", "c6")}

    @property
    def std_errors(self) -> dict[str, float]:
        """Standard errors of c5 and c6: the Gauss-Newton covariance in noise units, widened by the square root of
        the coupled misfit per frame where it exceeds 1 (the summary's intervals, Student t with R - 1 degrees of
        freedom as the jackknife's)."""
        widen = float(np.sqrt(max(self.coupled.chi2_per_frame, 1.0)))
        return {k: widen * self.coupled.std_errors[k] for k in ("c5", "c6")}

    def to_dict(self) -> dict:
        """The diagnosis.json form (``identification_rounds[i].candidates["velocity_coupling"].output_error``)."""
        return {"damping_law": self.null.damping_law, "statistic": self.statistic, "p_value": self.p_value,
                "likelihood_ratio": self.likelihood_ratio, "wald": self.wald,
                "max_misfit_per_frame": MAX_MISFIT_PER_FRAME,
                "damping_modulation": self.modulation, "min_modulation_fraction": MIN_MODULATION_FRACTION,
                "sign_flip_p": self.sign_flip_p, "alpha": self.alpha, "significant": self.significant,
                "params": self.params, "std_errors": self.std_errors,
                "null_chi2_per_frame": self.null.chi2_per_frame,
                "coupled_chi2_per_frame": self.coupled.chi2_per_frame,
                "other_law_chi2_per_frame": self.other_law_chi2 / max(self.null.frames, 1),
                "damping_rates": {k: self.null.params[k] for k in ("gamma_y", "gamma_theta")}}


def _restart(fit: TrajectoryFit, others: dict, coupling: bool) -> tuple[dict, dict]:
    """The starting values (shared parameters, other effects' parameters) of a fit from ``fit``'s optimum, with the
    coupling at fit's values (``coupling``; zero where fit had none) or without it."""
    start = {k: v for k, v in fit.params.items() if "." not in k and k not in ("c5", "c6")}
    if coupling:
        start.update(c5=fit.params.get("c5", 0.0), c6=fit.params.get("c6", 0.0))
    own = {k: {q: fit.params.get(f"{k}.{q}", x) for q, x in v.items()} for k, v in others.items()}
    return start, own


def _converged_pair(data: RunTrajectories, surrogate, law: str, shape: dict, others: dict, null: TrajectoryFit,
                    iterations: int) -> tuple[TrajectoryFit, TrajectoryFit]:
    """The null and coupled fits, each converged from the other's optimum (:data:`ALTERNATIONS`): the likelihood
    ratio compares the two maxima, so the coupled fit's head start (it begins where the null ended and takes further
    steps) must not count as its gain.  The null is refitted from the coupled fit's point with the coupling removed;
    where that lowers its misfit, the coupled fit is made again from the new null (c5 = c6 = 0, where it nests the
    null, so that it cannot end above it) and the better of the two coupled fits kept."""
    start, own = _restart(null, others, True)
    coupled = fit_trajectories(data, surrogate, law, shape, own, start, True, iterations, starts=null.starts,
                               scales=null.std_errors)
    for _ in range(ALTERNATIONS):
        start, own = _restart(coupled, others, False)
        again = fit_trajectories(data, surrogate, law, shape, own, start, False, iterations, starts=coupled.starts,
                                 scales=coupled.std_errors)
        if again.chi2 >= null.chi2 - CONVERGED_CHI2:
            break
        null = again
        start, own = _restart(null, others, True)
        refit = fit_trajectories(data, surrogate, law, shape, own, start, True, iterations, starts=null.starts,
                                 scales=coupled.std_errors)
        if refit.chi2 >= coupled.chi2 - CONVERGED_CHI2 and coupled.chi2 <= null.chi2:
            break
        coupled = refit if refit.chi2 < coupled.chi2 else coupled
    return null, coupled


def velocity_coupling_output_error(problem, fit, conditions, alpha: float = 0.01,
                                   iterations: int = 10) -> OutputErrorTest | None:
    """The output-error test of the velocity coupling on top of a fitted model with linear damping.

    Parameters
    ----------
    problem : DiagnosisProblem (its recorded runs, force model and drift)
    fit : GapFit of the effects named so far (linear damping among them; its calibration gives the pressure)
    conditions : the experiment conditions (side, densities, hinge gap) of the air's damping law
    alpha : significance level of the chi-square test (the sign-flip test of the per-run drops is reported only)

    Returns
    -------
    OutputErrorTest, or None when the test does not apply (no linear damping, a drifting pressure, the cavity's lag
    in the model, runs without integral data, a pressure that cannot levitate the dimer, a named effect fitted
    outside its physics: a negative damping rate or drag coefficient)
    """
    from scipy.stats import chi2 as chi2_law

    from acousim.dynamics.effects import EffectSet, air_damping_for

    effects = dict(fit.effects)
    if "linear_damping" not in effects or problem.drift is not None or "cavity_lag" in effects:
        return None
    data = run_trajectories(problem.recorded_runs)
    if data is None:
        return None
    cal = fit.calibration
    try:
        surrogate = problem.surrogate().with_pressure(cal.nominal_pressure_pa * np.sqrt(cal.pressure_scale))
        air = air_damping_for(surrogate, conditions).params()
    except ValueError:
        return None
    shape = {k: v for k, v in air.items() if k not in ("gamma_y", "gamma_theta")}
    others = {k: v for k, v in effects.items() if k not in ("linear_damping", "velocity_coupling")}
    try:  # the named effects' fit must lie within their physics (no negative damping) to be simulated
        EffectSet.from_dict({**others, "linear_damping": effects["linear_damping"]})
    except ValueError:
        return None
    start = {**effects["linear_damping"], "pressure_pa": cal.nominal_pressure_pa * np.sqrt(cal.pressure_scale)}
    nulls = {law: fit_trajectories(data, surrogate, law, shape, others, start, False, iterations)
             for law in ("air_damping", "linear_damping")}
    law = min(nulls, key=lambda name: nulls[name].chi2)
    null = nulls[law]
    other = nulls["linear_damping" if law == "air_damping" else "air_damping"]
    null, coupled = _converged_pair(data, surrogate, law, shape, others, null, iterations)
    # in noise units; a misfit per frame above 1 (a model error the noise does not hold) widens the unit alike.  The
    # likelihood ratio and the Wald statistic of (c5, c6) agree where both fits are converged in one basin (the
    # quadratic regime); the smaller is taken, so that a null fit left in another basin than the coupled one
    # (paper-like seed 804: Delta chi^2 = 292 for c5 = -0.26 +- 0.09 1/m, three standard errors) does not count as gain
    widen = max(coupled.chi2_per_frame, 1.0)
    lr = float(null.chi2 - coupled.chi2) / widen
    wald = _wald(coupled) / widen
    stat = min(lr, wald) if np.isfinite(wald) else lr
    p = float(chi2_law.sf(max(stat, 0.0), 2))
    flip = sign_flip_pvalue(np.subtract(null.per_run_chi2, coupled.per_run_chi2))
    modulation = damping_modulation(data, surrogate, law, shape, others, coupled)
    gamma = float(coupled.params["gamma_theta"])
    resolved = bool(np.isfinite(modulation) and modulation >= MIN_MODULATION_FRACTION * abs(gamma))
    significant = bool(np.isfinite(stat) and p < alpha and coupled.chi2_per_frame <= MAX_MISFIT_PER_FRAME
                       and resolved)
    logger.debug("velocity coupling, output error (%s): Delta chi2 = %.1f (p = %.3g), sign-flip p = %.3g, c5 = %.4g, "
                 "c6 = %.4g, damping modulation %.3g 1/s against gamma_theta %.3g 1/s", law, stat, p, flip,
                 coupled.params["c5"], coupled.params["c6"], modulation, gamma)
    return OutputErrorTest(null, coupled, other.chi2, stat, p, flip, alpha, significant, lr, wald, modulation,
                           gamma)


def damping_modulation(data: RunTrajectories, surrogate, law: str, shape: dict, others: dict,
                       coupled: TrajectoryFit) -> float:
    """The rms over every recorded frame of the coupled fit's damping-rate modulation ``(c5 thetadot + c6 ydot) y``
    [1/s] (the coupling adds ``(c5 thetadot + c6 ydot) y thetadot`` to thetaddot: a damping rate that follows the
    state), along the fit's own simulated trajectories; NaN where they cannot be simulated."""
    names = [k for k in coupled.params if k != "y_offset"]
    p = np.array([coupled.params[k] for k in names])
    out = _simulate_states(surrogate, coupled.params["pressure_pa"], _effects(law, shape, others, names, p),
                           coupled.starts, data.dt, data.frames)
    y, ydot, thetadot = out[..., 0], out[..., 1], out[..., 3]
    rate = (coupled.params["c5"] * thetadot + coupled.params["c6"] * ydot) * y
    recorded = np.arange(rate.shape[1]) < np.array([len(pos) for pos in data.positions])[:, None]
    rate = rate[recorded & np.isfinite(rate)]
    return float(np.sqrt(np.mean(rate ** 2))) if rate.size else float("nan")


def _wald(fit: TrajectoryFit) -> float:
    """c^T C^-1 c of the coupling (c5, c6) with its Gauss-Newton covariance C (noise units); NaN without it."""
    if fit.coupling_cov is None:
        return float("nan")
    c = np.array([fit.params["c5"], fit.params["c6"]])
    try:
        return float(c @ np.linalg.solve(fit.coupling_cov, c))
    except np.linalg.LinAlgError:
        return float("nan")
