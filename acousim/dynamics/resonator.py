"""The levitator as a resonator: the cavity mode's complex amplitude as a state of the dimer's dynamics.

A single-node levitator (a transducer and a planar reflector half a wavelength apart) is a single-mode cavity of
quality factor Q driven at a fixed angular frequency w_d.  Its pressure is ``p(Z, t) = Re[A(t) exp(i w_d t)]
sin(kZ)``, and the slowly varying complex envelope ``a = A / p0`` (p0: the pressure amplitude the force model is
built at) obeys the envelope equation of a driven, damped mode::

    da/dt = -(Gamma + i Delta(t)) a + Gamma a_d(t)

    Gamma = w / (2Q) = pi f / Q = 1 / tau           the amplitude's decay rate (tau: the ring time) [1/s]
    Delta(t) = w_c(y, theta) - w_d                   the cavity's detuning from the drive [rad/s]
    w_c(y, theta) = w_c0 (1 + eps(y, theta))         the loaded cavity's resonance
    eps(y, theta) = U_ac(y, theta) / E_mode          the dimer's fractional frequency shift (adiabatic invariant)
    E_mode = p0^2 / (4 rho0 c0^2) * A_cav * L        the mode's time-averaged stored energy, L = lambda / 2

with ``U_ac`` the time-averaged acoustic potential energy of the dimer at p0 (docs/conventions.md section 3; eps
does not depend on p0).  The body's slow motion does the work ``-dU_ac`` on the mode, and the adiabatic invariant
E / w of the mode turns it into the shift: ``d eps/dy = -F_Z,ac / E_mode`` and ``d eps/dtheta = -Q_theta / E_mode``.
Every acoustic generalised force scales with ``s = |a|^2`` (:func:`acousim.dynamics.switching.switching_acceleration`):
``xddot = xddot_off + |a|^2 (xddot_on - xddot_off)``.

Sign conventions:

* ``detuning`` x (in half-widths Gamma = f / (2Q) in Hz) is the loaded cavity's resonance minus the drive's
  frequency with the dimer at rest at (y, theta) = (0, 0): ``Delta = Gamma x + w (eps(y, theta) - eps(0, 0))``
  (w = 2 pi f, the drive's; w_c0 and w_d differ by O(1/Q), which the shift's coefficient ignores).  x > 0: the
  drive sits below the resonance; x < 0: above it.
* The drive's amplitude ``a_d = sqrt(1 + x^2)`` (the drive is switched on and off as the field-drop protocol
  says) makes the steady amplitude ``|a| = 1`` with the dimer at (0, 0): the trap is the configured one at rest,
  whatever the detuning, and Z_eq does not move.
* A dense rigid body at the pressure node lowers w_c (the -3/2 f2 term of the Gor'kov density), at a pressure
  antinode raises it (the f1 term).  The levitated dimer sits below the node, where ``F_Z,ac = M g > 0``, so
  eps falls as y rises; with x < 0 the lagged force feeds y, with x > 0 it damps y (:mod:`acousim.dynamics.cavity_stability`).

The potential comes from the force model's own height structure (:func:`potential_series`): the Z-dependence
integrates the vertical force exactly, the theta-dependence integrates Q_theta along y = 0.  For the Gor'kov
model this is its potential (up to a constant, which only shifts x's reference); for the full-wave model, whose
forces need not derive from one, it is the potential of its forces along that path (the difference with another
path measures the table's non-conservative part).

The switching ring of a field drop is the same equation with Delta = 0 and a_d switched between 0 and 1: its
solution ``a = a_d + (a_start - a_d) exp(-t / tau)`` is what :mod:`acousim.dynamics.switching` integrates in closed
form (:func:`acousim.dynamics.switching.ring_time` is the one definition of tau).  The instantaneous field is the limit Q -> 0.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numba as nb
import numpy as np
from numpy.polynomial import chebyshev as cheb
from numpy.typing import ArrayLike, NDArray

from cubedimer.rk4 import _box_check

from .equations import _chebval
from .integrator import _STATUS, DEFAULT_MAX_STEP, Trajectory
from .switching import FieldDrop, ring_time, switching_acceleration
from ..force_model import ForceModel
from ..medium import Medium

__all__ = ["DEFAULT_CAVITY_AREA", "CAVITY_AREA_RANGE", "MAX_DETUNING", "CavityMode", "mode_energy",
           "slow_response_gains", "PotentialSeries", "potential_series", "CoupledCavity", "ModeTrajectory", "integrate_coupled",
           "coupled_field_drop", "coupled_flow"]

#: The default effective cross-section of the cavity [m^2]: a transducer of 20 mm diameter.
DEFAULT_CAVITY_AREA = math.pi * 0.010**2
#: Accepted range of the cavity's cross-section [m^2]: transducers of 3.6 mm to 113 mm diameter.
CAVITY_AREA_RANGE = (1.0e-5, 1.0e-2)
#: Largest accepted |detuning| [half-widths].
MAX_DETUNING = 20.0
#: Longest RK4 step as a fraction of the ring time (h Gamma <= 0.1: RK4's amplitude error ~(h Gamma)^5 / 120).
_STEP_PER_TAU = 0.1


def slow_response_gains(decay_rate: float, drive_detuning: float,
                        detuning: ArrayLike | None = None) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The mode's response to a detuning that changes slowly against its ring time, to first order in the lag.

    With the drive normalised so that |a| = 1 at the drive's own detuning Delta_0, the steady response is
    s(Delta) = (Gamma^2 + Delta_0^2) / (Gamma^2 + Delta^2), and a detuning that moves answers after the lag
    T(Delta) = 2 Gamma / (Gamma^2 + Delta^2): |a|^2 = s(Delta) - T s'(Delta) dDelta/dt + O(T^2).

    Parameters
    ----------
    decay_rate : float
        Gamma = pi f / Q [1/s].
    drive_detuning : float
        Delta_0 = Gamma x [rad/s], the drive's detuning from the cavity with the dimer at rest.
    detuning : array_like, optional
        Delta [rad/s] at which to evaluate (default: Delta_0).

    Returns
    -------
    static_gain, lag_gain : ndarray
        s'(Delta) [s/rad] and -T(Delta) s'(Delta) [s^2/rad]: |a|^2 - 1 = static_gain (Delta - Delta_0)
        + lag_gain dDelta/dt to first order about Delta_0. Below the resonance (x < 0) the lag gain is negative.
    """
    ga, d0 = float(decay_rate), float(drive_detuning)
    d = np.asarray(d0 if detuning is None else detuning, dtype=float)
    static = -2.0 * d * (ga**2 + d0**2) / (ga**2 + d**2) ** 2
    return static, -2.0 * ga / (ga**2 + d**2) * static


