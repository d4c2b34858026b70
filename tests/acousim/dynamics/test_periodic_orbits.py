"""Periodic orbits by shooting and their Floquet multipliers (acousim.dynamics.periodic_orbits), against closed
forms: the Stuart-Landau oscillator with a damped linear oscillator beside it, and the dimer's own y oscillation with
an uncoupled cavity mode."""
import math

import numpy as np
import pytest
from scipy.linalg import expm

from acousim.dynamics.periodic_orbits import floquet_split, monodromy_matrix, shoot_periodic_orbit
from acousim.dynamics.resonator import CavityMode, CoupledCavity, coupled_flow
from acousim.medium import Medium
from acousim.twin import TwinConfig, twin_dynamics

MU, OMEGA, GAMMA, W0 = 0.3, 2.0, 0.4, 3.0  # Stuart-Landau growth and frequency; the linear oscillator's damping, w0
LINEAR = np.array([[0.0, 1.0], [-W0**2, -GAMMA]])


def stuart_landau_flow(x, t):
    """The exact flow of u + i v: r' = r (MU - r^2), phase' = OMEGA (the Hopf normal form), and of (z, zdot):
    z'' + GAMMA z' + W0^2 z = 0 (a matrix exponential)."""
    r0, ph0 = math.hypot(x[0], x[1]), math.atan2(x[1], x[0])
    r = math.sqrt(MU) / math.sqrt(1.0 + (MU / r0**2 - 1.0) * math.exp(-2.0 * MU * t))
    ph = ph0 + OMEGA * t
    return np.concatenate([[r * math.cos(ph), r * math.sin(ph)], expm(LINEAR * t) @ x[2:]])


def test_shooting_finds_the_stuart_landau_cycle_and_its_multipliers():
    """From a guess 20 % off in radius and 10 % in period, Newton finds r = sqrt(MU), T = 2 pi / OMEGA and z = 0.
    The multipliers: 1 along the flow, exp(-2 MU T) across the cycle and exp((-GAMMA/2 +- i w_d) T) for the linear
    oscillator (|mu| = exp(-GAMMA T / 2)).  The flow is exact, so the errors are the central differences' (eps^2 of
    the flow's third derivatives and round-off / eps: ~1e-10): checked to 1e-8."""
    guess = np.array([0.8 * math.sqrt(MU), 0.0, 0.05, -0.02])
    orbit = shoot_periodic_orbit(stuart_landau_flow, guess, 1.1 * 2 * math.pi / OMEGA, pinned=1)
    period = 2 * math.pi / OMEGA
    assert orbit.converged and orbit.residual < 1e-10
    assert orbit.period == pytest.approx(period, rel=1e-10)
    assert orbit.x0 == pytest.approx([math.sqrt(MU), 0.0, 0.0, 0.0], abs=1e-10)
    assert abs(orbit.trivial_multiplier - 1.0) < 1e-8 and orbit.flow_invariance < 1e-8
    w_d = math.sqrt(W0**2 - GAMMA**2 / 4)
    expected = [np.exp((-GAMMA / 2 + 1j * w_d) * period), np.exp((-GAMMA / 2 - 1j * w_d) * period),
                math.exp(-2 * MU * period)]
    got = sorted(orbit.multipliers, key=lambda m: (round(abs(m), 6), m.imag))
    want = sorted(expected, key=lambda m: (round(abs(m), 6), np.imag(m)))
    assert np.allclose(got, want, atol=1e-8)
    assert orbit.stable and orbit.max_multiplier == pytest.approx(math.exp(-GAMMA * period / 2), rel=1e-8)
    assert orbit.e_fold_periods == pytest.approx(2 / (GAMMA * period), rel=1e-7)


def test_the_monodromy_of_a_linear_damped_oscillator_is_its_matrix_exponential():
    """For z'' + gamma z' + w0^2 z = 0 the monodromy over any T is expm(A T), whose eigenvalues are
    exp((-gamma/2 +- i w_d) T); central differences of a linear flow are exact up to round-off (1e-10)."""
    flow = lambda x, t: expm(LINEAR * t) @ x  # noqa: E731
    m = monodromy_matrix(flow, np.array([0.3, -0.1]), 1.7, scale=[1.0, 3.0])
    s = np.diag([1.0, 3.0])
    assert np.allclose(s @ m @ np.linalg.inv(s), expm(LINEAR * 1.7), atol=1e-9)
    assert np.allclose(np.abs(np.linalg.eigvals(m)), math.exp(-GAMMA * 1.7 / 2), rtol=1e-9)


