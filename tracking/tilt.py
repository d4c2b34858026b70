"""The hinge line's tilt out of the camera axis, from the silhouette's shape.

A hinge line turned by ``tau`` about the vertical shows each cube's square shortened across by ``cos(tau)`` and
swept along the rows by ``s sin(tau)`` over its depth ``s``: skewed hexagons, whose fitted squares' hinge corners
lie apart by about ``s sin(tau)``, and whose silhouette area is ``2 s^2 (cos(tau) + sqrt(2) sin(tau) -
sin(tau)^2 / (4 cos(tau)))`` (the two hexagons overlap near the hinge).  The side the tracking infers from the
area, ``sqrt(area / 2)``, is therefore too large by the square root of the bracket, and the ratio of the hinge
gap to that side fixes ``tau``: :func:`tilt_from_gap` inverts it (monotonic up to 40 degrees).  The angle is
the median over the frames that were measured or failed only the fit checks.
"""
from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

__all__ = ["tilt_from_gap", "area_factor", "MAX_TILT_DEG"]

#: Largest tilt [degrees] a recording is measured at; beyond it the squares no longer describe the silhouette.
MAX_TILT_DEG = 20.0

_GRID = np.radians(np.linspace(0.0, 40.0, 401))


def area_factor(tau: NDArray | float) -> NDArray | float:
    """The silhouette area of a dimer tilted by ``tau`` [rad] over that of the untilted one (module docstring)."""
    c, s = np.cos(tau), np.sin(tau)
    return c + np.sqrt(2.0) * s - s * s / (4.0 * c)


def tilt_from_gap(gap_over_side: float) -> float:
    """The tilt [degrees] whose hinge gap over the area's side is ``gap_over_side`` (module docstring)."""
    ratio = np.sin(_GRID) / np.sqrt(area_factor(_GRID))
    return float(np.degrees(np.interp(max(0.0, gap_over_side), ratio, _GRID)))
