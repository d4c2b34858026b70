"""The rocking and sideways modes along the symmetric orbits (acousim.atlas.rocking_stability): the kinetic energy against hand
computations and limits, the Floquet multipliers of the rocking pair against constant-stiffness oscillators, the
Wronskian along a moving hinge, the air's rocking damping in its steady limit."""
import math

import numpy as np
import pytest

from acousim.atlas.rocking_stability import (AntisymmetricInertia, periodic_series, rocking_arguments, rocking_multipliers)

S, RHO, GAP = 500e-6, 2160.0, 5e-6
M_CUBE = RHO * S**3


def _inertia(gap=GAP):
    return AntisymmetricInertia(mass=2 * M_CUBE, side=S, arm=S / math.sqrt(2) + gap / 2)


def test_rocking_inertia_by_hand_at_the_straight_dimer():
    """theta = 0: centres at X = +-a, so I_r = 2 (m a^2 + m s^2 / 6) (parallel axes plus each cube's m s^2/6)."""
    a = S / math.sqrt(2) + GAP / 2
    hand = 2 * (M_CUBE * a**2 + M_CUBE * S**2 / 6)
    np.testing.assert_allclose(_inertia().rocking_inertia(0.0), hand, rtol=1e-14)  # the same sum: rounding only
    # the hinge line sits at the centre of mass's height: no inertia couples x and psi there
    mm = _inertia().mass_matrix(0.0, _inertia().hinge_height(0.0))
    np.testing.assert_allclose(mm, np.diag([2 * M_CUBE, hand]), rtol=1e-14, atol=0)


def test_rocking_inertia_face_to_face_is_a_block_of_two_cubes():
    """theta = 1, no gap: the cubes touch face to face, a 2s x s x s block: I = M (4 s^2 + s^2) / 12 = 5/6 m s^2."""
    block = 2 * M_CUBE * ((2 * S) ** 2 + S**2) / 12
    np.testing.assert_allclose(_inertia(gap=0.0).rocking_inertia(1.0), block, rtol=1e-12)  # cos^2(pi/4) = 1/2 exactly


def test_pivot_coupling_and_hinge_inertia_round_trip():
    """x read at the hinge line (h = a sin phi above the centre of mass) couples x and psi by -M h; the determinant
    is M I_r whatever h.  I_r = (I_0 + I_2 cos^2 phi) / (pi/4)^2 from the hinge inertia's constants."""
    inert = _inertia()
    theta = 0.4
    h = inert.hinge_height(theta)
    np.testing.assert_allclose(h, inert.arm * math.sin(math.pi * theta / 4), rtol=1e-15)
    mm = inert.mass_matrix(theta, h)
    np.testing.assert_allclose(mm[0, 1], -2 * M_CUBE * h, rtol=1e-15)
    np.testing.assert_allclose(np.linalg.det(mm), 2 * M_CUBE * inert.rocking_inertia(theta), rtol=1e-9)
    q = (math.pi / 4) ** 2
    i0, i2 = q * 2 * M_CUBE * S**2 / 6, q * 2 * M_CUBE * inert.arm**2
    back = AntisymmetricInertia.from_hinge_inertia(2 * M_CUBE, i0, i2)
    np.testing.assert_allclose([back.side, back.arm], [S, inert.arm], rtol=1e-12)
    phi = math.pi * theta / 4
    np.testing.assert_allclose(inert.rocking_inertia(theta), (i0 + i2 * math.cos(phi) ** 2) / q, rtol=1e-12)
    # the derivative against a central difference (error ~ h^2 I_r''' ~ 1e-10 relative)
    d = 1e-5
    fd = (inert.rocking_inertia(theta + d) - inert.rocking_inertia(theta - d)) / (2 * d)
    np.testing.assert_allclose(inert.rocking_inertia_derivative(theta), fd, rtol=1e-8)


def test_periodic_series_reproduces_a_trigonometric_polynomial():
    t = np.arange(16) / 16
    v = 0.3 + 0.5 * np.cos(2 * np.pi * t) - 0.2 * np.sin(2 * np.pi * 3 * t)
    c = periodic_series(v)
    np.testing.assert_allclose(c[0, :2], [0.3, 0.5], atol=1e-14)
    np.testing.assert_allclose(c[1, 3], -0.2, atol=1e-14)
    with pytest.raises(ValueError, match="even number"):
        periodic_series(v[:-1])


