"""The levitator's cavity as a cause the diagnosis can fit: the slow-lag expansion of acousim's resonator, linear in
two gains.

:mod:`acousim.dynamics.resonator` makes the cavity mode a state of the twin: every acoustic generalised force scales
with ``s = |a|^2``, and the dimer detunes the cavity by ``delta(y, theta) = w (U_ac(theta, y) - U_ac(0, 0)) / E_mode``
[rad/s].  For motion slow against the ring time (:mod:`acousim.dynamics.cavity_stability`'s module docstring),
``s = s_qs(Delta) - T(Delta) s_qs'(Delta) dDelta/dt``, whose expansion about rest to first order in the dimer's
shift is

    s - 1 = A delta + B d(delta)/dt,   d(delta)/dt = -(w / E_mode) (F_Z,ac ydot + Q_theta thetadot)

    A = -2 x / (Gamma (1 + x^2))          [s/rad]    the quasi-static response
    B = 4 x / (Gamma^2 (1 + x^2)^2)        [s^2/rad]  the lag

(x: the drive's detuning in half-widths, Gamma = pi f / Q; :class:`acousim.dynamics.resonator.CavityMode`).  The
accelerations the cavity adds are ``(s - 1)`` times the acoustic accelerations ``(F_Z,ac / M, Q_theta / I)``: linear in
(A, B), so the cavity is a candidate of the same linear least squares as the other effects.  The two gains give back
both of the mode's parameters, ``x = A^2 / B`` and ``Gamma = -2 A / (B (1 + x^2))`` (:func:`mode_from_gains`), once the
cavity's effective area is known: delta scales as 1 / E_mode, so a different area rescales (A, B) and therefore x and
Q.  The data resolve (A, B), that is, Q and x at the assumed area (default
:data:`acousim.dynamics.resonator.DEFAULT_CAVITY_AREA`); they do not resolve the area itself.

A on y alone is a linear stiffness ``A w F_Z^2 / (M E_mode)`` that the pressure and origin calibration absorb to first
order (both change the trap's curvature at a fixed balance of gravity); what sets the cavity apart from the pressure
is its dependence on theta and on the second order in y.  B on y alone is a damping (x > 0) or an anti-damping (x < 0)
of rate ``B w F_Z^2 / (M E_mode)``, which varies over a y cycle as F_Z^2 does (by about +-2 w_y^2 y / g: +-80 % at
100 um on the default dimer), unlike linear damping's constant rate, and it couples y and theta through
``F_Z Q_theta`` (the velocity couplings of :func:`acousim.dynamics.cavity_stability.lag_couplings`).

**The ring-up.**  When the drive comes back on after a field drop, the mode rings up from what is left of it
(``a = a_d + (a_start - a_d) exp(-(Gamma + i Delta) t)``): at Q 300-400 the acoustic forces start at a few per cent
of their steady value and overshoot it by a third before they settle over a few ring times.  That transient is no
response to the dimer's motion, and the slow expansion (a steady mode) does not hold it: on a blind twin case (Q 313,
x 1.48) it left the steady expansion off by up to 0.96 of the force in the first 20 ms, against 1e-5 of the force
(0.7 % of the lag's part) afterwards with the second-order columns, and the fit traded the lag for linear damping
(Q 1878, x 13.1, gamma_y 2.5 1/s against 313, 1.48, 0.59).  A diagnosis with the cavity among its candidates
therefore leaves the first :data:`RING_UP_S` (40 ms) of every run out (:func:`leave_out_ring_up`).

**Second order.**  At the drops of a real levitator (150-200 um) the dimer's shift reaches d = delta / Gamma = 3.5 %,
and the first-order expansion leaves errors the data resolve: the static curve's next term (``s - 1 = -d + d^2/2`` at
x = 1), which changes the pressure shift averaged over a cycle (the static gain's main signature once the
calibration has taken its linear part) by ~7 %, and the ring's lag at the oscillation's own frequency (the next terms
of the mode's transfer function).  The columns are completed to that order about a reference mode
(:func:`second_order_ratios`; :func:`validation.diagnosis.calibrate.gap_model.fit_cavity_reference`: the candidate's
own fit on the data set, made by the first fit that holds the cavity), staying linear in
(A, B); the fitted Q and x on acousim's simulated mode then move from 3-5 % off to within 0.3 % (Q 150-300).

Every quantity here comes from acousim's public functions (:func:`~acousim.dynamics.resonator.potential_series`,
:func:`~acousim.dynamics.resonator.mode_energy`, :class:`~acousim.dynamics.resonator.CavityMode`, the force model's
``generalized_forces``): one implementation of the resonator's equations.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable, Sequence

import numpy as np
from numpy.polynomial import chebyshev as cheb
from numpy.typing import ArrayLike, NDArray

from acousim.dynamics.resonator import (DEFAULT_CAVITY_AREA, CavityMode, mode_energy, potential_series,
                                       slow_response_gains)
from acousim.medium import Medium

__all__ = ["CAVITY_LAG_PARAMETERS", "CavityGains", "gains_from_mode", "mode_from_gains", "cavity_lag_columns",
           "CavityColumns", "AngleFactors", "ANGLE_SERIES", "problem_columns", "HeightExpansion", "height_expansion",
           "HEIGHT_DEGREE", "second_order_ratios", "cavity_reference", "derived_quantities", "quasi_static_response",
           "RING_UP_S",
           "leave_out_ring_up"]

#: The candidate's parameters: the quasi-static gain A [s/rad] and the lag gain B [s^2/rad] (module docstring).
CAVITY_LAG_PARAMETERS = ("static_gain", "lag_gain")


@dataclass(frozen=True)
class CavityGains:
    """The two gains of the slow-lag expansion (module docstring)."""

    static_gain: float  #: A [s/rad]
    lag_gain: float  #: B [s^2/rad]


def gains_from_mode(mode: CavityMode, frequency_hz: float) -> CavityGains:
    """(A, B) of a cavity mode at the drive's frequency [Hz] (Gamma from :meth:`CavityMode.decay_rate`)."""
    gamma = mode.decay_rate(frequency_hz)
    static, lag = slow_response_gains(gamma, gamma * mode.detuning)
    return CavityGains(float(static), float(lag))


