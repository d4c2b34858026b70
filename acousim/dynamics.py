"""Equations of motion of the hinged cube dimer (PHYSICS.md section 4) with the effects of section 5.

State ``x = [y, ydot, theta, thetadot]`` (m, m/s, -, 1/s).  With the field on::

    yddot     = Q_y(theta, y) / M                                        + effects
    thetaddot = [ Q_theta(theta, y) - 1/2 I'(theta) thetadot^2 ] / I(theta) + effects

where Q_y, Q_theta come from the energy-consistent :class:`~acousim.surrogate.ForceSurrogate`
(the gradient of one potential V, so without effects E = T + V is conserved) and
``I(theta) = (pi/4)^2 2 m s^2 (sin^2(phi)/2 + 1/6)``.

With the field off (the drop of the field-drop protocol) there is no acoustic force or torque:
``yddot = -g`` and ``thetaddot = -1/2 I'/I thetadot^2`` (the hinge is free and I theta-dot^2 is
conserved).  Air is still there, so ``linear_damping`` and ``quadratic_drag`` keep acting; the
acoustic effects (pair_scattering, mirror_asymmetry, velocity_coupling) are off.

Integration: classical fixed-step RK4 compiled with numba (:meth:`DimerDynamics.integrate`);
the internal step is the output interval divided into equal sub-steps no longer than
``max_step`` (default 50 us, i.e. 20 kHz: h omega <= 0.007 for the 22 Hz trap, RK4 relative energy
error ~1e-9 over 100 periods, see the tests).  Integration stops, and reports why, when the dimer
leaves the trap (falls below the barrier height), theta reaches +-1 (faces in contact) or the
state stops being finite.  :meth:`DimerDynamics.rhs` is the same right-hand side for
``scipy.integrate.solve_ivp`` (used to cross-check the compiled integrator and in the benchmark).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numba as nb
import numpy as np
from numpy.typing import ArrayLike, NDArray

from .effects import EffectSet
from .surrogate import ForceSurrogate

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

# packed parameter layout (see DimerDynamics._packed)
_P_TWO_K, _P_ZEQ, _P_MASS, _P_MG, _P_I0, _P_I2, _P_K, _P_G, _P_YLO, _P_YHI = range(10)


@nb.njit(cache=True, inline="always")
def _chebval(c, x):
    """Clenshaw evaluation of sum c_j T_j(x)."""
    n = c.shape[0]
    b1 = 0.0
    b2 = 0.0
    x2 = 2.0 * x
    for j in range(n - 1, 0, -1):
        b0 = c[j] + x2 * b1 - b2
        b2 = b1
        b1 = b0
    return c[0] + x * b1 - b2


@nb.njit(cache=True, inline="always")
def _accel(y, yd, th, thd, coefs, par, eff, field_on):
    """(yddot, thetaddot) of the state; coefs rows: beta, gamma, alpha', beta', gamma'."""
    phi = 0.7853981633974483 * th
    sphi = np.sin(phi)
    inertia = par[_P_I0] + par[_P_I2] * sphi * sphi
    dinertia = par[_P_I2] * 0.7853981633974483 * np.sin(2.0 * phi)
    # air drag acts with the field on or off
    ay = -eff[0] * yd - eff[2] * abs(yd) * yd
    at = -eff[1] * thd - eff[3] * abs(thd) * thd
    if field_on:
        z = par[_P_ZEQ] + y
        c = np.cos(par[_P_TWO_K] * z)
        s = np.sin(par[_P_TWO_K] * z)
        b = _chebval(coefs[0], th)
        g = _chebval(coefs[1], th)
        q_y = par[_P_TWO_K] * (b * s - g * c) - par[_P_MG]
        q_t = -(_chebval(coefs[2], th) + _chebval(coefs[3], th) * c + _chebval(coefs[4], th) * s)
        ay += q_y / par[_P_MASS]
        at += (q_t - 0.5 * dinertia * thd * thd) / inertia
        ckz = np.cos(par[_P_K] * z)
        at += -eff[4] * ckz * ckz * th            # pair_scattering
        at += eff[5] + eff[6] * y                 # mirror_asymmetry
        at += eff[7] * thd * thd * y + eff[8] * thd * yd * y   # velocity_coupling
    else:
        ay -= par[_P_G]
        at -= 0.5 * dinertia * thd * thd / inertia
    return ay, at


