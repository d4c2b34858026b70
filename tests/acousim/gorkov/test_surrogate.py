"""The force surrogate used by the dynamics: accuracy against the mesh model, energy consistency,
symmetry and the pressure scaling."""
import numpy as np
import pytest

from acousim.gorkov.forces import GorkovDimer
from acousim.gorkov.energy_surrogate import DEFAULT_BOX, SurrogateBox, build_surrogate, cached_surrogate
from acousim.statics.sweep import taylor_coefficients

# The issue's requirement: surrogate within 0.5 % of direct evaluation over the swept box,
# relative to max |Q| over the box.
ISSUE_TOLERANCE = 5e-3


@pytest.fixture(scope="module")
def surrogate(default_model):
    return build_surrogate(default_model)


def test_surrogate_matches_direct_mesh_model_over_the_box(default_model, surrogate):
    acc = surrogate.accuracy(default_model, n_theta=31, n_y=23, seed=7)
    # the form U = alpha + beta cos 2kZ + gamma sin 2kZ is exact for the mesh sum and the
    # coefficient functions are entire in theta, so the only errors are round-off (Q_y, U ~ 1e-15)
    # and the round-off floor of the Chebyshev derivative for Q_theta (~1e-4 of the energy scale):
    # both are orders of magnitude inside the 0.5 % asked for.
    assert acc["q_y"] < ISSUE_TOLERANCE and acc["q_theta"] < ISSUE_TOLERANCE
    assert acc["q_y"] < 1e-10
    assert acc["q_theta"] < 1e-6
    assert acc["potential"] < 1e-10
    # the build-time check against the swept q_y, q_theta columns (never fitted) agrees
    assert surrogate.build_accuracy["q_theta_vs_sweep"] < 1e-6
    assert surrogate.build_accuracy["separable_residual"] < 1e-12


@pytest.mark.parametrize("side", [400e-6, 700e-6])
def test_surrogate_accuracy_other_sides(side):
    from acousim.dimer import CubeDimer

    model = GorkovDimer(CubeDimer(side))
    acc = build_surrogate(model).accuracy(model, n_theta=15, n_y=11)
    assert acc["q_y"] < 1e-10 and acc["q_theta"] < 1e-6


def test_wrong_pressure_is_detected(default_model, surrogate):
    """The accuracy check can fail: a 10 % pressure error shows up as ~20 % force errors."""
    acc = surrogate.accuracy(default_model.with_pressure(3300.0))
    assert acc["q_theta"] > 0.1 and acc["q_y"] > ISSUE_TOLERANCE


def test_forces_are_the_gradient_of_the_potential(surrogate):
    rng = np.random.default_rng(3)
    th = rng.uniform(-0.9, 0.9, 40)
    y = rng.uniform(-8e-4, 6e-4, 40)
    q_y, q_t = surrogate.generalized_forces(th, y)
    # central differences of V: truncation error h^2 V'''/6 ~ (h / scale)^2, with h = 1e-6 m vs
    # the 1.9 mm quarter wavelength (3e-7) and h = 1e-4 vs theta's unit scale (1e-8); round-off
    # |V| eps / h ~ 1e-9 |V| / 1e-6 relative to Q_y, and for Q_theta the potential's theta variation
    # is only 1e-4 of |V| so the round-off is ~1e-12 / 1e-4 / 1e-4 ~ 1e-4: tolerances 1e-5, 1e-3.
    h_y, h_t = 1e-6, 1e-4
    dv_dy = (surrogate.potential(th, y + h_y) - surrogate.potential(th, y - h_y)) / (2 * h_y)
    dv_dt = (surrogate.potential(th + h_t, y) - surrogate.potential(th - h_t, y)) / (2 * h_t)
    np.testing.assert_allclose(-dv_dy, q_y, rtol=0, atol=1e-5 * np.abs(q_y).max())
    np.testing.assert_allclose(-dv_dt, q_t, rtol=0, atol=1e-3 * np.abs(q_t).max())