def mode_energy(pressure_amplitude_pa: float, area_m2: float, medium: Medium) -> float:
    """E_mode = p0^2 / (4 rho0 c0^2) * A_cav * lambda / 2 [J]: the time-averaged energy of the half-wave mode whose
    pressure is p0 sin(kZ) (potential and kinetic energy densities average to p0^2 / (8 rho0 c0^2) each)."""
    e0 = pressure_amplitude_pa**2 / (4.0 * medium.density_kg_m3 * medium.sound_speed_m_s**2)
    return e0 * float(area_m2) * 0.5 * medium.wavelength


@dataclass(frozen=True)
class CavityMode:
    """The levitator's cavity mode (module docstring).

    Parameters
    ----------
    quality_factor : float
        Q > 0; the amplitude's ring time is tau = Q / (pi f).
    detuning : float
        (w_c - w_d) / Gamma with the dimer at rest at (0, 0) [half-widths f / (2Q)]; > 0: the drive below the
        resonance (damps y), < 0: above it (feeds y).  Within +-:data:`MAX_DETUNING`.
    area : float
        Effective cross-section A_cav of the cavity [m^2] (the transducer's area; the mode's volume is
        A_cav lambda / 2); ``inf`` uncouples the mode from the dimer (the plain switching ring).
    """

    quality_factor: float
    detuning: float = 1.0
    area: float = DEFAULT_CAVITY_AREA

    def __post_init__(self) -> None:
        q, x, a = self.quality_factor, self.detuning, self.area
        if not (isinstance(q, (int, float)) and math.isfinite(q) and q > 0):
            raise ValueError(f"the cavity's quality factor must be positive and finite, got {q!r}")
        if not (isinstance(x, (int, float)) and math.isfinite(x) and abs(x) <= MAX_DETUNING):
            raise ValueError(f"the detuning must be finite and within +-{MAX_DETUNING:g} half-widths, got {x!r}")
        if not (isinstance(a, (int, float)) and (a == math.inf or CAVITY_AREA_RANGE[0] <= a <= CAVITY_AREA_RANGE[1])):
            raise ValueError(f"the cavity area must lie in [{CAVITY_AREA_RANGE[0]:g}, {CAVITY_AREA_RANGE[1]:g}] m^2 "
                             f"(or be inf: uncoupled), got {a!r}")

    def decay_rate(self, frequency_hz: float) -> float:
        """Gamma = pi f / Q [1/s]."""
        return 1.0 / ring_time(self.quality_factor, frequency_hz)

    def half_width_hz(self, frequency_hz: float) -> float:
        """The resonance's half-width f / (2Q) [Hz] (Gamma / 2 pi): the unit of :attr:`detuning`."""
        return frequency_hz / (2.0 * self.quality_factor)

    def drive_amplitude(self) -> float:
        """a_d = sqrt(1 + x^2): the drive that holds |a| = 1 at rest (module docstring)."""
        return math.sqrt(1.0 + self.detuning**2)

    def steady_amplitude(self) -> complex:
        """a at rest with the drive on: Gamma a_d / (Gamma + i Delta) = (1 - i x) / sqrt(1 + x^2)."""
        return complex(1.0, -self.detuning) / self.drive_amplitude()

    def to_dict(self, frequency_hz: float) -> dict:
        """JSON-ready record (SI units) for truth.json."""
        return {"quality_factor": float(self.quality_factor), "detuning_half_widths": float(self.detuning),
                "detuning_hz": float(self.detuning * self.half_width_hz(frequency_hz)),
                "cavity_area_m2": float(self.area), "ring_time_s": ring_time(self.quality_factor, frequency_hz),
                "model": "da/dt = -(Gamma + i Delta) a + Gamma a_d, Delta = Gamma x + w (eps - eps(0,0)), "
                         "eps = U_ac / E_mode; forces scale as |a|^2"}


