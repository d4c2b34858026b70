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

import numpy as np
from numpy.typing import ArrayLike, NDArray

from acousim.dynamics.resonator import (DEFAULT_CAVITY_AREA, CavityMode, mode_energy, potential_series,
                                       slow_response_gains)
from acousim.medium import Medium

__all__ = ["CAVITY_LAG_PARAMETERS", "CavityGains", "gains_from_mode", "mode_from_gains", "cavity_lag_columns",
           "second_order_ratios", "cavity_reference", "derived_quantities"]

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
    columns (A, B), as :func:`~validation.diagnosis.prepare.candidate_effects.effect_regressors` gives them.

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
    medium = Medium() if medium is None else medium
    y, yd, th, thd = np.atleast_2d(np.asarray(state, float)).T
    pot = potential_series(force_model)
    w = 2.0 * math.pi * medium.frequency_hz
    shift = w / mode_energy(force_model.pressure_amplitude_pa, area, medium)  # [rad/s per J]
    q_y, q_t = force_model.generalized_forces(th, y)
    f_z = q_y + force_model.mass * force_model.gravity  # the acoustic vertical force [N]
    delta = shift * (pot(th, y) - pot(0.0, rest_y))
    delta_rate = -shift * (f_z * yd + q_t * thd)
    inertia = force_model.hinge_inertia(th)
    accel = np.stack([f_z / force_model.mass, q_t / inertia], axis=1)  # (n, 2)
    static, lag = delta, delta_rate
    if reference is not None:
        a2, r2, b2, r3 = second_order_ratios(reference, medium.frequency_hz)
        curvature, omega2 = _detuning_curvature(force_model, y, yd, th, thd, f_z, q_t, inertia, shift, rest_y)
        static = delta + a2 * delta**2 + r2 * curvature
        # the third derivative as -w_y^2 delta' (the vertical oscillation's own frequency; the hinge barely moves delta)
        lag = delta_rate * (1.0 + b2 * delta - r3 * omega2)
    return np.stack([accel * static[:, None], accel * lag[:, None]], axis=2)


def _detuning_curvature(force_model, y, yd, th, thd, f_z, q_t, inertia, shift, rest_y):
    """d^2(delta)/dt^2 [rad/s^3] along the simulation's own motion: ``-shift d(F_Z ydot + Q_theta thetadot)/dt`` with
    the accelerations of the simulation at the pressure that holds the dimer at its rest height,
    ``yddot = g (F_Z / F_Z(0, rest) - 1)`` and ``thetaddot = g M Q_theta / (F_Z(0, rest) I)`` (no measured
    acceleration: their noise would enter), and the forces' gradients by central differences; with the vertical
    trap's w_y^2 at rest [1/s^2]."""
    h_y, h_t = 1e-7, 1e-4  # [m], [rad]: truncation (2k h_y)^2 ~ 1e-7 relative, round-off ~1e-8
    fz_up, qt_up = force_model.generalized_forces(th, y + h_y)
    fz_dn, qt_dn = force_model.generalized_forces(th, y - h_y)
    fz_r, qt_r = force_model.generalized_forces(th + h_t, y)
    fz_l, qt_l = force_model.generalized_forces(th - h_t, y)
    m, g = force_model.mass, force_model.gravity
    f_rest = float(np.asarray(force_model.generalized_forces(0.0, rest_y)[0])) + m * g
    f_dot = (fz_up - fz_dn) / (2 * h_y) * yd + (fz_r - fz_l) / (2 * h_t) * thd
    q_dot = (qt_up - qt_dn) / (2 * h_y) * yd + (qt_r - qt_l) / (2 * h_t) * thd
    ydd, thdd = g * (f_z / f_rest - 1.0), g * m * q_t / (f_rest * inertia)
    f_up = float(np.asarray(force_model.generalized_forces(0.0, rest_y + h_y)[0]))
    f_dn = float(np.asarray(force_model.generalized_forces(0.0, rest_y - h_y)[0]))
    omega2 = -g * (f_up - f_dn) / (2 * h_y) / f_rest  # w_y^2 at rest [1/s^2]
    return -shift * (f_z * ydd + q_t * thdd + f_dot * yd + q_dot * thd), omega2


def derived_quantities(params, calibration) -> dict[str, dict[str, float]]:
    """``{"cavity_lag": {"quality_factor", "detuning_half_widths"}}`` of a fit whose effects hold the cavity's lag (else
    ``{}``): its gains, fitted on the columns at the nominal pressure (the acoustic accelerations scale with the
    pressure scale s, the dimer's shift does not), are divided by s and turned into the mode (:func:`mode_from_gains`,
    at the default area and air); nan when no mode has them."""
    if "cavity_lag" not in params:
        return {}
    s = calibration.pressure_scale
    gains = CavityGains(params["cavity_lag"]["static_gain"] / s, params["cavity_lag"]["lag_gain"] / s)
    try:
        mode = mode_from_gains(gains, Medium().frequency_hz)
    except ValueError:
        return {"cavity_lag": {"quality_factor": math.nan, "detuning_half_widths": math.nan}}
    return {"cavity_lag": {"quality_factor": mode.quality_factor, "detuning_half_widths": mode.detuning}}



def cavity_reference(problem) -> CavityMode | None:
    """The reference mode of the cavity's second-order terms on ``problem``'s data set, once
    :func:`validation.diagnosis.calibrate.gap_model.fit_cavity_reference` has fitted it (None before, and on a data
    set without a cavity mode: the first-order columns)."""
    return problem._shared.get("cavity_reference")
