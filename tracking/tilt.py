"""The hinge line's tilt out of the camera axis, from the silhouette's shape.

A hinge line turned by ``tau`` about the vertical shows each cube's square shortened across by ``cos(tau)`` and
swept along the rows by ``s sin(tau)`` over its depth ``s``: skewed hexagons, whose fitted squares' hinge corners
lie apart by about ``s sin(tau)``, and whose silhouette area is ``2 s^2 (cos(tau) + sqrt(2) sin(tau) -
sin(tau)^2 / (4 cos(tau)))`` (the two hexagons overlap near the hinge).  The side the tracking infers from the
area, ``sqrt(area / 2)``, is therefore too large by the square root of the bracket, and the ratio of the hinge
gap to that side fixes ``tau``: :func:`tilt_from_gap` inverts it (monotonic up to 40 degrees).  The angle is
the median over the frames that were measured or failed only the fit checks.

Above :data:`TILT_CORRECTION_DEG` (read from the squares' faces, :func:`tilt_from_faces`) the projection is undone.  The face fits (:func:`tracking.face_fit.fit_tilted_square`)
sample each cube's hexagon where its slanted edges are (the shortened square's faces moved by ``(s/2) sin(tau)``
along the rows, clear of the other cube's sweep at the hinge) and turn each fitted image direction ``d`` back into
the cube's, ``atan2(sin d, cos d / cos(tau))``: theta is then the cube's bend.  y needs one more step: each cube's
hexagon is centrally symmetric about its centre, but the two overlap in two triangles at the hinge (the union is
what the camera sees), above it where the faces open by ``alpha``, below by ``beta``.  A triangle between faces at
``a1``, ``a2`` from the vertical is ``2 h - k z`` wide at height ``z`` from the hinge (``h = (s/2) sin(tau)``,
``k = cos(tau) (tan a1 + tan a2)``), up to ``z = 2 h / k`` (or the faces' end, ``s cos a``); the silhouette's
centre of mass is lowered by ``[A_up (dz + z_up) + A_down (dz - z_down)] / A`` below the cubes' centres (``dz =
(s / sqrt 2) sin(pi theta / 4)`` the hinge's height above them, ``A_*`` and ``z_*`` the triangles' areas and
centroid heights, ``A`` the silhouette's area): :func:`overlap_shift`, which the tracking adds back.
"""
from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

__all__ = ["tilt_from_gap", "tilt_from_faces", "tilt_from_centres", "area_factor", "overlap_shift", "MAX_TILT_DEG", "TILT_CORRECTION_DEG", "TILT_FLOOR_DEG"]

#: Largest tilt [degrees] a recording is measured at; beyond it the squares no longer describe the silhouette.
MAX_TILT_DEG = 20.0
#: Tilt [degrees] above which the projection is undone, as :func:`tilt_from_faces` reads it: it reads up to 1 degree
#: on an aligned camera at 2-3 % noise and up to 2.3 on bright cubes on black at 5 %, so an aligned recording is
#: measured exactly as without this module; left as it is, a tilt of 3 degrees costs 0.013 px RMS in y and 2e-4 in
#: theta (noise-free renders, |theta| <= 0.75), 2 degrees about half that.
TILT_CORRECTION_DEG = 3.0
#: The floor of the refined tilt's error [degrees]: on renders at 5-15 degrees (image noise 0-2 %) the centres'
#: estimate lies within 0.5 degrees of the truth (0.25 degrees high at 2 % noise; it reads 0.25 on an aligned camera).
TILT_FLOOR_DEG = 0.5

_GRID = np.radians(np.linspace(0.0, 40.0, 401))


def area_factor(tau: NDArray | float) -> NDArray | float:
    """The silhouette area of a dimer tilted by ``tau`` [rad] over that of the untilted one (module docstring)."""
    c, s = np.cos(tau), np.sin(tau)
    return c + np.sqrt(2.0) * s - s * s / (4.0 * c)


def tilt_from_faces(gap_over_side: float) -> float:
    """The tilt [degrees] from the fitted squares' hinge gap over their side *from their faces* (the distances of
    opposite faces): ``asin`` of the ratio.  Unlike :func:`tilt_from_gap` it does not use the silhouette's area,
    which a coverage offset of the background enlarges (bright cubes on black at a few % noise: 6 %, which reads
    as 2-6 degrees of tilt there); it reads 0.3-1 degree on an aligned camera and 1.5, 2.9, 7.9 and 9.4 degrees at
    1.5, 3, 8 and 10 (renders at 2 % noise)."""
    return float(np.degrees(np.arcsin(np.clip(gap_over_side, 0.0, 1.0))))


def tilt_from_gap(gap_over_side: float) -> float:
    """The tilt [degrees] whose hinge gap over the area's side is ``gap_over_side`` (module docstring)."""
    ratio = np.sin(_GRID) / np.sqrt(area_factor(_GRID))
    return float(np.degrees(np.interp(max(0.0, gap_over_side), ratio, _GRID)))