@dataclass(frozen=True, eq=False)
class PotentialSeries:
    """U_ac(theta, Z) = P(theta) + R(theta) cos(2kZ) + S(theta) sin(2kZ) + L(theta) Z [J], Chebyshev series in
    theta, Z = Z_eq + y (:func:`potential_series`)."""

    p: NDArray[np.float64]
    r: NDArray[np.float64]
    s: NDArray[np.float64]
    l: NDArray[np.float64]
    two_k: float
    z_eq: float

    def __call__(self, theta: ArrayLike, y: ArrayLike) -> NDArray[np.float64]:
        """U_ac [J] at (theta, y), up to the constant of :func:`potential_series`."""
        th, z = np.asarray(theta, float), np.asarray(y, float) + self.z_eq
        val = lambda c: cheb.chebval(th, c)  # noqa: E731
        return val(self.p) + val(self.r) * np.cos(self.two_k * z) + val(self.s) * np.sin(self.two_k * z) \
            + val(self.l) * z

    def derivatives(self, theta: ArrayLike, y: ArrayLike) -> tuple[NDArray[np.float64], ...]:
        """(U_y, U_theta, U_yy, U_ytheta, U_thetatheta) at (theta, y) [J/m, J, J/m^2, J/m, J], from the series."""
        th, z = np.asarray(theta, float), np.asarray(y, float) + self.z_eq
        c, s, tk = np.cos(self.two_k * z), np.sin(self.two_k * z), self.two_k
        der = lambda coef, n: cheb.chebval(th, cheb.chebder(coef, n) if coef.size > n else np.zeros(1))  # noqa: E731
        (r0, r1, r2), (s0, s1, s2) = ([der(v, n) for n in range(3)] for v in (self.r, self.s))
        l0, l1, l2 = (der(self.l, n) for n in range(3))
        u_y = tk * (-r0 * s + s0 * c) + l0
        u_t = der(self.p, 1) + r1 * c + s1 * s + l1 * z
        u_yy = -tk * tk * (r0 * c + s0 * s)
        u_yt = tk * (-r1 * s + s1 * c) + l1
        u_tt = der(self.p, 2) + r2 * c + s2 * s + l2 * z
        return u_y, u_t, u_yy, u_yt, u_tt

    def as_tuple(self) -> tuple:
        """(P, R, S, L, [two_k, z_eq]) for the compiled kernel."""
        return (self.p, self.r, self.s, self.l, np.array([self.two_k, self.z_eq]))