@nb.njit(cache=True)
def _rhs(x, coefs, par, eff, field_on):
    out = np.empty(4)
    ay, at = _accel(x[0], x[1], x[2], x[3], coefs, par, eff, field_on)
    out[0] = x[1]
    out[1] = ay
    out[2] = x[3]
    out[3] = at
    return out


@nb.njit(cache=True)
def _rk4(x0, h, substeps, n_out, coefs, par, eff, field_on, out):
    """Fill out[:n_valid] with the state every ``substeps`` RK4 steps of length h; return (n_valid, status)."""
    y, yd, th, thd = x0[0], x0[1], x0[2], x0[3]
    out[0, 0] = y
    out[0, 1] = yd
    out[0, 2] = th
    out[0, 3] = thd
    hh = 0.5 * h
    h6 = h / 6.0
    for i in range(1, n_out):
        for _ in range(substeps):
            a1, b1 = _accel(y, yd, th, thd, coefs, par, eff, field_on)
            y2, yd2, th2, thd2 = y + hh * yd, yd + hh * a1, th + hh * thd, thd + hh * b1
            a2, b2 = _accel(y2, yd2, th2, thd2, coefs, par, eff, field_on)
            y3, yd3, th3, thd3 = y + hh * yd2, yd + hh * a2, th + hh * thd2, thd + hh * b2
            a3, b3 = _accel(y3, yd3, th3, thd3, coefs, par, eff, field_on)
            y4, yd4, th4, thd4 = y + h * yd3, yd + h * a3, th + h * thd3, thd + h * b3
            a4, b4 = _accel(y4, yd4, th4, thd4, coefs, par, eff, field_on)
            y = y + h6 * (yd + 2.0 * yd2 + 2.0 * yd3 + yd4)
            yd = yd + h6 * (a1 + 2.0 * a2 + 2.0 * a3 + a4)
            th = th + h6 * (thd + 2.0 * thd2 + 2.0 * thd3 + thd4)
            thd = thd + h6 * (b1 + 2.0 * b2 + 2.0 * b3 + b4)
        if not (np.isfinite(y) and np.isfinite(yd) and np.isfinite(th) and np.isfinite(thd)):
            return i, 3
        if field_on and y < par[_P_YLO]:
            return i, 1
        if field_on and y > par[_P_YHI]:
            return i, 4
        if abs(th) >= 1.0:
            return i, 2
        out[i, 0] = y
        out[i, 1] = yd
        out[i, 2] = th
        out[i, 3] = thd
    return n_out, 0


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
    """Equations of motion of the dimer: Gor'kov surrogate forces plus an :class:`EffectSet`.

    Parameters
    ----------
    surrogate : ForceSurrogate
        Potential and generalised forces (sets the pressure, side, Z_eq, masses and inertia).
    effects : EffectSet
        The unmodelled effects switched on (default none).

    Examples
    --------
    >>> dyn = DimerDynamics(cached_surrogate(), EffectSet.parse(["linear_damping:gamma_y=0.3"]))  # doctest: +SKIP
    >>> traj = dyn.integrate([100e-6, 0, 0.1, 0], duration=4.0, dt_out=1 / 2000)            # doctest: +SKIP
    """

    surrogate: ForceSurrogate
    effects: EffectSet = field(default_factory=EffectSet)

    def __post_init__(self) -> None:
        s = self.surrogate
        _, b, g, da, db, dg = s.coefficient_arrays()
        object.__setattr__(self, "_coefs", np.ascontiguousarray(np.stack([b, g, da, db, dg])))
        y_lo = s.escape_height()
        y_hi = np.pi / s.two_k - s.z_eq
        par = np.array([s.two_k, s.z_eq, s.mass, s.mass * s.gravity, s.inertia_const, s.inertia_sin2,
                        s.wavenumber, s.gravity, y_lo if np.isfinite(y_lo) else -1.0, y_hi], float)
        object.__setattr__(self, "_par", par)
        object.__setattr__(self, "_eff", np.ascontiguousarray(self.effects.packed()))

    # ------------------------------------------------------------------ right-hand side
    def accelerations(self, state: ArrayLike, field_on: bool = True) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """(yddot [m/s^2], thetaddot [1/s^2]) for states (..., 4), numpy reference implementation."""
        x = np.asarray(state, float)
        y, yd, th, thd = x[..., 0], x[..., 1], x[..., 2], x[..., 3]
        s = self.surrogate
        inertia, dinertia = s.hinge_inertia(th), s.hinge_inertia_derivative(th)
        if field_on:
            q_y, q_t = s.generalized_forces(th, y)
            ay = q_y / s.mass
            at = (q_t - 0.5 * dinertia * thd**2) / inertia
            ey, et = self.effects.accelerations(y, yd, th, thd, s.wavenumber, s.z_eq)
        else:
            ay = np.full_like(y, -s.gravity)
            at = -0.5 * dinertia * thd**2 / inertia
            air = EffectSet(tuple(e for e in self.effects if e.name in ("linear_damping", "quadratic_drag")))
            ey, et = air.accelerations(y, yd, th, thd, s.wavenumber, s.z_eq)
        return ay + ey, at + et

    def rhs(self, t: float, x: ArrayLike, field_on: bool = True) -> NDArray[np.float64]:
        """dx/dt of one state (4,) for ``scipy.integrate.solve_ivp`` (compiled; ``t`` is unused)."""
        return _rhs(np.asarray(x, float), self._coefs, self._par, self._eff, bool(field_on))

    # ------------------------------------------------------------------ energy
    def kinetic_energy(self, state: ArrayLike) -> NDArray[np.float64]:
        """T = 1/2 M ydot^2 + 1/2 I(theta) thetadot^2 [J]."""
        x = np.asarray(state, float)
        s = self.surrogate
        return 0.5 * s.mass * x[..., 1] ** 2 + 0.5 * s.hinge_inertia(x[..., 2]) * x[..., 3] ** 2

    def energy(self, state: ArrayLike) -> NDArray[np.float64]:
        """E = T + V [J] with V = 0 at the equilibrium (conserved when no effect is on)."""
        x = np.asarray(state, float)
        return self.kinetic_energy(x) + self.surrogate.potential(x[..., 2], x[..., 0])

    # ------------------------------------------------------------------ integration
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
        if not (dt_out > 0 and duration >= 0 and max_step > 0):
            raise ValueError("need dt_out > 0, max_step > 0 and duration >= 0")
        if abs(x0[2]) >= 1:
            raise ValueError(f"initial theta must lie in (-1, 1), got {x0[2]!r}")
        n_out = int(round(duration / dt_out)) + 1
        substeps = max(1, int(np.ceil(dt_out / max_step - 1e-9)))
        out = np.empty((n_out, 4))
        n, status = _rk4(x0, dt_out / substeps, substeps, n_out, self._coefs, self._par, self._eff,
                         bool(field_on), out)
        return Trajectory(t=np.arange(n) * dt_out, state=out[:n], status=int(status))

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
        return DimerDynamics(self.surrogate, effects)

    def equilibrium(self, theta_guess: float = 0.0) -> NDArray[np.float64]:
        """Static equilibrium [y, 0, theta, 0] of the surrogate model plus the velocity-free effects,
        by Newton iteration on the numpy accelerations from (theta_guess, 0)."""
        from scipy.optimize import fsolve

        def f(v):
            ay, at = self.accelerations(np.array([v[1], 0.0, v[0], 0.0]))
            return [float(at), float(ay) * 1e3]

        th, y = fsolve(f, [theta_guess, 0.0], xtol=1e-13)
        return np.array([y, 0.0, th, 0.0])
