"""Steps 1 and 2 of the per-frame measurement (:mod:`tracking.measure`): background and particles.

The background plane with the frame's own level from a ring of border pixels, the coverage of every pixel, and
the pixels with coverage above 1/2 joined into 8-connected components (union-find over runs along the rows).
Compiled (numba).
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["BORDER_RING", "background", "coverage_runs", "particles"]

#: Width of the border ring the background level and pixel noise are measured on [px].
BORDER_RING = 2


@njit(cache=True)
def _find(parent, i):  # pragma: no cover - compiled
    while parent[i] != i:
        parent[i] = parent[parent[i]]
        i = parent[i]
    return i


@njit(cache=True)
def background(img, pol, bg_ref, contrast, slope_u, slope_v, out):  # pragma: no cover - compiled
    """The frame's background level on the border ring, with the recording's plane slopes ``slope_u``,
    ``slope_v`` (grey levels per pixel about the frame's centre): writes (offset, 0, 0, residual rms, status)
    into ``out``; status 1 for a blank or corrupt frame (non-finite pixels, or a border that looks like a
    cube nearly everywhere).  Pixels that look like a cube are left out."""
    h, w = img.shape
    uc0 = 0.5 * (w - 1)
    vc0 = 0.5 * (h - 1)
    n_all = 0
    n = 0
    s1 = 0.0
    s2 = 0.0
    out[4] = 0.0
    for v in range(h):
        edge_row = v < BORDER_RING or v >= h - BORDER_RING
        for j in range(w if edge_row else 2 * BORDER_RING):
            u = j if edge_row else (j if j < BORDER_RING else w - 2 * BORDER_RING + j)
            val = img[v, u]
            n_all += 1
            if not math.isfinite(val):
                out[4] = 1.0
                return
            x = val - slope_u * (u - uc0) - slope_v * (v - vc0)
            if pol * (x - bg_ref) / contrast > 0.3:
                continue
            n += 1
            s1 += x
            s2 += x * x
    if n < 0.3 * n_all:
        out[4] = 1.0
        return
    m = s1 / n
    out[0] = m
    out[1] = 0.0
    out[2] = 0.0
    out[3] = math.sqrt(max(s2 / n - m * m, 0.0) * n / max(1, n - 1))


@njit(cache=True)
def coverage_runs(img, base, slope_u, slope_v, inv, c, rv, r0, r1, row_start):  # pragma: no cover - compiled
    """Coverage ``c = (img - background) inv`` of every pixel and, in the same pass, the runs of pixels with
    c > 1/2 along the rows (row, first and last column; ``row_start[v]`` the first run of row v).  Returns the
    number of runs, or -1 when there are more than the arrays hold (a frame of noise)."""
    h, w = img.shape
    uc0 = 0.5 * (w - 1)
    vc0 = 0.5 * (h - 1)
    cap = rv.size
    n = 0
    for v in range(h):
        row_start[v] = n
        b = base + slope_v * (v - vc0) - slope_u * uc0
        inrun = False
        for u in range(w):
            x = (img[v, u] - b - slope_u * u) * inv
            c[v, u] = x
            if x > 0.5:
                if not inrun:
                    if n >= cap:
                        return -1
                    rv[n] = v
                    r0[n] = u
                    inrun = True
            elif inrun:
                r1[n] = u - 1
                n += 1
                inrun = False
        if inrun:
            r1[n] = w - 1
            n += 1
    row_start[h] = n
    return n


@njit(cache=True)
def particles(rv, r0, r1, row_start, n, h, w, min_area, box):  # pragma: no cover - compiled
    """Join the runs of :func:`_coverage_runs` into 8-connected components (union-find) and return the number of
    components of at least ``min_area`` pixels; ``box`` gets (u0, u1, v0, v1, area) of the largest two."""
    parent = np.empty(max(n, 1), np.int32)
    for i in range(n):
        parent[i] = i
    for v in range(1, h):
        j = row_start[v - 1]
        j_end = row_start[v]
        for i in range(row_start[v], row_start[v + 1]):
            # runs of the row above that touch run i (8-connected: overlap widened by one pixel)
            while j < j_end and r1[j] < r0[i] - 1:
                j += 1
            k = j
            while k < j_end and r0[k] <= r1[i] + 1:
                a = _find(parent, i)
                b = _find(parent, k)
                if a != b:
                    if a < b:
                        parent[b] = a
                    else:
                        parent[a] = b
                k += 1
    cnt = np.zeros(max(n, 1), np.int64)
    u0 = np.full(max(n, 1), w, np.int64)
    u1 = np.full(max(n, 1), -1, np.int64)
    v0 = np.full(max(n, 1), h, np.int64)
    v1 = np.full(max(n, 1), -1, np.int64)
    for i in range(n):
        r = _find(parent, i)
        cnt[r] += r1[i] - r0[i] + 1
        u0[r] = min(u0[r], r0[i])
        u1[r] = max(u1[r], r1[i])
        v0[r] = min(v0[r], rv[i])
        v1[r] = max(v1[r], rv[i])
    nbig = 0
    first = -1
    second = -1
    for r in range(n):
        if cnt[r] >= min_area:
            nbig += 1
            if first < 0 or cnt[r] > cnt[first]:
                second = first
                first = r
            elif second < 0 or cnt[r] > cnt[second]:
                second = r
    for j in range(2):
        r = first if j == 0 else second
        if r < 0:
            continue
        box[5 * j + 0] = u0[r]
        box[5 * j + 1] = u1[r]
        box[5 * j + 2] = v0[r]
        box[5 * j + 3] = v1[r]
        box[5 * j + 4] = cnt[r]
    return nbig
