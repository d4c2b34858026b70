"""The equations of motion of the hinged cube dimer (docs/conventions.md section 4) plus the effects of section 5.

State ``x = [y, ydot, theta, thetadot]`` (m, m/s, -, 1/s).  With the field on, for any
:class:`~acousim.force_model.ForceModel`::

    yddot     = Q_y(theta, y) / M                                          + effects
    thetaddot = [ Q_theta(theta, y) - 1/2 I'(theta) thetadot^2 ] / I(theta) + effects

(Lagrange's equations with ``T = 1/2 M ydot^2 + 1/2 I(theta) thetadot^2``,
``I(theta) = I_0 + I_2 sin^2(pi theta / 4)``).  With the field off (the drop of the field-drop
protocol) there is no acoustic force or torque: ``yddot = -g`` and
``thetaddot = -1/2 I'/I thetadot^2`` (the hinge is free); the air's effects keep acting
(:meth:`~acousim.dynamics.effects.EffectSet.acting`).

This module is the one place where a force model and effects become accelerations:

* :func:`accelerations`: the numpy reference, on arrays of states;
* :func:`hinge_acceleration`: Lagrange's theta equation, the one definition of the hinge term
  (the compiled kernel compiles the same source);
* :func:`field_on_acceleration` / :func:`field_off_acceleration`: the compiled per-state
  accelerations ``accel(y, ydot, theta, thetadot, args)`` that :func:`cubedimer.rk4.rk4` integrates,
  with ``args = kernel_arguments(force_model, effects, field_on)``: the six Chebyshev series of
  :meth:`~acousim.force_model.ForceModel.force_coefficients`, the scalar parameters, the packed
  effect parameters (:meth:`~acousim.dynamics.effects.EffectSet.packed`) and the compiled columns of the registered effects
  beyond docs/conventions.md (:func:`~acousim.dynamics.compiled_effects.registered_effect_kernels`, usually none).
"""
from __future__ import annotations

import numba as nb
import numpy as np
from numpy.typing import ArrayLike, NDArray

from .compiled_effects import packed_effect_accelerations, registered_effect_kernels
from .effects import EffectSet
from ..force_model import ForceModel

__all__ = [
    "accelerations",
    "hinge_acceleration",
    "kernel_arguments",
    "field_on_acceleration",
    "field_off_acceleration",
    "state_derivative",
]

_QUARTER_PI = 0.7853981633974483  # pi / 4: phi = pi theta / 4

# layout of the scalar parameter array of kernel_arguments
_P_TWO_K, _P_ZEQ, _P_MASS, _P_MG, _P_I0, _P_I2, _P_K, _P_G = range(8)


def hinge_acceleration(q_theta, inertia, inertia_derivative, thetadot):
    """Lagrange's theta equation without the effects: ``(Q_theta - 1/2 I' thetadot^2) / I`` [1/s^2].

    Parameters
    ----------
    q_theta : float or ndarray
        Generalised force Q_theta [N m] (0 with the field off).
    inertia, inertia_derivative : float or ndarray
        I(theta) and dI/dtheta [kg m^2].
    thetadot : float or ndarray
        [1/s].
    """
    return (q_theta - 0.5 * inertia_derivative * thetadot * thetadot) / inertia


_hinge_acceleration = nb.njit(cache=True)(hinge_acceleration)


def accelerations(force_model: ForceModel, effects: EffectSet, state: ArrayLike,
                  field_on: bool = True) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """(yddot [m/s^2], thetaddot [1/s^2]) for states (..., 4): numpy reference of the equations of motion.

    Parameters
    ----------
    force_model : ForceModel
    effects : EffectSet
        With the field off only the air's effects act.
    state : array_like (..., 4)
        [y, ydot, theta, thetadot] with y measured from ``force_model.z_eq``.
    field_on : bool
        Acoustic field on (trap) or off (free fall, free hinge).
    """
    x = np.asarray(state, float)
    y, yd, th, thd = x[..., 0], x[..., 1], x[..., 2], x[..., 3]
    fm = force_model
    inertia, d_inertia = fm.hinge_inertia(th), fm.hinge_inertia_derivative(th)
    if field_on:
        q_y, q_t = fm.generalized_forces(th, y)
        ay = q_y / fm.mass
    else:
        q_t = 0.0
        ay = np.full_like(y, -fm.gravity)
    at = hinge_acceleration(q_t, inertia, d_inertia, thd)
    ey, et = effects.acting(field_on).accelerations(y, yd, th, thd, fm.wavenumber, fm.z_eq)
    return ay + ey, at + et