def potential_series(force_model: ForceModel) -> PotentialSeries:
    """The acoustic potential of a force model from its height structure (module docstring).

    With ``F_Z,ac = A_y + B_y cos(2kZ) + C_y sin(2kZ)`` = -dU/dZ: R = C_y / 2k, S = -B_y / 2k, L = -A_y; and P from
    -dU/dtheta = Q_theta at Z = Z_eq: P' = -Q_theta(theta, Z_eq) - R' cos(2kZ_eq) - S' sin(2kZ_eq) - L' Z_eq, P(0) = 0.
    """
    fc = force_model.force_coefficients()
    tk, z0 = float(force_model.two_k), float(force_model.z_eq)
    r, s, lin = fc.q_y_c / tk, -fc.q_y_b / tk, -fc.q_y_a
    c0, s0 = math.cos(tk * z0), math.sin(tk * z0)
    q0 = cheb.chebadd(cheb.chebadd(fc.q_theta_a, c0 * fc.q_theta_b), s0 * fc.q_theta_c)
    der = lambda c: cheb.chebder(c) if c.size > 1 else np.zeros(1)  # noqa: E731
    dp = -cheb.chebadd(cheb.chebadd(q0, c0 * der(r)), cheb.chebadd(s0 * der(s), z0 * der(lin)))
    p = cheb.chebint(dp, lbnd=0.0)
    f = lambda c: np.ascontiguousarray(np.asarray(c, float))  # noqa: E731
    return PotentialSeries(f(p), f(r), f(s), f(lin), tk, z0)


@nb.njit(cache=True)
def _potential(theta, y, pot):
    p, r, s, lin, par = pot
    z = par[1] + y
    return (_chebval(p, theta) + _chebval(r, theta) * np.cos(par[0] * z) + _chebval(s, theta) * np.sin(par[0] * z)
            + _chebval(lin, theta) * z)


# layout of CoupledCavity's parameter array
_C_GAMMA, _C_DELTA, _C_CHI, _C_UREF = range(4)


@dataclass(frozen=True, eq=False)
class CoupledCavity:
    """A :class:`CavityMode` coupled to a dimer's dynamics: the compiled parameters of the six-state system.

    Parameters
    ----------
    dynamics : acousim.dynamics.integrator.DimerDynamics
    mode : CavityMode
    medium : Medium
        The air and the drive's frequency (rho0, c0 and lambda of E_mode; w and Gamma).
    """

    dynamics: object
    mode: CavityMode
    medium: Medium = field(default_factory=Medium)

    def __post_init__(self) -> None:
        fm = self.dynamics.force_model
        pot = potential_series(fm)
        f = self.medium.frequency_hz
        e_mode = mode_energy(fm.pressure_amplitude_pa, self.mode.area, self.medium)
        gamma = self.mode.decay_rate(f)
        chi = 2.0 * math.pi * f / e_mode  # [rad/s per J]: 0 for an uncoupled (infinite) cavity
        par = np.array([gamma, gamma * self.mode.detuning, chi, float(pot(0.0, 0.0))])
        object.__setattr__(self, "potential", pot)
        object.__setattr__(self, "stored_energy", e_mode)
        object.__setattr__(self, "_kernel", (self.dynamics._args_on, self.dynamics._args_off, pot.as_tuple(), par))

    @property
    def decay_rate(self) -> float:
        """Gamma [1/s]."""
        return float(self._kernel[3][_C_GAMMA])

    @property
    def shift_per_joule(self) -> float:
        """w / E_mode [rad/s per J]: Delta changes by this times the change of U_ac."""
        return float(self._kernel[3][_C_CHI])

    def fractional_shift(self, theta: ArrayLike, y: ArrayLike) -> NDArray[np.float64]:
        """eps(y, theta) - eps(0, 0) = (U_ac(theta, y) - U_ac(0, 0)) / E_mode [-]."""
        return (self.potential(theta, y) - self.potential(0.0, 0.0)) / self.stored_energy

    def detuning_rad_s(self, theta: ArrayLike, y: ArrayLike) -> NDArray[np.float64]:
        """Delta(y, theta) = Gamma x + w (eps(y, theta) - eps(0, 0)) [rad/s]."""
        return self.decay_rate * self.mode.detuning + 2 * math.pi * self.medium.frequency_hz \
            * self.fractional_shift(theta, y)

    def max_step(self, max_step: float) -> float:
        """The RK4 step bound: ``max_step`` or a tenth of the ring time, whichever is shorter [s]."""
        return min(float(max_step), _STEP_PER_TAU / self.decay_rate)


