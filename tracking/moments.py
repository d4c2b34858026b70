"""Steps 3 and 4 of the per-frame measurement (:mod:`tracking.measure`): the coverage moments of the dimer's two
halves in one pass over its window, and from them each half's centroid and first face direction.  Compiled (numba).
"""
from __future__ import annotations

import math

from numba import njit

__all__ = ["half_moments", "window_moments", "half_direction"]


@njit(cache=True)
def half_moments(c, ua, ub, v0, v1, uo, vo, mom, j):  # pragma: no cover - compiled
    """M0 and the complex moments M_k = sum c z^k (k = 1..4, z = (u - uo) + i (vo - v)) of the columns
    ``ua..ub`` and rows ``v0..v1``, into ``mom[j:j + 9]`` (M0, Re M1, Im M1, ..., Re M4, Im M4)."""
    s0 = 0.0
    s1r = 0.0
    s1i = 0.0
    s2r = 0.0
    s2i = 0.0
    s3r = 0.0
    s3i = 0.0
    s4r = 0.0
    s4i = 0.0
    for v in range(v0, v1 + 1):
        Z = vo - v
        Z2 = Z * Z
        for u in range(ua, ub + 1):
            x = c[v, u]
            X = u - uo
            a2 = X * X - Z2
            b2 = 2.0 * X * Z
            s0 += x
            s1r += x * X
            s1i += x * Z
            s2r += x * a2
            s2i += x * b2
            s3r += x * (a2 * X - b2 * Z)
            s3i += x * (a2 * Z + b2 * X)
            s4r += x * (a2 * a2 - b2 * b2)
            s4i += x * (2.0 * a2 * b2)
    mom[j] = s0
    mom[j + 1] = s1r
    mom[j + 2] = s1i
    mom[j + 3] = s2r
    mom[j + 4] = s2i
    mom[j + 5] = s3r
    mom[j + 6] = s3i
    mom[j + 7] = s4r
    mom[j + 8] = s4i


@njit(cache=True)
def window_moments(c, u0, u1, v0, v1, u_split, ua, ub, vo, mom):  # pragma: no cover - compiled
    """One pass over the window: per half (A: columns below ``u_split``, about (ua, vo); B: about (ub, vo)) the
    coverage sum M0 and the complex moments M_k = sum c z^k, k = 1..4, with z = (u - u_o) + i (v_o - v).
    ``mom`` = (A: M0, Re M1, Im M1, ..., Re M4, Im M4, B: the same): 18 numbers."""
    us = int(math.ceil(u_split))
    for k in range(2):  # A, then B; the offset into mom known at run time (a constant compiles once per value)
        half_moments(c, u0 if k == 0 else us, us - 1 if k == 0 else u1, v0, v1, ua if k == 0 else ub, vo, mom, 9 * k)


@njit(cache=True)
def half_direction(mom, j, uo, vo, cen):  # pragma: no cover - compiled
    """Centroid (u, v) of one half into ``cen`` and the face direction (mod pi/2) of its square from the fourth-order
    complex moment about that centroid: for a square with faces along gamma, sum c (z - z_c)^4 =
    -(16/15) a^6 exp(4 i gamma)."""
    m0 = mom[j]
    m1 = complex(mom[j + 1], mom[j + 2])
    m2 = complex(mom[j + 3], mom[j + 4])
    m3 = complex(mom[j + 5], mom[j + 6])
    m4 = complex(mom[j + 7], mom[j + 8])
    d = m1 / m0
    m4c = m4 - 4.0 * d * m3 + 6.0 * d * d * m2 - 4.0 * d * d * d * m1 + d * d * d * d * m0
    cen[0] = uo + d.real
    cen[1] = vo - d.imag
    return 0.25 * (math.atan2(m4c.imag, m4c.real) - math.pi)
