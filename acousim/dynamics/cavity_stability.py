"""The cavity's lagged force: the linear stability of y, its threshold and the velocity couplings it implies.

Linearised about rest (y = 0, the mode at its steady amplitude, |a| = 1; :mod:`acousim.dynamics.resonator`), a
point body in a single-mode cavity obeys, with ``a = a_s (1 + u + i v)`` and ``s = |a|^2 = 1 + 2u``::

    yddot = -w_y^2 y - gamma_y ydot + g_ac (s - 1)          g_ac = F_Z,ac / M (= g at the equilibrium)
    du/dt = -Gamma u + Delta_0 v
    dv/dt = -Gamma v - Delta_0 u - kappa y                   kappa = dDelta/dy = -w F_Z,ac / E_mode  [rad/(s m)]

(Delta_0 = Gamma x).  Its characteristic equation is the quartic

    (lambda^2 + gamma_y lambda + w_y^2) ((lambda + Gamma)^2 + Delta_0^2) + 2 g_ac kappa Delta_0 = 0,

whose root of largest real part gives y's growth rate (:meth:`LinearCavityCoupling.growth_rate`).  To first order
in the coupling (lambda = i w_y + delta):

    sigma = -gamma_y / 2 + 2 g_ac kappa Delta_0 Gamma / |D|^2,   |D|^2 = (Gamma^2 + Delta_0^2 - w_y^2)^2 + 4 Gamma^2 w_y^2

(:meth:`LinearCavityCoupling.first_order_growth_rate`).  kappa < 0 below the node, so the drive above the resonance
(x < 0) feeds y and below it (x > 0) damps it; y oscillates by itself where sigma > 0 (the threshold,
:meth:`LinearCavityCoupling.unstable_detunings`).  The quasi-static part adds the stiffness
``2 g_ac kappa Delta_0 / (Gamma^2 + Delta_0^2)`` to w_y^2 (:meth:`LinearCavityCoupling.static_stiffness`; > 0, a
stiffer trap, for x < 0): the trap is lost when the sum is <= 0, the quartic's constant term, which then has a
real positive root.

For motion slow against the ring time, ``s = s_qs(Delta) - T(Delta) s_qs'(Delta) dDelta/dt`` with
``s_qs = (Gamma^2 + Delta_0^2) / (Gamma^2 + Delta^2)`` and the lag ``T = 2 Gamma / (Gamma^2 + Delta^2)``; with
``dDelta/dt = -(w / E_mode) (F_Z,ac ydot + Q_theta thetadot)`` this is a force linear in the velocities whose
coefficients, expanded about rest, are those of the suite's term names (:func:`lag_couplings`).

At a finite amplitude Y of y the same energy balance gives the describing-function gain (:func:`cycle_gain`): with
y held on ``Y cos(w_y t)`` (theta at rest) the mode is integrated to its periodic response and the work of the
modulated force over a cycle, ``W = int (|a|^2 - 1) F_Z,ac(y) ydot dt``, sets ``sigma(Y) = W / (2 E T) - gamma_y / 2``
(E = M w_y^2 Y^2 / 2, T = 2 pi / w_y).  It tends to the first-order growth rate as Y -> 0; a limit cycle of y sits
where sigma(Y) = 0 with d sigma / dY < 0.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from cubedimer.terms import term_name

from .resonator import CoupledCavity, slow_response_gains

__all__ = ["LinearCavityCoupling", "lag_couplings", "LAG_TERMS", "second_order_gains", "second_order_lag_couplings",
           "SECOND_ORDER_TERMS", "cycle_gain", "limit_cycle_amplitude"]


@dataclass(frozen=True)
class LinearCavityCoupling:
    """The linearised (y, ydot, u, v) system of the module docstring (SI units, rad/s for the rates).

    Attributes
    ----------
    omega_y : float
        y's angular frequency without the cavity's response [rad/s].
    gamma_y : float
        y's linear damping rate [1/s] (amplitude decays as exp(-gamma_y t / 2)).
    force_per_mass : float
        g_ac = F_Z,ac / M at rest [m/s^2].
    decay_rate : float
        Gamma [1/s].
    detuning : float
        Delta_0 [rad/s].
    kappa : float
        dDelta/dy at rest [rad/(s m)].
    """

    omega_y: float
    gamma_y: float
    force_per_mass: float
    decay_rate: float
    detuning: float
    kappa: float

    @classmethod
    def from_cavity(cls, cavity: CoupledCavity, gamma_y: float = 0.0, omega_y: float | None = None) -> "LinearCavityCoupling":
        """The coupling of a dimer's y at theta = 0 (``omega_y``: 2 pi f_y of its force model unless given)."""
        fm = cavity.dynamics.force_model
        f_ac = float(fm.generalized_forces(0.0, 0.0)[0]) + fm.mass * fm.gravity
        w = 2 * math.pi * fm.linear_frequencies()[0] if omega_y is None else float(omega_y)
        return cls(omega_y=w, gamma_y=float(gamma_y), force_per_mass=f_ac / fm.mass, decay_rate=cavity.decay_rate,
                   detuning=cavity.decay_rate * cavity.mode.detuning, kappa=-cavity.shift_per_joule * f_ac)

    def matrix(self) -> NDArray[np.float64]:
        """d/dt [y, ydot, u, v] = J [y, ydot, u, v]."""
        w, g, ga, d = self.omega_y, self.gamma_y, self.decay_rate, self.detuning
        return np.array([[0.0, 1.0, 0.0, 0.0],
                         [-w * w, -g, 2.0 * self.force_per_mass, 0.0],
                         [0.0, 0.0, -ga, d],
                         [-self.kappa, 0.0, -d, -ga]])

    def characteristic_polynomial(self) -> NDArray[np.float64]:
        """Coefficients (highest power first) of the quartic of the module docstring."""
        mech = np.array([1.0, self.gamma_y, self.omega_y**2])
        mode = np.array([1.0, 2.0 * self.decay_rate, self.decay_rate**2 + self.detuning**2])
        poly = np.polymul(mech, mode)
        poly[-1] += 2.0 * self.force_per_mass * self.kappa * self.detuning
        return poly

    def growth_rate(self) -> float:
        """The largest real part of the quartic's roots [1/s]: y's amplitude grows as exp(sigma t)."""
        return float(np.max(np.roots(self.characteristic_polynomial()).real))

    def oscillation_frequency(self) -> float:
        """|Im| of the root of largest real part [rad/s]."""
        r = np.roots(self.characteristic_polynomial())
        return float(abs(r[np.argmax(r.real)].imag))

    def first_order_growth_rate(self) -> float:
        """sigma to first order in the coupling (module docstring) [1/s]."""
        ga, d, w = self.decay_rate, self.detuning, self.omega_y
        dd = (ga**2 + d**2 - w**2) ** 2 + 4.0 * ga**2 * w**2
        return -0.5 * self.gamma_y + 2.0 * self.force_per_mass * self.kappa * d * ga / dd

    def static_stiffness(self) -> float:
        """w_y^2 plus the quasi-static stiffness of the cavity's response [1/s^2] (<= 0: the trap is lost)."""
        ga, d = self.decay_rate, self.detuning
        return self.omega_y**2 + 2.0 * self.force_per_mass * self.kappa * d / (ga**2 + d**2)

    def unstable_detunings(self) -> tuple[float, float] | None:
        """The detunings x = Delta_0 / Gamma [half-widths] between which the first-order sigma > 0, or None.

        sigma = 0 is ``gamma_y |D(x)|^2 / 2 = 2 g_ac kappa Gamma^2 x``, a quartic in x; its real roots of the sign
        of kappa bound the unstable band.
        """
        ga, w = self.decay_rate, self.omega_y
        # |D|^2 = (Gamma^2 x^2 + (Gamma^2 - w^2))^2 + 4 Gamma^2 w^2, a quartic in x
        c = ga**2 - w**2
        quartic = 0.5 * self.gamma_y * np.array([ga**4, 0.0, 2 * c * ga**2, 0.0, c * c + 4 * ga**2 * w**2])
        quartic[3] -= 2.0 * self.force_per_mass * self.kappa * ga**2
        if self.gamma_y == 0:
            return (-math.inf, 0.0) if self.kappa < 0 else (0.0, math.inf)
        roots = np.roots(quartic)
        real = np.sort(roots[np.abs(roots.imag) < 1e-9 * np.abs(roots).max()].real)
        if real.size < 2:
            return None
        # two real roots bound the one band (four would need w_y > Gamma and a strong coupling: the band nearest 0)
        if real.size == 4:
            real = real[:2] if self.kappa < 0 else real[2:]
        return float(real[0]), float(real[1])


