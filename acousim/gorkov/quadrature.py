"""Quadrature rules on tetrahedra.

A rule is a set of barycentric points and weights summing to one; the integral of f over a
tetrahedron T is ``vol(T) * sum_i w_i f(x_i)``.  Rules provided:

* degree 1: the centroid;
* degree 2: the symmetric 4-point rule (points at barycentric (a, a, a, b), a = (5 - sqrt 5)/20);
* any degree p >= 3: the collapsed (Duffy) tensor product of Gauss-Jacobi rules with
  n = ceil((p + 1) / 2) points per direction (n^3 points, all weights positive), exact for
  polynomials of total degree 2n - 1.
"""
from __future__ import annotations

from functools import lru_cache

import numpy as np
from numpy.typing import NDArray
from scipy.special import roots_jacobi

__all__ = ["tetrahedron_rule", "tetrahedral_quadrature", "tetrahedron_volumes"]


@lru_cache(maxsize=None)
def _rule(degree: int) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    if degree < 1:
        raise ValueError(f"quadrature degree must be >= 1, got {degree}")
    if degree == 1:
        return np.full((1, 4), 0.25), np.ones(1)
    if degree == 2:
        a = (5.0 - np.sqrt(5.0)) / 20.0
        b = 1.0 - 3.0 * a
        bary = np.full((4, 4), a)
        np.fill_diagonal(bary, b)
        return bary, np.full(4, 0.25)
    n = (degree + 2) // 2  # 2n - 1 >= degree
    # Reference tetrahedron {x, y, z >= 0, x + y + z <= 1} from the unit cube:
    # x = u, y = v (1 - u), z = w (1 - u)(1 - v), Jacobian (1 - u)^2 (1 - v).
    xu, wu = roots_jacobi(n, 2.0, 0.0)  # weight (1 - t)^2 on [-1, 1]
    xv, wv = roots_jacobi(n, 1.0, 0.0)  # weight (1 - t)
    xw, ww = roots_jacobi(n, 0.0, 0.0)  # Legendre
    u, wu = (xu + 1) / 2, wu / 8.0
    v, wv = (xv + 1) / 2, wv / 4.0
    w, ww = (xw + 1) / 2, ww / 2.0
    U, Vv, W = np.meshgrid(u, v, w, indexing="ij")
    weights = (wu[:, None, None] * wv[None, :, None] * ww[None, None, :]).ravel()
    x = U.ravel()
    y = (Vv * (1 - U)).ravel()
    z = (W * (1 - U) * (1 - Vv)).ravel()
    bary = np.column_stack([1 - x - y - z, x, y, z])
    weights = weights * 6.0  # reference volume is 1/6; weights sum to one
    return bary, weights


def tetrahedron_rule(degree: int) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Barycentric points (n, 4) and weights (n,) summing to one, exact to polynomial ``degree``."""
    bary, w = _rule(int(degree))
    return bary.copy(), w.copy()


def tetrahedron_volumes(points: NDArray[np.float64], cells: NDArray[np.integer]) -> NDArray[np.float64]:
    """Signed volumes [m^3] of tetrahedra ``cells`` (m, 4) with vertices ``points`` (N, 3)."""
    p = points[cells]
    return np.einsum(
        "ij,ij->i", np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), p[:, 3] - p[:, 0]
    ) / 6.0


def tetrahedral_quadrature(
    points: NDArray[np.float64], cells: NDArray[np.integer], degree: int = 2
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Quadrature nodes and weights for a whole tetrahedral mesh.

    Parameters
    ----------
    points : (N, 3) array
        Mesh vertices [m].
    cells : (m, 4) int array
        Tetrahedra.
    degree : int
        Polynomial degree integrated exactly on every tetrahedron.

    Returns
    -------
    nodes : (m * n, 3) array
        Quadrature points [m].
    weights : (m * n,) array
        Weights [m^3]; ``sum(weights * f(nodes))`` approximates the volume integral of f.
    """
    bary, w = _rule(int(degree))
    vol = np.abs(tetrahedron_volumes(points, cells))
    nodes = np.einsum("qv,tvd->tqd", bary, points[cells]).reshape(-1, 3)
    weights = (vol[:, None] * w[None, :]).ravel()
    return nodes, weights