def test_the_trivial_multiplier_is_found_by_its_eigenvector_not_its_value():
    """A second multiplier closer to 1 than the trivial one (as near a threshold) is not taken for it."""
    m = np.diag([1.0 + 1e-3, 1.0 + 1e-7])
    trivial, rest, inv = floquet_split(m, np.array([1.0, 0.0]))
    assert trivial == pytest.approx(1.0 + 1e-3) and rest == pytest.approx([1.0 + 1e-7])
    assert inv == pytest.approx(1e-3)


def test_shooting_refuses_a_guess_with_no_orbit_nearby():
    """A damped linear oscillator has no periodic orbit but rest; from a guess far from rest Newton walks to rest
    (a fixed point, which closes for any period), which is not reported as an orbit."""
    flow = lambda x, t: expm(LINEAR * t) @ x  # noqa: E731
    orbit = shoot_periodic_orbit(flow, np.array([1.0, 0.0]), 2.0, pinned=1)
    assert not orbit.converged and orbit.multipliers.size == 0


@pytest.fixture(scope="module")
def inviscid_gorkov():
    """The twin's default Gor'kov dimer (500 um, 3 kPa), no air: the mirror-symmetric hinge stays at theta = 0."""
    return twin_dynamics(TwinConfig(air_damping=False))[0]


def test_the_dimer_y_oscillation_with_an_uncoupled_mode(inviscid_gorkov):
    """An uncoupled cavity (A_cav = inf), the inviscid Gor'kov dimer at theta = 0 and y 0.3 um below rest: the orbit
    is the trap's linear oscillation, T = 1 / f_y (the anharmonic shift ~(2k A)^2 ~ 2e-7 and RK4's phase error
    (w h)^4 / 120 ~ 1e-10 at h = 50 us: checked to 1e-6).  Its multipliers: the cavity's pair exp((-Gamma +- i
    Gamma x) T) (|mu| = exp(-Gamma T), to 1e-6 of RK4 at h Gamma = 1.4e-3); the hinge's pair on the unit circle
    (an undamped parametric oscillator, to 1e-6); y's pair at 1 (a conservative oscillator's family of orbits: a
    Jordan block, which the differences' ~1e-10 error splits by its square root, ~1e-5: checked to 1e-4)."""
    dyn = inviscid_gorkov
    f_y = dyn.force_model.linear_frequencies()[0]
    mode = CavityMode(5000.0, 1.0, math.inf)
    cav = CoupledCavity(dyn, mode, Medium())
    a_s = mode.steady_amplitude()
    x0 = np.array([-0.3e-6, 0.0, 0.0, 0.0, a_s.real, a_s.imag])
    steps = int(math.ceil(1.02 / f_y / cav.max_step(5e-5)))
    w = 2 * math.pi * f_y
    scale = [1e-6, w * 1e-6, 0.1, w * 0.1, 1.0, 1.0]
    # a conservative oscillator's orbits form a family: y's depth is held too (else Newton may walk to rest)
    orbit = shoot_periodic_orbit(coupled_flow(cav, steps), x0 + [0, 0, 0, 0, 0.01, -0.01], 1.02 / f_y,
                                 pinned=(0, 1), scale=scale)
    assert orbit.converged
    assert orbit.period == pytest.approx(1 / f_y, rel=1e-6)
    assert orbit.x0[4:] == pytest.approx([a_s.real, a_s.imag], abs=1e-9)
    assert orbit.flow_invariance < 1e-6
    mus = np.abs(np.append(orbit.multipliers, orbit.trivial_multiplier))
    gamma = cav.decay_rate
    assert np.sum(np.isclose(mus, math.exp(-gamma * orbit.period), rtol=1e-6)) == 2
    assert np.sum(np.isclose(mus, 1.0, atol=1e-4)) == 4