def test_linear_frequencies_equal_swept_stiffnesses(default_model, surrogate):
    taylor = taylor_coefficients(default_model)
    f_y, f_t = surrogate.linear_frequencies()
    # the Taylor coefficients are a least-squares fit on a separate 17 x 17 sweep: agree to ~1e-8
    assert f_y == pytest.approx(np.sqrt(-taylor["yddot"]["y"]) / (2 * np.pi), rel=1e-6)
    assert f_t == pytest.approx(np.sqrt(-taylor["thetaddot"]["theta"]) / (2 * np.pi), rel=1e-6)
    # docs/conventions.md: the Gor'kov hinge is soft, ~0.08 x the y frequency; f_y ~ 22 Hz at the defaults
    assert 20 < f_y < 24 and 0.05 < f_t / f_y < 0.1


def test_symmetric_dimer_has_exactly_invariant_theta_zero(surrogate):
    assert surrogate.build_accuracy["symmetric"]
    y = np.linspace(-1e-3, 8e-4, 50)
    _, q_t = surrogate.generalized_forces(np.zeros_like(y), y)
    assert np.all(q_t == 0.0)  # exact: only even Chebyshev terms are kept
    assert np.all(np.asarray(surrogate.beta)[1::2] == 0)


def test_symmetry_can_be_switched_off(default_model):
    free = build_surrogate(default_model, symmetric=False)
    q_t = free.generalized_forces(np.zeros(5), np.linspace(-5e-4, 5e-4, 5))[1]
    q_max = np.abs(free.generalized_forces(0.5, 0.0)[1])
    # without enforcement the odd part is the round-off of the symmetrised quadrature: tiny, not zero
    assert np.all(np.abs(q_t) < 1e-8 * q_max)


@pytest.mark.parametrize("pressure", [2700.0, 3300.0])
def test_with_pressure_is_exact(default_model, surrogate, pressure):
    scaled = surrogate.with_pressure(pressure)
    model = default_model.with_pressure(pressure)
    assert scaled.z_eq == pytest.approx(model.equilibrium_height, rel=1e-10)
    acc = scaled.accuracy(model, n_theta=11, n_y=9)
    assert acc["q_y"] < 1e-10 and acc["q_theta"] < 1e-6


def test_escape_height_is_the_barrier(surrogate):
    y_esc = surrogate.escape_height()
    q_y, _ = surrogate.generalized_forces(0.0, y_esc)
    assert abs(q_y) < 1e-9 * surrogate.mass * surrogate.gravity
    # restoring (upwards) just above the barrier, downwards (out of the trap) just below
    assert surrogate.generalized_forces(0.0, y_esc + 1e-6)[0] > 0
    assert surrogate.generalized_forces(0.0, y_esc - 1e-6)[0] < 0
    # PHYSICS: Z_esc = -lambda/4 + |Z_eq| at the symmetric point of sin(2kZ)
    lam = 2 * np.pi / surrogate.wavenumber
    assert y_esc + surrogate.z_eq == pytest.approx(-lam / 4 - surrogate.z_eq, rel=1e-9)


def test_cache_returns_the_same_object():
    assert cached_surrogate(500e-6, 3000.0) is cached_surrogate(500e-6, 3000.0)


@pytest.mark.parametrize("kwargs", [{"theta_max": 1.0}, {"y_min": 1e-4, "y_max": -1e-4}, {"n_theta": 4}])
def test_bad_box_is_rejected(kwargs):
    with pytest.raises(ValueError):
        SurrogateBox(**kwargs)


def test_default_box_covers_the_trap(surrogate):
    # the escape height (~ -1.02 mm) lies just below the box, the node (+0.43 mm) inside it
    assert DEFAULT_BOX.y_min > surrogate.escape_height() - 1e-4
    assert DEFAULT_BOX.y_max > -surrogate.z_eq