def mode_from_gains(gains: CavityGains, frequency_hz: float, area: float = DEFAULT_CAVITY_AREA) -> CavityMode:
    """The cavity mode (Q, detuning) whose gains are ``gains``: ``x = A^2 / B``, ``Gamma = -2 A / (B (1 + x^2))``.

    Raises
    ------
    ValueError
        When no mode has these gains: B = 0 (no lag: x = 0 or an uncoupled cavity), or A and B of the same sign
        (a negative Gamma), or a detuning beyond the resonator's accepted range.
    """
    a, b = float(gains.static_gain), float(gains.lag_gain)
    if not (math.isfinite(a) and math.isfinite(b)) or b == 0.0:
        raise ValueError(f"no cavity mode has the gains A = {a:.3g} s/rad, B = {b:.3g} s^2/rad (B must be non-zero)")
    x = a * a / b
    gamma = -2.0 * a / (b * (1.0 + x * x))
    if not gamma > 0:
        raise ValueError(f"no cavity mode has the gains A = {a:.3g} s/rad, B = {b:.3g} s^2/rad: A and B must have "
                         "opposite signs (the ring's decay rate comes out negative)")
    return CavityMode(quality_factor=math.pi * frequency_hz / gamma, detuning=x, area=area)


def second_order_ratios(mode: CavityMode | None, frequency_hz: float) -> tuple[float, float, float, float]:
    """(a2, r2, b2, r3): the next terms of the slow expansion relative to its gains, for the mode ``mode`` (zeros
    without one): ``s - 1 = A (delta + a2 delta^2 + r2 delta'') + B (delta' + b2 delta delta' + r3 d^3delta/dt^3)``
    (module docstring).

    * a2 = s''(Delta_0) / (2 s'(Delta_0)) = -(3 x^2 - 1) / (2 x Gamma (1 + x^2)) [s/rad]: the quasi-static response's
      curvature (at x = 1, ``s - 1 = -d + d^2/2`` in d = delta / Gamma);
    * r2 = (3 - x^2) / (Gamma^2 (1 + x^2)^2) [s^2]: the ring's in-phase lag, the next term of the mode's transfer
      function ``H(w) = i / (Gamma + i (w - Delta_0)) - i / (Gamma + i (w + Delta_0))`` (at x = 1 the response at w is
      lower by (w / Gamma)^2 / 2);
    * b2 = (1/x - 6 x / (1 + x^2)) / Gamma [s/rad]: the lag gain's change with the detuning, d ln B / dDelta;
    * r3 = 2 (1 - x^2) / (Gamma^2 (1 + x^2)^2) [s^2]: the transfer function's next quadrature term relative to the
      lag (zero at x = 1).
    """
    if mode is None:
        return 0.0, 0.0, 0.0, 0.0
    gamma, x = mode.decay_rate(frequency_hz), mode.detuning
    d = 1.0 + x * x
    return (-(3 * x * x - 1) / (2 * x * gamma * d), (3 - x * x) / (gamma * d) ** 2, (1 / x - 6 * x / d) / gamma,
            2 * (1 - x * x) / (gamma * d) ** 2)