@nb.njit(cache=True)
def _mode_rhs(y, ydot, theta, thetadot, ar, ai, drive, args):
    """(yddot, thetaddot, dRe(a)/dt, dIm(a)/dt) of the six-state system (module docstring)."""
    args_on, args_off, pot, par = args
    ay, at = switching_acceleration(y, ydot, theta, thetadot, ar * ar + ai * ai, args_on, args_off)
    gam = par[_C_GAMMA]
    delta = par[_C_DELTA] + par[_C_CHI] * (_potential(theta, y, pot) - par[_C_UREF])
    return ay, at, -gam * ar + delta * ai + gam * drive, -gam * ai - delta * ar


@nb.njit(cache=True)
def _rk4_coupled(args, x0, drive, h, substeps, n_out, lower, upper, out):
    """Fixed-step RK4 of the six-state system (the stages of :func:`cubedimer.rk4.rk4`); ``out`` (n_out, 6);
    stops at the first sample whose (y, ydot, theta, thetadot) leaves the box (:func:`cubedimer.rk4.rk4`'s codes)."""
    x = x0.copy()
    out[0, :] = x
    k1, k2, k3, k4, tmp = np.empty(6), np.empty(6), np.empty(6), np.empty(6), np.empty(6)
    for i in range(1, n_out):
        for _ in range(substeps):
            for st in range(4):
                if st == 0:
                    tmp[:] = x
                    k = k1
                elif st == 1:
                    for j in range(6):
                        tmp[j] = x[j] + 0.5 * h * k1[j]
                    k = k2
                elif st == 2:
                    for j in range(6):
                        tmp[j] = x[j] + 0.5 * h * k2[j]
                    k = k3
                else:
                    for j in range(6):
                        tmp[j] = x[j] + h * k3[j]
                    k = k4
                a_y, a_t, d_r, d_i = _mode_rhs(tmp[0], tmp[1], tmp[2], tmp[3], tmp[4], tmp[5], drive, args)
                k[0], k[1], k[2], k[3], k[4], k[5] = tmp[1], a_y, tmp[3], a_t, d_r, d_i
            for j in range(6):
                x[j] += h / 6.0 * (k1[j] + 2.0 * k2[j] + 2.0 * k3[j] + k4[j])
        status = _box_check(x[0], x[1], x[2], x[3], lower, upper)
        if status == 0 and not (np.isfinite(x[4]) and np.isfinite(x[5])):
            status = 1
        if status != 0:
            return i, status
        out[i, :] = x
    return n_out, 0


@dataclass(frozen=True, eq=False)
class ModeTrajectory:
    """Samples of the six-state system.

    Attributes
    ----------
    t : ndarray (n,)
        [s].
    state : ndarray (n, 4)
        [y, ydot, theta, thetadot].
    mode : ndarray of complex (n,)
        a = A / p0.
    status : int
        A key of :data:`acousim.dynamics.integrator.STATUS_MESSAGES`.
    """

    t: NDArray[np.float64]
    state: NDArray[np.float64]
    mode: NDArray[np.complex128]
    status: int = 0

    @property
    def ok(self) -> bool:
        return self.status == 0


