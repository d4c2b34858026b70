"""Exact nearest-point distances between two sampled trajectories (the attractor-shape loss).

The shape term of the long-time loss needs, for every simulated point, the distance to the nearest data
point, and the reverse.  :class:`PointGrid` bins the points on a square grid over their two widest
coordinates (about two cells per sqrt(n) along each).  A query starts from the squared distance to a
guessed point: both sets are trajectories sampled at the same times, and the same-time point of the other
set is usually close to the nearest one.  It then visits the grid cells ring by ring around its own cell,
skips every cell whose rectangle is already farther (in the two binned coordinates) than the best
distance found, and stops when a whole ring is.  The result is exact (the same distances as a k-d tree):
near the data, where a long-time refinement spends its evaluations, a query looks at a handful of cells;
far from it, at the cells within the best distance.
"""
from __future__ import annotations

from dataclasses import dataclass

import numba as nb
import numpy as np
from numpy.typing import NDArray

__all__ = ["PointGrid"]

#: relative slack on the pruning bounds, so that rounding in the cell edges never prunes the nearest point
_SLACK = 1.0 - 1e-9


@nb.njit(cache=True)
def _scan_cell(q: NDArray, points: NDArray, lo: int, hi: int, best: float) -> float:
    dim = points.shape[1]
    for j in range(lo, hi):
        s = 0.0
        for c in range(dim):
            d = q[c] - points[j, c]
            s += d * d
        if s < best:
            best = s
    return best


@nb.njit(cache=True)
def _bin(p: NDArray):
    """Grid of the points ``p`` (n, d) over their two widest coordinates: the coordinates, the grid's origin,
    cell size and shape, the points in cell-major order, the cells' start offsets and each point's rank."""
    n, dim = p.shape
    lo = p[0].copy()
    hi = p[0].copy()
    for i in range(1, n):
        for c in range(dim):
            lo[c] = min(lo[c], p[i, c])
            hi[c] = max(hi[c], p[i, c])
    spread = hi - lo
    a = 0
    for c in range(1, dim):
        if spread[c] > spread[a]:
            a = c
    b = 1 if a == 0 else 0
    for c in range(dim):
        if c != a and spread[c] > spread[b]:
            b = c
    per_axis = max(1, int(np.ceil(0.5 * np.sqrt(n))))
    cell = max(spread[a], spread[b]) / per_axis
    if not cell > 0.0:  # all points coincide in the binned coordinates
        cell = 1.0
    na = max(1, int(np.ceil(spread[a] / cell)))
    nb_ = max(1, int(np.ceil(spread[b] / cell)))
    cid = np.empty(n, dtype=np.int64)
    start = np.zeros(na * nb_ + 1, dtype=np.int64)
    for i in range(n):
        ia = min(max(int(np.floor((p[i, a] - lo[a]) / cell)), 0), na - 1)
        ib = min(max(int(np.floor((p[i, b] - lo[b]) / cell)), 0), nb_ - 1)
        cid[i] = ia * nb_ + ib
        start[cid[i] + 1] += 1
    for k in range(na * nb_):
        start[k + 1] += start[k]
    fill = start[:-1].copy()
    binned = np.empty_like(p)
    rank = np.empty(n, dtype=np.int64)
    for i in range(n):  # counting sort: stable, cell-major
        r = fill[cid[i]]
        fill[cid[i]] += 1
        rank[i] = r
        binned[r] = p[i]
    return a, b, lo[a], lo[b], cell, na, nb_, binned, start, rank