def cavity_lag_columns(force_model, state: ArrayLike, area: float = DEFAULT_CAVITY_AREA,
                       medium: Medium | None = None, rest_y: float = 0.0,
                       reference: CavityMode | None = None) -> NDArray[np.float64]:
    """d(accelerations)/d(A, B) of the cavity's slow lag at the states: array (n, 2, 2), rows (yddot, thetaddot),
    columns (A, B), as :func:`~validation.diagnosis.prepare.candidate_effects.effect_regressors` gives them
    (:meth:`CavityColumns.columns`; build a :class:`CavityColumns` once to evaluate many sets of states).

    Parameters
    ----------
    force_model : acousim.ForceModel
        The dimer's forces at the pressure the data are at (y from its own Z_eq).
    state : array (n, 4)
        [y, ydot, theta, thetadot] (SI).
    area : the cavity's effective cross-section [m^2]
    medium : the air and the drive's frequency (default :class:`acousim.Medium`)
    rest_y : the dimer's rest height, where the drive's detuning x is defined (delta = 0), as a y of the force
        model [m]: 0 when the force model is at the data's pressure; in the diagnosis, the calibrated equilibrium
        (the force model is the nominal pressure's)
    reference : the mode whose second-order terms (:func:`second_order_ratios`) complete the two columns (None: the
        first-order expansion alone); the columns stay linear in (A, B)
    """
    return CavityColumns(force_model, area, medium).columns(state, rest_y, reference)


#: The force model's series an :class:`AngleFactors` holds, in its order: the height structure of the acoustic
#: forces (:class:`acousim.ForceCoefficients`), the potential's (:class:`acousim.dynamics.resonator.PotentialSeries`)
#: and the forces' theta derivatives.
ANGLE_SERIES = ("f_a", "f_b", "f_c", "q_a", "q_b", "q_c", "u_p", "u_r", "u_s", "u_l",
                "f_a'", "f_b'", "f_c'", "q_a'", "q_b'", "q_c'")


@dataclass(frozen=True, eq=False)
class AngleFactors:
    """What the cavity's columns need of the dimer's bend, at one set of angles (:meth:`CavityColumns.angle_factors`):
    every series of :data:`ANGLE_SERIES` evaluated there, and the hinge inertia.  The columns at any heights are then
    sums of these times the standing wave's cos(2kZ) and sin(2kZ): the angles of a run are evaluated once per data
    set, whatever origin height or equilibrium a fit tries."""

    theta: NDArray[np.float64]  #: (n,) [rad]
    values: NDArray[np.float64]  #: (16, n): the series of :data:`ANGLE_SERIES` at theta (SI)
    inertia: NDArray[np.float64]  #: (n,) I(theta) [kg m^2]


