"""Tetrahedral quadrature rules integrate polynomials exactly up to their degree."""
from math import factorial

import numpy as np
import pytest

from acousim.gorkov.quadrature import tetrahedral_quadrature, tetrahedron_rule, tetrahedron_volumes


def exact_barycentric_moment(a, b, c, d):
    """Integral of l1^a l2^b l3^c l4^d over a tetrahedron of unit volume (Dirichlet integral)."""
    return factorial(a) * factorial(b) * factorial(c) * factorial(d) * 6 / factorial(a + b + c + d + 3)


@pytest.mark.parametrize("degree", [1, 2, 3, 5, 7])
def test_rule_is_exact_to_its_degree(degree):
    bary, w = tetrahedron_rule(degree)
    np.testing.assert_allclose(w.sum(), 1.0, rtol=1e-14)
    assert np.all(w > 0)  # no negative weights in any rule we provide
    for a in range(degree + 1):
        for b in range(degree + 1 - a):
            for c in range(degree + 1 - a - b):
                got = np.sum(w * bary[:, 0] ** a * bary[:, 1] ** b * bary[:, 2] ** c)
                # exactness is to round-off
                np.testing.assert_allclose(got, exact_barycentric_moment(a, b, c, 0), rtol=1e-12)


@pytest.mark.parametrize("degree", [1, 2])
def test_rule_is_not_exact_beyond_its_degree(degree):
    """A check that can fail: one degree higher the rule must show an error."""
    bary, w = tetrahedron_rule(degree)
    p = degree + 1
    errors = [abs(np.sum(w * bary[:, 0] ** p) - exact_barycentric_moment(p, 0, 0, 0))]
    assert max(errors) > 1e-6


def test_mesh_quadrature_of_unit_cube_moments(rng):
    """Split the unit cube into 6 Kuhn tetrahedra: degree-5 rule gives x^2 z^2 and x z^3 moments exactly."""
    corners = np.array([[i, j, k] for i in (0, 1) for j in (0, 1) for k in (0, 1)], float) - 0.5
    idx = lambda v: int(v[0] * 4 + v[1] * 2 + v[2])  # noqa: E731
    cells = []
    import itertools

    for perm in itertools.permutations(range(3)):
        v = np.zeros(3, int)
        path = [idx(v)]
        for ax in perm:
            v[ax] = 1
            path.append(idx(v))
        cells.append(path)
    cells = np.array(cells)
    vol = tetrahedron_volumes(corners, cells)
    cells[vol < 0] = cells[vol < 0][:, [0, 2, 1, 3]]
    x, w = tetrahedral_quadrature(corners, cells, degree=5)
    np.testing.assert_allclose(w.sum(), 1.0, rtol=1e-14)
    np.testing.assert_allclose(np.sum(w * x[:, 0] ** 2 * x[:, 2] ** 2), 1 / 144, rtol=1e-12)
    np.testing.assert_allclose(np.sum(w * x[:, 0] ** 4), 1 / 80, rtol=1e-12)
    np.testing.assert_allclose(np.sum(w * x[:, 0] * x[:, 2] ** 3), 0.0, atol=1e-15)