def kernel_arguments(force_model: ForceModel, effects: EffectSet, field_on: bool = True) -> tuple:
    """The ``args`` tuple of :func:`field_on_acceleration` / :func:`field_off_acceleration`:
    (A_y, B_y, C_y, A_theta, B_theta, C_theta, scalar parameters, packed effect parameters, registered effect
    kernels)."""
    fm = force_model
    par = np.array([fm.two_k, fm.z_eq, fm.mass, fm.mass * fm.gravity, fm.inertia_const, fm.inertia_sin2,
                    fm.wavenumber, fm.gravity], float)
    eff = np.ascontiguousarray(effects.acting(field_on).packed())
    return tuple(fm.force_coefficients().as_tuple()) + (par, eff, registered_effect_kernels())


@nb.njit(cache=True)
def _chebval(c, x):
    """Clenshaw evaluation of sum_j c_j T_j(x)."""
    b1 = 0.0
    b2 = 0.0
    x2 = 2.0 * x
    for j in range(c.shape[0] - 1, 0, -1):
        b0 = c[j] + x2 * b1 - b2
        b2 = b1
        b1 = b0
    return c[0] + x * b1 - b2


@nb.njit(cache=True)
def _inertia(theta, par):
    """(I(theta), dI/dtheta) [kg m^2] from the scalar parameters."""
    phi = _QUARTER_PI * theta
    sphi = np.sin(phi)
    return par[_P_I0] + par[_P_I2] * sphi * sphi, par[_P_I2] * _QUARTER_PI * np.sin(2.0 * phi)


@nb.njit(cache=True)
def field_on_acceleration(t, y, ydot, theta, thetadot, args):
    """Compiled (yddot, thetaddot) of one state with the field on; ``args`` from :func:`kernel_arguments` (``t`` [s]:
    the :func:`cubedimer.rk4.rk4` contract; the field-on dynamics are autonomous)."""
    a_y, b_y, c_y, a_t, b_t, c_t, par, eff, registered = args
    inertia, d_inertia = _inertia(theta, par)
    z = par[_P_ZEQ] + y
    c = np.cos(par[_P_TWO_K] * z)
    s = np.sin(par[_P_TWO_K] * z)
    q_y = _chebval(a_y, theta) + _chebval(b_y, theta) * c + _chebval(c_y, theta) * s - par[_P_MG]
    q_t = _chebval(a_t, theta) + _chebval(b_t, theta) * c + _chebval(c_t, theta) * s
    ey, et = packed_effect_accelerations(y, ydot, theta, thetadot, par[_P_K], par[_P_ZEQ], eff, registered)
    return q_y / par[_P_MASS] + ey, _hinge_acceleration(q_t, inertia, d_inertia, thetadot) + et


@nb.njit(cache=True)
def field_off_acceleration(t, y, ydot, theta, thetadot, args):
    """Compiled (yddot, thetaddot) of one state with the field off (``args`` built with ``field_on=False``;
    autonomous, ``t`` unused)."""
    par, eff, registered = args[6], args[7], args[8]
    inertia, d_inertia = _inertia(theta, par)
    ey, et = packed_effect_accelerations(y, ydot, theta, thetadot, par[_P_K], par[_P_ZEQ], eff, registered)
    return -par[_P_G] + ey, _hinge_acceleration(0.0, inertia, d_inertia, thetadot) + et


@nb.njit(cache=True)
def state_derivative(x, args, field_on):
    """Compiled dx/dt = [ydot, yddot, thetadot, thetaddot] of one state (4,)."""
    out = np.empty(4)
    if field_on:
        ay, at = field_on_acceleration(0.0, x[0], x[1], x[2], x[3], args)
    else:
        ay, at = field_off_acceleration(0.0, x[0], x[1], x[2], x[3], args)
    out[0] = x[1]
    out[1] = ay
    out[2] = x[3]
    out[3] = at
    return out