class CavityColumns:
    """The cavity's columns for one force model, cavity area and air (module docstring).

    Every acoustic quantity the columns use has the force models' height structure (:mod:`acousim.force_model`):
    ``F_Z,ac = A_y + B_y cos(2kZ) + C_y sin(2kZ)``, ``Q_theta`` likewise, and ``U_ac = P + R cos(2kZ) + S sin(2kZ) +
    L Z`` (:func:`~acousim.dynamics.resonator.potential_series`), with Chebyshev series in theta.  The series and
    their theta derivatives are built once here, evaluated once per set of angles (:meth:`angle_factors`), and the
    height enters through the standing wave's phase alone; the forces' gradients (for the detuning's curvature) are
    the series' exact derivatives.
    """

    def __init__(self, force_model, area: float = DEFAULT_CAVITY_AREA, medium: Medium | None = None):
        medium = Medium() if medium is None else medium
        self.force_model = force_model
        self.frequency_hz = float(medium.frequency_hz)
        # [rad/s per J]: the drive's angular frequency over the mode's stored energy
        self.shift = 2.0 * math.pi * self.frequency_hz / mode_energy(force_model.pressure_amplitude_pa, area, medium)
        forces = force_model.force_coefficients().as_tuple()
        pot = potential_series(force_model)
        der = lambda c: cheb.chebder(c) if c.size > 1 else np.zeros(1)  # noqa: E731
        self._series = forces + (pot.p, pot.r, pot.s, pot.l) + tuple(der(c) for c in forces)
        self._at_zero = self._evaluate(np.zeros(1))[:, 0]  # every series at theta = 0 (the dimer at rest)
        #: whether every column is periodic in the height (U_ac has no ``L Z`` term): :func:`height_expansion`
        self.height_periodic = not np.any(self._series[ANGLE_SERIES.index("u_l")])

    def _evaluate(self, theta: NDArray[np.float64]) -> NDArray[np.float64]:
        return np.stack([cheb.chebval(theta, c) * np.ones_like(theta) for c in self._series])

    def angle_factors(self, theta: ArrayLike) -> AngleFactors:
        """The factors of the columns at the angles ``theta`` [rad] (:class:`AngleFactors`)."""
        th = np.asarray(theta, float).ravel()
        return AngleFactors(th, self._evaluate(th), np.asarray(self.force_model.hinge_inertia(th), float))

    def _height_terms(self, values: NDArray, z: NDArray) -> dict[str, NDArray]:
        """F_Z,ac, Q_theta, U_ac and their gradients in Z and theta at the absolute heights ``z`` [m] for series
        values ``values`` (16, n)."""
        tk = float(self.force_model.two_k)
        c, s = np.cos(tk * z), np.sin(tk * z)
        f_a, f_b, f_c, q_a, q_b, q_c, u_p, u_r, u_s, u_l, df_a, df_b, df_c, dq_a, dq_b, dq_c = values
        return {"f": f_a + f_b * c + f_c * s, "q": q_a + q_b * c + q_c * s, "u": u_p + u_r * c + u_s * s + u_l * z,
                "f_z": tk * (f_c * c - f_b * s), "q_z": tk * (q_c * c - q_b * s),
                "f_t": df_a + df_b * c + df_c * s, "q_t": dq_a + dq_b * c + dq_c * s}

    def rest_force(self, z: ArrayLike) -> NDArray[np.float64]:
        """F_Z,ac(theta = 0, Z) [N] at the absolute heights ``z`` [m]: the F of :meth:`column_parts` at rest there."""
        return self._height_terms(self._at_zero[:, None], np.atleast_1d(np.asarray(z, float)))["f"]

    def columns(self, state: ArrayLike, rest_y: float = 0.0, reference: CavityMode | None = None,
                angles: AngleFactors | None = None) -> NDArray[np.float64]:
        """The columns (n, 2, 2) at the states (:func:`cavity_lag_columns` for the parameters); ``angles``: the
        :meth:`angle_factors` of the states' theta, when already evaluated."""
        regular, over_rest, rest_force = self.column_parts(state, rest_y, reference, angles)
        return regular + over_rest / rest_force

    def column_parts(self, state: ArrayLike, rest_y: float = 0.0, reference: CavityMode | None = None,
                     angles: AngleFactors | None = None) -> tuple[NDArray[np.float64], NDArray[np.float64], float]:
        """``(C0, C1, F)``: the columns are ``C0 + C1 / F`` with F = F_Z,ac(theta = 0, rest) [N], the one division
        of the second-order terms (the simulation's accelerations at the pressure that holds the dimer at rest).

        C0 and C1 are sums of products of at most three factors with the height structure (the standing wave's
        cos and sin of 2kZ at the dimer and at rest; U_ac's ``L Z`` aside, zero for a Gor'kov model): at fixed data
        states they are trigonometric polynomials of degree 3 in 2k z0 when the data's origin moves to z0 with the
        rest height (:func:`height_expansion`)."""
        y, yd, th, thd = np.atleast_2d(np.asarray(state, float)).T
        if angles is None:
            angles = self.angle_factors(th)
        fm = self.force_model
        at = self._height_terms(angles.values, fm.z_eq + y)
        rest = self._height_terms(self._at_zero[:, None], np.array([fm.z_eq + rest_y]))
        delta = self.shift * (at["u"] - rest["u"])
        delta_rate = -self.shift * (at["f"] * yd + at["q"] * thd)
        accel = np.stack([at["f"] / fm.mass, at["q"] / angles.inertia], axis=1)[:, :, None]  # (n, 2, 1)
        rest_force = float(rest["f"][0])
        if reference is None:
            return (np.stack([accel[:, :, 0] * delta[:, None], accel[:, :, 0] * delta_rate[:, None]], axis=2),
                    np.zeros((len(y), 2, 2)), rest_force)
        a2, r2, b2, r3 = second_order_ratios(reference, self.frequency_hz)
        g = fm.gravity
        # the detuning's curvature d^2(delta)/dt^2 along the simulation's own motion at the pressure that holds the
        # dimer at its rest height (no measured acceleration: their noise would enter):
        # yddot = g (F_Z / F_rest - 1), thetaddot = g M Q_theta / (F_rest I), so that
        # curvature = -shift (g (F_Z^2 + M Q_theta^2 / I) / F_rest - g F_Z + dF_Z/dt ydot + dQ_theta/dt thetadot)
        f_dot = at["f_z"] * yd + at["f_t"] * thd
        q_dot = at["q_z"] * yd + at["q_t"] * thd
        static = delta + a2 * delta**2 - r2 * self.shift * (f_dot * yd + q_dot * thd - g * at["f"])
        static_over = -r2 * self.shift * g * (at["f"] ** 2 + fm.mass * at["q"] ** 2 / angles.inertia)
        # the third derivative as -w_y^2 delta' (the vertical oscillation's own frequency; the hinge barely moves
        # delta), w_y^2 = -g dF_Z/dZ(0, rest) / F_rest at rest
        lag = delta_rate * (1.0 + b2 * delta)
        lag_over = delta_rate * r3 * g * float(rest["f_z"][0])
        regular = np.concatenate([accel * static[:, None, None], accel * lag[:, None, None]], axis=2)
        over_rest = np.concatenate([accel * static_over[:, None, None], accel * lag_over[:, None, None]], axis=2)
        return regular, over_rest, rest_force