#: The library terms (docs/conventions.md section 6) the first-order lag produces up to degree 3: one velocity
#: times a monomial of degree <= 2 in (y, theta).
LAG_TERMS = tuple(term_name(e) for e in
                  [(0, 1, 0, 0), (1, 1, 0, 0), (0, 1, 1, 0), (2, 1, 0, 0), (1, 1, 1, 0), (0, 1, 2, 0),
                   (0, 0, 0, 1), (1, 0, 0, 1), (0, 0, 1, 1), (2, 0, 0, 1), (1, 0, 1, 1), (0, 0, 2, 1)])


def _lag_gains(cavity: CoupledCavity, theta: NDArray, y: NDArray) -> tuple[NDArray, NDArray, NDArray, NDArray]:
    """(dyddot/dydot, dyddot/dthetadot, dthetaddot/dydot, dthetaddot/dthetadot) of the first-order lag force at
    (theta, y) [1/s, m, 1/(m s), 1/s] (module docstring)."""
    fm = cavity.dynamics.force_model
    q_y, q_t = fm.generalized_forces(theta, y)
    f_z = q_y + fm.mass * fm.gravity
    _, lag_gain = slow_response_gains(cavity.decay_rate, cavity.decay_rate * cavity.mode.detuning,
                                      cavity.detuning_rad_s(theta, y))
    # s_vel = -T s' dDelta/dt = T s' chi (F_Z ydot + Q_theta thetadot)
    k = -lag_gain * cavity.shift_per_joule
    inertia = fm.hinge_inertia(theta)
    return (f_z / fm.mass * k * f_z, f_z / fm.mass * k * q_t, q_t / inertia * k * f_z, q_t / inertia * k * q_t)


