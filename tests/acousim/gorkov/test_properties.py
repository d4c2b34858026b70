"""Property-based checks (hypothesis) of invariants that hold for any dimer and pose."""
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from acousim.dimer import CubeDimer
from acousim.gorkov.forces import GorkovDimer

sides = st.floats(min_value=300e-6, max_value=800e-6)
thetas = st.floats(min_value=-0.99, max_value=0.99)


@given(sa=sides, sb=sides, theta=thetas)
@settings(max_examples=60, deadline=None, derandomize=True)  # the same examples on every run
def test_inertia_bounds(sa, sb, theta):
    """I(theta) lies between the spin-only value and the value with the centres swinging at full radius."""
    d = CubeDimer(sa, sb)
    (ma, mb) = d.cube_masses
    spin = (np.pi / 4) ** 2 * (ma * sa**2 + mb * sb**2) / 6
    inertia = d.hinge_inertia(theta)
    assert spin * (1 - 1e-12) <= inertia <= spin + (np.pi / 4) ** 2 * (ma * sa**2 + mb * sb**2) / 2 * (1 + 1e-12)


@pytest.fixture(scope="module")
def model():
    return GorkovDimer()


@given(theta=thetas, y=st.floats(min_value=-250e-6, max_value=250e-6))
@settings(max_examples=40, deadline=None, derandomize=True)
def test_generalized_forces_invariants(model, theta, y):
    s = model.static_forces(theta, y)
    # restoring hinge torque at the default pressure: Q_theta has the opposite sign of theta
    # (theta within [-0.99, 0.99]: Q_theta ~ -sin(4 phi) only changes sign at |theta| = 1)
    assert s.q_theta * theta <= 1e-25
    # vertical restoring force for |y| below lambda/8 - |Z_eq|, about the bent dimer's own equilibrium: Z_eq is the
    # straight dimer's, and a bend moves the equilibrium by up to 45 nm (theta = 0.99), so within nanometres of
    # y = 0 the force at y = 0 decides the sign and the invariant is the force relative to it
    s0 = model.static_forces(theta, 0.0)
    assert (s.q_y - s0.q_y) * y <= 1e-25
    # that shift: the force at y = 0 over the trap's stiffness, below 0.1 um (1/2500 of the range above)
    h = 1e-7
    stiffness = -(model.static_forces(theta, h).q_y - model.static_forces(theta, -h).q_y) / (2 * h)
    assert stiffness > 0 and abs(s0.q_y / stiffness) < 1e-7
    # energy and forces consistent under a small step in y: dU/dy = -F_Z
    h = 1e-8
    fd = -(model.static_forces(theta, y + h).potential - model.static_forces(theta, y - h).potential) / (2 * h)
    np.testing.assert_allclose(s.force_z, fd, rtol=1e-5)  # FD truncation ~ (2kh)^2 ~ 3e-10, round-off ~1e-7