#: What a diagnosis with the cavity among its candidates leaves out of the start of every run [s]: about 10 ring
#: times tau = Q / (pi f) at the largest Q the reference mode accepts (600 at 45.65 kHz: tau = 4.2 ms; the ring-up
#: is then down to exp(-9.6) = 7e-5 of its start), 14 at Q 400.  On acousim's six-state system after a 3 ms drop
#: (Q 600, x 1.5) the steady second-order expansion's misfit of the y acceleration is still 6 % of the cavity's part
#: 25 ms after the drive's return, and from 30 ms on 2 %, the expansion's own error at that Q (0.5 % at Q 400,
#: reached by 25 ms there; test_cavity_lag.py).  1.3 % of a 3 s run.
RING_UP_S = 0.04


def leave_out_ring_up(dataset, duration: float = RING_UP_S):
    """``dataset`` (:class:`cubedimer.dataset.Dataset`) with the first ``duration`` [s] of every run left out (from
    its first frame: the drive's return, t = 0 in a field-drop recording), where the cavity rings up (module
    docstring).  Glitch frames keep their places; ``frames`` (a run split at a gap) moves with the start."""
    from dataclasses import replace

    runs = []
    for run in dataset.runs:
        first = int(np.searchsorted(run.t, run.t[0] + duration - 1e-9 * max(run.dt, 1e-12)))
        if first == 0:
            runs.append(run)
            continue
        vel = None if run.velocities is None else run.velocities[first:]
        frames = None if run.frames is None else (run.frames[0] + first, run.frames[1])
        glitches = tuple(i - first for i in run.glitch_frames if i >= first)
        runs.append(replace(run, t=run.t[first:], y=run.y[first:], theta=run.theta[first:], velocities=vel,
                            frames=frames, glitch_frames=glitches))
    return replace(dataset, runs=tuple(runs))


