"""The hinge corners of a measured frame (compiled): the opening angles of the faces that meet at each hinge corner,
fitted alone, and the distance between the two squares' hinge corners.

These check the measurement (:mod:`tracking.measure`, step 6): each cube's hinge corner is square
(``alpha_free + beta_free = pi``) and the two corners touch; :mod:`tracking.track` bounds both per recording.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from .face_fit import wrap_angle
from .frame_row import _I_ALPHA_FREE, _I_BETA_FREE, _I_HINGE_GAP, _I_SQUARENESS_SIGMA

__all__ = ["hinge_geometry"]


@njit(cache=True)
def _hinge_corner(g, left):  # pragma: no cover - compiled
    """Index k of the face whose corner with face k + 1 is the hinge corner: the rightmost corner of cube A
    (``left``) or the leftmost of cube B, for a square with faces along ``g``."""
    best = 0
    bestx = 0.0
    for k in range(4):
        n1 = g - 0.5 * math.pi + 0.5 * math.pi * k
        x = math.cos(n1) + math.cos(n1 + 0.5 * math.pi)
        if k == 0 or (left and x > bestx) or ((not left) and x < bestx):
            best = k
            bestx = x
    return best


@njit(cache=True)
def hinge_geometry(gam, cen, a_half, resA, resB, row):  # pragma: no cover - compiled
    """alpha_free, beta_free from the faces that meet at each hinge corner, fitted alone, and the distance
    between the two squares' hinge corners (written into ``row``), the squares as the image shows them (faces along
    ``res[24]``: the cubes' own directions unless the hinge line is tilted)."""
    free_ok = True
    var = 0.0
    dirs = np.zeros(4)  # A upper, A lower, B upper, B lower: directions pointing away from the hinge
    hx = np.zeros(2)
    hz = np.zeros(2)
    for sq in range(2):
        g = gam[sq]
        k1 = _hinge_corner(g, sq == 0)
        k2 = (k1 + 1) % 4
        nu1 = g - 0.5 * math.pi + 0.5 * math.pi * k1
        nu2 = nu1 + 0.5 * math.pi
        gi = resA[24] if sq == 0 else resB[24]
        ni = gi - 0.5 * math.pi + 0.5 * math.pi * _hinge_corner(gi, sq == 0)
        hx[sq] = cen[sq, 0] + a_half * (math.cos(ni) + math.cos(ni + 0.5 * math.pi))
        hz[sq] = -cen[sq, 1] + a_half * (math.sin(ni) + math.sin(ni + 0.5 * math.pi))
        if math.sin(nu1) >= math.sin(nu2):
            ku = k1
            kl = k2
            nuu = nu1
            nul = nu2
        else:
            ku = k2
            kl = k1
            nuu = nu2
            nul = nu1
        # the upper face points away from the hinge at its normal turned by -pi/2 on cube B, +pi/2 on cube A
        turn = 0.5 * math.pi if sq == 0 else -0.5 * math.pi
        du_nom = nuu + turn
        dl_nom = nul - turn
        fu = resA[8 + ku] if sq == 0 else resB[8 + ku]
        fl = resA[8 + kl] if sq == 0 else resB[8 + kl]
        if math.isnan(fu) or math.isnan(fl):
            free_ok = False
            continue
        dirs[2 * sq] = du_nom + wrap_angle(fu - du_nom, math.pi)
        dirs[2 * sq + 1] = dl_nom + wrap_angle(fl - dl_nom, math.pi)
        var += (resA[20 + ku] + resA[20 + kl]) if sq == 0 else (resB[20 + ku] + resB[20 + kl])
    if free_ok:
        row[_I_ALPHA_FREE] = wrap_angle(dirs[0] - dirs[2], 2.0 * math.pi)
        row[_I_BETA_FREE] = wrap_angle(dirs[3] - dirs[1], 2.0 * math.pi)
        row[_I_SQUARENESS_SIGMA] = math.sqrt(var)
    row[_I_HINGE_GAP] = math.sqrt((hx[0] - hx[1]) ** 2 + (hz[0] - hz[1]) ** 2)
