"""Steps 1 and 2 of the per-frame measurement (:mod:`tracking.measure`): background and particles.

The recording's background image with the frame's own light level from a ring of border pixels, the coverage of
every pixel (static structures masked), and
the pixels with coverage above 1/2 joined into 8-connected components (union-find over runs along the rows).
Compiled (numba).
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["BORDER_RING", "background", "coverage_runs", "fill_holes", "particles"]

#: Width of the border ring the background level and pixel noise are measured on [px].
BORDER_RING = 2


@njit(cache=True)
def _find(parent, i):  # pragma: no cover - compiled
    while parent[i] != i:
        parent[i] = parent[parent[i]]
        i = parent[i]
    return i


@njit(cache=True)
def background(img, dark, pol, kappa, pinv, out):  # pragma: no cover - compiled
    """The frame's light level on the border ring, relative to the recording's background image (``pinv`` its
    reciprocal per pixel, 0 on static structures, which are left out; grey levels ``img + dark``): writes (level, 0, 0, residual rms of the
    relative grey levels, status) into ``out``; status 1 for a blank or corrupt frame (non-finite pixels, or a
    border that looks like a cube nearly everywhere).  Pixels that look like a cube are left out."""
    h, w = img.shape
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
            if not math.isfinite(val):
                out[4] = 1.0
                return
            p = pinv[v, u]
            if p == 0.0:
                continue
            n_all += 1
            x = (val + dark) * p
            if pol * (x - 1.0) / kappa > 0.3:
                continue
            n += 1
            s1 += x
            s2 += x * x
    if n < 0.3 * n_all or n < 8:
        out[4] = 1.0
        return
    m = s1 / n
    out[0] = m
    out[1] = 0.0
    out[2] = 0.0
    out[3] = math.sqrt(max(s2 / n - m * m, 0.0) * n / max(1, n - 1))


@njit(cache=True)
def coverage_runs(img, dark, pinv, gain, offset, c, rv, r0, r1, row_start):  # pragma: no cover - compiled
    """Coverage ``c = (img + dark) pinv gain - offset`` of every pixel (0 on static structures, where ``pinv`` is 0) and,
    in the same pass, the runs of pixels with c > 1/2 along the rows (row, first and last column;
    ``row_start[v]`` the first run of row v).  Returns the number of runs, or -1 when there are more than the
    arrays hold (a frame of noise)."""
    h, w = img.shape
    cap = rv.size
    n = 0
    for v in range(h):
        row_start[v] = n
        inrun = False
        for u in range(w):
            p = pinv[v, u]
            x = (img[v, u] + dark) * p * gain - offset if p != 0.0 else 0.0
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
    components of at least ``min_area`` pixels; ``box`` gets (u0, u1, v0, v1, area) of the largest ``box.size // 5``,
    by area (-1 where there are fewer)."""
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
    kmax = box.size // 5
    for j in range(box.size):
        box[j] = -1.0
    for r in range(n):
        if cnt[r] < min_area:
            continue
        nbig += 1
        # insert into the list of the kmax largest, kept sorted by area (descending)
        j = min(nbig, kmax) - 1
        if nbig > kmax and cnt[r] <= box[5 * (kmax - 1) + 4]:
            continue
        while j > 0 and box[5 * (j - 1) + 4] < cnt[r]:
            for q in range(5):
                box[5 * j + q] = box[5 * (j - 1) + q]
            j -= 1
        box[5 * j + 0] = u0[r]
        box[5 * j + 1] = u1[r]
        box[5 * j + 2] = v0[r]
        box[5 * j + 3] = v1[r]
        box[5 * j + 4] = cnt[r]
    return nbig


@njit(cache=True)
def fill_holes(c, u0, u1, v0, v1, grow):  # pragma: no cover - compiled
    """Fill the holes of the silhouette in the box ``u0..u1, v0..v1`` (a transparent crystal's interior inside its
    outline): pixels with c <= 1/2 not connected (4-connected) to the box's surroundings, and the pixels within
    ``grow`` px of them that are not outside the silhouette, get coverage 1."""
    h, w = c.shape
    a0 = max(0, u0 - 1)
    a1 = min(w - 1, u1 + 1)
    b0 = max(0, v0 - 1)
    b1 = min(h - 1, v1 + 1)
    nu = a1 - a0 + 1
    nv = b1 - b0 + 1
    mark = np.zeros((nv, nu), np.uint8)  # 1: outside (reached), 2: hole
    stack = np.empty(nu * nv, np.int64)
    top = 0
    for j in range(nv):
        for i in range(nu):
            if (j == 0 or j == nv - 1 or i == 0 or i == nu - 1) and c[b0 + j, a0 + i] <= 0.5:
                mark[j, i] = 1
                stack[top] = j * nu + i
                top += 1
    while top > 0:
        top -= 1
        j = stack[top] // nu
        i = stack[top] % nu
        for dj, di in ((1, 0), (-1, 0), (0, 1), (0, -1)):
            jj = j + dj
            ii = i + di
            if 0 <= jj < nv and 0 <= ii < nu and mark[jj, ii] == 0 and c[b0 + jj, a0 + ii] <= 0.5:
                mark[jj, ii] = 1
                stack[top] = jj * nu + ii
                top += 1
    for j in range(nv):
        for i in range(nu):
            if mark[j, i] == 0 and c[b0 + j, a0 + i] <= 0.5:
                mark[j, i] = 2
    for j in range(nv):
        for i in range(nu):
            if mark[j, i] != 2:
                continue
            for jj in range(max(0, j - grow), min(nv, j + grow + 1)):
                for ii in range(max(0, i - grow), min(nu, i + grow + 1)):
                    if mark[jj, ii] != 1:
                        c[b0 + jj, a0 + ii] = 1.0