def quasi_static_response(quality_factor: float, detuning: float) -> float:
    """``Q x / (1 + x^2)`` [-]: the mode's quasi-static response, ``-pi f A / 2`` (A = -2 x / (Gamma (1 + x^2)),
    Gamma = pi f / Q), the combination of Q and the detuning x that the quasi-static gain alone gives."""
    return float(quality_factor) * float(detuning) / (1.0 + float(detuning) ** 2)


def derived_quantities(params, calibration) -> dict[str, dict[str, float]]:
    """``{"cavity_lag": {"quality_factor", "detuning_half_widths", "quasi_static_response"}}`` of a fit whose effects
    hold the cavity's lag (else ``{}``): its gains, fitted on the columns at the nominal pressure (the acoustic
    accelerations scale with the pressure scale s, the dimer's shift does not), are divided by s and turned into the
    mode (:func:`mode_from_gains`, at the default area and air; Q and x nan when no mode has them), and the static gain
    alone into ``Q x / (1 + x^2) = -pi f A / 2`` (:func:`quasi_static_response`): the combination the data resolve
    where the lag gain, and with it Q and x apart, is not (beside the air's damping of y, which shares the lag's)."""
    if "cavity_lag" not in params:
        return {}
    s = calibration.pressure_scale
    gains = CavityGains(params["cavity_lag"]["static_gain"] / s, params["cavity_lag"]["lag_gain"] / s)
    frequency = Medium().frequency_hz
    response = -math.pi * frequency * gains.static_gain / 2.0
    try:
        mode = mode_from_gains(gains, frequency)
        quality_factor, detuning = mode.quality_factor, mode.detuning
    except ValueError:
        quality_factor = detuning = math.nan
    return {"cavity_lag": {"quality_factor": quality_factor, "detuning_half_widths": detuning,
                           "quasi_static_response": response}}


def cavity_reference(problem) -> CavityMode | None:
    """The reference mode of the cavity's second-order terms on ``problem``'s data set, once
    :func:`validation.diagnosis.calibrate.gap_model.fit_cavity_reference` has fitted it (None before, and on a data
    set without a cavity mode: the first-order columns)."""
    return problem._shared.get("cavity_reference")


#: Sets of angles whose :class:`AngleFactors` a data set keeps (a run's states, its integral form's and its energy
#: balance's: three per run); beyond it the store starts over.
_ANGLE_STORE_SIZE = 256


def problem_columns(problem, state: NDArray, z_com: NDArray, z_eq: float | None) -> NDArray[np.float64]:
    """The cavity's columns (n, 2, 2) on ``problem``'s data set at ``state`` with the centre of mass at the absolute
    heights ``z_com`` [m], the detuning defined at rest at ``z_eq`` (the calibrated equilibrium; None: the data's
    origin), with the data set's reference mode (:func:`cavity_reference`).

    The force model is the problem's surrogate at nominal pressure; its :class:`CavityColumns` is built once per data
    set and the :class:`AngleFactors` once per states array (kept by identity with the array itself, so that an id
    is never reused): every fold, jackknife refit and trial origin height of the data set shares them."""
    cavity = _problem_cavity(problem)
    fm = cavity.force_model
    st = np.array(state, float, copy=True).reshape(-1, 4)
    z_com = np.broadcast_to(np.asarray(z_com, float), st[:, 0].shape)
    rest = (float(np.mean(z_com - st[:, 0])) if z_eq is None else float(z_eq)) - fm.z_eq
    st[:, 0] = z_com - fm.z_eq
    return cavity.columns(st, rest_y=rest, reference=cavity_reference(problem), angles=_angles(problem, cavity, state, st[:, 2]))


def _problem_cavity(problem) -> CavityColumns:
    """The data set's :class:`CavityColumns` (its surrogate at nominal pressure), built once."""
    shared = problem._shared
    if shared.get("cavity_columns") is None:
        shared["cavity_columns"] = CavityColumns(problem.surrogate())
    return shared["cavity_columns"]


