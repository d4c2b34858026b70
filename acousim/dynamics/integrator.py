"""Integration of the equations of motion (:mod:`acousim.dynamics.equations`) of the dimer.

:class:`DimerDynamics` pairs a :class:`~acousim.force_model.ForceModel` (the Gor'kov surrogate
today) with an :class:`~acousim.dynamics.effects.EffectSet` and integrates the state
``x = [y, ydot, theta, thetadot]`` (m, m/s, -, 1/s) with the suite's compiled fixed-step RK4
(:func:`cubedimer.rk4.rk4`).  The internal step is the output interval divided into equal sub-steps
no longer than ``max_step`` (default 50 us, i.e. 20 kHz: h omega <= 0.007 for the 22 Hz trap, RK4
relative energy error ~1e-9 over 100 periods, see the tests).

Integration stops, and reports why (:data:`STATUS_MESSAGES`), when the dimer leaves the trap (falls
below the barrier height, or rises beyond a quarter wavelength above the node; with the field on
only), theta reaches +-1 (faces in contact) or the state stops being finite.
:meth:`DimerDynamics.rhs` is the same compiled right-hand side for ``scipy.integrate.solve_ivp``
(the cross-check of the compiled integrator).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numba as nb
import numpy as np
from numpy.typing import ArrayLike, NDArray

from cubedimer.rk4 import STATUS_NONFINITE, STATUS_OK, box_status, rk4, rk4_batch

from .effects import EffectSet
from .equations import (accelerations, field_off_acceleration, field_on_acceleration, kernel_arguments,
                        state_derivative)
from ..force_model import ForceModel

__all__ = ["DimerDynamics", "Trajectory", "STATUS_MESSAGES", "DEFAULT_MAX_STEP"]

#: Default longest internal RK4 step [s] (20 kHz).
DEFAULT_MAX_STEP = 5e-5

#: Integration status codes and their meaning.
STATUS_MESSAGES = {
    0: "ok",
    1: "the dimer fell out of the trap (below the potential barrier)",
    2: "theta reached +-1 (the cube faces touch)",
    3: "the state became non-finite",
    4: "the dimer rose beyond a quarter wavelength above the node",
}

# status of cubedimer.rk4 -> key of STATUS_MESSAGES
_STATUS = {STATUS_OK: 0, STATUS_NONFINITE: 3, box_status(0, False): 1, box_status(0, True): 4,
           box_status(2, False): 2, box_status(2, True): 2}

# the largest float below 1: "theta <= _BELOW_ONE" is "theta < 1"
_BELOW_ONE = float(np.nextafter(1.0, 0.0))


@nb.njit(cache=True)
def _integrate_field_on(args, x0, h, substeps, n_out, lower, upper, out):
    return rk4(field_on_acceleration, args, x0, h, substeps, n_out, lower, upper, out)


@nb.njit(cache=True)
def _integrate_field_off(args, x0, h, substeps, n_out, lower, upper, out):
    return rk4(field_off_acceleration, args, x0, h, substeps, n_out, lower, upper, out)


@nb.njit(cache=True)
def _integrate_field_on_batch(args, x0s, h, substeps, n_out, lower, upper, out, n_valid, status):
    rk4_batch(field_on_acceleration, args, x0s, h, substeps, n_out, lower, upper, out, n_valid, status)


@dataclass(frozen=True, eq=False)
class Trajectory:
    """Output of :meth:`DimerDynamics.integrate`.

    Attributes
    ----------
    t : ndarray (n,)
        Times [s] of the valid samples.
    state : ndarray (n, 4)
        [y, ydot, theta, thetadot] (m, m/s, -, 1/s).
    status : int
        0 if the whole span was integrated, else a key of :data:`STATUS_MESSAGES`.
    """

    t: NDArray[np.float64]
    state: NDArray[np.float64]
    status: int = 0

    @property
    def ok(self) -> bool:
        return self.status == 0

    @property
    def message(self) -> str:
        return STATUS_MESSAGES[self.status]

    @property
    def y(self) -> NDArray[np.float64]:
        return self.state[:, 0]

    @property
    def theta(self) -> NDArray[np.float64]:
        return self.state[:, 2]


@dataclass(frozen=True, eq=False)
class DimerDynamics:
    """Equations of motion of the dimer: a force model plus an :class:`EffectSet`.

    Parameters
    ----------
    force_model : ForceModel
        Generalised forces and their height structure (sets the pressure, side, Z_eq, masses and
        inertia), e.g. :class:`~acousim.gorkov.energy_surrogate.ForceSurrogate`.
    effects : EffectSet
        The unmodelled effects switched on (default none).

    Examples
    --------
    >>> dyn = DimerDynamics(cached_surrogate(), EffectSet.parse(["linear_damping:gamma_y=0.3"]))  # doctest: +SKIP
    >>> traj = dyn.integrate([100e-6, 0, 0.1, 0], duration=4.0, dt_out=1 / 2000)            # doctest: +SKIP
    """

    force_model: ForceModel
    effects: EffectSet = field(default_factory=EffectSet)

    def __post_init__(self) -> None:
        if not isinstance(self.force_model, ForceModel):
            raise TypeError(f"not a ForceModel: {type(self.force_model).__name__}")
        fm = self.force_model
        object.__setattr__(self, "_args_on", kernel_arguments(fm, self.effects, True))
        object.__setattr__(self, "_args_off", kernel_arguments(fm, self.effects, False))
        y_lo = fm.escape_height()
        y_hi = np.pi / fm.two_k - fm.z_eq
        # the box of cubedimer.rk4: y within the trap (field on only), |theta| < 1
        lo_on = np.array([y_lo if np.isfinite(y_lo) else -1.0, -np.inf, -_BELOW_ONE, -np.inf])
        hi_on = np.array([y_hi, np.inf, _BELOW_ONE, np.inf])
        object.__setattr__(self, "_box_on", (lo_on, hi_on))
        object.__setattr__(self, "_box_off", (np.array([-np.inf, -np.inf, -_BELOW_ONE, -np.inf]),
                                              np.array([np.inf, np.inf, _BELOW_ONE, np.inf])))

    # ------------------------------------------------------------------ right-hand side
    def accelerations(self, state: ArrayLike, field_on: bool = True) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """(yddot [m/s^2], thetaddot [1/s^2]) for states (..., 4): :func:`acousim.dynamics.equations.accelerations`."""
        return accelerations(self.force_model, self.effects, state, field_on)

    def rhs(self, t: float, x: ArrayLike, field_on: bool = True) -> NDArray[np.float64]:
        """dx/dt of one state (4,) for ``scipy.integrate.solve_ivp`` (compiled; ``t`` is unused)."""
        args = self._args_on if field_on else self._args_off
        return state_derivative(np.asarray(x, float), args, bool(field_on))

    # ------------------------------------------------------------------ energy
    def kinetic_energy(self, state: ArrayLike) -> NDArray[np.float64]:
        """T = 1/2 M ydot^2 + 1/2 I(theta) thetadot^2 [J]."""
        x = np.asarray(state, float)
        fm = self.force_model
        return 0.5 * fm.mass * x[..., 1] ** 2 + 0.5 * fm.hinge_inertia(x[..., 2]) * x[..., 3] ** 2

    def energy(self, state: ArrayLike) -> NDArray[np.float64]:
        """E = T + V [J] with V = 0 at the equilibrium (conserved when no effect is on).

        Needs a force model derived from a potential (a ``potential(theta, y)`` method, as the
        Gor'kov surrogate has).
        """
        potential = getattr(self.force_model, "potential", None)
        if potential is None:
            raise TypeError(f"{type(self.force_model).__name__} has no potential: its energy is not defined")
        x = np.asarray(state, float)
        return self.kinetic_energy(x) + potential(x[..., 2], x[..., 0])

    # ------------------------------------------------------------------ integration
    @staticmethod
    def _steps(duration: float, dt_out: float, max_step: float) -> tuple[int, int]:
        if not (dt_out > 0 and duration >= 0 and max_step > 0):
            raise ValueError("need dt_out > 0, max_step > 0 and duration >= 0")
        n_out = int(round(duration / dt_out)) + 1
        return n_out, max(1, int(np.ceil(dt_out / max_step - 1e-9)))

    def integrate(self, x0: ArrayLike, duration: float, dt_out: float, max_step: float = DEFAULT_MAX_STEP,
                  field_on: bool = True) -> Trajectory:
        """Fixed-step RK4 (compiled) from ``x0`` over ``duration`` [s], sampled every ``dt_out`` [s].

        Parameters
        ----------
        x0 : array_like (4,)
            Initial [y, ydot, theta, thetadot].
        duration : float
            Span [s]; the output holds ``round(duration / dt_out) + 1`` samples at t = k dt_out.
        dt_out : float
            Output interval [s]; divided into equal RK4 steps no longer than ``max_step``.
        max_step : float
            Longest internal step [s].
        field_on : bool
            Acoustic field on (trap) or off (free fall, free hinge).

        Returns
        -------
        Trajectory
            Stops early (``status != 0``) if the dimer leaves the trap, theta reaches +-1 or the
            state becomes non-finite; the samples up to then are valid.
        """
        x0 = np.asarray(x0, float).reshape(4)
        n_out, substeps = self._steps(duration, dt_out, max_step)
        if abs(x0[2]) >= 1:
            raise ValueError(f"initial theta must lie in (-1, 1), got {x0[2]!r}")
        out = np.empty((n_out, 4))
        if field_on:
            n, status = _integrate_field_on(self._args_on, x0, dt_out / substeps, substeps, n_out, *self._box_on, out)
        else:
            n, status = _integrate_field_off(self._args_off, x0, dt_out / substeps, substeps, n_out, *self._box_off, out)
        return Trajectory(t=np.arange(n) * dt_out, state=out[:n], status=_STATUS[int(status)])

    def integrate_batch(self, x0s: ArrayLike, duration: float, dt_out: float, max_step: float = DEFAULT_MAX_STEP,
                        y_bound: float | None = None) -> tuple[NDArray[np.float64], NDArray[np.int64], NDArray[np.int64]]:
        """:meth:`integrate` (field on) from B initial states at once, in one compiled call.

        Parameters
        ----------
        x0s : array_like (B, 4)
            Initial states.
        duration, dt_out, max_step : float
            As for :meth:`integrate`.
        y_bound : float, optional
            Also stop a trajectory when |y| exceeds this [m] (besides the trap's own limits).

        Returns
        -------
        states : ndarray (B, n, 4)
            Rows from ``n_valid[b]`` on are NaN.
        n_valid : ndarray of int (B,)
        status : ndarray of int (B,)
            Keys of :data:`STATUS_MESSAGES`.
        """
        x0s = np.ascontiguousarray(np.atleast_2d(np.asarray(x0s, float)))
        if x0s.ndim != 2 or x0s.shape[1] != 4:
            raise ValueError(f"initial states must have shape (B, 4), got {x0s.shape}")
        if np.any(np.abs(x0s[:, 2]) >= 1):
            raise ValueError("initial theta must lie in (-1, 1)")
        n_out, substeps = self._steps(duration, dt_out, max_step)
        b = x0s.shape[0]
        lower, upper = (np.tile(v, (b, 1)) for v in self._box_on)
        if y_bound is not None:
            lower[:, 0] = np.maximum(lower[:, 0], -float(y_bound))
            upper[:, 0] = np.minimum(upper[:, 0], float(y_bound))
        out = np.full((b, n_out, 4), np.nan)
        n_valid = np.zeros(b, np.int64)
        status = np.zeros(b, np.int64)
        _integrate_field_on_batch(self._args_on, x0s, np.full(b, dt_out / substeps), substeps, np.full(b, n_out),
                                  lower, upper, out, n_valid, status)
        return out, n_valid, np.array([_STATUS[int(s)] for s in status], np.int64)

    def integrate_scipy(self, x0: ArrayLike, t_eval: ArrayLike, method: str = "DOP853", rtol: float = 1e-11,
                        atol: ArrayLike | None = None, field_on: bool = True) -> Trajectory:
        """Reference integration with ``scipy.integrate.solve_ivp`` on the same right-hand side."""
        from scipy.integrate import solve_ivp

        t_eval = np.asarray(t_eval, float)
        if atol is None:
            atol = np.array([1e-14, 1e-12, 1e-12, 1e-10])
        sol = solve_ivp(lambda t, x: self.rhs(t, x, field_on), (t_eval[0], t_eval[-1]), np.asarray(x0, float),
                        method=method, t_eval=t_eval, rtol=rtol, atol=atol)
        return Trajectory(t=sol.t, state=sol.y.T, status=0 if sol.success else 3)

    def with_effects(self, effects: EffectSet) -> "DimerDynamics":
        """The same dimer with another effect set."""
        return DimerDynamics(self.force_model, effects)

    def equilibrium(self, theta_guess: float = 0.0) -> NDArray[np.float64]:
        """Static equilibrium [y, 0, theta, 0] of the force model plus the velocity-free effects,
        by Newton iteration on the numpy accelerations from (theta_guess, 0)."""
        from scipy.optimize import fsolve

        def f(v):
            ay, at = self.accelerations(np.array([v[1], 0.0, v[0], 0.0]))
            return [float(at), float(ay) * 1e3]

        th, y = fsolve(f, [theta_guess, 0.0], xtol=1e-13)
        return np.array([y, 0.0, th, 0.0])
