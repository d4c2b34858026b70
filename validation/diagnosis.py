"""Diagnose the sim-to-real gap: where it lies, which unmodelled effect causes it, how far it shrinks.

"Sim" is the Gor'kov model of PHYSICS.md section 4 calibrated to the data; "real" is any data set in
the FORMATS.md format.  Every candidate effect of PHYSICS.md section 5 is *linear in its parameters*,
so every fit here is a linear least-squares problem at the measured states.

Two forms of the equations of motion
    *Accelerations*: Savitzky-Golay second derivatives of the data (:mod:`fitting.derivatives`) against
    the model's accelerations passed through the filter's matched kernel.  *Integral form*
    (:mod:`fitting.integral_form`, data in :class:`PositionIntegrals`): the measured coordinate minus each
    window's straight line against the detrended double integral of the model's accelerations.  Its
    residual is the white tracking noise itself for a model that explains the data, where the
    accelerations carry that noise times the filter's derivative gain (thetaddot on the soft Gor'kov
    hinge is ~95 % noise).  The model's columns are evaluated at the raw y and at theta smoothed over
    half a hinge period (:func:`fitting.integral_form.column_states`).  With integral data (what
    :func:`validation.diagnose.prepare_runs` gives) the calibration and the theta equation use the
    integral form; the y component of the gap and the y rows of the effect fits use the accelerations.

Calibration (nothing else is free at this stage)
    The simulated accelerations at nominal pressure ``p_nom`` are ``a_y = s F_Z(theta, Z)/M - g`` and
    ``a_theta = (s Q_theta(theta, Z) - I'(theta) thetadot^2 / 2) / I(theta)`` with ``s = (p0/p_nom)^2``
    (the Gor'kov forces scale exactly with p0^2 at fixed lab height) and ``Z = z0 + y``: ``z0`` is the
    lab height of the data's y origin.  ``s`` and ``z0`` are fitted to the *y equation only* (integral
    form): the vertical trap is what the acoustic model describes best, while the hinge is where the
    largest expected gap lies (pair scattering), which must not be absorbed into the pressure.  For
    fixed ``z0`` the fit is linear (in ``s`` and any y-effect parameters); ``z0`` is found by a bounded
    scalar search.  Measured on no-effect twin data: the pressure within 0.02 % (the accelerations gave
    +0.1 %, enough of a hinge-stiffness mismatch for pair scattering to absorb with p = 0.001).  Each
    run's initial state is the smoothed measured state at its first interior frame.

Energy balance
    Weak dissipation is invisible in instantaneous accelerations (gamma ydot is ~1e-2 of the trap
    acceleration) but dominates the long-time behaviour.  Over windows of ``energy_window`` seconds
    (about ten periods) the change of the calibrated mechanical energy
    ``E = M ydot^2/2 + I(theta) thetadot^2/2 + s U_ac(theta, z0 + y) + M g y`` must equal the work of the
    non-conservative effect terms, ``integral (M ydot a_y,eff + I thetadot a_theta,eff) dt``, which is
    again linear in every effect parameter (and in s).  This is the third equation of every fit.

Gap
    Short-time gap of run r, y equation: ``R_ry = sum (a_data - a_sim)^2 / sum (a_data - mean)^2``, the
    fraction of the measured acceleration variance the simulation leaves unexplained (1 for a model no
    better than a constant, 0 for a perfect one; derivative noise sets a floor > 0).  Theta equation,
    integral form: ``R_rtheta = sum r^2 / sum (P theta)^2``, the unexplained fraction of the detrended
    measured angle (accelerations as for y when there is no integral data).  The energy component is
    ``R_rE = sum_k (dE_k,data - W_k,sim)^2 / sum_k (E_k - E_rest)^2``: the unexplained energy change per
    window relative to the oscillation energy.  Each component has a noise floor, the value a perfect
    model would show: for accelerations and energies the tracking-noise variance (raw minus smoothed
    positions) times the Savitzky-Golay gain, for the integral form ``(frames - 2 per window)
    sigma_theta^2``, over the same normalisation.  ``gap`` = mean over runs of the mean over the three
    components of ``R - floor``: the unexplained fraction *in excess of measurement noise* (about 0 for
    a model that explains the data within its noise; it can be slightly negative because the floor is
    an estimate).  This is the scalar of ``gap_before`` and ``gap_after``; the long-time errors
    (attractor shape, Poincare, frequency of :mod:`fitting.losses`) are reported beside it.

Which effect
    A candidate is fitted (with the calibration) on all runs but one and scored on the held-out
    run (K-fold over runs), giving one held-out gap per run with and without the candidate.  The
    improvement is significant when the one-sided sign-flip permutation test of the mean per-run
    held-out improvement (:func:`sign_flip_pvalue`, exact) gives p < ``alpha`` and the median
    held-out improvement exceeds ``min_absolute_improvement`` of the variance and
    ``min_relative_improvement`` of the current gap.  The permutation test uses the size of each run's
    improvement, not only its rank: runs with little motion in the affected coordinate carry almost
    no signal and, with random signs but small sizes, barely move it, where they cost the Wilcoxon
    signed-rank test (also reported) whole ranks.  Held-out scoring is the penalty for added
    parameters: a parameter that only fits noise, or a run-specific disturbance, does not improve
    other runs.  Candidates are added greedily (largest median held-out improvement first) while a
    significant one remains.  No cause is named while the calibration equation itself stays
    unexplained (:func:`identify_effects`, ``max_vertical_gap``).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, Sequence

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import minimize_scalar
from scipy.stats import wilcoxon


def sign_flip_pvalue(diff: NDArray, n_random: int = 200_000, seed: int = 0) -> float:
    """One-sided p-value of "mean(diff) > 0" by the sign-flip (Fisher-Pitman) permutation test.

    Under H0 each run's difference is symmetric about zero, so every assignment of signs is equally
    likely; p is the fraction of the 2^n sign patterns whose mean is at least the observed one
    (exact enumeration for n <= 18, else ``n_random`` seeded random patterns).  Returns 1 for n = 0
    or an all-zero ``diff``.
    """
    d = np.asarray(diff, float)
    n = d.size
    if n == 0 or not np.any(d != 0):
        return 1.0
    obs = d.sum()
    if n <= 18:
        signs = 1 - 2 * ((np.arange(2**n)[:, None] >> np.arange(n)) & 1)
    else:
        signs = np.random.default_rng(seed).choice([-1, 1], size=(n_random, n))
    sums = signs @ np.abs(d)
    return float(np.mean(sums >= obs - 1e-12 * np.abs(d).sum()))

__all__ = [
    "CANDIDATE_EFFECTS",
    "effect_regressors",
    "RunAccelerations",
    "Calibration",
    "GapFit",
    "fit_gap_model",
    "short_time_gaps",
    "identify_effects",
    "localize_residuals",
    "simulate_runs",
    "long_time_gaps",
    "scalar_gap",
    "sign_flip_pvalue",
    "fit_gaps",
    "noise_floors",
]

def _candidates() -> dict[str, tuple[str, ...]]:
    from acousim.effects import EFFECT_TYPES

    return {name: cls.parameter_names() for name, cls in EFFECT_TYPES.items()}


#: Candidate effects and their parameters (PHYSICS.md section 5, as defined in :mod:`acousim.effects`).
CANDIDATE_EFFECTS: dict[str, tuple[str, ...]] = _candidates()


def effect_regressors(name: str, state: NDArray, z_com: NDArray, wavenumber: float,
                      z_eq: float | None = None) -> NDArray[np.float64]:
    """d(accelerations)/d(parameters) of one effect: array (n, 2, n_params).

    Every effect of PHYSICS.md section 5 is linear in its parameters, so its added accelerations are
    ``regressors @ params``; column j is the effect of :mod:`acousim.effects` evaluated with parameter j
    set to 1 and the others to 0 (one definition of the physics).  Columns follow
    ``CANDIDATE_EFFECTS[name]``; the two rows are the yddot and thetaddot equations.  ``z_com`` is the
    height above the node [m]; ``z_eq`` the equilibrium height of the (calibrated) simulation: the
    effects' y is ``Z_com - Z_eq`` as in PHYSICS.md (default: the state's own y, i.e. Z_eq = Z_com - y).
    """
    from acousim.effects import EFFECT_TYPES

    if name not in EFFECT_TYPES:
        raise ValueError(f"unknown effect {name!r}; candidates are {', '.join(CANDIDATE_EFFECTS)}")
    cls = EFFECT_TYPES[name]
    y, yd, th, thd = np.asarray(state, float).T
    z_com = np.broadcast_to(np.asarray(z_com, float), y.shape)
    if z_eq is None:
        y_eff, z_ref = y, z_com - y
    else:
        y_eff, z_ref = z_com - z_eq, z_eq
    cols = []
    for p in cls.parameter_names():
        unit = cls(**{q: (1.0 if q == p else 0.0) for q in cls.parameter_names()})
        ay, at = unit.accelerations(y_eff, yd, th, thd, wavenumber, z_ref)
        cols.append(np.stack([np.broadcast_to(ay, y.shape), np.broadcast_to(at, y.shape)], axis=-1))
    return np.stack(cols, axis=-1).astype(float)


@dataclass(frozen=True, eq=False)
class PositionIntegrals:
    """One run's data for the integral form of both equations (:mod:`fitting.integral_form`), at every
    recorded frame (interior frames only, never thinned).

    Each gap component of an equation compares the *measured* coordinate (raw, its tracking noise
    white) with the double integral of the model's accelerations over windows, each window's initial
    position and rate eliminated by removing its straight-line trend.  For a model that explains the
    data the residual is the tracking noise itself, so the noise floor is known:
    ``(frames - 2 per window) sigma^2``.  Coordinate index q: 0 for y, 1 for theta.
    """

    dt: float
    positions: NDArray[np.float64]  # (n, 2) raw measured [y, theta], gaps filled
    state: NDArray[np.float64]  # (n, 4) smoothed states at the same frames
    windows: tuple[int, int]  # frames per window for y and theta (fitting.integral_form.integral_window)
    noise_var: tuple[float, float]  # tracking-noise variances of y [m^2] and theta [-]

    def starts(self, q: int) -> NDArray[np.int64]:
        from fitting.integral_form import window_starts

        return window_starts(self.positions.shape[0], self.windows[q])

    def target(self, q: int) -> NDArray[np.float64]:
        """Detrended measured coordinate q, window by window."""
        from fitting.integral_form import detrend_windows

        return detrend_windows(self.positions[:, q], self.starts(q), self.windows[q])

    def columns(self, q: int, accel: NDArray) -> NDArray[np.float64]:
        """Detrended double integrals of accelerations (n, ...) of coordinate q, sampled at every frame."""
        from fitting.integral_form import integral_columns

        return integral_columns(accel, self.dt, self.starts(q), self.windows[q])

    def floor(self, q: int) -> float:
        """Expected residual sum of squares of a perfect model: (rows - 2 per window) sigma^2."""
        return float(self.starts(q).size * (self.windows[q] - 2) * self.noise_var[q])

    @property
    def usable(self) -> bool:
        return all(self.starts(q).size > 0 for q in (0, 1))


@dataclass(frozen=True, eq=False)
class RunAccelerations:
    """One run's smoothed states and measured accelerations (interior frames only, SI)."""

    name: str
    t: NDArray[np.float64]
    state: NDArray[np.float64]  # (n, 4) [y, ydot, theta, thetadot]
    accel: NDArray[np.float64]  # (n, 2) [yddot, thetaddot]
    #: derivative-noise variances [yddot, thetaddot, ydot, thetadot] (SI^2); None: noise-free data
    noise: NDArray[np.float64] | None = None
    #: (duration [s], polynomial order) of the Savitzky-Golay window that produced ``accel``; the model's
    #: accelerations are filtered by the matched kernel (:meth:`smooth`) before comparison, so that the
    #: filter's attenuation (strong at 2 f_y for a window of 0.75 y periods) cancels.  None: no filtering.
    smoothing: tuple[float, int] | None = None
    #: frame interval of the recording [s] (``t`` may be thinned); None: ``t``'s own spacing
    frame_dt: float | None = None
    #: positions and states at every frame for the integral form of both equations; None: the gap
    #: components of the equations use the accelerations instead
    integral: PositionIntegrals | None = None

    def subsample(self, step: int) -> "RunAccelerations":
        return RunAccelerations(self.name, self.t[::step], self.state[::step], self.accel[::step], self.noise,
                                self.smoothing, self.frame_dt, self.integral)

    def smooth(self, x: NDArray) -> NDArray:
        """Filter a model's accelerations (axis 0 along ``t``) as the data's Savitzky-Golay second derivative
        filtered the true ones: the matched kernel of :func:`fitting.derivatives.acceleration_kernel`.

        The kernel is built at the recording's frame rate; on thinned frames (every ``step``-th) it is
        sampled every ``step`` taps, times ``step`` (a Riemann sum of the same smooth kernel), and
        renormalised to sum 1.  Nothing is done without ``smoothing``."""
        if self.smoothing is None or len(self.t) < 3:
            return x
        from fitting.derivatives import acceleration_kernel, apply_acceleration_kernel

        duration, order = self.smoothing
        dt = float(np.median(np.diff(self.t)))
        frame_dt = self.frame_dt or dt
        w = int(round(duration / frame_dt))
        w = w if w % 2 else w + 1
        if w <= order + 2:
            return x
        kernel = acceleration_kernel(w, order, frame_dt)
        step = max(1, int(round(dt / frame_dt)))
        if step > 1:
            c = w // 2
            taps = c + step * np.arange(-(c // step), c // step + 1)
            kernel = kernel[taps] / np.sum(kernel[taps])
        return apply_acceleration_kernel(x, kernel)


@dataclass(frozen=True)
class Calibration:
    """Calibrated settings: pressure scale s = (p0 / p_nom)^2, the lab height z0 [m] of the data's y = 0,
    and the equilibrium height Z_eq [m] of the simulation at the calibrated pressure (the origin of
    the effects' y, PHYSICS.md section 5)."""

    pressure_scale: float
    z_origin_m: float
    nominal_pressure_pa: float
    equilibrium_height_m: float = float("nan")

    @classmethod
    def at(cls, model, pressure_scale: float, z_origin_m: float) -> "Calibration":
        """Calibration with the equilibrium height of ``model`` (nominal pressure) rescaled to ``s``."""
        p_nom = model.wave.pressure_amplitude_pa
        try:
            z_eq = model.with_pressure(p_nom * np.sqrt(pressure_scale)).equilibrium_height if pressure_scale > 0 else float("nan")
        except ValueError:
            z_eq = float("nan")  # the calibrated pressure cannot levitate the dimer: reported by the caller
        return cls(float(pressure_scale), float(z_origin_m), p_nom, float(z_eq))

    @property
    def origin_offset_m(self) -> float:
        """delta = z0 - Z_eq(calibrated): the simulation's y is the data's y + delta [m]."""
        return self.z_origin_m - self.equilibrium_height_m

    @property
    def pressure_amplitude_pa(self) -> float:
        return float(self.nominal_pressure_pa * np.sqrt(max(self.pressure_scale, 0.0)))


_SUMS_CACHE: "weakref.WeakKeyDictionary" = None  # RunAccelerations -> {id(model): sums}


def _cached_sums(model, run: "RunAccelerations"):
    """The model's orientation sums at the run's bends, computed once per (run, model)."""
    import weakref

    global _SUMS_CACHE
    if _SUMS_CACHE is None:
        _SUMS_CACHE = weakref.WeakKeyDictionary()
    per_run = _SUMS_CACHE.setdefault(run, {})
    key = id(model)
    if key not in per_run:
        per_run[key] = (model, model.orientation_sums(run.state[:, 2]))
    return per_run[key][1]


class _Physics:
    """Static Gor'kov terms at the data states for a fast (interpolated) model at nominal pressure."""

    def __init__(self, model, runs: Sequence[RunAccelerations], energy_window: float = 0.4):
        self.energy_window = float(energy_window)
        self.model = model
        self.runs = runs
        self.mass = model.dimer.total_mass
        self.g = model.gravity
        self.k = model.wave.wavenumber
        self._cache: dict[float, list[tuple[NDArray, NDArray]]] = {}

    def forces(self, z0: float) -> list[tuple[NDArray, NDArray]]:
        """Per run: (F_Z/M [m/s^2], Q_theta/I [1/s^2]) at nominal pressure."""
        return [(f, q) for f, q, _ in self._static(z0)]

    def _static(self, z0: float) -> list[tuple[NDArray, NDArray, NDArray]]:
        key = round(z0, 12)
        if key not in self._cache:
            out = []
            if not hasattr(self, "_sums"):
                self._sums = [_cached_sums(self.model, r) for r in self.runs]
            for r, sums in zip(self.runs, self._sums):
                s = self.model.integrals_at_height(r.state[:, 2], z0 + r.state[:, 0], sums)
                # accelerations as the data see them (same smoothing); the potential is used raw
                out.append((r.smooth(s.force_z / self.mass), r.smooth(s.q_theta / self.model.dimer.hinge_inertia(r.state[:, 2])),
                            s.potential))
            if len(self._cache) > 64:
                self._cache.clear()
            self._cache[key] = out
        return self._cache[key]

    def energy_terms(self, z0: float, effects: Sequence[str], z_eq: float | None = None) -> list[dict]:
        """Per run, per energy window: the data side of the energy balance and the effect work columns.

        Keys: ``dk`` (change of M ydot^2/2 + I thetadot^2/2 + M g y) [J], ``du`` (change of U_ac at
        nominal pressure) [J], ``work`` (n_windows, n_params) work of each effect parameter's unit
        term [J per unit parameter], ``e_osc`` (n_windows,) oscillation energy at the window start
        without the acoustic part, ``u_osc`` its acoustic part at nominal pressure [J].
        """
        d = self.model.dimer
        rest_u = float(self.model.integrals_at_height(0.0, z0).potential)
        out = []
        for r, (_, _, pot) in zip(self.runs, self._static(z0)):
            y, yd, th, thd = r.state.T
            inertia = d.hinge_inertia(th)
            kin = 0.5 * self.mass * yd**2 + 0.5 * inertia * thd**2 + self.mass * self.g * y
            dt = float(np.median(np.diff(r.t)))
            step = max(2, int(round(self.energy_window / dt)))
            idx = np.arange(0, len(r.t), step)
            if idx[-1] != len(r.t) - 1:
                idx = np.append(idx, len(r.t) - 1)
            regs = [effect_regressors(n, r.state, z0 + y, self.k, z_eq) for n in effects]
            regs = np.concatenate(regs, axis=2) if regs else np.zeros((len(r.t), 2, 0))
            power = self.mass * yd[:, None] * regs[:, 0, :] + inertia[:, None] * thd[:, None] * regs[:, 1, :]
            cum = np.concatenate([np.zeros((1, power.shape[1])), np.cumsum(0.5 * (power[1:] + power[:-1]) * np.diff(r.t)[:, None], axis=0)])
            a, b = idx[:-1], idx[1:]
            out.append({"dk": kin[b] - kin[a], "du": pot[b] - pot[a], "work": cum[b] - cum[a],
                        "k0": kin[a], "u0": pot[a]})
        return out

    def rest_energy(self, s: float, z0: float) -> float:
        """Minimum of M g y + s U_ac(0, z0 + y): the energy of the dimer at rest at its equilibrium [J]."""
        from scipy.optimize import minimize_scalar

        f = lambda y: self.mass * self.g * y + s * float(self.model.integrals_at_height(0.0, z0 + y).potential)  # noqa: E731
        res = minimize_scalar(f, bounds=(-4e-4, min(4e-4, -z0 - 1e-6)), method="bounded", options={"xatol": 1e-10})
        return float(res.fun)

    def integral_known(self, z0: float, q: int) -> list[tuple[NDArray, NDArray]]:
        """Per run (runs must carry integral data), for coordinate q (0: y, 1: theta): the integral-form
        columns of (the acoustic acceleration at nominal pressure, to be scaled by s; the rest of the
        simulation's acceleration): (F_Z / M, -g) or (Q_theta / I, -I' thetadot^2 / (2 I)), at every frame.
        Only the coordinate asked for is integrated (the calibration's height search needs y alone)."""
        key = ("integral", q, round(z0, 12))
        if key not in self._cache:
            d = self.model.dimer
            out = []
            for r in self.runs:
                pi = r.integral
                y, th, thd = pi.state[:, 0], pi.state[:, 2], pi.state[:, 3]
                st = self.model.integrals_at_height(th, z0 + y, _cached_sums(self.model, pi))
                if q == 0:
                    out.append((pi.columns(0, st.force_z / self.mass), pi.columns(0, np.full(y.shape, -self.g))))
                else:
                    inertia = d.hinge_inertia(th)
                    out.append((pi.columns(1, st.q_theta / inertia),
                                pi.columns(1, -0.5 * d.hinge_inertia_derivative(th) * thd**2 / inertia)))
            self._cache[key] = out
        return self._cache[key]

    def integral_effect_columns(self, z0: float, effects: Sequence[str], z_eq: float | None, q: int) -> list[NDArray]:
        """Per run: integral-form columns (rows, n_params) of the effects' accelerations of coordinate q."""
        out = []
        for r in self.runs:
            pi = r.integral
            regs = [effect_regressors(n, pi.state, z0 + pi.state[:, 0], self.k, z_eq)[:, q, :] for n in effects]
            out.append(pi.columns(q, np.concatenate(regs, axis=1) if regs else np.zeros((pi.state.shape[0], 0))))
        return out

    def centrifugal(self, r: RunAccelerations) -> NDArray:
        th, thd = r.state[:, 2], r.state[:, 3]
        d = self.model.dimer
        return r.smooth(-0.5 * d.hinge_inertia_derivative(th) * thd**2 / d.hinge_inertia(th))


@dataclass(frozen=True, eq=False)
class GapFit:
    """A calibrated simulation (plus effects) fitted to runs, and its residuals."""

    calibration: Calibration
    effects: dict[str, dict[str, float]]
    residuals: list[NDArray[np.float64]]  # per run (n, 2): a_data - a_sim
    predicted: list[NDArray[np.float64]]  # per run (n, 2)
    energy: list[tuple]  # per run: (energy residual per window [J], oscillation energy [J], noise variance of dE [J^2])
    #: per run: (integral-form theta residual, sum of the detrended measured theta squared, noise floor);
    #: None: the thetaddot accelerations were used
    integral: list | None = None

    def effect_parameter_vector(self, names: Sequence[str]) -> NDArray:
        return np.array([self.effects[n][p] for n in names for p in CANDIDATE_EFFECTS[n]], float)


def _design(physics: _Physics, runs, z0: float, effects: Sequence[str], eq: int):
    """Stacked design matrix and target for one equation at origin z0.

    Unknowns for eq 0 (y): [s, y-effect parameters]; for eq 1 (theta): [theta-effect parameters],
    with s entering the target.  Returns per-run lists.
    """
    forces = physics.forces(z0)
    cols_per_run, target_per_run = [], []
    for r, (fz, qt) in zip(runs, forces):
        z = z0 + r.state[:, 0]
        regs = [r.smooth(effect_regressors(n, r.state, z, physics.k)[:, eq, :]) for n in effects]
        regs = np.concatenate(regs, axis=1) if regs else np.zeros((r.state.shape[0], 0))
        if eq == 0:
            cols_per_run.append(np.column_stack([fz, regs]))
            target_per_run.append(r.accel[:, 0] + physics.g)
        else:
            cols_per_run.append(regs)
            target_per_run.append((r.accel[:, 1] - physics.centrifugal(r), qt))
    return cols_per_run, target_per_run


def _param_slices(effects: Sequence[str], eq: int) -> list[tuple[str, str, int]]:
    """(effect, parameter, column) of the unknowns that act in equation eq."""
    out, col = [], (1 if eq == 0 else 0)  # column 0 of the y design is the pressure term
    for n in effects:
        probe = effect_regressors(n, np.ones((1, 4)), np.zeros(1), 1.0)[0, eq, :]
        for p_i, p in enumerate(CANDIDATE_EFFECTS[n]):
            if probe[p_i] != 0:
                out.append((n, p, col))
            col += 1
    return out


def fit_gap_model(model, runs: Sequence[RunAccelerations], effects: Sequence[str] = (),
                  z0_window: float = 4e-4, fixed: Calibration | None = None) -> GapFit:
    """Fit the calibration (s, z0) and the parameters of ``effects`` to the runs.

    With integral data on every run (:class:`PositionIntegrals`, what :func:`validation.diagnose.prepare_runs`
    gives) the calibration (vertical equation) and the theta rows of the effect fit use the integral form,
    against the measured positions; the y rows of the effect fit, and everything without integral data,
    use the Savitzky-Golay accelerations (matched kernel).

    Parameters
    ----------
    model : acousim.GorkovDimer
        The simulation at nominal pressure (use ``model.interpolated()`` for speed).
    runs : sequence of RunAccelerations
    effects : names from CANDIDATE_EFFECTS
    z0_window : float
        z0 is searched within +-z0_window [m] of the nominal Z_eq (kept below the node).
    fixed : Calibration, optional
        Use this calibration instead of fitting one (effects are still fitted).
    """
    physics = _Physics(model, runs)
    y_slots = _param_slices(effects, 0)
    y_effects_cols = [c for _, _, c in y_slots]
    integral = _uses_integral(runs)

    def y_system(z0: float) -> tuple[NDArray, NDArray]:
        """Stacked y-equation design [s column, all effect columns] and target at origin z0: the integral form
        against the measured y when the runs carry integral data (calibrated pressure within 0.02 % on
        no-effect twin data, against +0.1 % from the Savitzky-Golay accelerations), else the accelerations."""
        if integral:
            known = physics.integral_known(z0, 0)
            cols = physics.integral_effect_columns(z0, effects, None, 0)
            x = np.concatenate([np.column_stack([kn[0], c]) for kn, c in zip(known, cols)])
            b = np.concatenate([r.integral.target(0) - kn[1] for r, kn in zip(runs, known)])
            return x, b
        cols, tgt = _design(physics, runs, z0, effects, 0)
        return np.concatenate(cols), np.concatenate(tgt)

    def solve_y(z0: float):
        x, b = y_system(z0)
        x = x[:, [0] + y_effects_cols]
        scale = np.maximum(np.abs(x).max(axis=0), 1e-300)
        sol, *_ = np.linalg.lstsq(x / scale, b, rcond=None)
        sol = sol / scale
        resid = b - x @ sol
        return sol, float(resid @ resid)

    if fixed is None:
        z_eq = model.equilibrium_height
        lo, hi = z_eq - z0_window, min(z_eq + z0_window, -1e-6)
        res = minimize_scalar(lambda z: solve_y(z)[1], bounds=(lo, hi), method="bounded",
                              options={"xatol": 1e-9})
        z0 = float(res.x)
        sol_y, _ = solve_y(z0)
        cal = Calibration.at(model, float(sol_y[0]), z0)
        if not np.isfinite(cal.equilibrium_height_m):
            raise ValueError(f"the calibrated pressure ({cal.pressure_amplitude_pa:.0f} Pa) cannot levitate the dimer: "
                             "the data do not look like a levitated dimer of the meta.json size and material")
    else:
        cal = fixed
        z0 = cal.z_origin_m
    # all effect parameters jointly at the calibrated (s, z0): y and theta equations and the energy
    # balance, each weighted by its normalisation so that the fit minimises R_y + R_theta + R_E
    params = {n: {p: 0.0 for p in CANDIDATE_EFFECTS[n]} for n in effects}
    n_par = sum(len(CANDIDATE_EFFECTS[n]) for n in effects)
    if n_par:
        s_cal = cal.pressure_scale
        rows, rhs = [], []
        forces = physics.forces(z0)
        ay_all = np.concatenate([r.accel[:, 0] for r in runs])
        at_all = np.concatenate([r.accel[:, 1] for r in runs])
        w_y = 1.0 / np.sqrt(max(np.sum((ay_all - ay_all.mean()) ** 2), 1e-300))
        w_t = 1.0 / np.sqrt(max(np.sum((at_all - at_all.mean()) ** 2), 1e-300))
        if integral:  # the theta equation in its integral form, against the measured theta
            known = physics.integral_known(z0, 1)
            cols = physics.integral_effect_columns(z0, effects, cal.equilibrium_height_m, 1)
            w_t = 1.0 / np.sqrt(max(sum(float(np.sum(r.integral.target(1) ** 2)) for r in runs), 1e-300))
        for i, (r, (fz, qt)) in enumerate(zip(runs, forces)):
            z = z0 + r.state[:, 0]
            regs = r.smooth(np.concatenate([effect_regressors(n, r.state, z, physics.k, cal.equilibrium_height_m) for n in effects], axis=2))
            rows.append(w_y * regs[:, 0, :])
            rhs.append(w_y * (r.accel[:, 0] - (s_cal * fz - physics.g)))
            if integral:
                rows.append(w_t * cols[i])
                rhs.append(w_t * (r.integral.target(1) - s_cal * known[i][0] - known[i][1]))
            else:
                rows.append(w_t * regs[:, 1, :])
                rhs.append(w_t * (r.accel[:, 1] - (s_cal * qt + physics.centrifugal(r))))
        en = physics.energy_terms(z0, effects, cal.equilibrium_height_m)
        e_rest = physics.rest_energy(s_cal, z0)
        e_scale = np.concatenate([e["k0"] + s_cal * e["u0"] - e_rest for e in en])
        w_e = 1.0 / np.sqrt(max(np.sum(e_scale**2), 1e-300))
        for e in en:
            rows.append(w_e * e["work"])
            rhs.append(w_e * (e["dk"] + s_cal * e["du"]))
        x, b = np.concatenate(rows), np.concatenate(rhs)
        scale = np.maximum(np.abs(x).max(axis=0), 1e-300)
        sol = np.linalg.lstsq(x / scale, b, rcond=None)[0] / scale
        i = 0
        for n in effects:
            for p in CANDIDATE_EFFECTS[n]:
                params[n][p] = float(sol[i])
                i += 1
    residuals, predicted = _residuals(physics, runs, cal, params)
    return GapFit(cal, params, residuals, predicted, _energy_residuals(physics, cal, params),
                  _integral_residuals(physics, cal, params))


def _uses_integral(runs: Sequence[RunAccelerations]) -> bool:
    """The integral form (calibration and theta equation) is used when every run carries usable integral data."""
    return bool(runs) and all(r.integral is not None and r.integral.usable for r in runs)


def _integral_residuals(physics: _Physics, cal: Calibration, params: dict) -> list[tuple[NDArray, float, float]] | None:
    """Per run: (integral-form theta residual, sum of the detrended measured theta squared, noise floor of
    the residual sum of squares); None without integral data."""
    if not _uses_integral(physics.runs):
        return None
    names = list(params)
    pv = np.array([params[n][p] for n in names for p in CANDIDATE_EFFECTS[n]], float)
    known = physics.integral_known(cal.z_origin_m, 1)
    cols = physics.integral_effect_columns(cal.z_origin_m, names, cal.equilibrium_height_m, 1)
    out = []
    for r, kn, c in zip(physics.runs, known, cols):
        target = r.integral.target(1)
        res = target - cal.pressure_scale * kn[0] - kn[1] - (c @ pv if pv.size else 0.0)
        out.append((res, float(np.sum(target**2)), r.integral.floor(1)))
    return out


def _energy_residuals(physics: _Physics, cal: Calibration, params: dict) -> list[tuple[NDArray, NDArray]]:
    names = list(params)
    pv = np.array([params[n][p] for n in names for p in CANDIDATE_EFFECTS[n]], float)
    out = []
    e_rest = physics.rest_energy(cal.pressure_scale, cal.z_origin_m)
    d = physics.model.dimer
    for r, e in zip(physics.runs, physics.energy_terms(cal.z_origin_m, names, cal.equilibrium_height_m)):
        res = e["dk"] + cal.pressure_scale * e["du"] - (e["work"] @ pv if pv.size else 0.0)
        # noise of dE over a window: two independent endpoint energies, each with velocity noise
        # through the kinetic energy (M ydot sigma_vy)^2 + (I thetadot sigma_vtheta)^2
        if r.noise is not None:
            ke_var = (physics.mass * r.state[:, 1]) ** 2 * r.noise[2] + (d.hinge_inertia(r.state[:, 2]) * r.state[:, 3]) ** 2 * r.noise[3]
            floor_var = 2.0 * float(np.mean(ke_var))
        else:
            floor_var = 0.0
        out.append((res, e["k0"] + cal.pressure_scale * e["u0"] - e_rest, floor_var))
    return out


def _residuals(physics: _Physics, runs, cal: Calibration, params: dict) -> tuple[list, list]:
    forces = physics.forces(cal.z_origin_m)
    res, pred = [], []
    for r, (fz, qt) in zip(runs, forces):
        a_y = cal.pressure_scale * fz - physics.g
        a_t = cal.pressure_scale * qt + physics.centrifugal(r)
        a = np.column_stack([a_y, a_t])
        z = cal.z_origin_m + r.state[:, 0]
        for n, pv in params.items():
            a = a + r.smooth(effect_regressors(n, r.state, z, physics.k, cal.equilibrium_height_m)) @ np.array([pv[p] for p in CANDIDATE_EFFECTS[n]])
        pred.append(a)
        res.append(r.accel - a)
    return res, pred


def short_time_gaps(runs: Sequence[RunAccelerations], residuals: Sequence[NDArray],
                    energy: Sequence[tuple] | None = None, subtract_floor: bool = True,
                    integral: Sequence | None = None) -> NDArray[np.float64]:
    """Per run (n_runs, 3): unexplained fraction of the y and theta equations and of the energy balance
    (R_E), each minus its noise floor unless ``subtract_floor`` is False (module docstring).

    The y component is the unexplained fraction of the Savitzky-Golay yddot variance.  With ``integral``
    (integral-form residuals, :class:`PositionIntegrals`) the theta component is the unexplained fraction
    of the detrended measured theta, ``sum r^2 / sum (P theta)^2``, whose floor is
    ``(frames - 2 per window) sigma_theta^2 / sum (P theta)^2``; without, that of the thetaddot variance."""
    out = np.zeros((len(runs), 3))
    for i, (r, e) in enumerate(zip(runs, residuals)):
        var = np.sum((r.accel - r.accel.mean(axis=0)) ** 2, axis=0)
        out[i, :2] = np.sum(e**2, axis=0) / np.maximum(var, 1e-300)
        if subtract_floor and r.noise is not None:
            out[i, :2] -= len(r.t) * r.noise[:2] / np.maximum(var, 1e-300)
        if integral is not None:
            res, norm, floor = integral[i]
            out[i, 1] = (float(np.sum(res**2)) - (floor if subtract_floor else 0.0)) / max(norm, 1e-300)
        if energy is not None:
            res, eosc, floor_var = energy[i]
            norm = max(float(np.sum(eosc**2)), 1e-300)
            out[i, 2] = float(np.sum(res**2)) / norm - (len(res) * floor_var / norm if subtract_floor else 0.0)
    return out


def noise_floors(runs: Sequence[RunAccelerations], fit: "GapFit") -> NDArray[np.float64]:
    """Per run (n_runs, 3): the floors subtracted by :func:`short_time_gaps`."""
    raw = short_time_gaps(runs, fit.residuals, fit.energy, subtract_floor=False, integral=fit.integral)
    return raw - short_time_gaps(runs, fit.residuals, fit.energy, integral=fit.integral)


def fit_gaps(runs: Sequence[RunAccelerations], fit: "GapFit") -> NDArray[np.float64]:
    """Per-run gap components (n_runs, 3) of a fit on these runs."""
    return short_time_gaps(runs, fit.residuals, fit.energy, integral=fit.integral)


def scalar_gap(per_run: NDArray) -> float:
    """The documented scalar: mean over runs of the mean over the three components (y, theta, energy)."""
    return float(np.mean(per_run))


def _held_out_gaps(model, runs, effects: Sequence[str], folds: int = 5) -> NDArray[np.float64]:
    """K-fold over runs (run i is in fold i mod K): per run, the gap components (beyond the noise floor;
    (n_runs, 3): y, theta, energy) of a fit made on the other folds.

    Every run is held out exactly once, so each run gets one held-out score (leave-one-run-out when
    K >= the number of runs)."""
    n = len(runs)
    k = min(folds, n)
    out = np.empty((n, 3))
    for f in range(k):
        test = [i for i in range(n) if i % k == f]
        train = [r for i, r in enumerate(runs) if i % k != f]
        fit = fit_gap_model(model, train, effects)
        held = [runs[i] for i in test]
        physics = _Physics(model, held)
        res, _ = _residuals(physics, held, fit.calibration, fit.effects)
        en = _energy_residuals(physics, fit.calibration, fit.effects)
        integral = _integral_residuals(physics, fit.calibration, fit.effects)
        out[test] = short_time_gaps(held, res, en, integral=integral)
    return out


def _acting_components(name: str) -> list[int]:
    """Gap components an effect acts in: y (0) and theta (1) where it has parameters, and the energy (2)."""
    return [q for q in (0, 1) if _param_slices([name], q)] + [2]


@dataclass
class Identification:
    identified: list[str]
    steps: list[dict] = field(default_factory=list)  # one per greedy round: candidates and their tests
    #: unexplained fraction (beyond noise) of the vertical equation, with the effects the greedy rounds chose
    vertical_gap: float = float("nan")
    #: effects the greedy rounds chose but that are not named because the calibration is not trustworthy
    withheld: list[str] = field(default_factory=list)


def identify_effects(model, runs: Sequence[RunAccelerations], candidates: Sequence[str] = tuple(CANDIDATE_EFFECTS),
                     alpha: float = 0.01, min_relative_improvement: float = 0.05,
                     progress: Callable[[str], None] | None = None,
                     min_absolute_improvement: float = 5e-6, max_vertical_gap: float = 0.05) -> Identification:
    """Greedy, held-out identification of the effects present (see module docstring).

    A trustworthy calibration is required for naming any cause: the pressure and origin come from the
    vertical equation alone, so if that equation stays unexplained beyond ``max_vertical_gap`` of its
    variance (beyond noise) even with the chosen effects, the calibration is distorted by something
    outside the candidates (e.g. a pressure drifting during the runs), and hinge effects fitted on top
    of it mostly compensate the distortion (measured: a 6 % pressure drift calibrated 9 % low, and
    pair scattering then explained 94 % of the resulting hinge gap).  The chosen effects are then
    reported in ``withheld`` and ``identified`` is empty."""
    if len(runs) < 3:
        raise ValueError("identification needs at least 3 runs (held-out runs are the significance test)")
    chosen: list[str] = []
    result = Identification([])
    # each run's held-out gap is a fraction of its own variance (and energy): every run counts equally.
    # Weighing runs by their share of the pooled variance instead was measured to lose a constant
    # hinge torque (mirror_asymmetry, beta0 = 60 1/s^2, tests/validation/test_diagnosis.py), whose
    # signal is the same in every run while the energy residual's noise grows with the run's energy.
    current_c = _held_out_gaps(model, runs, chosen)
    current = current_c.mean(axis=1)
    remaining = [c for c in candidates]
    while remaining:
        round_info = {"base": list(chosen), "base_held_out_gap": float(np.mean(current)), "candidates": {}}
        best, best_gain = None, 0.0
        for c in remaining:
            if progress:
                progress(f"testing {c} on top of {chosen or 'calibration'}")
            trial_c = _held_out_gaps(model, runs, chosen + [c])
            trial = trial_c.mean(axis=1)
            diff = current - trial  # > 0: the candidate helps the held-out run (the floor cancels)
            try:
                p_w = float(wilcoxon(diff, alternative="greater", zero_method="zsplit").pvalue) if np.any(diff != 0) else 1.0
            except ValueError:
                p_w = 1.0
            p = sign_flip_pvalue(diff)
            # practical significance: the median held-out improvement (in gap units, the noise floor
            # cancels) must exceed min_absolute_improvement of the variance, and its improvement of the
            # gap components the candidate acts in (its equations and the energy) must exceed
            # min_relative_improvement of what remains in them: a hinge effect is not judged against a
            # remaining gap of the vertical equation it cannot touch
            gain = float(np.median(diff))
            comps = _acting_components(c)
            base_c = max(float(np.mean(current_c[:, comps])), 0.0)
            gain_c = float(np.median(current_c[:, comps].mean(axis=1) - trial_c[:, comps].mean(axis=1)))
            rel = gain / max(float(np.mean(current)), min_absolute_improvement)
            significant = bool(p < alpha and gain > min_absolute_improvement and gain_c > min_relative_improvement * base_c)
            round_info["candidates"][c] = {"held_out_gap": float(np.mean(trial)), "median_improvement": gain,
                                           "median_improvement_fraction": rel, "threshold": min_absolute_improvement,
                                           "components": comps, "median_improvement_in_components": gain_c,
                                           "remaining_gap_in_components": base_c,
                                           "p_value": p, "wilcoxon_p": p_w, "significant": significant, "per_run_held_out": trial.tolist()}
            if significant and rel > best_gain:
                best, best_gain, best_trial = c, rel, trial_c
        result.steps.append(round_info)
        if best is None:
            break
        chosen.append(best)
        remaining.remove(best)
        current_c = best_trial
        current = current_c.mean(axis=1)
    result.vertical_gap = float(np.mean(fit_gaps(runs, fit_gap_model(model, runs, chosen))[:, 0]))
    if result.vertical_gap > max_vertical_gap:
        result.withheld, chosen = chosen, []
    result.identified = chosen
    return result


def localize_residuals(runs: Sequence[RunAccelerations], residuals: Sequence[NDArray], n_bins: int = 8) -> dict:
    """Where the residual lies: library terms (z-scores across runs), state-space bins, time scales.

    * ``terms``: per equation, each library term's coefficient from a per-run least-squares fit of
      the residual on the 35-term library (variables scaled), its mean, std and z-score across runs,
      and the fraction of residual variance each term explains when fitted alone.
    * ``regions``: RMS residual per equation on an (theta, y) grid and an (thetadot, ydot) grid.
    * ``time_scales``: fraction of the residual variance per frequency band, relative to the
      dominant y frequency of the data.
    """
    from cubedimer.terms import evaluate_library, library_terms

    terms = library_terms()
    allstate = np.concatenate([r.state for r in runs])
    scale = np.maximum(np.abs(allstate).max(axis=0), 1e-300)
    coefs = []
    for r, e in zip(runs, residuals):
        lib = evaluate_library(r.state / scale)
        c, *_ = np.linalg.lstsq(lib, e, rcond=None)
        coefs.append(c)
    coefs = np.array(coefs)  # (n_runs, 35, 2)
    libs = [evaluate_library(r.state / scale) for r in runs]
    terms_out = {}
    for q, eq in enumerate(("yddot", "thetaddot")):
        mean, std = coefs[:, :, q].mean(axis=0), coefs[:, :, q].std(axis=0, ddof=1) if len(runs) > 1 else np.full(35, np.nan)
        explained = []
        tot = sum(float(np.sum(e[:, q] ** 2)) for e in residuals)
        for j in range(len(terms)):
            num = 0.0
            for lib, e in zip(libs, residuals):
                col = lib[:, j]
                den = col @ col
                if den > 0:
                    num += (col @ e[:, q]) ** 2 / den
            explained.append(num / max(tot, 1e-300))
        rows = []
        for j, t in enumerate(terms):
            z = mean[j] / std[j] if std[j] > 0 else float("nan")
            rows.append({"term": t, "mean_scaled": float(mean[j]), "std_scaled": float(std[j]), "z": float(z),
                         "explained_fraction_alone": float(explained[j])})
        # rank by the share each term explains alone: along trajectories the library columns are
        # strongly correlated, so multivariate coefficients (and their z-scores) spread over them
        rows.sort(key=lambda d: -d["explained_fraction_alone"])
        terms_out[eq] = rows
    # regions
    res_all = np.concatenate(residuals)
    regions = {}
    for label, (i, j) in (("theta_y", (2, 0)), ("thetadot_ydot", (3, 1))):
        xe = np.quantile(allstate[:, i], np.linspace(0, 1, n_bins + 1))
        ye = np.quantile(allstate[:, j], np.linspace(0, 1, n_bins + 1))
        xi = np.clip(np.searchsorted(xe, allstate[:, i]) - 1, 0, n_bins - 1)
        yi = np.clip(np.searchsorted(ye, allstate[:, j]) - 1, 0, n_bins - 1)
        rms = np.full((2, n_bins, n_bins), np.nan)
        for a in range(n_bins):
            for b in range(n_bins):
                m = (xi == a) & (yi == b)
                if m.sum() >= 5:
                    rms[:, a, b] = np.sqrt(np.mean(res_all[m] ** 2, axis=0))
        regions[label] = {"x_edges": xe.tolist(), "y_edges": ye.tolist(), "rms_yddot": rms[0].tolist(), "rms_thetaddot": rms[1].tolist()}
    # time scales
    from cubedimer.spectra import dominant_frequency

    bands = [(0.0, 0.25), (0.25, 0.75), (0.75, 1.5), (1.5, 2.5), (2.5, np.inf)]
    power = np.zeros((len(bands), 2))
    for r, e in zip(runs, residuals):
        dt = float(np.median(np.diff(r.t)))
        fy = dominant_frequency(r.state[:, 0], dt)
        f = np.fft.rfftfreq(len(e), dt) / max(fy, 1e-12)
        spec = np.abs(np.fft.rfft(e - e.mean(axis=0), axis=0)) ** 2
        for b, (lo, hi) in enumerate(bands):
            m = (f >= lo) & (f < hi)
            power[b] += spec[m].sum(axis=0)
    power /= np.maximum(power.sum(axis=0), 1e-300)
    time_scales = {"bands_in_units_of_f_y": [[lo, hi if np.isfinite(hi) else None] for lo, hi in bands],
                   "fraction_yddot": power[:, 0].tolist(), "fraction_thetaddot": power[:, 1].tolist()}
    return {"terms": terms_out, "regions": regions, "time_scales": time_scales}


def simulate_runs(model, cal: Calibration, effects: dict, x0: NDArray, t: NDArray, substeps: int = 2,
                  bound: float = 2e-3) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Integrate the calibrated simulation model (+ effects) from each run's initial state.

    Classical RK4 with step ``dt / substeps`` on a uniform output grid ``t``, batched over runs (all
    runs advance together; the model is evaluated once per stage for the whole batch).  A run whose
    |y| exceeds ``bound`` [m] (it left the trap) or turns non-finite is frozen and reported through
    ``n_valid``.

    Parameters
    ----------
    model : acousim.GorkovDimer (interpolated), at nominal pressure
    x0 : (n_runs, 4) initial states; t : (n,) uniform times [s]

    Returns
    -------
    states (n_runs, n, 4), n_valid (n_runs,)
    """
    x = np.array(x0, float)
    n_runs, n = x.shape[0], len(t)
    h = float(t[1] - t[0]) / substeps
    out = np.empty((n_runs, n, 4))
    out[:, 0] = x
    n_valid = np.full(n_runs, n, dtype=np.int64)
    alive = np.ones(n_runs, bool)
    dimer, g, k = model.dimer, model.gravity, model.wave.wavenumber
    mass = dimer.total_mass
    names = list(effects)
    pvec = [np.array([effects[e][p] for p in CANDIDATE_EFFECTS[e]]) for e in names]

    def rhs(s: NDArray) -> NDArray:
        th = np.clip(s[:, 2], -1.0, 1.0)
        z = cal.z_origin_m + s[:, 0]
        st = model.integrals_at_height(th, z)
        inertia = dimer.hinge_inertia(th)
        a = np.column_stack([cal.pressure_scale * st.force_z / mass - g,
                             (cal.pressure_scale * st.q_theta - 0.5 * dimer.hinge_inertia_derivative(th) * s[:, 3] ** 2) / inertia])
        for e, pv in zip(names, pvec):
            a = a + effect_regressors(e, s, z, k, cal.equilibrium_height_m) @ pv
        return np.column_stack([s[:, 1], a[:, 0], s[:, 3], a[:, 1]])

    for i in range(1, n):
        for _ in range(substeps):
            k1 = rhs(x)
            k2 = rhs(x + 0.5 * h * k1)
            k3 = rhs(x + 0.5 * h * k2)
            k4 = rhs(x + h * k3)
            x = np.where(alive[:, None], x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4), x)
        bad = alive & (~np.all(np.isfinite(x), axis=1) | (np.abs(x[:, 0]) > bound) | (np.abs(x[:, 2]) >= 1.0))
        if np.any(bad):
            n_valid[bad] = i
            alive &= ~bad
            x[bad] = out[bad, i - 1]
        out[:, i] = x
    return out, n_valid


def long_time_gaps(model, runs: Sequence[RunAccelerations], fit: GapFit, max_duration: float | None = None) -> list[dict]:
    """Per run: the fitting package's long-time loss terms (shape, Poincare, frequency) of the simulation
    started from the run's first smoothed state, sampled on the run's own frames.

    Integrated with the compiled RK4 of :class:`acousim.dynamics.DimerDynamics` on the surrogate of
    ``model`` rescaled to the calibrated pressure (its y is measured from the calibrated Z_eq, i.e. the
    data's y + ``calibration.origin_offset_m``), with the fitted effects.
    """
    from acousim.dynamics import DimerDynamics
    from acousim.effects import EffectSet
    from acousim.surrogate import build_surrogate
    from fitting.losses import loss_terms, make_reference

    cal = fit.calibration
    key = id(model)
    if _SURROGATES.get(key, (None,))[0] is not model:
        _SURROGATES.clear()
        _SURROGATES[key] = (model, build_surrogate(model))
    surrogate = _SURROGATES[key][1].with_pressure(cal.pressure_amplitude_pa)
    dynamics = DimerDynamics(surrogate, EffectSet.from_dict(fit.effects))
    delta = cal.z_origin_m - surrogate.z_eq
    out = []
    for r in runs:
        n = len(r.t) if max_duration is None else int(np.searchsorted(r.t - r.t[0], max_duration))
        t = r.t[:n] - r.t[0]
        x0 = r.state[0].copy()
        x0[0] += delta
        x0[2] = float(np.clip(x0[2], -0.999, 0.999))
        dt = float(np.median(np.diff(t)))
        traj = dynamics.integrate(x0, duration=t[-1], dt_out=dt)
        sim = np.zeros((n, 4))
        m = min(n, len(traj.t))
        sim[:m] = traj.state[:m]
        sim[:m, 0] -= delta
        ref = make_reference(t, r.state[:n])
        lt = loss_terms(sim, int(m), ref)
        out.append({"shape": lt.shape, "poincare": lt.poincare, "frequency": lt.frequency, "total": lt.total,
                    "diverged": bool(m < n), "status": traj.message})
    return out


_SURROGATES: dict = {}
