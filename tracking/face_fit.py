"""Step 5 of the per-frame measurement (:mod:`tracking.measure`): the sub-pixel edge fits of one square's faces.

For each of the four faces of a cube's square, sample lines cross the face (pixel columns for faces flatter than
45 degrees, rows otherwise) away from its corners and from the other cube; the coverage summed over a window
across the edge is the length of the line inside the cube, so the crossing is sub-pixel and unbiased for any
symmetric blur.  Compiled (numba).
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["fit_square", "fit_tilted_square", "wrap_angle"]


@njit(cache=True)
def wrap_angle(x, period):  # pragma: no cover - compiled
    """x wrapped into (-period/2, period/2]."""
    y = x - period * math.floor(x / period + 0.5)
    if y <= -0.5 * period:
        y += period
    return y


#: Most edge samples a face keeps.
_MAX_SAMPLES = 512


@njit(cache=True)
def _column_samples(c, px, rho, nx, nz, a, W, blur, u_split, side, h, w, clear, xs, ys):  # pragma: no cover
    """Edge crossings of a face flatter than 45 degrees along the pixel columns across it, away from its corners
    and from the other cube: (u, Z of the crossing) into ``xs``, ``ys``.  Returns (count, sum of the coverage
    variance along the samples times |n_z|, the edge width's information)."""
    cnt = 0
    wsum = 0.0
    tx = -nz
    margin = W * abs(nx) + 2.0 * blur + 1.0
    lo = px - (a - margin) * abs(tx)
    hi = px + (a - margin) * abs(tx)
    if hi <= lo:
        return cnt, wsum
    for uu in range(int(math.ceil(lo)), int(math.floor(hi)) + 1):
        if side > 0 and uu < u_split + clear:
            continue
        if side < 0 and uu > u_split - clear:
            continue
        if uu < 0 or uu >= w:
            continue
        ze = (rho - nx * uu) / nz
        ve = int(math.floor(-ze + 0.5))
        v0 = ve - W
        v1 = ve + W
        if v0 < 0 or v1 >= h:
            continue
        L = 0.0
        q = 0.0
        for vv in range(v0, v1 + 1):
            cv = c[vv, uu]
            L += cv
            q += cv * (1.0 - cv)
        if nz > 0:
            vedge = (v1 + 0.5) - L
        else:
            vedge = (v0 - 0.5) + L
        if cnt < _MAX_SAMPLES:
            xs[cnt] = uu
            ys[cnt] = -vedge
            cnt += 1
            wsum += q * abs(nz)
    return cnt, wsum


@njit(cache=True)
def _row_samples(c, pz, rho, nx, nz, a, W, blur, u_split, side, h, w, clear, xs, ys):  # pragma: no cover
    """Edge crossings of a face steeper than 45 degrees along the pixel rows across it, away from its corners and
    from the other cube: (Z, u of the crossing) into ``xs``, ``ys``.  Returns (count, sum of the coverage variance
    along the samples times |n_x|)."""
    cnt = 0
    wsum = 0.0
    tz = nx
    margin = W * abs(nz) + 2.0 * blur + 1.0
    lo = pz - (a - margin) * abs(tz)
    hi = pz + (a - margin) * abs(tz)
    if hi <= lo:
        return cnt, wsum
    for mz in range(int(math.ceil(lo)), int(math.floor(hi)) + 1):
        vv = -mz
        if vv < 0 or vv >= h:
            continue
        xe = (rho - nz * mz) / nx
        ue = int(math.floor(xe + 0.5))
        u0 = ue - W
        u1 = ue + W
        if u0 < 0 or u1 >= w:
            continue
        if side > 0 and u0 < u_split + clear:
            continue
        if side < 0 and u1 > u_split - clear:
            continue
        L = 0.0
        q = 0.0
        for uu in range(u0, u1 + 1):
            cv = c[vv, uu]
            L += cv
            q += cv * (1.0 - cv)
        if nx > 0:
            uedge = (u0 - 0.5) + L
        else:
            uedge = (u1 + 0.5) - L
        if cnt < _MAX_SAMPLES:
            xs[cnt] = mz
            ys[cnt] = uedge
            cnt += 1
            wsum += q * abs(nx)
    return cnt, wsum


@njit(cache=True)
def _line_fit(xs, ys, cnt):  # pragma: no cover - compiled
    """Least squares r = alpha + beta s through the first ``cnt`` samples.  Returns (mean s, mean r, S_ss, beta,
    residual sum of squares); S_ss <= 0 (all s equal): no line, beta and the residual 0."""
    sm = 0.0
    rm = 0.0
    for i in range(cnt):
        sm += xs[i]
        rm += ys[i]
    sm /= cnt
    rm /= cnt
    sss = 0.0
    ssr = 0.0
    for i in range(cnt):
        sss += (xs[i] - sm) ** 2
        ssr += (xs[i] - sm) * (ys[i] - rm)
    if sss <= 0:
        return sm, rm, sss, 0.0, 0.0
    beta = ssr / sss
    alpha0 = rm - beta * sm
    rr = 0.0
    for i in range(cnt):
        e = ys[i] - alpha0 - beta * xs[i]
        rr += e * e
    return sm, rm, sss, beta, rr


@njit(cache=True)
def _fitted_edge(xs, ys, cnt, wsum, cols):  # pragma: no cover - compiled
    """The straight edge through the first ``cnt`` samples of a face (sampled along columns when ``cols``, else
    along rows; ``wsum`` the sum of their blur weights): (found, direction [rad], mean point (x, z') [px], blur
    width [px], the residual sum of squares normal to the edge, S_ss (1 + beta^2)); not found when all samples
    share one coordinate."""
    sm, rm, sss, beta, rr = _line_fit(xs, ys, cnt)
    if sss <= 0:
        return False, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    if cols:
        delta = math.atan(beta)
        mx = sm
        mzp = rm
    else:
        delta = math.atan2(1.0, beta)
        mx = rm
        mzp = sm
    width = math.sqrt(math.pi) * wsum / cnt
    return True, delta, mx, mzp, width, rr * (1.0 / (1.0 + beta * beta)), sss * (1.0 + beta * beta)


@njit(cache=True)
def _centre_and_side(res, g, X0, Z0):  # pragma: no cover - compiled
    """The square's centre (``res[1]``, ``res[2]``) and half side (``res[7]``) from the offsets of opposite faces
    (``res[12..15]``) along the fitted direction ``g``; a pair of faces not both fitted keeps the centre's
    component of the starting point (X0, Z0)."""
    a_sum = 0.0
    a_n = 0
    n0x = math.cos(g - 0.5 * math.pi)
    n0z = math.sin(g - 0.5 * math.pi)
    n1x = -n0z
    n1z = n0x
    comp0 = n0x * X0 + n0z * Z0
    comp1 = n1x * X0 + n1z * Z0
    if not math.isnan(res[12]) and not math.isnan(res[14]):
        comp0 = 0.5 * (res[12] - res[14])
        a_sum += 0.5 * (res[12] + res[14])
        a_n += 1
    if not math.isnan(res[13]) and not math.isnan(res[15]):
        comp1 = 0.5 * (res[13] - res[15])
        a_sum += 0.5 * (res[13] + res[15])
        a_n += 1
    Xc = comp0 * n0x + comp1 * n1x
    Zc = comp0 * n0z + comp1 * n1z
    res[1] = Xc
    res[2] = -Zc
    res[7] = a_sum / a_n if a_n > 0 else np.nan


@njit(cache=True)
def fit_square(c, uc, vc, gamma, a, W, blur, u_split, side, h, w, res, tilt_cos=1.0, sweep=0.0,
               a_true=0.0):  # pragma: no cover - compiled
    """Edge fits of the four faces of one square (module docstring, step 5).

    ``side`` is -1 for cube A (left of ``u_split``) and +1 for cube B.  Writes into ``res`` (length 25):
    0 gamma, 1 u centre, 2 v centre, 3 pooled rms residual [px], 4 weight sum (information of gamma per
    unit residual variance), 5 number of faces fitted, 6 max edge width [px], 7 half side estimate [px],
    8..11 fitted face directions [rad] (NaN if not fitted), 12..15 face offsets rho along their normals,
    16..19 face edge widths, 20..23 variances of the face directions [rad^2] (from each face's own residual),
    24 the direction of the faces as the image shows them (gamma without a tilt).

    With ``sweep > 0`` the hinge line is tilted out of the camera axis (:func:`fit_tilted_square`): ``gamma``
    and the face directions are then the cube's own, ``tilt_cos`` and ``sweep`` describe the projection and
    ``a_true`` is the cube's half side [px].
    """
    if sweep > 0.0:
        fit_tilted_square(c, uc, vc, gamma, a_true, W, blur, u_split, side, h, w, res, tilt_cos, sweep)
        return
    _fit_aligned_square(c, uc, vc, gamma, a, W, blur, u_split, side, h, w, res)
    res[24] = res[0]


@njit(cache=True)
def _fit_aligned_square(c, uc, vc, gamma, a, W, blur, u_split, side, h, w, res):  # pragma: no cover - compiled
    """:func:`fit_square` of a square seen along the hinge line."""
    clear = 3.0 * blur + 1.0
    X0 = uc
    Z0 = -vc
    sw = 0.0
    swr = 0.0
    ss_res = 0.0
    n_res = 0
    nf = 0
    wmax = 0.0
    for k in range(4):
        res[8 + k] = np.nan
        res[12 + k] = np.nan
        res[16 + k] = np.nan
        res[20 + k] = np.nan
    xs = np.empty(_MAX_SAMPLES)
    ys = np.empty(_MAX_SAMPLES)
    for k in range(4):
        nu = gamma - 0.5 * math.pi + 0.5 * math.pi * k
        nx = math.cos(nu)
        nz = math.sin(nu)
        rho = nx * X0 + nz * Z0 + a
        cols = abs(nz) >= abs(nx)
        if cols:
            cnt, wsum = _column_samples(c, X0 + a * nx, rho, nx, nz, a, W, blur, u_split, side, h, w, clear, xs, ys)
        else:
            cnt, wsum = _row_samples(c, Z0 + a * nz, rho, nx, nz, a, W, blur, u_split, side, h, w, clear, xs, ys)
        if cnt < 5:
            continue
        ok, delta, mx, mzp, width, r_normal, wk = _fitted_edge(xs, ys, cnt, wsum, cols)
        if not ok:
            continue
        ss_res += r_normal
        n_res += cnt - 2
        if width > wmax:
            wmax = width
        res[8 + k] = delta
        res[12 + k] = nx * mx + nz * mzp
        res[16 + k] = width
        res[20 + k] = r_normal / max(1, cnt - 2) / wk  # var(direction) = normal residual^2 / (Sss (1 + beta^2))
        sw += wk
        swr += wk * wrap_angle(delta - gamma, 0.5 * math.pi)
        nf += 1
    res[5] = nf
    res[6] = wmax
    if nf < 2 or sw <= 0:
        res[0] = np.nan
        return
    g = gamma + swr / sw
    res[0] = g
    res[3] = math.sqrt(ss_res / n_res) if n_res > 0 else np.nan
    res[4] = sw
    _centre_and_side(res, g, X0, Z0)


@njit(cache=True)
def _image_normal(nu, tilt_cos):  # pragma: no cover - compiled
    """The image's unit normal (nx, nz) of a cube face whose own normal points at angle ``nu``, the image
    shortened across by ``tilt_cos``: normals transform with the inverse of the shortening."""
    nx = math.cos(nu) / tilt_cos
    nz = math.sin(nu)
    r = math.sqrt(nx * nx + nz * nz)
    return nx / r, nz / r


@njit(cache=True)
def fit_tilted_square(c, uc, vc, gamma, a, W, blur, u_split, side, h, w, res, tilt_cos, sweep):  # pragma: no cover
    """:func:`fit_square` of a cube whose hinge line is turned out of the camera axis (:mod:`tracking.tilt`).

    The image shows the cube's square (half side ``a``, faces along ``gamma``, centre ``(uc, vc)``) shortened
    across by ``tilt_cos`` and swept along the rows by +-``sweep`` px: a hexagon whose four slanted edges are the
    shortened square's faces, each moved by ``sweep`` away from the centre along the rows.  A face of normal
    ``n`` (unit, the image's) then lies at ``a q + sweep |n_x|`` from the centre, ``q = sqrt(c^2 n_x^2 + n_z^2)``,
    with its middle at ``a (c^2 n_x, n_z) / q + (sweep sign(n_x), 0)`` and half length ``a c / q``; it is sampled
    there, clear of the other cube's sweep at the hinge.  Each fitted face's image direction ``d`` is the cube's
    ``atan2(sin d, cos d / c)``, its variance scaled with the derivative; the centre (the hexagon's, in the
    image) solves the two pairs of opposite faces' offsets along their image normals, and ``res[7]`` is the
    cube's half side.  ``res[24]`` is the faces' mean direction in the image (for the hinge corners' gap)."""
    clear = 3.0 * blur + 1.0 + sweep
    X0 = uc
    Z0 = -vc
    tc = tilt_cos
    sw = 0.0
    swr = 0.0
    swi = 0.0
    swri = 0.0
    ss_res = 0.0
    n_res = 0
    nf = 0
    wmax = 0.0
    for k in range(4):
        res[8 + k] = np.nan
        res[12 + k] = np.nan
        res[16 + k] = np.nan
        res[20 + k] = np.nan
    xs = np.empty(_MAX_SAMPLES)
    ys = np.empty(_MAX_SAMPLES)
    g_img = math.atan2(math.sin(gamma), tc * math.cos(gamma))
    for k in range(4):
        nx, nz = _image_normal(gamma - 0.5 * math.pi + 0.5 * math.pi * k, tc)
        q = math.sqrt(tc * tc * nx * nx + nz * nz)
        rho = nx * X0 + nz * Z0 + a * q + sweep * abs(nx)
        half = a * tc / q
        cols = abs(nz) >= abs(nx)
        if cols:
            mid = X0 + a * tc * tc * nx / q + math.copysign(sweep, nx)
            cnt, wsum = _column_samples(c, mid, rho, nx, nz, half, W, blur, u_split, side, h, w, clear, xs, ys)
        else:
            mid = Z0 + a * nz / q
            cnt, wsum = _row_samples(c, mid, rho, nx, nz, half, W, blur, u_split, side, h, w, clear, xs, ys)
        if cnt < 5:
            continue
        ok, delta, mx, mzp, width, r_normal, wk = _fitted_edge(xs, ys, cnt, wsum, cols)
        if not ok:
            continue
        ss_res += r_normal
        n_res += cnt - 2
        if width > wmax:
            wmax = width
        cd = math.cos(delta)
        sd = math.sin(delta)
        jac = (1.0 / tc) / (cd * cd / (tc * tc) + sd * sd)  # d(cube's direction) / d(image direction)
        var = r_normal / max(1, cnt - 2) / wk
        res[8 + k] = math.atan2(sd, cd / tc)
        res[12 + k] = nx * mx + nz * mzp
        res[16 + k] = width
        res[20 + k] = var * jac * jac
        swi += wk
        swri += wk * wrap_angle(delta - g_img, 0.5 * math.pi)
        sw += wk / (jac * jac)
        swr += wk / (jac * jac) * wrap_angle(res[8 + k] - gamma, 0.5 * math.pi)
        nf += 1
    res[5] = nf
    res[6] = wmax
    if nf < 2 or sw <= 0:
        res[0] = np.nan
        return
    g = gamma + swr / sw
    res[0] = g
    res[24] = g_img + swri / swi
    res[3] = math.sqrt(ss_res / n_res) if n_res > 0 else np.nan
    res[4] = sw
    _tilted_centre_and_side(res, g, X0, Z0, tc, sweep, a)


@njit(cache=True)
def _tilted_centre_and_side(res, g, X0, Z0, tc, sweep, a):  # pragma: no cover - compiled
    """The hexagon's centre (``res[1]``, ``res[2]``) from the offsets of opposite faces along their image normals
    (``res[12..15]``; not perpendicular under a tilt: a 2 x 2 system) and the cube's half side (``res[7]``).  A pair
    of which one face was fitted takes that face's offset less its distance from the centre, ``a q + sweep |n_x|``
    (near the hinge the other cube's sweep may hide the face beside it); a pair with neither keeps the starting
    point's."""
    n0x, n0z = _image_normal(g - 0.5 * math.pi, tc)
    n1x, n1z = _image_normal(g, tc)
    comp = np.array([n0x * X0 + n0z * Z0, n1x * X0 + n1z * Z0])
    a_sum = 0.0
    a_n = 0
    for p, nx, nz in ((0, n0x, n0z), (1, n1x, n1z)):
        near, far = res[12 + p], res[14 + p]
        if not math.isnan(near) and not math.isnan(far):
            comp[p] = 0.5 * (near - far)
            a_sum += (0.5 * (near + far) - sweep * abs(nx)) / math.sqrt(tc * tc * nx * nx + nz * nz)
            a_n += 1
    a_fit = a_sum / a_n if a_n > 0 else a  # the half side of a pair both fitted, else the silhouette's
    for p, nx, nz in ((0, n0x, n0z), (1, n1x, n1z)):
        near, far = res[12 + p], res[14 + p]
        d = a_fit * math.sqrt(tc * tc * nx * nx + nz * nz) + sweep * abs(nx)
        if math.isnan(far) and not math.isnan(near):
            comp[p] = near - d
        elif math.isnan(near) and not math.isnan(far):
            comp[p] = d - far
    det = n0x * n1z - n0z * n1x
    Xc = (comp[0] * n1z - comp[1] * n0z) / det
    Zc = (n0x * comp[1] - n1x * comp[0]) / det
    res[1] = Xc
    res[2] = -Zc
    res[7] = a_sum / a_n if a_n > 0 else np.nan