def _constant_args(theta0, k0, period, gamma=0.0, k_mod=0.0):
    """An orbit at rest at (y, theta) = (0, theta0); K_psipsi = k0 (+ k_mod cos 2kZ with Z = Z_eq = 0)."""
    orbit = np.zeros((8, 4))
    orbit[:, 2] = theta0
    poly = {"k_psipsi": np.array([[k0, 0, 0], [k_mod, 0, 0], [0, 0, 0]], float), "k_xpsi": np.zeros((3, 3))}
    return rocking_arguments(orbit, period, poly, two_k=1.0, z_eq=0.0, inertia=_inertia(), gamma_psi=gamma)


def test_constant_stiffness_gives_multipliers_on_the_unit_circle_with_the_right_phase():
    """K and I_r constant: psi'' = -w^2 psi, so mu = exp(+-i w P) exactly; RK4 at h w ~ 3e-3 errs by ~(h w)^4 P/h."""
    inert = _inertia()
    theta0, f_r = 0.3, 20.0
    w = 2 * np.pi * f_r
    k0 = w**2 * float(inert.rocking_inertia(theta0))
    period = 0.0417
    mu = rocking_multipliers(_constant_args(theta0, k0, period), period)
    np.testing.assert_allclose(np.abs(mu), 1.0, atol=1e-9)
    phase = w * period % (2 * np.pi)  # the pair is exp(+-i phase); np.angle folds it into [-pi, pi]
    np.testing.assert_allclose(sorted(np.abs(np.angle(mu))), [min(phase, 2 * np.pi - phase)] * 2, atol=1e-8)
    # damping gamma: the product of the pair is exp(-gamma P)
    mu = rocking_multipliers(_constant_args(theta0, k0, period, gamma=3.0), period)
    np.testing.assert_allclose(abs(np.prod(mu)), math.exp(-3.0 * period), rtol=1e-8)


def test_a_negative_stiffness_is_unstable():
    """K < 0: psi grows as exp(w P); the monodromy's eigenvalues are exp(+-w P) (real)."""
    inert = _inertia()
    w, period = 30.0, 0.05
    k0 = -w**2 * float(inert.rocking_inertia(0.0))
    mu = rocking_multipliers(_constant_args(0.0, k0, period), period)
    np.testing.assert_allclose(sorted(np.abs(mu)), [math.exp(-w * period), math.exp(w * period)], rtol=1e-8)


def test_rocking_damping_has_the_steady_stokes_limit():
    """At a vanishing frequency the Stokes layer is unbounded: c_rot -> 8 pi mu a^3 (a = 0.620 s) and the centre's
    drag -> 6 pi mu a_S (a_S = 0.661 s), so gamma_psi -> 2 (8 pi mu a^3 + 6 pi mu a_S X^2) / I_r (to ~1e-6: a / delta)."""
    from acousim.atlas.rocking_stability import rocking_damping_rate
    from acousim.dynamics.air_damping import AIR_DYNAMIC_VISCOSITY_PA_S as MU

    inert = _inertia()
    a_rot = (3 / (4 * math.pi)) ** (1 / 3) * S
    steady = 2 * (8 * math.pi * MU * a_rot**3 + 6 * math.pi * MU * 0.661 * S * inert.arm**2) / inert.rocking_inertia(0.0)
    np.testing.assert_allclose(rocking_damping_rate(inert, 0.0, 1e-9), steady, rtol=1e-3)
    # the Stokes layer thins with the frequency: more drag at 24 Hz than steady
    assert rocking_damping_rate(inert, 0.0, 24.0) > steady


def test_undamped_multipliers_keep_the_wronskian_along_a_moving_hinge():
    """d/dt (I_r(theta(t)) psidot) = -K psi with a periodic theta(t) swinging by 0.5: the monodromy's determinant is
    I_r(0) / I_r(P) = 1 (to the RK4's ~1e-10 at 2e-5 s steps), whatever the swing does to the rocking."""
    inert = _inertia()
    period = 0.0415
    t = np.arange(64) / 64
    orbit = np.zeros((64, 4))
    orbit[:, 2] = 0.1 + 0.5 * np.cos(2 * np.pi * t)
    k0 = (2 * np.pi * 34.0) ** 2 * float(inert.rocking_inertia(0.0))
    poly = {"k_psipsi": np.array([[k0, 0, 0], [0, 0, 0], [0, 0, 0]], float), "k_xpsi": np.zeros((3, 3))}
    mu = rocking_multipliers(rocking_arguments(orbit, period, poly, 1.0, 0.0, inert), period)
    np.testing.assert_allclose(abs(np.prod(mu)), 1.0, atol=1e-8)
