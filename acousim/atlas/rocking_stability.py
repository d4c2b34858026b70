"""Stability of the symmetric hinge orbits against the rocking and sideways modes (Floquet multipliers).

The kinetic energy.  Cube i (mass m, side s, inertia ``I_c = m s^2 / 6`` about any axis through its centre) has
its centre at ``r_com + R(psi) rho_i`` with ``rho_B = (X, 0)`` and ``rho_A = -rho_B`` in the (X, Z) plane,
``X = a cos(phi)``, ``a = d + g/2`` the hinge arm and ``phi = pi theta / 4``; its orientation angle about +Y is
``psi - phi`` (cube B) or ``psi + phi`` (cube A).  With ``J`` the quarter turn, ``d(R rho)/dt = R (psidot J rho +
rhodot)``, and because both centres sit at the height of the centre of mass, ``J rho . rhodot = 0``.  So, exactly::

    T = 1/2 M (xdot^2 + zdot^2) + 1/2 I_r(theta) psidot^2 + [m Xdot^2 + I_c phidot^2]
    I_r(theta) = 2 (m X^2 + I_c) = 2 m (a^2 cos^2(phi) + s^2 / 6),

where x is the centre of mass's X.  The bracket is the hinge's ``1/2 I(theta) thetadot^2`` of the equations of motion
(docs/conventions.md section 4), and the cross terms of the two cubes' spins, ``I_c psidot (-/+ phidot)``, cancel.
In terms of the hinge constants ``I(theta) = I_0 + I_2 sin^2(phi)`` (``I_0 = (pi/4)^2 2 m s^2 / 6``, ``I_2 = (pi/4)^2
2 m a^2``): ``I_r = (I_0 + I_2 cos^2(phi)) / (pi/4)^2``.  In the centre of mass's coordinates (x, psi) the mass
matrix is ``diag(M, I_r(theta))``: no inertia couples x and psi.  Coupling appears when x is read at another point
of the dimer's mirror axis, e.g. the hinge line, at the height ``h = a sin(phi)`` above the centre of mass (above it
for theta > 0): its X is ``x_p = x + h sin(psi)``, so to second order::

    T_anti = 1/2 M (x_p' - h psi')^2 + 1/2 I_r psi'^2   ->   [[M, -M h], [-M h, I_r + M h^2]]

(:meth:`AntisymmetricInertia.mass_matrix`), which couples the two through the opening theta; its determinant
``M I_r`` does not depend on h.  Gravity acts at the centre of mass, whose height neither motion changes.

The linearised antisymmetric equations along a symmetric orbit (y(t), theta(t)).  By the mirror symmetry the
antisymmetric loads are odd in (x, psi) and the symmetric ones even, so the two decouple at linear order; with the
stiffnesses of :mod:`acousim.fullwave.antisymmetric_loads` (``K_xx = K_psix = 0``: a plane standing wave does not depend on X)::

    M xddot                       = -K_xpsi(theta, Z) psi
    d/dt [I_r(theta) psidot]      = -K_psipsi(theta, Z) psi - gamma_psi I_r psidot,    Z = Z_eq + y(t).

x has no restoring force: its two multipliers are 1 (a free drift, neutral), and it does not act back on psi.  The
rocking pair's multipliers come from the monodromy of (psi, psidot) over the orbit's period, by
:func:`acousim.atlas.held_y.floquet_multipliers` (central differences of the compiled flow, exact for this linear
system to rounding).  Without damping the product of the pair is 1 (the Wronskian of ``d/dt(I_r psidot) = -K psi``
is conserved with I_r): the orbit is stable when the pair lies on the unit circle and unstable when it is real with
one |mu| > 1 (a parametric resonance of the rocking mode).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numba as nb
import numpy as np
from numpy.typing import ArrayLike, NDArray

from cubedimer.meta import DEFAULT_AIR_DENSITY_KG_M3
from cubedimer.rk4 import rk4

from ..dynamics.air_damping import (AIR_DYNAMIC_VISCOSITY_PA_S, dimer_drag_radii, oscillating_rotation_drag,
                                    oscillating_translation_drag, stokes_layer_thickness)
from .held_y import HINGE_BOX, integrate_held, floquet_multipliers

__all__ = ["AntisymmetricInertia", "rocking_damping_rate", "rocking_acceleration", "periodic_series", "rocking_arguments",
           "rocking_multipliers", "sample_orbit"]

_QUARTER = (np.pi / 4) ** 2


@dataclass(frozen=True)
class AntisymmetricInertia:
    """Mass and rocking inertia of the dimer (module docstring).

    Parameters
    ----------
    mass : float
        Total mass M = 2 m [kg].
    side : float
        Cube side s [m].
    arm : float
        Hinge arm a = d + g/2 [m] (distance from the hinge line to each cube's centre).
    """

    mass: float
    side: float
    arm: float

    def __post_init__(self) -> None:
        for name in ("mass", "side", "arm"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                raise ValueError(f"{name} must be positive, got {v!r}")

    @classmethod
    def from_hinge_inertia(cls, mass: float, inertia_const: float, inertia_sin2: float) -> "AntisymmetricInertia":
        """From the hinge inertia ``I(theta) = inertia_const + inertia_sin2 sin^2(pi theta / 4)`` [kg m^2] of a force
        model and its total mass [kg] (``inertia_const = (pi/4)^2 M s^2 / 6``, ``inertia_sin2 = (pi/4)^2 M a^2``)."""
        side = math.sqrt(6.0 * inertia_const / (_QUARTER * mass))
        arm = math.sqrt(inertia_sin2 / (_QUARTER * mass))
        return cls(mass, side, arm)

    def rocking_inertia(self, theta: ArrayLike) -> NDArray[np.float64]:
        """I_r(theta) [kg m^2]: both cubes about the Y axis through the centre of mass."""
        phi = np.pi * np.asarray(theta, float) / 4
        return self.mass * (self.arm**2 * np.cos(phi) ** 2 + self.side**2 / 6.0)

    def rocking_inertia_derivative(self, theta: ArrayLike) -> NDArray[np.float64]:
        """dI_r/dtheta [kg m^2]."""
        phi = np.pi * np.asarray(theta, float) / 4
        return -self.mass * self.arm**2 * (np.pi / 4) * np.sin(2 * phi)

    def mass_matrix(self, theta: float, pivot_height: float = 0.0) -> NDArray[np.float64]:
        """The (2, 2) mass matrix of (x_p, psi), x_p the X of the point ``pivot_height`` [m] above the centre of
        mass on the mirror axis (0: the centre of mass; ``arm sin(pi theta / 4)``: the hinge line)."""
        h = float(pivot_height)
        m, ir = self.mass, float(self.rocking_inertia(theta))
        return np.array([[m, -m * h], [-m * h, ir + m * h * h]])

    def hinge_height(self, theta: float) -> float:
        """Height [m] of the hinge line above the centre of mass."""
        return float(self.arm * np.sin(np.pi * float(theta) / 4))


def rocking_damping_rate(inertia: AntisymmetricInertia, theta: float, frequency_hz: float, air_density: float = DEFAULT_AIR_DENSITY_KG_M3,
                         viscosity: float = AIR_DYNAMIC_VISCOSITY_PA_S) -> float:
    """The air's damping rate gamma_psi [1/s] of rocking at bend ``theta`` and frequency ``frequency_hz`` [Hz].

    Each cube turns about its own centre at psidot (the rotary drag ``c_rot`` of :mod:`acousim.dynamics.air_damping`)
    while its centre moves vertically at ``X psidot`` (one cube's oscillating translation drag ``c_tr``), so
    ``Q_psi = -2 (c_rot + c_tr X^2) psidot`` and ``gamma_psi = 2 (c_rot + c_tr X^2) / I_r``, with the two cubes' flows
    independent (an upper estimate, as for the hinge's own rotary and sideways parts)."""
    delta = stokes_layer_thickness(viscosity / air_density, frequency_hz)
    r = dimer_drag_radii(inertia.side)
    c_rot = oscillating_rotation_drag(viscosity, r.cube_rotation, delta)
    c_tr = oscillating_translation_drag(viscosity, r.cube_stokes, r.cube_area, delta)
    x_c = inertia.arm * math.cos(math.pi * float(theta) / 4)
    return float(2.0 * (c_rot + c_tr * x_c**2) / inertia.rocking_inertia(theta))


# ---------------------------------------------------------------------- the orbit as a periodic series
def periodic_series(samples: ArrayLike) -> NDArray[np.float64]:
    """(2, H + 1) cosine and sine coefficients of the trigonometric interpolant of ``samples`` taken at
    ``t_j = j P / N``, j = 0..N-1 (one period P, N even; the Nyquist term is dropped, H = N/2 - 1)."""
    v = np.asarray(samples, float)
    n = v.size
    if n < 4 or n % 2:
        raise ValueError(f"a periodic series needs an even number (>= 4) of samples, got {n}")
    c = np.fft.rfft(v) / n
    h = n // 2 - 1
    out = np.zeros((2, h + 1))
    out[0, 0] = c[0].real
    out[0, 1:] = 2 * c[1:h + 1].real
    out[1, 1:] = -2 * c[1:h + 1].imag
    return out


@nb.njit(cache=True)
def _series_at(coef, omega_t):
    v = coef[0, 0]
    for j in range(1, coef.shape[1]):
        v += coef[0, j] * math.cos(j * omega_t) + coef[1, j] * math.sin(j * omega_t)
    return v


@nb.njit(cache=True)
def _poly(c, x):
    v = 0.0
    for j in range(c.size - 1, -1, -1):
        v = v * x + c[j]
    return v


@nb.njit(cache=True)
def _series_slope(coef, omega_t):
    """d/d(omega t) of :func:`_series_at`."""
    v = 0.0
    for j in range(1, coef.shape[1]):
        v += j * (coef[1, j] * math.cos(j * omega_t) - coef[0, j] * math.sin(j * omega_t))
    return v


@nb.njit(cache=True)
def rocking_acceleration(t, x, xdot, psi, psidot, args):
    """(xddot, psiddot) of the linearised antisymmetric equations (module docstring) at time t along the orbit.

    ``args = (y series, theta series, K_psipsi polynomials (3, n), K_xpsi polynomials (3, n), par)`` with
    ``par = [omega = 2 pi / P, 2k, Z_eq, M, arm, side, gamma_psi, load scale]``.  thetadot is the derivative of the
    theta series itself, so that I_r and dI_r/dt are consistent and the undamped monodromy's determinant is
    I_r(0) / I_r(P) = 1 to the integrator's accuracy."""
    y_s, th_s, kpp, kxp, par = args
    wt = par[0] * t
    y, th = _series_at(y_s, wt), _series_at(th_s, wt)
    thd = par[0] * _series_slope(th_s, wt)
    z = par[2] + y
    c, s = math.cos(par[1] * z), math.sin(par[1] * z)
    k_pp = par[7] * (_poly(kpp[0], th) + _poly(kpp[1], th) * c + _poly(kpp[2], th) * s)
    k_xp = par[7] * (_poly(kxp[0], th) + _poly(kxp[1], th) * c + _poly(kxp[2], th) * s)
    phi = math.pi * th / 4
    m, a, side = par[3], par[4], par[5]
    ir = m * (a * a * math.cos(phi) ** 2 + side * side / 6.0)
    dir_dt = -m * a * a * (math.pi / 4) * math.sin(2 * phi) * thd
    return -k_xp * psi / m, (-k_pp * psi - dir_dt * psidot) / ir - par[6] * psidot


@nb.njit(cache=True)
def _integrate_rocking(args, x0, h, substeps, n_out, lower, upper, out):
    return rk4(rocking_acceleration, args, x0, h, substeps, n_out, lower, upper, out)


def sample_orbit(args: tuple, x_orbit: ArrayLike, period: float, n: int, max_step: float = 2e-5) -> NDArray[np.float64]:
    """``n`` states (n, 4) of the held-y orbit through ``x_orbit`` at ``t_j = j period / n`` (the compiled held flow
    of :mod:`acousim.atlas.held_y`, ``args`` its kernel arguments), steps <= ``max_step`` [s]."""
    substeps = max(1, int(math.ceil(period / n / max_step - 1e-9)))
    out = np.empty((n + 1, 4))
    m, status = integrate_held(args, np.asarray(x_orbit, float), period / n / substeps, substeps, n + 1, *HINGE_BOX, out)
    if m < n + 1:
        raise ValueError(f"the held orbit left the box (status {status}) while being sampled")
    return out


def rocking_arguments(orbit: NDArray, period: float, polynomials: dict, two_k: float, z_eq: float,
                      inertia: AntisymmetricInertia, load_scale: float = 1.0, gamma_psi: float = 0.0) -> tuple:
    """The ``args`` of :func:`rocking_acceleration` from ``orbit`` (n, 4) states at ``t_j = j period / n`` (y and
    theta are read; n even).

    ``polynomials``: ``{"k_psipsi": (3, n), "k_xpsi": (3, n)}`` (:meth:`acousim.fullwave.antisymmetric_loads.RockingStiffness.
    polynomials`); ``load_scale`` multiplies both (``(p0 / p_table)^2``); ``gamma_psi`` [1/s] is a rocking damping."""
    orb = np.asarray(orbit, float)
    series = tuple(periodic_series(orb[:, j]) for j in (0, 2))
    par = np.array([2 * np.pi / period, two_k, z_eq, inertia.mass, inertia.arm, inertia.side, gamma_psi, load_scale])
    return (*series, np.ascontiguousarray(polynomials["k_psipsi"], float),
            np.ascontiguousarray(polynomials["k_xpsi"], float), par)


def rocking_multipliers(args: tuple, period: float, max_step: float = 2e-5) -> NDArray[np.complex128]:
    """The Floquet multipliers (2,) of the rocking pair (psi, psidot) over one ``period`` [s] of the orbit in
    ``args`` (:func:`rocking_arguments`); the sideways pair's are 1 (module docstring)."""
    steps = max(1, int(math.ceil(period / max_step)))
    return floquet_multipliers(_integrate_rocking, args, np.zeros(4), period, steps)
