"""The full-wave table as a static simulation model at absolute heights (acousim.fullwave.statics)."""
import numpy as np
import pytest

from acousim.fullwave.statics import FullwaveDimer, TableMismatch, default_fullwave_dimer


@pytest.fixture(scope="module")
def fw() -> FullwaveDimer:
    return default_fullwave_dimer()


def test_forces_are_the_surrogates_at_absolute_heights(fw):
    """integrals_at_height(theta, Z) is the surrogate's (Q_y, Q_theta) at y = Z - Z_eq, to round-off."""
    rng = np.random.default_rng(0)
    theta = rng.uniform(-0.85, 0.85, 50)
    y = rng.uniform(-3e-4, 3e-4, 50)
    s = fw.integrals_at_height(theta, fw.equilibrium_height + y)
    q_y, q_theta = fw.surrogate.generalized_forces(theta, y)
    # same series, evaluated through a different grouping of the terms: round-off only
    np.testing.assert_allclose(s.q_y, q_y, rtol=1e-9, atol=1e-9 * np.abs(q_y).max())
    np.testing.assert_allclose(s.q_theta, q_theta, rtol=1e-9, atol=1e-9 * np.abs(q_theta).max())
    np.testing.assert_allclose(s.thetaddot, q_theta / fw.dimer.hinge_inertia(theta), rtol=1e-12)
    # precomputed orientation sums give the same numbers
    s2 = fw.integrals_at_height(theta, fw.equilibrium_height + y, fw.orientation_sums(theta))
    np.testing.assert_array_equal(s2.force_z, s.force_z)


@pytest.mark.parametrize("theta", [0.0, 0.3, -0.6])
def test_path_potential_derivatives(fw, theta):
    """-dU/dtheta = Q_theta at every height (the path's last leg); -dU/dZ = F_Z along theta = 0 (its first leg)."""
    z = fw.equilibrium_height + np.array([-2e-4, 0.0, 1.5e-4])
    h = 1e-5
    u = lambda th, zz: fw.integrals_at_height(th, zz).potential  # noqa: E731
    dudth = (u(theta + h, z) - u(theta - h, z)) / (2 * h)
    # central differences of a smooth series: truncation error ~ h^2 (1e-10 relative)
    np.testing.assert_allclose(-dudth, fw.integrals_at_height(theta, z).q_theta, rtol=1e-6,
                               atol=1e-6 * abs(fw.integrals_at_height(0.5, z).q_theta).max())
    hz = 1e-8
    dudz = (u(0.0, z + hz) - u(0.0, z - hz)) / (2 * hz)
    np.testing.assert_allclose(-dudz, fw.integrals_at_height(0.0, z).force_z, rtol=1e-6)


def test_pressure_scaling_and_equilibrium(fw):
    """Forces scale as p0^2; the equilibrium height balances the weight."""
    other = fw.with_pressure(3300.0)
    th, z = np.array([0.2, -0.4]), np.array([-3e-4, -4e-4])
    np.testing.assert_allclose(other.integrals_at_height(th, z).force_z, 1.1**2 * fw.integrals_at_height(th, z).force_z,
                               rtol=1e-12)
    s = other.integrals_at_height(0.0, other.equilibrium_height)
    np.testing.assert_allclose(float(s.q_y), 0.0, atol=1e-9 * other.dimer.total_mass * other.gravity)


def test_refusals_name_the_problem(fw):
    with pytest.raises(TableMismatch, match="theta"):
        fw.orientation_sums(np.array([0.1, 0.95]))
