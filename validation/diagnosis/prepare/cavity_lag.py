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
           "derived_quantities"]

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


def cavity_lag_columns(force_model, state: ArrayLike, area: float = DEFAULT_CAVITY_AREA,
                       medium: Medium | None = None, rest_y: float = 0.0) -> NDArray[np.float64]:
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
    accel = np.stack([f_z / force_model.mass, q_t / force_model.hinge_inertia(th)], axis=1)  # (n, 2)
    return np.stack([accel * delta[:, None], accel * delta_rate[:, None]], axis=2)


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
