"""Dimer geometry (docs/conventions.md section 2) and the hinge inertia (section 4)."""
import numpy as np
import pytest

from acousim.dimer import CubeDimer
from acousim.gorkov.mesh import grid_arrays, tetrahedralize_cube
from acousim.gorkov.quadrature import tetrahedral_quadrature

THETAS = [-0.9, -0.4, 0.0, 0.25, 0.7]


def _corners(side):
    return np.array([[a, b, c] for a in (-1, 1) for b in (-1, 1) for c in (-1, 1)], float) * side / 2


@pytest.mark.parametrize("theta", THETAS)
@pytest.mark.parametrize("sides", [(500e-6, None), (400e-6, 650e-6)])
def test_cubes_share_the_hinge_edge(theta, sides):
    dimer = CubeDimer(*sides)
    rot, off = dimer.cube_rotations(theta), dimer.centre_offsets(theta)
    hinge = []
    for i, side in enumerate(dimer.sides):
        lab = _corners(side) @ rot[i].T + off[i]
        # the hinge edge is the pair of corners closest to the other cube (parallel to Y)
        j = np.argsort(lab[:, 0] * (1 if i == 0 else -1))[-2:]
        hinge.append(lab[j][:, [0, 2]])
    np.testing.assert_allclose(hinge[0], hinge[1], atol=1e-15)  # same X and Z of both hinge corners
    np.testing.assert_allclose(hinge[0][:, 1], dimer.hinge_height(theta, 0.0), atol=1e-15)


@pytest.mark.parametrize("theta", THETAS)
def test_equal_cube_conventions(theta):
    s = 500e-6
    dimer = CubeDimer(s)
    phi, d = np.pi * theta / 4, s / np.sqrt(2)
    off = dimer.centre_offsets(theta)
    np.testing.assert_allclose(off[:, 0], [-d * np.cos(phi), d * np.cos(phi)], atol=1e-18)
    np.testing.assert_allclose(off[:, 2], 0.0, atol=1e-18)  # both centres at Z_com
    np.testing.assert_allclose(dimer.hinge_height(theta, 0.0), d * np.sin(phi), atol=1e-18)
    # cube B is turned clockwise (as the camera sees it) by phi from the diamond: its body
    # axis (1, 0, 0) points at pi/4 - phi above the horizontal
    ex = dimer.cube_rotations(theta)[1] @ np.array([1.0, 0, 0])
    np.testing.assert_allclose(np.arctan2(ex[2], ex[0]), np.pi / 4 - phi, atol=1e-14)


@pytest.mark.parametrize("sides", [(500e-6, None), (400e-6, 650e-6)])
def test_inertia_matches_mesh_kinetic_energy(sides):
    """I(theta) = sum over the mesh of rho |d r / d theta|^2 dV, r relative to the centre of mass."""
    dimer = CubeDimer(*sides)
    rho = dimer.material.density_kg_m3
    nodes = []
    for side in dimer.sides:
        pts, cells = grid_arrays(tetrahedralize_cube(side, 0.3 * side))
        nodes.append(tetrahedral_quadrature(pts, cells, degree=2))  # |dr/dtheta|^2 is quadratic: exact
    for theta in THETAS:
        h = 1e-6
        def pos(t):
            rot, off = dimer.cube_rotations(t), dimer.centre_offsets(t)
            return [x @ rot[i].T + off[i] for i, (x, _) in enumerate(nodes)]
        vel = [(a - b) / (2 * h) for a, b in zip(pos(theta + h), pos(theta - h))]
        inertia = sum(rho * np.sum(w * np.sum(v**2, axis=1)) for v, (_, w) in zip(vel, nodes))
        # central differences: O(h^2) ~ 1e-12 relative; quadrature exact for quadratics
        np.testing.assert_allclose(dimer.hinge_inertia(theta), inertia, rtol=1e-8)


def test_inertia_formula_of_physics_md():
    s, rho = 500e-6, 2160.0
    m = rho * s**3
    dimer = CubeDimer(s)
    theta = np.linspace(-1, 1, 11)
    phi = np.pi * theta / 4
    expected = (np.pi / 4) ** 2 * 2 * m * s**2 * (np.sin(phi) ** 2 / 2 + 1 / 6)
    np.testing.assert_allclose(dimer.hinge_inertia(theta), expected, rtol=1e-14)
    np.testing.assert_allclose(dimer.hinge_inertia_derivative(theta), (np.pi / 4) ** 3 * m * s**2 * np.sin(2 * phi), rtol=1e-12, atol=1e-30)


@pytest.mark.parametrize("sides", [(500e-6, None), (400e-6, 650e-6)])
def test_inertia_derivative_finite_difference(sides):
    dimer = CubeDimer(*sides)
    theta, h = np.linspace(-0.9, 0.9, 7), 1e-6
    fd = (dimer.hinge_inertia(theta + h) - dimer.hinge_inertia(theta - h)) / (2 * h)
    scale = dimer.hinge_inertia(0.0)
    np.testing.assert_allclose(dimer.hinge_inertia_derivative(theta), fd, atol=1e-8 * scale)


def test_centre_of_mass_is_origin():
    dimer = CubeDimer(400e-6, 650e-6)
    ma, mb = dimer.cube_masses
    for theta in THETAS:
        off = dimer.centre_offsets(theta)
        np.testing.assert_allclose(ma * off[0] + mb * off[1], 0.0, atol=1e-20)


@pytest.mark.parametrize("bad", [-1e-4, 0.0, np.nan])
def test_bad_side_rejected(bad):
    with pytest.raises(ValueError, match="side"):
        CubeDimer(bad)