def lag_couplings(cavity: CoupledCavity, y_scale: float = 50e-6, theta_scale: float = 0.2) -> dict[str, dict[str, float]]:
    """The velocity-dependent terms the cavity's lag adds to the accelerations, to first order in the lag, as
    coefficients of the suite's term names (:data:`LAG_TERMS`; SI units, docs/formats.md).

    The gains (module docstring) are fitted by least squares with the quadratic monomials of (y, theta) on a 9 x 9
    Chebyshev grid over +-``y_scale`` [m] x +-``theta_scale`` (their Taylor coefficients about rest, up to the
    cubic remainder over that box).

    Returns
    -------
    dict
        ``{"yddot": {term: coefficient}, "thetaddot": {term: coefficient}}``.
    """
    nodes = np.cos(np.pi * (np.arange(9) + 0.5) / 9)
    th, yy = np.meshgrid(theta_scale * nodes, y_scale * nodes, indexing="ij")
    th, yy = th.ravel(), yy.ravel()
    basis = np.stack([np.ones_like(yy), yy, th, yy * yy, yy * th, th * th], axis=1)
    g_yy, g_yt, g_ty, g_tt = _lag_gains(cavity, th, yy)
    fit = lambda v: np.linalg.lstsq(basis, v, rcond=None)[0]  # noqa: E731
    out = {}
    for eq, (gy, gt) in (("yddot", (g_yy, g_yt)), ("thetaddot", (g_ty, g_tt))):
        coef = np.concatenate([fit(gy), fit(gt)])
        out[eq] = {name: float(c) for name, c in zip(LAG_TERMS, coef)}
    return out


