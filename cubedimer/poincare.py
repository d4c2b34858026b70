"""Poincare section y = 0 crossed downwards (ydot < 0) and the Poincare map (docs/conventions.md section 6).

Crossing times are found by linear interpolation of y between the two frames that bracket the
sign change (y[k] > 0 >= y[k+1]); near y = 0 the curvature of y is small (yddot ~ -omega^2 y),
so the interpolation error is O(dt^3) rather than the O(dt) of taking the nearest frame.  The
other state components are interpolated linearly at the same fractional index.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

__all__ = ["PoincareSection", "poincare_section", "poincare_map"]


@dataclass(frozen=True, eq=False)
class PoincareSection:
    """Crossings of y = 0 with ydot < 0.

    Attributes
    ----------
    times : ndarray (K,) [s]
    points : ndarray (K, 3)
        (ydot [m/s], theta [-], thetadot [1/s]) at each crossing.
    """

    times: NDArray[np.float64]
    points: NDArray[np.float64]

    @property
    def theta(self) -> NDArray[np.float64]:
        return self.points[:, 1]

    @property
    def thetadot(self) -> NDArray[np.float64]:
        return self.points[:, 2]

    def __len__(self) -> int:
        return self.times.size


def poincare_section(t: NDArray, state: NDArray) -> PoincareSection:
    """Crossings of y = 0 with ydot < 0 of a sampled trajectory.

    Parameters
    ----------
    t : ndarray (n,) [s] (or any time unit)
    state : ndarray (n, 4)
        [y, ydot, theta, thetadot]; non-finite rows (after a blow-up) are ignored.
    """
    t = np.asarray(t, float)
    x = np.asarray(state, float)
    n = x.shape[0]
    ok = np.all(np.isfinite(x), axis=1)
    if not ok.all():
        n = int(np.argmin(ok))
        x, t = x[:n], t[:n]
    y = x[:, 0]
    k = np.flatnonzero((y[:-1] > 0.0) & (y[1:] <= 0.0))
    frac = y[k] / (y[k] - y[k + 1])
    times = t[k] + frac * (t[k + 1] - t[k])
    pts = x[k, 1:] + frac[:, None] * (x[k + 1, 1:] - x[k, 1:])
    keep = pts[:, 0] < 0.0
    return PoincareSection(times=times[keep], points=pts[keep])


def poincare_map(section: PoincareSection, components: slice = slice(1, 3)) -> tuple[NDArray, NDArray]:
    """Pairs (P_k, P_{k+1}) of successive crossings; default components (theta, thetadot)."""
    p = section.points[:, components]
    return p[:-1], p[1:]
