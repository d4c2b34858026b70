"""The air's damping from physics (acousim.dynamics.air_damping, docs/damping.md): each formula against its limits."""
import math

import numpy as np
import pytest
from scipy.integrate import quad

from acousim.dynamics.air_damping import (AIR_DYNAMIC_VISCOSITY_PA_S, air_damping_rates, dimer_drag_radii,
                                 hinge_damping_shape, oscillating_rotation_drag, oscillating_translation_drag,
                                 stokes_corner_factor, stokes_layer_thickness, wedge_gap_factor, wedge_squeeze_torque)

MU = AIR_DYNAMIC_VISCOSITY_PA_S
S = 500e-6


def test_stokes_layer_at_the_trap_frequency():
    # nu = 1.81e-5 / 1.204 = 1.503e-5 m^2/s; at 24 Hz sqrt(2 nu / omega) = sqrt(1.994e-7) = 0.4465 mm
    assert stokes_layer_thickness(MU / 1.204, 24.0) == pytest.approx(4.465e-4, rel=1e-3)


def test_translation_drag_limits():
    a = 300e-6
    # delta >> a: the steady Stokes drag, exactly
    assert oscillating_translation_drag(MU, a, a, math.inf) == 6 * math.pi * MU * a
    # sphere: the in-phase part of the oscillating-sphere drag, 6 pi mu a (1 + a / delta)
    assert oscillating_translation_drag(MU, a, a, a / 2) == pytest.approx(6 * math.pi * MU * a * 3, rel=1e-14)
    # delta << a: the Stokes-layer drag 6 pi mu a^2 / delta dominates (relative remainder delta / a)
    d = a * 1e-4
    assert oscillating_translation_drag(MU, a, a, d) == pytest.approx(6 * math.pi * MU * a ** 2 / d, rel=2e-4)


def _rotary_in_phase(a, delta):
    """Independent: the real part of the exact torque of a sphere in rotary oscillation, from the outgoing
    solution v_phi ~ (1 - i k r) exp(i k r) / r^2 with k = (1 + i) / delta (time factor exp(-i w t))."""
    k = (1 + 1j) / delta
    ratio = (k * k * a * a + 3j * k * a - 3) / (1 - 1j * k * a)
    return -(8 * math.pi / 3) * MU * a ** 3 * ratio.real


@pytest.mark.parametrize("x", [1e-6, 0.3, 1.0, 3.0, 1e4])
def test_rotation_drag_is_the_exact_rotary_oscillation(x):
    a = 300e-6
    assert oscillating_rotation_drag(MU, a, a / x) == pytest.approx(_rotary_in_phase(a, a / x), rel=1e-12)


def test_rotation_drag_limits():
    a = 300e-6
    # steady rotation 8 pi mu a^3 (relative correction 2x at x = 1e-6)
    assert oscillating_rotation_drag(MU, a, a * 1e6) == pytest.approx(8 * math.pi * MU * a ** 3, rel=1e-5)
    # thin layer: (8 pi / 3) mu a^4 / delta, the shear mu Omega a sin(t) / delta over the sphere (remainder 1/x)
    assert oscillating_rotation_drag(MU, a, a / 1e4) == pytest.approx(8 * math.pi / 3 * MU * a ** 4 / (a / 1e4), rel=2e-4)


def _reynolds_wedge_torque(s, h0, beta):
    """Independent lubrication solution by quadrature: film h0 + x beta on 0 < x < s turning about x = 0
    (squeeze velocity x), p = 0 at both ends; the torque per unit length and unit beta_dot is
    3 mu (I4 - I2^2 / I0), I_n = integral x^n / h^3."""
    moments = [quad(lambda x, n=n: x ** n / (h0 + x * beta) ** 3, 0, s, epsabs=0, epsrel=1e-12, limit=200)[0]
               for n in (0, 2, 4)]
    return 3 * MU * (moments[2] - moments[1] ** 2 / moments[0]) * s  # times the hinge length s


@pytest.mark.parametrize("beta, gap_ratio", [(0.02, 0.03), (0.1, 0.03), (0.3, 0.01), (0.3, 0.05), (0.05, 0.001)])
def test_wedge_torque_solves_the_reynolds_equation(beta, gap_ratio):
    # the corner factor is 1 - 0.4 beta^2 at small openings: divide it out to compare with lubrication alone
    got = wedge_squeeze_torque(MU, S, gap_ratio * S, beta) / stokes_corner_factor(beta)
    assert got == pytest.approx(_reynolds_wedge_torque(S, gap_ratio * S, beta), rel=1e-8)