def second_order_gains(decay_rate: float, drive_detuning: float, detuning) -> tuple[NDArray, NDArray]:
    """The mode's response to a slowly changing detuning at second order in the lag: (P, R) with
    ``|a|^2 = s_qs - T s_qs' dDelta/dt + P (dDelta/dt)^2 + R d^2Delta/dt^2 + O(T^3)``.

    The slow manifold of ``da/dt = -D a + g``, D = Gamma + i Delta, g = Gamma a_d: a = a0 + a1 + a2 + ... with
    a0 = g / D and a_(n+1) = -(da_n/dt) / D, so a1 = i g Delta' / D^3 and a2 = -i g Delta'' / D^4 - 3 g Delta'^2 / D^5;
    |a|^2 at second order is |a1|^2 + 2 Re(conj(a0) a2):

        P = g^2 / |D|^6 - 6 g^2 Re(conj(D)^4) / |D|^10        [s^2/rad^2]
        R = 2 g^2 Im(conj(D)^3) / |D|^8                        [s^2/rad]

    (the first order, -2 g^2 Im(conj(D)^2) / |D|^6 Delta' = -T s_qs' Delta', is :func:`slow_response_gains`'s), with
    g^2 = Gamma^2 + Delta_0^2 (the drive that holds |a| = 1 at rest).

    Parameters
    ----------
    decay_rate : float
        Gamma [1/s].
    drive_detuning : float
        Delta_0 [rad/s].
    detuning : array_like
        Delta [rad/s].
    """
    ga, d0 = float(decay_rate), float(drive_detuning)
    dc = ga - 1j * np.asarray(detuning, dtype=float)  # conj(D)
    mag2 = np.abs(dc) ** 2
    g2 = ga**2 + d0**2
    return g2 / mag2**3 - 6.0 * g2 * np.real(dc**4) / mag2**5, 2.0 * g2 * np.imag(dc**3) / mag2**4


#: The velocity-quadratic terms of the second order in the lag (each equation), in the suite's names.
SECOND_ORDER_TERMS = tuple(term_name(e) for e in
                           [(0, 2, 0, 0), (1, 2, 0, 0), (0, 2, 1, 0), (0, 1, 0, 1), (1, 1, 0, 1), (0, 1, 1, 1),
                            (0, 0, 0, 2), (1, 0, 0, 2), (0, 0, 1, 2)])


def _second_order_gains_at(cavity: CoupledCavity, theta: NDArray, y: NDArray) -> dict[str, tuple[NDArray, NDArray]]:
    """Per equation, the gains of ydot^2, ydot*thetadot and thetadot^2 at (theta, y): the force (xddot_on -
    xddot_off) times P Delta'^2 + R Delta''_vel, with Delta' = chi (U_y ydot + U_theta thetadot) and Delta''_vel =
    chi (U_yy ydot^2 + 2 U_ytheta ydot thetadot + U_thetatheta thetadot^2), U's derivatives those of the potential
    series that detunes the simulated mode (:meth:`acousim.dynamics.resonator.PotentialSeries.derivatives`)."""
    fm = cavity.dynamics.force_model
    q_y, q_t = fm.generalized_forces(theta, y)
    f_z = q_y + fm.mass * fm.gravity
    chi = cavity.shift_per_joule
    p, r = second_order_gains(cavity.decay_rate, cavity.decay_rate * cavity.mode.detuning,
                              cavity.detuning_rad_s(theta, y))
    u_y, u_t, u_yy, u_yt, u_tt = cavity.potential.derivatives(theta, y)
    quad = (p * chi**2 * u_y**2 + r * chi * u_yy, 2 * p * chi**2 * u_y * u_t + 2 * r * chi * u_yt,
            p * chi**2 * u_t**2 + r * chi * u_tt)
    return {"yddot": tuple(f_z / fm.mass * c for c in quad), "thetaddot": tuple(q_t / fm.hinge_inertia(theta) * c
                                                                                for c in quad)}


