"""The field's switching: the transducer's ring-down and ring-up, and the motion of a field drop.

A transducer of quality factor Q driven at f is a resonator: when its drive stops, the pressure amplitude decays
as ``exp(-t / tau)``, and when the drive comes back (in phase) it rises towards p0 with the same time constant,

    tau = Q / (pi f)                       (the amplitude's ring time; 1.0-2.8 ms for Q = 150-400 at 45.65 kHz)

so the pressure amplitude relative to p0 is ``a(t) = a_end + (a_start - a_end) exp(-t / tau)``, with a_start = 1,
a_end = 0 while the drive is off and a_start = exp(-t_off / tau) (what is left), a_end = 1 once it is back.  The
acoustic forces are time averages over the acoustic period (22 us), far shorter than tau, so they follow the
envelope quasi-statically and scale exactly as ``s(t) = a(t)^2``:

    xddot = xddot_off + s(t) (xddot_on - xddot_off)

where ``xddot_on`` are the accelerations with the field on (:func:`acousim.dynamics.equations.field_on_acceleration`, the
acoustic forces and every effect) and ``xddot_off`` those with it off (gravity, the free hinge's inertial term and
the effects that act without the field, :meth:`acousim.dynamics.effects.EffectSet.acting`).  The difference holds the
acoustic generalised forces and the effects that need the field, so exactly those scale with p(t)^2 / p0^2.

:func:`field_drop` runs the drop protocol (off for ``t_off``, then on): with ``tau = 0`` the switch is instant, as
the twin's default; otherwise the off phase and the first :data:`RING_SPAN` tau of the on phase are integrated
with the envelope (the core RK4, :func:`cubedimer.rk4.rk4`, which evaluates the envelope at its stages' times t,
t + h/2 and t + h), and the rest with the field fully on (the forces are then within
2 exp(-20) = 4e-9 of their full value, relative).

The ring is the levitator's cavity mode (:mod:`acousim.dynamics.resonator`) when the dimer does not detune it: the
envelope equation ``da/dt = -(Gamma + i Delta) a + Gamma a_d`` with Delta = 0, Gamma = 1 / tau and the drive a_d
switched from 1 to 0 and back, whose exact solution is the a(t) above.  With the dimer detuning the mode,
:func:`acousim.dynamics.resonator.coupled_field_drop` integrates the same equation with the motion; with the coupling
removed it reproduces this module's ring (tests/acousim/dynamics/test_resonator.py).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numba as nb
import numpy as np
from numpy.typing import ArrayLike, NDArray

from cubedimer.rk4 import rk4

from .equations import field_off_acceleration, field_on_acceleration

__all__ = ["DEFAULT_TRANSDUCER_Q", "RING_SPAN", "ring_time", "pressure_ratio", "switching_acceleration",
           "FieldDrop", "field_drop"]

#: The transducer quality factor the twin states when a ring time is asked for (within the range 150-400 of
#: Langevin transducers of acoustic levitators at 40-50 kHz; tau = 1.74 ms at 45.65 kHz).
DEFAULT_TRANSDUCER_Q = 250.0
#: Ring times after the drive is back over which the envelope is integrated (then the field counts as fully on).
RING_SPAN = 20.0


def ring_time(quality_factor: float, frequency_hz: float) -> float:
    """The transducer's amplitude ring time tau = Q / (pi f) [s] (0 for Q = 0: an instant switch)."""
    q, f = float(quality_factor), float(frequency_hz)
    if not (math.isfinite(q) and q >= 0 and math.isfinite(f) and f > 0):
        raise ValueError(f"need a quality factor >= 0 and a frequency > 0, got Q = {quality_factor!r}, "
                         f"f = {frequency_hz!r} Hz")
    return q / (math.pi * f)


def pressure_ratio(t: ArrayLike, tau: float, a_start: float, a_end: float) -> NDArray[np.float64]:
    """p(t) / p0 = a_end + (a_start - a_end) exp(-t / tau) (a step to a_end for tau = 0)."""
    t = np.asarray(t, float)
    if tau <= 0:
        return np.full_like(t, float(a_end))
    return a_end + (a_start - a_end) * np.exp(-t / tau)


@nb.njit(cache=True)
def _envelope(t, tau, a_start, a_end):
    a = a_end + (a_start - a_end) * np.exp(-t / tau)
    return a * a


@nb.njit(cache=True)
def switching_acceleration(y, ydot, theta, thetadot, s, args_on, args_off):
    """(yddot, thetaddot) with the acoustic forces scaled by s = p(t)^2 / p0^2 (module docstring)."""
    ay_on, at_on = field_on_acceleration(0.0, y, ydot, theta, thetadot, args_on)
    ay_off, at_off = field_off_acceleration(0.0, y, ydot, theta, thetadot, args_off)
    return ay_off + s * (ay_on - ay_off), at_off + s * (at_on - at_off)


@nb.njit(cache=True)
def _ringing_acceleration(t, y, ydot, theta, thetadot, args):
    """:func:`switching_acceleration` at s(t) = a(t)^2, a(t) = a_end + (a_start - a_end) exp(-t / tau), ``t`` [s]
    from the start of the ring; ``args = (args_on, args_off, tau, a_start, a_end)``."""
    args_on, args_off, tau, a_start, a_end = args
    return switching_acceleration(y, ydot, theta, thetadot, _envelope(t, tau, a_start, a_end), args_on, args_off)


