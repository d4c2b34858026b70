"""The one compiled fixed-step RK4 integrator of second-order systems in (y, theta).

Every model of the suite (the twin's equations of motion, a fitted polynomial model, the field's ring-down and
ring-up) is a pair of accelerations ``(yddot, thetaddot) = accel(t, y, ydot, theta, thetadot, args)`` over the
state ``x = [y, ydot, theta, thetadot]``, at the time ``t`` from the first state (an autonomous model ignores it).  :func:`rk4` integrates such a model with the classical
fourth-order Runge-Kutta method at a fixed step ``h``, writing the state every ``substeps`` steps,
and stops at the first output sample that leaves a box:

* a non-finite component stops with :data:`STATUS_NONFINITE`;
* component ``i`` below ``lower[i]`` or above ``upper[i]`` stops with :func:`box_status` ``(i, upper)``
  (checked in the order y, ydot, theta, thetadot).

The samples written before the stop are valid; the function returns ``(n_valid, status)``.  The
box expresses both the twin's stop rules (falling out of the trap below y_lo, rising past the node,
the hinge closing at |theta| = 1) and the blow-up bound of the fitted models (|x_i| <= bound_i).

``accel`` is a numba-compiled function passed as a first-class argument and ``args`` any tuple
(usually of arrays) it reads.  The drivers are inlined into their caller at numba's IR level, so
the acceleration function becomes a global of the caller, is called directly (and inlined by
LLVM) and the caller can be cached on disk.  Write the entry point of a model as::

    @nb.njit(cache=True)
    def integrate_my_model(args, x0, h, substeps, n_out, lower, upper, out):
        return rk4(my_accel, args, x0, h, substeps, n_out, lower, upper, out)

Calling :func:`rk4` from Python with a dispatcher works too, but numba then compiles it anew in
every process (a dispatcher argument has no stable cache key).

One RK4 step costs four acceleration evaluations; with ``h omega <= 0.05`` the phase error is about
``(h omega)^5 / 120`` per step.
"""
from __future__ import annotations

import numba as nb
import numpy as np

__all__ = ["rk4", "rk4_batch", "STATUS_OK", "STATUS_NONFINITE", "box_status", "describe_status"]

#: The whole span was integrated.
STATUS_OK = 0
#: A state component became non-finite.
STATUS_NONFINITE = 1

_COMPONENTS = ("y", "ydot", "theta", "thetadot")


def box_status(component: int, upper: bool) -> int:
    """Status code of leaving the box through component ``component`` (0..3) at its upper or lower bound."""
    return 2 + 2 * int(component) + int(bool(upper))


def describe_status(status: int) -> str:
    """A short English description of a status code of :func:`rk4`."""
    if status == STATUS_OK:
        return "ok"
    if status == STATUS_NONFINITE:
        return "the state became non-finite"
    i, up = divmod(int(status) - 2, 2)
    return f"{_COMPONENTS[i]} went {'above its upper' if up else 'below its lower'} bound"


@nb.njit(cache=True)
def _box_check(y, yd, th, thd, lower, upper):
    """0 inside the box, else the status code of the first violation."""
    if not (np.isfinite(y) and np.isfinite(yd) and np.isfinite(th) and np.isfinite(thd)):
        return 1
    x = (y, yd, th, thd)
    for i in range(4):
        if x[i] < lower[i]:
            return 2 + 2 * i
        if x[i] > upper[i]:
            return 3 + 2 * i
    return 0


@nb.njit(cache=True, inline="always")
def rk4(accel, args, x0, h, substeps, n_out, lower, upper, out):
    """Fixed-step RK4 of ``accel`` from ``x0``; the state every ``substeps`` steps of length ``h``.

    Parameters
    ----------
    accel : numba-compiled function
        ``accel(t, y, ydot, theta, thetadot, args) -> (yddot, thetaddot)``, ``t`` from the first state (the
        stages at t, t + h/2 (twice) and t + h of each step).
    args : tuple
        Passed to ``accel`` unchanged.
    x0 : ndarray (4,)
        Initial [y, ydot, theta, thetadot].
    h : float
        Step (time unit of the model).
    substeps : int
        Steps per output sample.
    n_out : int
        Output samples including ``x0``.
    lower, upper : ndarray (4,)
        The box (``-inf`` / ``inf`` for no bound).
    out : ndarray (>= n_out, 4)
        Filled with the states at ``t = k substeps h`` for k < n_valid.

    Returns
    -------
    (n_valid, status)
        Number of valid rows of ``out`` and :data:`STATUS_OK`, :data:`STATUS_NONFINITE` or a
        :func:`box_status` code.
    """
    y, yd, th, thd = x0[0], x0[1], x0[2], x0[3]
    out[0, 0] = y
    out[0, 1] = yd
    out[0, 2] = th
    out[0, 3] = thd
    hh = 0.5 * h
    h6 = h / 6.0
    t = 0.0
    for i in range(1, n_out):
        for _ in range(substeps):
            a1, b1 = accel(t, y, yd, th, thd, args)
            y2, yd2, th2, thd2 = y + hh * yd, yd + hh * a1, th + hh * thd, thd + hh * b1
            a2, b2 = accel(t + hh, y2, yd2, th2, thd2, args)
            y3, yd3, th3, thd3 = y + hh * yd2, yd + hh * a2, th + hh * thd2, thd + hh * b2
            a3, b3 = accel(t + hh, y3, yd3, th3, thd3, args)
            y4, yd4, th4, thd4 = y + h * yd3, yd + h * a3, th + h * thd3, thd + h * b3
            a4, b4 = accel(t + h, y4, yd4, th4, thd4, args)
            y = y + h6 * (yd + 2.0 * yd2 + 2.0 * yd3 + yd4)
            yd = yd + h6 * (a1 + 2.0 * a2 + 2.0 * a3 + a4)
            th = th + h6 * (thd + 2.0 * thd2 + 2.0 * thd3 + thd4)
            thd = thd + h6 * (b1 + 2.0 * b2 + 2.0 * b3 + b4)
            t += h
        status = _box_check(y, yd, th, thd, lower, upper)
        if status != 0:
            return i, status
        out[i, 0] = y
        out[i, 1] = yd
        out[i, 2] = th
        out[i, 3] = thd
    return n_out, 0


@nb.njit(cache=True, inline="always")
def rk4_batch(accel, args, x0s, h, substeps, n_out, lower, upper, out, n_valid, status):
    """:func:`rk4` of one model (shared ``args``) from B initial states ``x0s`` (B, 4).

    ``h`` (B,), ``n_out`` (B,) and the box ``lower``/``upper`` (B, 4) are per trajectory; ``out``
    (B, max n_out, 4), ``n_valid`` (B,) and ``status`` (B,) are filled.  Serial on purpose:
    parallelism comes from the process pool (:mod:`cubedimer.executor`), and numba's threading layer
    is not fork-safe.
    """
    for b in range(x0s.shape[0]):
        n_valid[b], status[b] = rk4(accel, args, x0s[b], h[b], substeps, n_out[b], lower[b], upper[b], out[b])