def integrate_coupled(cavity: CoupledCavity, x0: ArrayLike, a0: complex, duration: float, dt_out: float,
                      drive_on: bool = True, max_step: float = DEFAULT_MAX_STEP) -> ModeTrajectory:
    """Integrate the dimer and its cavity mode from ``x0`` = [y, ydot, theta, thetadot] and ``a0`` = A / p0.

    Parameters
    ----------
    cavity : CoupledCavity
    x0 : array_like (4,)
    a0 : complex
    duration, dt_out : float
        Span and output interval [s].
    drive_on : bool
        The drive on (a_d = sqrt(1 + x^2)) or off (a_d = 0: the field drop).
    max_step : float
        Longest RK4 step [s]; at most a tenth of the ring time (:meth:`CoupledCavity.max_step`).

    Returns
    -------
    ModeTrajectory
        Stops, as :meth:`acousim.dynamics.integrator.DimerDynamics.integrate`, when the dimer leaves the trap (the
        field-on box while the drive is on), folds or the state stops being finite.
    """
    dyn = cavity.dynamics
    n_out, substeps = dyn._steps(duration, dt_out, cavity.max_step(max_step))
    x = np.empty(6)
    x[:4] = np.asarray(x0, float).reshape(4)
    x[4], x[5] = complex(a0).real, complex(a0).imag
    if abs(x[2]) >= 1:
        raise ValueError(f"initial theta must lie in (-1, 1), got {x[2]!r}")
    box = dyn._box_on if drive_on else dyn._box_off
    drive = cavity.mode.drive_amplitude() if drive_on else 0.0
    out = np.empty((n_out, 6))
    n, status = _rk4_coupled(cavity._kernel, x, drive, dt_out / substeps, substeps, n_out, *box, out)
    return ModeTrajectory(t=np.arange(n) * dt_out, state=out[:n, :4].copy(), mode=out[:n, 4] + 1j * out[:n, 5],
                          status=_STATUS[int(status)])


def coupled_flow(cavity: CoupledCavity, steps: int, drive_on: bool = True):
    """The flow ``phi(x, t)`` of the six-state system, x = [y, ydot, theta, thetadot, Re a, Im a], by ``steps`` RK4
    steps of t / steps (:func:`integrate_coupled`'s integrator, a fixed number of steps so that phi is smooth in t:
    :func:`acousim.dynamics.periodic_orbits.shoot_periodic_orbit`); NaN where the run leaves the box or folds."""
    dyn = cavity.dynamics
    box = dyn._box_on if drive_on else dyn._box_off
    drive = cavity.mode.drive_amplitude() if drive_on else 0.0
    n_steps = int(steps)

    def flow(x: NDArray[np.float64], t: float) -> NDArray[np.float64]:
        out = np.empty((2, 6))
        n, _ = _rk4_coupled(cavity._kernel, np.asarray(x, float), drive, float(t) / n_steps, n_steps, 2, *box, out)
        return out[1].copy() if n == 2 else np.full(6, np.nan)

    return flow


def coupled_field_drop(cavity: CoupledCavity, x_drop: ArrayLike, t_off: float, duration: float, dt_out: float,
                       max_step: float = DEFAULT_MAX_STEP) -> FieldDrop:
    """The field-drop protocol of :func:`acousim.dynamics.switching.field_drop` with the cavity mode as a state.

    The mode starts at its steady amplitude with the dimer at ``x_drop``'s rest, rings down with the drive off for
    ``t_off`` [s] (a_d = 0) and is driven again for ``duration`` [s] sampled every ``dt_out`` [s]; the dimer detunes it
    all along.  With an uncoupled cavity (``area = inf``) and zero detuning this is the closed-form ring of
    :func:`~acousim.dynamics.switching.field_drop` with tau = Q / (pi f), integrated instead of evaluated.
    """
    x, a = np.asarray(x_drop, float).reshape(4), cavity.mode.steady_amplitude()
    if t_off > 0:
        fall = integrate_coupled(cavity, x, a, t_off, t_off, drive_on=False, max_step=max_step)
        if not fall.ok:
            return FieldDrop(fall.state[-1], None, fall.status, -float(t_off), float(abs(fall.mode[-1])))
        x, a = fall.state[-1], complex(fall.mode[-1])
    on = integrate_coupled(cavity, x, a, duration, dt_out, drive_on=True, max_step=max_step)
    traj = Trajectory(t=on.t, state=on.state, status=on.status)
    return FieldDrop(x.copy(), traj, on.status, float(on.t[-1]) if not on.ok else float("nan"), abs(a), on.mode)