def second_order_lag_couplings(cavity: CoupledCavity, y_scale: float = 50e-6,
                               theta_scale: float = 0.2) -> dict[str, dict[str, float]]:
    """The velocity-quadratic terms of the lagged force at second order in the lag, as coefficients of the suite's
    term names (:data:`SECOND_ORDER_TERMS`: ydot^2, ydot*thetadot and thetadot^2, each times 1, y and theta; SI).

    The gains (:func:`second_order_gains`, the velocity-quadratic part of d^2Delta/dt^2; its acceleration part,
    chi (U_y yddot + U_theta thetaddot), becomes position terms and damping-linear ones through the equations of
    motion and is left out) are fitted with the cubic monomials of (y, theta) on a 9 x 9 Chebyshev grid over
    +-``y_scale`` [m] x +-``theta_scale``, and the constant and linear coefficients reported (the library's degree
    3): the Taylor coefficients about rest up to the quartic remainder (a quadratic fit would alias y*theta^2 into y)."""
    nodes = np.cos(np.pi * (np.arange(9) + 0.5) / 9)
    th, yy = np.meshgrid(theta_scale * nodes, y_scale * nodes, indexing="ij")
    th, yy = th.ravel(), yy.ravel()
    basis = np.stack([yy**i * th**j for d in range(4) for i in range(d, -1, -1) for j in [d - i]], axis=1)
    fit = lambda v: np.linalg.lstsq(basis, v, rcond=None)[0][:3]  # noqa: E731
    gains = _second_order_gains_at(cavity, th, yy)
    return {eq: {name: float(c) for name, c in zip(SECOND_ORDER_TERMS, np.concatenate([fit(g) for g in gains[eq]]))}
            for eq in ("yddot", "thetaddot")}


def cycle_gain(cavity: CoupledCavity, amplitudes, gamma_y: float = 0.0, omega_y: float | None = None,
               cycles: int | None = None, steps_per_cycle: int = 2000) -> NDArray[np.float64]:
    """sigma(Y) [1/s] of the module docstring for each amplitude Y [m] (vectorised RK4 of the mode over ``cycles``
    periods, the last one integrated; by default enough periods for the mode's transient to decay to exp(-12))."""
    fm = cavity.dynamics.force_model
    w = 2 * math.pi * fm.linear_frequencies()[0] if omega_y is None else float(omega_y)
    period = 2 * math.pi / w
    ga = cavity.decay_rate
    if cycles is None:
        cycles = 1 + int(math.ceil(12.0 / (ga * period)))
    amp = np.atleast_1d(np.asarray(amplitudes, float))
    h = period / steps_per_cycle
    a = np.full(amp.shape, cavity.mode.steady_amplitude(), complex)
    drive = ga * cavity.mode.drive_amplitude()

    def rate(t, a):
        y = amp * np.cos(w * t)
        return -(ga + 1j * cavity.detuning_rad_s(0.0, y)) * a + drive

    def power(t, a):
        y, ydot = amp * np.cos(w * t), -amp * w * np.sin(w * t)
        f_z = fm.generalized_forces(0.0, y)[0] + fm.mass * fm.gravity
        return (np.abs(a) ** 2 - 1.0) * f_z * ydot

    work = np.zeros(amp.shape)
    t = 0.0
    for step in range(cycles * steps_per_cycle):
        k1 = rate(t, a)
        k2 = rate(t + h / 2, a + h / 2 * k1)
        k3 = rate(t + h / 2, a + h / 2 * k2)
        k4 = rate(t + h, a + h * k3)
        a_next = a + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        if step >= (cycles - 1) * steps_per_cycle:  # trapezoid over the last cycle (periodic integrand: spectral)
            work += 0.5 * h * (power(t, a) + power(t + h, a_next))
        a, t = a_next, t + h
    energy = 0.5 * fm.mass * w * w * amp * amp
    return work / (2.0 * energy * period) - 0.5 * gamma_y


def limit_cycle_amplitude(cavity: CoupledCavity, gamma_y: float, amplitudes) -> float:
    """The smallest amplitude Y [m] among the increasing grid ``amplitudes`` where the describing-function gain
    :func:`cycle_gain` (with the air's ``gamma_y`` [1/s]) falls through zero (a stable limit cycle of y), linearly
    interpolated; NaN if it does not within the grid."""
    amp = np.asarray(amplitudes, float)
    sigma = cycle_gain(cavity, amp, gamma_y=gamma_y, steps_per_cycle=600)
    down = np.flatnonzero((sigma[:-1] > 0) & (sigma[1:] <= 0))
    if not down.size:
        return float("nan")
    j = down[0]
    return float(amp[j] + (amp[j + 1] - amp[j]) * sigma[j] / (sigma[j] - sigma[j + 1]))