@nb.njit(cache=True)
def _nearest_squared(query: NDArray, points: NDArray, start: NDArray, rank: NDArray, guess: NDArray,
                     a: int, b: int, origin_a: float, origin_b: float, cell: float, na: int, nb_: int) -> NDArray:
    """Squared distance from each query row to the nearest row of ``points`` (binned, cell-major)."""
    m, dim = query.shape
    out = np.empty(m)
    kmax = max(na, nb_)
    for i in range(m):
        q = query[i]
        g = rank[guess[i]]
        best = 0.0
        for c in range(dim):
            d = q[c] - points[g, c]
            best += d * d
        qa = q[a]
        qb = q[b]
        ia = min(max(int(np.floor((qa - origin_a) / cell)), 0), na - 1)
        ib = min(max(int(np.floor((qb - origin_b) / cell)), 0), nb_ - 1)
        for k in range(kmax + 1):
            if k >= 1:
                lb = (k - 1) * cell * _SLACK
                if lb * lb >= best:
                    break
            for ja in range(ia - k, ia + k + 1):
                if ja < 0 or ja >= na:
                    continue
                edge = ja == ia - k or ja == ia + k
                step = 1 if edge else 2 * k
                jb = ib - k
                while jb <= ib + k:
                    if 0 <= jb < nb_:
                        # distance from q to the cell's rectangle in the two binned coordinates
                        x0 = origin_a + ja * cell
                        y0 = origin_b + jb * cell
                        dx = max(x0 - qa, qa - (x0 + cell), 0.0)
                        dy = max(y0 - qb, qb - (y0 + cell), 0.0)
                        if (dx * dx + dy * dy) * _SLACK < best:
                            cid = ja * nb_ + jb
                            best = _scan_cell(q, points, start[cid], start[cid + 1], best)
                    jb += step
        out[i] = best
    return out


@dataclass(frozen=True, eq=False)
class PointGrid:
    """A point set (n, d) binned on a grid over its two widest coordinates, for exact nearest-point queries.

    Attributes
    ----------
    points : ndarray (n, d)
        The points in their original order.
    axes : tuple of int
        The two binned coordinates.
    """

    points: NDArray[np.float64]
    axes: tuple[int, int]
    _binned: NDArray[np.float64]
    _start: NDArray[np.int64]
    _rank: NDArray[np.int64]
    _origin: tuple[float, float]
    _cell: float
    _shape: tuple[int, int]

    @classmethod
    def of(cls, points: NDArray) -> "PointGrid":
        """Bin ``points`` (n, d), n >= 1, d >= 2."""
        p = np.ascontiguousarray(points, dtype=float)
        if p.ndim != 2 or p.shape[0] == 0 or p.shape[1] < 2:
            raise ValueError(f"expected a non-empty (n, d >= 2) point array, got shape {p.shape}")
        if not np.all(np.isfinite(p)):
            raise ValueError("points must be finite")
        a, b, oa, ob, cell, na, nb_, binned, start, rank = _bin(p)
        return cls(points=p, axes=(int(a), int(b)), _binned=binned, _start=start, _rank=rank,
                   _origin=(float(oa), float(ob)), _cell=float(cell), _shape=(int(na), int(nb_)))

    def nearest_squared(self, query: NDArray, guess: NDArray | None = None) -> NDArray[np.float64]:
        """Squared distance from every row of ``query`` (m, d) to its nearest point.

        Parameters
        ----------
        query : ndarray (m, d), finite
        guess : ndarray (m,) of int, optional
            Index (into :attr:`points`) of a point expected to be close to each query; any valid index gives
            the exact answer, a close one makes it fast.  Default: the query's own row index, clipped to the
            point count (the same-time point of a trajectory sampled at the same times).
        """
        q = np.ascontiguousarray(query, dtype=float)
        n, d = self.points.shape
        if q.ndim != 2 or q.shape[1] != d:
            raise ValueError(f"query has shape {q.shape}, expected (m, {d})")
        if not np.all(np.isfinite(q)):
            raise ValueError("query points must be finite")
        if guess is None:
            g = np.minimum(np.arange(q.shape[0], dtype=np.int64), n - 1)
        else:
            g = np.asarray(guess, dtype=np.int64)
            if g.shape != (q.shape[0],) or (g.size and (g.min() < 0 or g.max() >= n)):
                raise ValueError("guess must hold one valid point index per query")
        return _nearest_squared(q, self._binned, self._start, self._rank, g, self.axes[0], self.axes[1],
                                self._origin[0], self._origin[1], self._cell, self._shape[0], self._shape[1])
