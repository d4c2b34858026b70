"""Gaps in a run: short ones filled (PCHIP through the neighbours), long ones the places a run is split.

A tracking leaves frames empty where the dimer could not be measured.  A gap of at most ``max_gap`` frames is
filled by :func:`fill_gaps`; a longer one (the dimer out of view, a lost stretch of the recording) cannot be
bridged, and :func:`gap_segments` gives the stretches between such gaps, each a run of its own
(:func:`cubedimer.dataset.load_run_parts`).  A tracker that leaves the rows of lost frames out makes gaps in time
instead; :func:`fill_lost_frames` puts them back as missing frames.
"""
from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from scipy.interpolate import PchipInterpolator

from .errors import DatasetError

__all__ = ["fill_lost_frames", "fill_gaps", "gap_segments"]


def fill_gaps(t: NDArray, x: NDArray, max_gap: int, what: str, name: str) -> tuple[NDArray, int]:
    """Fill runs of at most ``max_gap`` non-finite samples by PCHIP interpolation.

    Raises DatasetError on a longer gap or on missing first/last frames beyond ``max_gap``.
    """
    bad = ~np.isfinite(x)
    if not bad.any():
        return x, 0
    # lengths of consecutive missing runs
    d = np.diff(np.r_[0, bad.astype(np.int8), 0])
    starts, ends = np.flatnonzero(d == 1), np.flatnonzero(d == -1)
    longest = int((ends - starts).max())
    if longest > max_gap:
        raise DatasetError(f"{name}: {longest} consecutive missing values of {what} at t={t[starts[np.argmax(ends - starts)]]:.4g} s "
                           f"(at most {max_gap} are filled)")
    good = ~bad
    if good.sum() < 4:
        raise DatasetError(f"{name}: almost no valid values of {what}")
    out = x.copy()
    out[bad] = PchipInterpolator(t[good], x[good], extrapolate=True)(t[bad])
    return out, int(bad.sum())



def gap_segments(missing: NDArray, max_gap: int) -> list[tuple[int, int]]:
    """The stretches ``[start, stop)`` of a run between its gaps of more than ``max_gap`` missing frames (and without
    longer missing stretches at its ends): one stretch, the whole run, when there is no such gap."""
    bad = np.asarray(missing, bool)
    d = np.diff(np.r_[0, bad.astype(np.int8), 0])
    starts, ends = np.flatnonzero(d == 1), np.flatnonzero(d == -1)
    cuts = [(a, b) for a, b in zip(starts, ends) if b - a > max_gap]
    edges, pos = [], 0
    for a, b in cuts:
        if a > pos:
            edges.append((pos, int(a)))
        pos = int(b)
    if pos < bad.size:
        edges.append((pos, int(bad.size)))
    return edges


def fill_lost_frames(t: NDArray, cols: list[NDArray], line_no: list[int | None], tol: float
                     ) -> tuple[NDArray, list[NDArray], list[int | None], int]:
    """Insert missing rows where a time step is an integer multiple (2 or more) of the median frame interval
    within ``tol`` of it: the rows of lost frames that a tracker left out.  Their values are missing
    (NaN; filled later like any missing frame) and their times lie on the uniform grid."""
    dt = np.diff(t)
    med = float(np.median(dt))
    n = np.rint(dt / med)
    lost = (n >= 2) & (np.abs(dt - n * med) <= tol * med)
    if not lost.any():
        return t, cols, line_no, 0
    steps = np.where(lost, n, 1).astype(np.int64)
    index = np.r_[0, np.cumsum(steps)]
    size = int(index[-1]) + 1
    grid = np.arange(size, dtype=float)
    t_full = np.interp(grid, index, t)
    out = []
    for c in cols:
        full = np.full(size, np.nan)
        full[index] = c
        out.append(full)
    lines: list[int | None] = [None] * size
    for i, k in zip(index, line_no):
        lines[int(i)] = k
    return t_full, out, lines, size - t.size