def _triangle(h: NDArray, k: NDArray, z_end: NDArray) -> tuple[NDArray, NDArray]:
    """Area and first moment (about the hinge) of the overlap ``2 h - k z`` wide for ``0 <= z <= min(2 h / k,
    z_end)``."""
    zm = np.minimum(2.0 * h / np.maximum(k, 1e-12), z_end)
    return 2.0 * h * zm - 0.5 * k * zm ** 2, h * zm ** 2 - k * zm ** 3 / 3.0


def _overlap(theta: NDArray, body_tilt: NDArray, tau: NDArray | float, side_px: NDArray | float) -> tuple[NDArray, NDArray]:
    """Area [px^2] of the two cubes' overlap at the hinge and its first moment [px^3] about the cubes' centres'
    height (up positive), module docstring."""
    h = 0.5 * side_px * np.abs(np.sin(tau))
    alpha = 0.5 * np.pi * (1.0 + theta)
    dz = side_px / np.sqrt(2.0) * np.sin(0.25 * np.pi * theta)
    area = 0.0
    moment = 0.0
    for open_, sign in ((alpha, 1.0), (np.pi - alpha, -1.0)):
        a1 = np.clip(0.5 * open_ + body_tilt, 0.0, 0.5 * np.pi)
        a2 = np.clip(0.5 * open_ - body_tilt, 0.0, 0.5 * np.pi)
        k = np.cos(tau) * (np.tan(a1) + np.tan(a2))
        tri, mom = _triangle(h, k, side_px * np.minimum(np.cos(a1), np.cos(a2)))
        area = area + tri
        moment = moment + tri * dz + sign * mom
    return area, moment


def overlap_shift(theta: NDArray, body_tilt: NDArray, tau: float, side_px: float, area_px2: NDArray) -> NDArray:
    """How far [px] the silhouette's centre of mass lies *above* the cubes' centres (negative: below) for a hinge
    line tilted by ``tau`` [rad] (module docstring): 0 at ``tau = 0``.

    Parameters
    ----------
    theta : ndarray
        The bend [-] (``alpha = pi/2 + pi theta / 2``, ``beta = pi - alpha``).
    body_tilt : ndarray
        The dimer's turn in the image plane [rad] (``tilt`` of :data:`tracking.measure.COLUMNS`): it turns the
        bisectors of ``alpha`` and ``beta`` off the vertical.
    tau : float
        The hinge line's tilt out of the camera axis [rad].
    side_px : float
        The cubes' side [px].
    area_px2 : ndarray
        The silhouette's area [px^2].
    """
    theta = np.asarray(theta, float)
    return -_overlap(theta, np.asarray(body_tilt, float), tau, side_px)[1] / np.asarray(area_px2, float)


def tilt_from_centres(du: NDArray, dv: NDArray, theta: NDArray, body_tilt: NDArray, area_px2: NDArray) -> NDArray:
    """Each frame's tilt [rad] from its cubes' centres and its silhouette's area, NaN where none fits.

    The image shortens the centres' spacing ``sqrt(2) s cos(pi theta / 4)`` across by ``cos(tau)``, so ``s`` follows
    from ``du^2 / cos(tau)^2 + dv^2`` at every ``tau``; the silhouette's area is two swept squares, ``s^2 (cos(tau)
    + sin(tau) (|cos g| + |sin g|))`` each (``g`` a cube's face direction), less their overlap at the hinge.  The
    ``tau`` at which that area is the measured one is the tilt (a grid of 0.01 degrees up to 30): a 0.1 % error of
    the area or the spacing moves it by about 0.05 degrees.
    """
    du, dv, theta, body_tilt, area = (np.asarray(x, float)[:, None] for x in (du, dv, theta, body_tilt, area_px2))
    tau = np.radians(np.arange(0.0, 30.0, 0.01))[None, :]
    phi = 0.25 * np.pi * theta
    side2 = (du ** 2 / np.cos(tau) ** 2 + dv ** 2) / (2.0 * np.cos(phi) ** 2)
    side = np.sqrt(side2)
    extent = sum(np.abs(np.cos(g)) + np.abs(np.sin(g)) for g in (0.25 * np.pi - phi - body_tilt,
                                                                 0.25 * np.pi - phi + body_tilt))
    model = side2 * (2.0 * np.cos(tau) + np.sin(tau) * extent) - _overlap(theta, body_tilt, tau, side)[0]
    f = model - area
    cross = (f[:, :-1] <= 0) & (f[:, 1:] > 0)
    out = np.full(du.shape[0], np.nan)
    has = cross.any(axis=1)
    j = np.argmax(cross, axis=1)[has]
    f0, f1 = f[has, j], f[has, j + 1]
    out[has] = tau[0, j] + (tau[0, j + 1] - tau[0, j]) * f0 / (f0 - f1)
    return out