def _angles(problem, cavity: CavityColumns, state: NDArray, theta: NDArray) -> AngleFactors:
    """The :class:`AngleFactors` of ``state``'s angles ``theta``, kept per states array for the data set."""
    store = problem._shared.setdefault("cavity_angles", {})
    held = store.get(id(state))
    if held is None or held[0] is not state or not np.array_equal(held[1].theta, theta):
        if len(store) >= _ANGLE_STORE_SIZE:
            store.clear()
        held = (state, cavity.angle_factors(theta))
        store[id(state)] = held
    return held[1]


#: The degree of the cavity's columns (each part of :meth:`CavityColumns.column_parts`) as trigonometric
#: polynomials in 2k z0 at fixed data states, the rest height at the origin z0: 2 HEIGHT_DEGREE + 1 heights give
#: them exactly (:func:`height_expansion`).
HEIGHT_DEGREE = 3


@dataclass(frozen=True, eq=False)
class HeightExpansion:
    """An effect's integral-form columns of one coordinate on a data set's runs at every origin height z0 [m]:
    ``columns(z0) = sum_b weights(z0)[b] blocks[run][b]``, exact."""

    blocks: list[NDArray[np.float64]]  #: per run (n_blocks, rows, parameters)
    weights: Callable[[float], NDArray[np.float64]]  #: z0 [m] -> (n_blocks,)


def height_expansion(problem, runs: Sequence, q: int) -> HeightExpansion | None:
    """The cavity's integral-form columns of coordinate q (0: y, 1: theta) on ``runs`` (with integral data) at every
    origin height z0, the effects' y and the rest height at the data's origin (as the calibration's height search
    asks for them: :func:`validation.diagnosis.calibrate.calibration.calibrate`).

    Each part of :meth:`CavityColumns.column_parts` is a trigonometric polynomial of degree :data:`HEIGHT_DEGREE` in
    phi = 2k z0, so its values at the 7 phases phi_j = 2 pi j / 7 give it at every phi through the Dirichlet kernel
    ``D(phi - phi_j) = (1 + 2 sum_m cos(m (phi - phi_j))) / 7``, m = 1..3; the part over F_Z,ac(0, z0) takes that
    factor at z0.  The integral form is linear, so the blocks are the parts' integral-form columns at the 7 heights,
    computed once per run and reference mode and shared by every fold and jackknife refit.  None when the force
    model's potential has a term linear in Z (its columns are not periodic in z0: evaluated at every trial height)."""
    cavity = _problem_cavity(problem)
    if not cavity.height_periodic:
        return None
    reference = cavity_reference(problem)
    two_k = float(cavity.force_model.two_k)
    n_nodes = 2 * HEIGHT_DEGREE + 1
    phases = 2.0 * np.pi * np.arange(n_nodes) / n_nodes
    store = problem._shared.setdefault("cavity_height_blocks", {})
    blocks = []
    for r in runs:
        pi = r.integral
        key = (id(pi), q, reference)
        if key not in store:
            st = pi.state
            angles = _angles(problem, cavity, st, st[:, 2])
            parts = []
            for phi in phases:
                z0 = phi / two_k
                shifted = np.array(st, float, copy=True)
                shifted[:, 0] = z0 + st[:, 0] - cavity.force_model.z_eq
                regular, over, _ = cavity.column_parts(shifted, z0 - cavity.force_model.z_eq, reference, angles)
                parts.append(pi.columns(q, np.concatenate([regular[:, q, :], over[:, q, :]], axis=1)))
            p = len(CAVITY_LAG_PARAMETERS)
            store[key] = (pi, np.stack([c[:, :p] for c in parts] + [c[:, p:] for c in parts]))
        blocks.append(store[key][1])

    def weights(z0: float) -> NDArray[np.float64]:
        m = np.arange(1, HEIGHT_DEGREE + 1)
        kernel = (1.0 + 2.0 * np.cos(np.outer(two_k * z0 - phases, m)).sum(axis=1)) / n_nodes
        return np.concatenate([kernel, kernel / float(cavity.rest_force(z0)[0])])

    return HeightExpansion(blocks, weights)
