"""The near-field quadrature of the exterior field (acousim.fullwave.flux.double_layer_potential) against Gauss's
solid-angle identity and against finite differences of itself. No boundary-element solve is needed."""
from __future__ import annotations

import numpy as np
import pytest

trimesh = pytest.importorskip("trimesh")

from acousim.fullwave.flux import double_layer_potential  # noqa: E402
from acousim.medium import Medium  # noqa: E402


@pytest.fixture(scope="module")
def unit_cube():
    """The 12-triangle unit cube centred on the origin: elements 1.4 long, sharp edges and corners."""
    box = trimesh.creation.box(extents=(1.0, 1.0, 1.0))
    return np.asarray(box.vertices), np.asarray(box.faces)


def _points_near_the_edge_and_corner(distance: float, outside: bool) -> np.ndarray:
    """Points ``distance`` from the face x = 0.5, the edge x = y = 0.5 and the corner (0.5, 0.5, 0.5)."""
    e = 0.5 + distance if outside else 0.5 - distance
    return np.array([[e, 0.1, -0.2], [e, e, 0.1], [e, e, e], [e, 0.5 - distance, 0.3] if outside else [e, 0.0, 0.0]])


@pytest.mark.parametrize("distance", [0.1, 0.01, 0.003])
@pytest.mark.parametrize("outside", [True, False])
def test_unit_density_gives_the_solid_angle(unit_cube, distance, outside):
    """Laplace (k = 0): the double layer of sigma = 1 on a closed surface is 0 outside and -1 inside, with zero
    gradient, at any distance. Points 0.003 from an element 1.4 long (ratio 470) need eight recursive splittings;
    the 6-point rule then leaves errors of 1e-7 (measured 2e-8 to 2.5e-7), so 1e-6 tests the near-field
    recursion and not round-off. Gradients are scaled by the distance (their natural size near the surface)."""
    v, f = unit_cube
    pts = _points_near_the_edge_and_corner(distance, outside)
    val, grad = double_layer_potential(pts, v, f, np.ones(len(v)), 0.0)
    np.testing.assert_allclose(val, 0.0 if outside else -1.0, atol=1e-6)
    assert np.abs(grad).max() * distance < 1e-6


def test_without_recursion_the_near_field_is_wrong(unit_cube):
    """The same points 0.01 from the cube with the recursion switched off (max_depth 0): the one-rule sum is off
    by far more than the tolerance above, so that test checks the recursion."""
    v, f = unit_cube
    val, _ = double_layer_potential(_points_near_the_edge_and_corner(0.01, True), v, f, np.ones(len(v)), 0.0,
                                    max_depth=0)
    assert np.abs(val).max() > 1e-2


def test_gradient_is_the_derivative_of_the_value(unit_cube):
    """Helmholtz at the default wavenumber on a 500 um cube, two complex linear densities, points 0.02 to 0.2 side
    lengths from its edges: the returned gradient equals central differences of the value, to 1e-5 of the
    largest gradient. Every triangle is split three times regardless of distance (near_ratio infinite), so that
    the quadrature nodes do not move with the field point and the sum is smooth in it (the adaptive splitting
    changes where the point crosses a threshold, which differences would amplify by 1/step); step 1e-5 side:
    truncation ~ (1e-5 / 0.02)^2 = 2.5e-7 of the gradient's scale."""
    v, f = trimesh.remesh.subdivide(*unit_cube)
    side = 500e-6
    v = v * side
    k = Medium().wavenumber
    sigma = np.column_stack([v[:, 0] / side + 2j * v[:, 2] / side, 1.0 - 0.5j * v[:, 1] / side])
    pts = side * np.array([[0.52, 0.1, -0.3], [0.6, 0.55, 0.2], [0.7, 0.7, 0.7], [0.02, 0.53, -0.4]])
    rule = {"near_ratio": np.inf, "max_depth": 3}
    _, grad = double_layer_potential(pts, v, f, sigma, k, **rule)
    h = 1e-5 * side
    fd = np.empty_like(grad)
    for j in range(3):
        step = np.zeros(3)
        step[j] = h
        plus, _ = double_layer_potential(pts + step, v, f, sigma, k, **rule)
        minus, _ = double_layer_potential(pts - step, v, f, sigma, k, **rule)
        fd[:, j] = (plus - minus) / (2 * h)
    np.testing.assert_allclose(grad, fd, atol=1e-5 * np.abs(grad).max())


def test_one_density_column_and_bad_shapes(unit_cube):
    """A single density column gives (P,) values and (P, 3) gradients equal to the first of two columns; a density
    of the wrong length is refused."""
    v, f = unit_cube
    pts = np.array([[0.8, 0.2, 0.1], [0.0, 0.0, 0.9]])
    sig = np.linspace(0.5, 1.5, len(v))
    val1, grad1 = double_layer_potential(pts, v, f, sig, 3.0)
    val2, grad2 = double_layer_potential(pts, v, f, np.column_stack([sig, 2 * sig]), 3.0)
    assert val1.shape == (2,) and grad1.shape == (2, 3)
    np.testing.assert_allclose(val1, val2[:, 0], rtol=1e-13)
    np.testing.assert_allclose(grad2[:, :, 1], 2 * grad1, rtol=1e-13)
    with pytest.raises(ValueError, match="density must have shape"):
        double_layer_potential(pts, v, f, sig[:-1], 3.0)