def test_wedge_torque_scales_as_one_over_the_opening_cubed_and_is_cut_off_by_the_gap():
    g = 1e-7 * S  # a nearly closed hinge
    lead = [wedge_squeeze_torque(MU, S, g, b) * b ** 3 / (1.5 * MU * S ** 3) for b in (0.01, 0.02, 0.04)]
    # (3/2) mu s^3 / beta^3 times the corner factor 1 - 0.4 beta^2 (<= 6e-4 here) and the gap's
    # 1 - O((h0/(s beta))^2 ln^2) (<= 1e-8): equal within 1e-3
    np.testing.assert_allclose(lead, 1.0, atol=1e-3)
    # parallel faces (opening << gap / side): the squeeze film (4/15) mu s^5 / h0^3 per unit hinge length s, finite
    h0 = 0.03 * S
    assert wedge_squeeze_torque(MU, S, h0, 1e-6) == pytest.approx(4 / 15 * MU * S ** 6 / h0 ** 3, rel=1e-3)
    # the gap factor of a wide-open wedge over a small gap: F = 1 - 6 / lam + O((ln lam)^2 / lam^2)
    # (lam = s beta / h0); the logarithm is the cut-off of the hinge pressure's ln(s beta / h0)
    for lam in (1e2, 1e3, 1e4):
        assert abs((1 - wedge_gap_factor(lam)) * lam - 6) < 4 * math.log(lam) ** 2 / lam


def test_corner_factor_limits():
    assert stokes_corner_factor(1e-4) == pytest.approx(1.0, abs=1e-8)
    assert stokes_corner_factor(0.2) == pytest.approx(1 - 0.4 * 0.04, rel=2e-4)  # next term O(beta^4)
    assert stokes_corner_factor(math.pi / 4) == pytest.approx(
        (math.pi / 4) ** 3 * math.cos(math.pi / 4) / (3 * (math.sin(math.pi / 4) - math.pi / 4 * math.cos(math.pi / 4))))
    assert stokes_corner_factor(math.pi / 2) == 0.0 and stokes_corner_factor(2.0) == 0.0


def test_hinge_shape_is_symmetric_and_one_at_the_diamond():
    assert hinge_damping_shape(0.0, 0.03, 1.8, 0.47) == pytest.approx(1.0, abs=1e-15)  # both wedges at pi/2
    for th in (0.2, 0.6, 0.95):
        assert hinge_damping_shape(th, 0.03, 1.8, 0.47) == pytest.approx(hinge_damping_shape(-th, 0.03, 1.8, 0.47), rel=1e-14)
    # closing a wedge raises the damping steeply, and a smaller gap more
    assert hinge_damping_shape(0.9, 0.01, 1.8, 0.47) > hinge_damping_shape(0.9, 0.05, 1.8, 0.47) > hinge_damping_shape(0.5, 0.05, 1.8, 0.47)


def test_rates_of_the_paper_dimer():
    """500 um NaCl cubes, g = 0.03 s, f_y = 24 Hz, f_theta = 26 Hz, air at 1.204 kg/m^3, 1.81e-5 Pa s.

    By hand: delta_y = 0.4465 mm; dimer radii 0.834 s (steady) and 0.977 s (area); 6 pi mu (0.417 + 0.2387^2/... )
    -> c = 3.41e-4 * (4.17e-4 + 4.885e-4^2 / 4.465e-4) = 3.245e-7 kg/s over M = 5.4e-7 kg: 0.601 1/s.
    Hinge: a = 0.620 s, x = a / delta = 0.72, c_rot = 8 pi mu a^3 * 1.067 = 1.46e-14; 6 c_rot / (m s^2) = 1.29 1/s.
    """
    r = air_damping_rates(S, 0.03 * S, 24.0, 26.0)
    assert r.gamma_y == pytest.approx(0.601, rel=2e-3)  # hand value to 3 digits
    assert r.gamma_theta == pytest.approx(1.29, rel=5e-3)
    radii = dimer_drag_radii(S)
    assert radii.dimer_area == pytest.approx(math.sqrt(12 / (4 * math.pi)) * S)
    assert radii.cube_stokes == pytest.approx(0.661 * S)
    # the rates grow with the Stokes layer's share: at a lower frequency (thicker layer) less damping
    assert air_damping_rates(S, 0.03 * S, 5.0, 5.0).gamma_y < r.gamma_y
    # bad input: one line naming the quantity
    with pytest.raises(ValueError, match="gap must be positive"):
        air_damping_rates(S, 0.0, 24.0, 26.0)


def test_the_twin_loses_energy_at_the_computed_rate():
    """With only the air's damping, a small vertical oscillation (theta = 0 stays 0 in the Gor'kov model) loses its
    energy at exp(-gamma_y t): the effect enters the compiled equations of motion as -gamma_y ydot."""
    from acousim.dynamics.effects import air_damping_for
    from acousim.dynamics.integrator import DimerDynamics
    from acousim.dynamics.effects import EffectSet
    from acousim.models import ExperimentConditions
    from acousim.gorkov.energy_surrogate import cached_surrogate

    sur = cached_surrogate()
    effect = air_damping_for(sur, ExperimentConditions())
    dyn = DimerDynamics(sur, EffectSet((effect,)))
    traj = dyn.integrate([20e-6, 0.0, 0.0, 0.0], 4.0, 1e-3)
    energy = dyn.energy(traj.state)
    e0 = energy - dyn.energy(np.zeros(4))
    rate = -np.polyfit(traj.t, np.log(e0), 1)[0]
    # a weakly damped linear oscillator loses energy at exactly gamma_y; the energy's ripple at 2 f_y is
    # gamma_y / (2 w_y) ~ 2e-3 of it and averages out of a fit over 87 cycles; 20 um keeps the anharmonicity out
    assert rate == pytest.approx(effect.gamma_y, rel=1e-2)
    assert np.all(traj.state[:, 2] == 0.0)
