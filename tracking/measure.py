"""The per-frame measurement of the dimer: compiled (numba); a batch of frames is shared by the kernel's own threads.

Image coordinates: pixel centres at integer ``(u, v)``, ``u`` the column (right) and ``v`` the row
(counting down); the lab frame of the measurement has ``X = u`` and ``Z = -v`` (up).  Every frame goes
through these steps (:func:`measure_frames`):

1. **Background and light.**  The recording's background image ``B`` (:mod:`tracking.background`: its smooth
   illumination and static structures, which are masked) times the frame's own light level ``L``, the mean of
   ``I / B`` over a ring of pixels along the frame's border (pixels that look like a cube and static ones are
   left out); the white pixel noise from the ring's spread.  The coverage of every pixel is
   ``c = polarity (I / (L B) - 1) / kappa`` (0 background, 1 cube; ``kappa`` the relative contrast): the light
   multiplies the scene, so a flicker or a gradient scales background and cube alike.
2. **Particles.**  The pixels with ``c > 1/2`` (found as runs along the rows in the same pass), joined in
   8-connected components.  Components larger
   than ``min_area`` are particles: the largest (with the second when of similar size and less than
   ``3 + 3 blur`` px apart: the cubes meet at a corner, where the coverage may stay below 1/2) is the dimer;
   another particle in the dimer's window is masked (its box widened by ``ceil(2.5 blur)`` set to background) when
   the dimer's silhouette lies at least twice that from its box, and counts (third particle) only when closer.  A dimer whose window
   reaches the border is out of view.  With ``fill_holes`` the holes of the dimer's silhouette (a transparent
   crystal's bright interior) become cube.
3. **Height.**  The centre of mass of the coverage over the dimer's window (its bounding box widened by
   the edge window), unclipped: a symmetric point-spread function and white noise leave it unbiased.
4. **First orientation.**  The dimer is split at the middle column of its bounding box (the hinge of the
   mirror-symmetric dimer; docs/conventions.md section 2: each cube lies wholly on its side of it).  Each half's
   fourth-order complex moment ``sum c (X + iZ)^4`` about its own centroid gives the orientation of that
   square's faces modulo 90 degrees (a square's second moments are isotropic and say nothing); the moments
   of order 0-4 of both halves come from one pass over the window, shifted to each centroid exactly.
5. **Edge fits.**  For each of the four faces of each square, sample lines cross the face (pixel columns
   for faces flatter than 45 degrees, rows otherwise) away from its corners and from the other cube.  On
   each sample line the coverage summed over a window of ``2 W + 1`` pixels across the edge is the length
   of the line inside the cube, so the edge crossing is sub-pixel and unbiased for any symmetric blur.
   A straight line fitted through the crossings gives the face's direction; the four faces of a square
   (weighted by their information, ``Sss (1 + slope^2)`` over the residual variance) give its orientation
   and, from the offsets of opposite faces, its centre.  Two passes.  The hinge's height relative to the
   centres settles the sign of a bend near face contact, where the orientations alone cannot.
6. **Angles.**  From the squares' orientations: cube B's bend ``phi_B = pi/4 - gamma_B`` and cube A's
   ``phi_A = gamma_A - 3 pi/4`` (``gamma`` the direction of a face, counter-clockwise from +X), the opening
   angles ``alpha = pi/2 + phi_A + phi_B`` above the hinge and ``beta = pi/2 - phi_A - phi_B`` below it,
   ``theta = (alpha - beta) / pi``.  A frame with ``alpha <= 0`` or ``beta <= 0`` is impossible
   (interpenetrating cubes) and is not measured, so ``|theta| < 1`` by construction.  The two faces
   that meet at each hinge corner are also fitted alone: their angles ``alpha_free``, ``beta_free``
   check ``alpha + beta = pi`` (each cube's hinge corner is square).

The output of a frame is one row of :data:`COLUMNS`; ``status`` is one of :data:`STATUS`.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit, prange
from numpy.typing import NDArray

from cubedimer.config_checks import check_non_negative, check_positive, check_that, check_whole
from .face_fit import fit_square, wrap_angle
from .frame_row import (COLUMNS, NCOL, STATUS, STATUS_NAMES, STATUS_TEXT, _MAX_PARTICLES, _I_ALPHA, _I_AREA,
                        _I_BACKGROUND, _I_BETA, _I_EDGE_RMS, _I_EDGE_WIDTH, _I_GAMMA_A, _I_GAMMA_B, _I_HALF_SIDE,
                        _I_N_FACES, _I_PIXEL_NOISE, _I_SIDE_A, _I_SIDE_B, _I_SIGMA_THETA, _I_SIGMA_V, _I_THETA,
                        _I_TILT, _I_U_A, _I_U_B, _I_U_COM, _I_V_A, _I_V_B, _I_V_COM)
from .hinge_corners import hinge_geometry
from .moments import half_direction, window_moments
from .segmentation import BORDER_RING, background, coverage_runs, fill_holes, particles

__all__ = ["COLUMNS", "STATUS", "STATUS_NAMES", "STATUS_TEXT", "measure_frames", "MeasureSettings", "numba_threads",
           "reciprocal_background"]

@dataclass(frozen=True)
class MeasureSettings:
    """Numbers the compiled kernel needs (packed into one float array by :meth:`pack`).

    Parameters
    ----------
    polarity : float
        -1 for dark cubes on a bright background, +1 for bright cubes on a dark one.
    background_ref : float
        The recording's background grey level.
    contrast : float
        |cube level - background level| (grey levels).
    edge_window : int
        Half-length W of the window across an edge [px].
    edge_blur : float
        The recording's edge blur (standard deviation) [px]: sets the corner and hinge clearances.
    min_area : float
        Smallest component counted as a particle [px^2].
    area_ref : float
        The dimer's silhouette area [px^2] (0: not checked).
    area_tolerance : float
        Allowed relative deviation of a frame's area from ``area_ref``.
    slope_u, slope_v : float
        The recording's background gradient along columns and rows [grey levels / px], about the frame's
        centre, used when no background image is given to :func:`measure_frames`; each frame fits only its own
        light level (a per-frame gradient would add noise to y).
    fill_holes : bool
        Fill the silhouette's holes (transparent crystals: a bright interior inside a dark outline).
    dark_offset : float
        Grey levels added to every pixel before the light is normalised (``background_ref`` includes it): a
        background near black (bright cubes on a black background) is then normalised nearly additively.
    hinge_tilt : float
        Angle [rad] of the hinge line out of the camera axis that the face fits undo (:mod:`tracking.tilt`); 0:
        the camera looks along the hinge line.
    """

    polarity: float
    background_ref: float
    contrast: float
    edge_window: int = 7
    edge_blur: float = 1.5
    min_area: float = 20.0
    area_ref: float = 0.0
    area_tolerance: float = 0.06
    slope_u: float = 0.0
    slope_v: float = 0.0
    fill_holes: bool = False
    dark_offset: float = 0.0
    hinge_tilt: float = 0.0

    def __post_init__(self) -> None:
        check_that(self, self.polarity in (-1.0, 1.0),
                   f"polarity must be -1 (dark cubes) or +1 (bright cubes), got {self.polarity!r}")
        check_positive(self, "contrast")
        check_whole(self, "edge_window", minimum=2)
        check_non_negative(self, "hinge_tilt")
        check_that(self, self.hinge_tilt < 0.5 * math.pi, f"hinge_tilt must lie in [0, pi/2) rad, got {self.hinge_tilt!r}")

    def pack(self) -> NDArray[np.float64]:
        """The settings in the order the kernel reads them (the hinge tilt as its cosine, sine and the silhouette's
        side over the cube's, :func:`tracking.tilt.area_factor`)."""
        from .tilt import area_factor

        tau = self.hinge_tilt
        return np.array([self.polarity, self.background_ref, self.contrast, self.edge_window, self.edge_blur,
                         self.min_area, self.area_ref, self.area_tolerance, self.slope_u, self.slope_v,
                         float(self.fill_holes), self.dark_offset, math.cos(tau), math.sin(tau),
                         math.sqrt(area_factor(tau))], float)

    def plane(self, shape: tuple[int, int]) -> NDArray[np.float32]:
        """The reciprocal background image of the plane ``background_ref + slope_u (u - uc) + slope_v (v - vc)``
        (about the frame's centre) for frames of ``shape``: what :func:`measure_frames` uses without one."""
        h, w = shape
        plane = (self.background_ref + self.slope_u * (np.arange(w) - 0.5 * (w - 1))[None, :]
                 + self.slope_v * (np.arange(h) - 0.5 * (h - 1))[:, None])
        return reciprocal_background(plane, self.background_ref)


def reciprocal_background(image: NDArray, background_ref: float, static: NDArray | None = None) -> NDArray[np.float32]:
    """``1 / image`` as the kernel reads it (a frame's grey levels relative to its background are ``img x this``),
    0 on the ``static`` pixels (left out of every frame); the image is held at no less than a fifth of
    ``background_ref``."""
    img = np.maximum(np.asarray(image, float), 0.2 * background_ref)
    out = (1.0 / img).astype(np.float32)
    if static is not None:
        out[np.asarray(static, bool)] = 0.0
    return np.ascontiguousarray(out)


def measure_frames(frames: NDArray, settings: MeasureSettings, threads: int | None = None,
                   pinv: NDArray | None = None) -> NDArray[np.float64]:
    """Measure every frame of a batch (module docstring).

    Parameters
    ----------
    frames : ndarray (n, height, width)
        Grey levels (any real or integer type).
    settings : MeasureSettings
    threads : int, optional
        Threads sharing the batch (default :func:`numba_threads`): the compiled kernel's own (numba's prange, at
        most ``NUMBA_NUM_THREADS``), never a pool of Python threads.
    pinv : ndarray (height, width), optional
        The recording's reciprocal background image (:func:`reciprocal_background`; 0 on static structures);
        default: the plane of ``settings`` (:meth:`MeasureSettings.plane`).

    Returns
    -------
    ndarray (n, len(COLUMNS)) float64
        One row per frame; the columns of :data:`COLUMNS` (NaN where a frame was not measured that far).
    """
    f = np.ascontiguousarray(frames, dtype=np.float32)
    if f.ndim != 3:
        raise ValueError(f"frames must be (n, height, width), got shape {f.shape}")
    out = np.full((f.shape[0], NCOL), np.nan)
    prm = settings.pack()
    pinv = settings.plane(f.shape[1:]) if pinv is None else np.ascontiguousarray(pinv, dtype=np.float32)
    if pinv.shape != f.shape[1:]:
        raise ValueError(f"background image of shape {pinv.shape} for frames of {f.shape[1:]}")
    n = f.shape[0]
    threads = max(1, min(int(threads or numba_threads()), n // 32 or 1))
    if threads == 1:
        _measure_batch(f, pinv, prm, out)
        return out
    import numba

    before = numba.get_num_threads()
    numba.set_num_threads(min(threads, numba.config.NUMBA_NUM_THREADS))
    try:  # the compiled kernel's own threads (prange over frames): no pool is opened
        _measure_batch_parallel(f, pinv, prm, out)
    finally:
        numba.set_num_threads(before)
    return out


def numba_threads() -> int:
    """Threads a batch is measured on: numba's thread count (``NUMBA_NUM_THREADS``, default one per core), or 1
    inside a parallel task of :func:`cubedimer.executor.map_ordered` (the parallelism is then across tasks)."""
    from cubedimer.executor import in_task

    if in_task():
        return 1
    import numba

    return int(numba.get_num_threads())


# ---------------------------------------------------------------------------------------------- compiled kernel
@njit(cache=True)
def _light_level(img, pinv, prm, row):  # pragma: no cover - compiled
    """Step 1: the frame's light level relative to the recording's, from the border ring (the background image is
    the recording's), and the pixel noise in coverage units.  Returns (status, level, sigma_pix); status 0: go on."""
    pol = prm[0]
    bg_ref = prm[1]
    kappa = prm[2] / bg_ref
    dark = prm[11]
    bgp = np.zeros(5)
    background(img, dark, pol, kappa, pinv, bgp)
    if bgp[4] > 0:
        return 1, 0.0, 0.0
    level = bgp[0]
    row[_I_BACKGROUND] = level * bg_ref - dark
    if abs(level - 1.0) > 0.25 * kappa:
        return 1, level, 0.0
    if level < 0.05:  # an unlit (black) frame on a dark background
        return 2, level, 0.0
    sigma_pix = bgp[3] / (kappa * level)
    row[_I_PIXEL_NOISE] = sigma_pix
    return 0, level, sigma_pix


@njit(cache=True)
def _dimer_box(c, rv, r0, r1, row_start, nruns, h, w, min_area, blur, M, win):  # pragma: no cover - compiled
    """Step 2: the particles of the coverage runs and the dimer's bounding box (u0, u1, v0, v1 into ``win``): the
    largest particle, joined by the second when both are cube-sized and touch.  Another particle in the dimer's
    window ``M`` px around the box is masked in the coverage ``c`` (:func:`_mask_particle`, its box widened by its
    blurred edge's reach ``ceil(2.5 blur)``) when the dimer's silhouette stays twice that reach from its box.  Returns the status
    (0: a dimer alone in its window, once such particles are masked; 4: a particle too close)."""
    box = np.zeros(5 * _MAX_PARTICLES)
    nbig = particles(rv, r0, r1, row_start, nruns, h, w, min_area, box)
    if nbig == 0:
        return 2
    bu0, bu1, bv0, bv1 = int(box[0]), int(box[1]), int(box[2]), int(box[3])
    first_other = 1
    if nbig >= 2:
        ratio = box[4] / box[9]
        gap_u = max(box[5] - box[1], box[0] - box[6])
        gap_v = max(box[7] - box[3], box[2] - box[8])
        if ratio <= 2.0:
            if gap_u > 3.0 + 3.0 * blur or gap_v > 3:  # two cube-sized particles apart
                return 4
            bu0 = min(bu0, int(box[5]))
            bu1 = max(bu1, int(box[6]))
            bv0 = min(bv0, int(box[7]))
            bv1 = max(bv1, int(box[8]))
            first_other = 2
    if nbig > _MAX_PARTICLES:
        return 4
    r = int(math.ceil(2.5 * blur))  # a blurred edge's reach: 0.6 % of full coverage beyond it
    for k in range(first_other, nbig):  # another particle counts only where it reaches the dimer's window
        pu0, pu1, pv0, pv1 = int(box[5 * k]), int(box[5 * k + 1]), int(box[5 * k + 2]), int(box[5 * k + 3])
        if pu0 <= bu1 + M and pu1 >= bu0 - M and pv0 <= bv1 + M and pv1 >= bv0 - M:
            if not _mask_particle(c, pu0, pu1, pv0, pv1, r, h, w):
                return 4
    win[0] = bu0
    win[1] = bu1
    win[2] = bv0
    win[3] = bv1
    return 0


@njit(cache=True)
def _mask_particle(c, pu0, pu1, pv0, pv1, r, h, w):  # pragma: no cover - compiled
    """Mask a particle near the dimer: its box widened by ``r`` (its blurred edge) set to background in ``c``, when
    no other pixel of coverage above 1/2 lies within ``2 r`` of its box (the dimer's blurred edge then keeps clear of
    the mask by ``r``).  Returns whether it was masked (False: too close, nothing changed)."""
    for v in range(max(0, pv0 - 2 * r), min(h, pv1 + 2 * r + 1)):
        for u in range(max(0, pu0 - 2 * r), min(w, pu1 + 2 * r + 1)):
            if c[v, u] > 0.5 and not (pu0 <= u <= pu1 and pv0 <= v <= pv1):
                return False
    for v in range(max(0, pv0 - r), min(h, pv1 + r + 1)):
        for u in range(max(0, pu0 - r), min(w, pu1 + r + 1)):
            c[v, u] = 0.0
    return True


@njit(cache=True)
def _centre_of_mass(mom, ua, ub, vo, u0, u1, v0, v1, sigma_pix, row):  # pragma: no cover - compiled
    """Step 3: the silhouette's centre of mass (u, v), area and the standard deviation of v from the pixel noise,
    from the two halves' moments, into ``row``.  Returns the area (<= 0: nothing covered)."""
    s0 = mom[0] + mom[9]
    if s0 <= 0 or mom[0] <= 0 or mom[9] <= 0:
        return -1.0
    ucom = (mom[0] * ua + mom[1] + mom[9] * ub + mom[10]) / s0
    vcom = vo - (mom[2] + mom[11]) / s0
    svv = 0.0
    for v in range(v0, v1 + 1):
        svv += (u1 - u0 + 1) * (v - vcom) ** 2
    row[_I_V_COM] = vcom
    row[_I_U_COM] = ucom
    row[_I_AREA] = s0
    row[_I_SIGMA_V] = sigma_pix * math.sqrt(svv) / s0
    return s0


@njit(cache=True)
def _first_orientations(c, mom, ua, ub, vo, u_split, v0, v1, vcom, d, cen, gam):  # pragma: no cover - compiled
    """Step 4: each half's centroid (``cen``) and face direction (``gam``) from its moments, the bend of each cube
    put on the side the hinge's height says near face contact.  Returns the bends (phi_A, phi_B)."""
    for k in range(2):  # the halves' moments from mom[0] and mom[9] (an offset known at run time: one compilation)
        gam[k] = half_direction(mom, 9 * k, ua if k == 0 else ub, vo, cen[k])
    phiA = wrap_angle(gam[0] - 0.75 * math.pi, 0.5 * math.pi)
    phiB = wrap_angle(0.25 * math.pi - gam[1], 0.5 * math.pi)
    hz = 0.0
    hn = 0.0
    iu = int(math.floor(u_split + 0.5))
    for u in range(iu - 1, iu + 2):
        for v in range(v0, v1 + 1):
            cv = c[v, u]
            if cv > 0.1:
                hz += cv * v
                hn += cv
    if hn > 0:
        dz = vcom - hz / hn  # hinge above the centres (in Z) when positive
        if abs(dz) > 0.3 * d:
            if abs(phiA) > 0.5236 and phiA * dz < 0:
                phiA -= math.copysign(0.5 * math.pi, phiA)
            if abs(phiB) > 0.5236 and phiB * dz < 0:
                phiB -= math.copysign(0.5 * math.pi, phiB)
    gam[0] = phiA + 0.75 * math.pi
    gam[1] = 0.25 * math.pi - phiB
    return phiA, phiB


@njit(cache=True)
def _edge_fits(c, cen, gam, a_half, W, blur, u_split, h, w, resA, resB, prm):  # pragma: no cover - compiled
    """Step 5: the two squares' edge fits, two passes, each from the previous pass's centres and directions
    (updated in ``cen``, ``gam``), undoing a tilted hinge line's projection when the settings give one (the cube's
    half side from the silhouette's, its sweep ``a sin(tilt)``).  Returns False when a square has too few edge
    samples."""
    a_true = a_half / prm[14]
    sweep = a_true * prm[13]
    for it in range(2):
        # cube A (side -1), then B (+1), the side an integer known at run time: a constant argument would compile
        # the fit and everything it calls once per value
        for k in range(2):
            fit_square(c, cen[k, 0], cen[k, 1], gam[k], a_half, W, blur, u_split, 2 * k - 1, h, w,
                       resA if k == 0 else resB, prm[12], sweep, a_true)
        if math.isnan(resA[0]) or math.isnan(resB[0]):
            return False
        gam[0] = resA[0]
        gam[1] = resB[0]
        cen[0, 0] = resA[1]
        cen[0, 1] = resA[2]
        cen[1, 0] = resB[1]
        cen[1, 1] = resB[2]
    return True


@njit(cache=True)
def _angles(phiA, phiB, gam, cen, a_half, resA, resB, row):  # pragma: no cover - compiled
    """Step 6: the opening angles alpha, beta, the tilt and the fitted squares' geometry and uncertainties into
    ``row``, the bends kept on the side step 4 chose.  Returns (alpha, beta)."""
    phiA2 = phiA + wrap_angle(gam[0] - 0.75 * math.pi - phiA, 0.5 * math.pi)
    phiB2 = phiB + wrap_angle(0.25 * math.pi - gam[1] - phiB, 0.5 * math.pi)
    alpha = 0.5 * math.pi + phiA2 + phiB2
    beta = 0.5 * math.pi - phiA2 - phiB2
    row[_I_ALPHA] = alpha
    row[_I_BETA] = beta
    row[_I_TILT] = 0.5 * (phiA2 - phiB2)
    row[_I_U_A] = cen[0, 0]
    row[_I_V_A] = cen[0, 1]
    row[_I_GAMMA_A] = gam[0]
    row[_I_U_B] = cen[1, 0]
    row[_I_V_B] = cen[1, 1]
    row[_I_GAMMA_B] = gam[1]
    row[_I_HALF_SIDE] = a_half
    row[_I_SIDE_A] = 2.0 * resA[7]
    row[_I_SIDE_B] = 2.0 * resB[7]
    row[_I_N_FACES] = resA[5] + resB[5]
    row[_I_EDGE_WIDTH] = max(resA[6], resB[6])
    ra = resA[3]
    rb = resB[3]
    row[_I_EDGE_RMS] = math.sqrt(0.5 * (ra * ra + rb * rb))
    row[_I_SIGMA_THETA] = (2.0 / math.pi) * math.sqrt(ra * ra / resA[4] + rb * rb / resB[4])
    hinge_geometry(gam, cen, a_half, resA, resB, row)
    return alpha, beta


@njit(cache=True)
def _measure_one(img, pinv, prm, row):  # pragma: no cover - compiled
    """One frame's measurement into ``row`` (:data:`COLUMNS`), the steps of the module docstring; ``row[0]`` is the
    status."""
    h, w = img.shape
    pol = prm[0]
    kappa = prm[2] / prm[1]
    W = int(prm[3])
    blur = prm[4]
    status, level, sigma_pix = _light_level(img, pinv, prm, row)
    if status != 0:
        row[0] = status
        return
    # ---- 2. coverage and particles
    c = np.empty((h, w), np.float32)
    cap = 16384
    rv = np.empty(cap, np.int32)
    r0 = np.empty(cap, np.int32)
    r1 = np.empty(cap, np.int32)
    row_start = np.empty(h + 1, np.int32)
    nruns = coverage_runs(img, prm[11], pinv, pol / (kappa * level), pol / kappa, c, rv, r0, r1, row_start)
    if nruns < 0:
        row[0] = 1
        return
    M = W + 2
    win = np.zeros(4, np.int64)
    status = _dimer_box(c, rv, r0, r1, row_start, nruns, h, w, prm[5], blur, M, win)
    if status != 0:
        row[0] = status
        return
    bu0, bu1, bv0, bv1 = win[0], win[1], win[2], win[3]
    if prm[10] > 0:
        fill_holes(c, bu0, bu1, bv0, bv1, int(math.ceil(3.0 * blur)) + 1)
    u0 = bu0 - M
    u1 = bu1 + M
    v0 = bv0 - M
    v1 = bv1 + M
    if u0 < BORDER_RING or v0 < BORDER_RING or u1 >= w - BORDER_RING or v1 >= h - BORDER_RING:
        row[0] = 3
        return
    # ---- 3. centre of mass and 4. each half's first orientation, in one pass (the halves split at the bounding
    #         box's middle column, the hinge of a mirror-symmetric dimer)
    u_split = 0.5 * (bu0 + bu1)
    ua = 0.5 * (bu0 + u_split)
    ub = 0.5 * (u_split + bu1)
    vo = 0.5 * (bv0 + bv1)
    mom = np.zeros(18)
    window_moments(c, u0, u1, v0, v1, u_split, ua, ub, vo, mom)
    s0 = _centre_of_mass(mom, ua, ub, vo, u0, u1, v0, v1, sigma_pix, row)
    if s0 <= 0:
        row[0] = 2
        return
    if prm[6] > 0 and abs(s0 / prm[6] - 1.0) > prm[7]:
        row[0] = 5
        return
    a_half = 0.5 * math.sqrt(0.5 * s0)
    cen = np.zeros((2, 2))
    gam = np.zeros(2)
    phiA, phiB = _first_orientations(c, mom, ua, ub, vo, u_split, v0, v1, row[_I_V_COM], a_half * math.sqrt(2.0),
                                     cen, gam)
    # ---- 5. edge fits, two passes
    resA = np.empty(25)
    resB = np.empty(25)
    if not _edge_fits(c, cen, gam, a_half, W, blur, u_split, h, w, resA, resB, prm):
        row[0] = 6
        return
    alpha, beta = _angles(phiA, phiB, gam, cen, a_half, resA, resB, row)
    if alpha <= 0.0 or beta <= 0.0:
        row[0] = 7
        return
    row[_I_THETA] = (alpha - beta) / math.pi
    row[0] = 0


@njit(cache=True, nogil=True)
def _measure_batch(frames, pinv, prm, out):  # pragma: no cover - compiled
    for i in range(frames.shape[0]):
        _measure_one(frames[i], pinv, prm, out[i])


@njit(cache=True, nogil=True, parallel=True)
def _measure_batch_parallel(frames, pinv, prm, out):  # pragma: no cover - compiled
    for i in prange(frames.shape[0]):
        _measure_one(frames[i], pinv, prm, out[i])