@nb.njit(cache=True)
def _integrate_switching(args, x0, h, substeps, n_out, lower, upper, out):
    """The core RK4 (:func:`cubedimer.rk4.rk4`) of :func:`_ringing_acceleration`."""
    return rk4(_ringing_acceleration, args, x0, h, substeps, n_out, lower, upper, out)


@dataclass(frozen=True, eq=False)
class FieldDrop:
    """The motion of one field drop.

    Attributes
    ----------
    state_at_field_on : ndarray (4,)
        The state when the drive comes back (the end of the off phase; the last valid state if it stopped there).
    trajectory : Trajectory or None
        From the moment the drive is back (t = 0), sampled at ``dt_out``; None if the drop stopped during the off
        phase.
    status : int
        0, or the key of :data:`acousim.dynamics.integrator.STATUS_MESSAGES` that stopped the motion.
    t_stop : float
        When it stopped [s] from the moment the drive is back (negative: during the off phase); NaN if it did not.
    pressure_at_field_on : float
        |p| / p0 when the drive comes back (exp(-t_off / tau); 0 for an instant switch).
    mode : ndarray of complex or None
        With a coupled cavity (:func:`acousim.dynamics.resonator.coupled_field_drop`): the mode's amplitude a = A / p0 at the
        trajectory's samples (:mod:`acousim.dynamics.resonator`); None otherwise.
    """

    state_at_field_on: NDArray[np.float64]
    trajectory: object
    status: int
    t_stop: float
    pressure_at_field_on: float
    mode: NDArray[np.complex128] | None = None

    @property
    def ok(self) -> bool:
        return self.status == 0


def field_drop(dynamics, x_drop: ArrayLike, t_off: float, duration: float, dt_out: float, tau: float = 0.0,
               max_step: float | None = None) -> FieldDrop:
    """The field-drop protocol: the drive off for ``t_off`` [s], then on for ``duration`` [s] sampled every
    ``dt_out`` [s], with the transducer's ring time ``tau`` [s] (0: instant switching).

    Parameters
    ----------
    dynamics : acousim.dynamics.integrator.DimerDynamics
    x_drop : array_like (4,)
        [y, ydot, theta, thetadot] when the drive stops.
    t_off, duration, dt_out, tau : float
        [s].
    max_step : float, optional
        Longest internal RK4 step [s] (default :data:`acousim.dynamics.integrator.DEFAULT_MAX_STEP`).

    Returns
    -------
    FieldDrop
        A run that leaves the trap or folds (theta = +-1) stops there; the samples up to then are valid.
    """
    from .integrator import DEFAULT_MAX_STEP, Trajectory

    max_step = DEFAULT_MAX_STEP if max_step is None else float(max_step)
    if not (math.isfinite(tau) and tau >= 0):
        raise ValueError(f"the ring time must be >= 0, got {tau!r} s")
    x = np.asarray(x_drop, float).reshape(4)
    a_on = math.exp(-t_off / tau) if tau > 0 else 0.0
    if t_off > 0:
        if tau > 0:
            fall = _switching(dynamics, x, t_off, t_off, tau, 1.0, 0.0, max_step, dynamics._box_off)
        else:
            fall = dynamics.integrate(x, t_off, t_off, max_step=max_step, field_on=False)
        if not fall.ok:
            return FieldDrop(fall.state[-1], None, fall.status, -float(t_off), a_on)
        x = fall.state[-1]
    x_on = x.copy()
    if tau > 0 and a_on < 1.0:
        n_ring = min(int(round(duration / dt_out)), int(math.ceil(RING_SPAN * tau / dt_out)))
        ring = _switching(dynamics, x, n_ring * dt_out, dt_out, tau, a_on, 1.0, max_step, dynamics._box_on)
        if not ring.ok or n_ring * dt_out >= duration - 0.5 * dt_out:
            return FieldDrop(x_on, ring, ring.status, float(ring.t[-1]) if not ring.ok else float("nan"), a_on)
        rest = dynamics.integrate(ring.state[-1], duration - n_ring * dt_out, dt_out, max_step=max_step, field_on=True)
        traj = Trajectory(t=np.arange(n_ring + rest.t.size) * dt_out,
                          state=np.concatenate([ring.state[:-1], rest.state]), status=rest.status)
    else:
        traj = dynamics.integrate(x, duration, dt_out, max_step=max_step, field_on=True)
    return FieldDrop(x_on, traj, traj.status, float(traj.t[-1]) if not traj.ok else float("nan"), a_on)


def _switching(dynamics, x0, duration, dt_out, tau, a_start, a_end, max_step, box):
    """:class:`~acousim.dynamics.integrator.Trajectory` of the envelope-scaled dynamics (module docstring)."""
    from .integrator import Trajectory, _STATUS

    n_out, substeps = dynamics._steps(duration, dt_out, max_step)
    out = np.empty((n_out, 4))
    args = (dynamics._args_on, dynamics._args_off, float(tau), float(a_start), float(a_end))
    n, status = _integrate_switching(args, np.asarray(x0, float), dt_out / substeps, substeps, n_out, *box, out)
    return Trajectory(t=np.arange(n) * dt_out, state=out[:n], status=_STATUS[int(status)])
