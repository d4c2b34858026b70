"""Step 1 of the tracking (:mod:`tracking.track`): what a recording's calibration frames give.

Up to ``TrackConfig.calibration_frames`` frames spread over the recording give the polarity (dark cubes on a
bright background or bright on dark: the side of the grey-level histogram the far tail lies on, by majority),
the background level and the cube/background contrast (on at most 16 of them), the background image (its
illumination and static structures, :mod:`tracking.background`), whether the silhouettes have holes (transparent
crystals: filled), then a first measurement of those frames for the dimer's silhouette area and the edge blur,
which set the edge window ``W = ceil(3.5 blur + 2)`` px and the area check; and the hinge line's tilt out of the
camera axis from the hinge gap (:mod:`tracking.tilt`); when the gap over the squares' sides from their faces
(:func:`tracking.tilt.tilt_from_faces`) reads more than ``TILT_CORRECTION_DEG``, the tilt is refined from the
cubes' centres and the silhouette's area with the projection undone (:func:`tracking.tilt.tilt_from_centres`, on
the calibration frames whose eight faces were fitted; twice), its error from the estimate's spread and its floor
(at least the difference from the faces' reading), and what that error does to theta (the calibration frames
measured again at the tilt plus its error).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np
from numpy.typing import NDArray

from .background import Background, estimate_background
from .measure import COLUMNS, STATUS, STATUS_TEXT, MeasureSettings, measure_frames, reciprocal_background
from .recording import TrackingError
from .tilt import MAX_TILT_DEG, TILT_CORRECTION_DEG, TILT_FLOOR_DEG, tilt_from_centres, tilt_from_faces, tilt_from_gap

__all__ = ["Calibration", "calibrate", "faces_tilt"]

_C = {name: i for i, name in enumerate(COLUMNS)}


@dataclass(frozen=True, eq=False)
class Calibration:
    """What the calibration frames gave (grey levels in the recording's units, lengths in pixels).

    ``dark_offset`` grey levels are added to every pixel before the light is normalised (a background near
    black); ``pinv`` is the reciprocal background image the kernel reads (0 on static structures);
    ``hinge_tilt_deg`` the tilt the hinge gap gives; ``tilt`` the tilt the measurement undoes (None: none), a dict
    with ``tilt_deg``, ``error_deg``, ``theta_bias`` (RMS change of theta over the calibration frames when the tilt
    is off by its error), ``from_hinge_gap_deg`` and ``frames``."""

    polarity: str
    polarity_from: str
    background: float
    contrast: float
    slope_u: float
    slope_v: float
    edge_blur_px: float
    edge_window_px: int
    area_px2: float
    frames_used: int
    dark_offset: float = 0.0
    fill_holes: bool = False
    scene: Background | None = None
    pinv: NDArray | None = field(default=None, repr=False)
    hinge_tilt_deg: float | None = None
    tilt: dict | None = None

    def settings(self, config) -> MeasureSettings:
        return MeasureSettings(-1.0 if self.polarity == "dark" else 1.0, self.background + self.dark_offset,
                               self.contrast, self.edge_window_px, self.edge_blur_px, max(9.0, 0.01 * self.area_px2),
                               self.area_px2, config.area_tolerance, self.slope_u, self.slope_v, self.fill_holes,
                               self.dark_offset, math.radians(self.tilt["tilt_deg"]) if self.tilt else 0.0)


def _grey_levels(stats: NDArray, config) -> tuple[str, str, float, float]:
    """Polarity (and where it came from), background level and contrast from the grey-level statistics."""
    flat = stats.reshape(stats.shape[0], -1)
    med = np.median(flat, axis=1)
    lo, hi = np.percentile(flat, [0.5, 99.5], axis=1)
    noise = 1.4826 * np.median(np.abs(np.diff(stats, axis=2)), axis=(1, 2)) / math.sqrt(2.0)
    spread = np.maximum(med - lo, hi - med)
    valid = np.isfinite(spread) & (spread > np.maximum(10.0 * noise, 1e-12))
    if not valid.any():
        raise TrackingError(f"no dimer found: none of {flat.shape[0]} frames sampled over the recording shows an "
                            "object against its background (check: python -m tracking inspect)")
    dark_votes = (med - lo > hi - med)[valid]
    if config.polarity == "auto":
        polarity, polarity_from = ("dark" if dark_votes.mean() >= 0.5 else "bright"), "detected"
    else:
        polarity, polarity_from = config.polarity, "option"
    background = float(np.median(med[valid]))
    levels = []
    for i in np.flatnonzero(valid):
        mid = 0.5 * (med[i] + (lo[i] if polarity == "dark" else hi[i]))
        obj = flat[i][flat[i] < mid] if polarity == "dark" else flat[i][flat[i] > mid]
        if obj.size:
            levels.append(float(np.median(obj)))
    contrast = abs(float(np.median(levels)) - background) if levels else 0.0
    if not contrast > 0:
        raise TrackingError("no dimer found: the frames show no contrast between object and background")
    return polarity, polarity_from, background, contrast


def _relative_contrast(frames: NDArray, pinv: NDArray, pol: float, kappa: float) -> float:
    """The cubes' contrast relative to the background as the coverage sees it: ``kappa`` (from the grey levels)
    times the median coverage of the pixels deep inside the cubes (coverage above 0.8) of the normalised frames, each
    frame divided by its own light level (the mean of its border ring's background-like pixels, as the measurement
    takes it).  The grey-level statistics put
    the background at the frame's median, which the cubes' pixels and the noise move (bright cubes on black at 2 %
    noise: 6 % too low a relative contrast, every coverage 6 % high and the edges 0.19 px outward); in the frames
    the background image normalises, the cubes' interior is the contrast itself.  ``kappa`` unchanged without such
    pixels."""
    from .segmentation import BORDER_RING

    ring = np.zeros(pinv.shape, bool)
    ring[:BORDER_RING], ring[-BORDER_RING:], ring[:, :BORDER_RING], ring[:, -BORDER_RING:] = True, True, True, True
    values = []
    for f in frames:
        x = np.where(pinv > 0, f * pinv, np.nan)
        c = pol * (x - 1.0) / kappa
        bg = ring & (c <= 0.3) & (pinv > 0)  # the frame's light level as the measurement takes it (its border ring)
        if bg.sum() < 16:
            continue
        level = float(np.mean(x[bg]))
        c = pol * (x / level - 1.0) / kappa
        values.append(c[c > 0.8])
    inside = np.concatenate(values) if values else np.zeros(0)
    return kappa * float(np.median(inside)) if inside.size >= 16 else kappa


def _has_holes(frames: NDArray, pinv: NDArray, pol: float, kappa: float) -> bool:
    """Whether the largest silhouette of most of ``frames`` has holes of more than 5 % of its area (a transparent
    crystal's bright interior inside its dark outline)."""
    from scipy import ndimage

    votes = []
    for f in frames:
        c = np.where(pinv > 0, pol * (f * pinv - 1.0) / kappa, 0.0)
        lab, n = ndimage.label(c > 0.5, structure=np.ones((3, 3), bool))
        if n == 0:
            continue
        big = lab == 1 + int(np.argmax(np.bincount(lab.ravel())[1:]))
        votes.append(ndimage.binary_fill_holes(big).sum() > 1.05 * big.sum())
    return bool(votes) and float(np.mean(votes)) > 0.5


def calibrate(frames: NDArray, config) -> Calibration:
    """Polarity, grey levels, background image, holes, edge blur and silhouette area (module docstring).

    Parameters
    ----------
    frames : ndarray (n, height, width)
    config : tracking.track.TrackConfig

    Raises
    ------
    TrackingError
        When no calibration frame shows a dimer (``"no dimer found ..."``, naming the check that failed).
    """
    n = frames.shape[0]
    idx = np.unique(np.linspace(0, n - 1, min(n, config.calibration_frames)).round().astype(int))
    sample = frames[idx].astype(np.float32)
    k, h, w = sample.shape
    # grey-level statistics (medians, tails) on at most 16 of the calibration frames: they are costly per frame
    # and the same in every frame of a recording; all calibration frames are measured below
    stats = sample[np.unique(np.linspace(0, k - 1, min(k, 16)).round().astype(int))]
    polarity, polarity_from, background, contrast = _grey_levels(stats, config)
    pol = -1.0 if polarity == "dark" else 1.0
    dark = max(0.0, 0.2 * contrast - background)  # a background near black is normalised nearly additively
    ref = background + dark
    scene = estimate_background(sample + dark, pol, ref, contrast)
    pinv = reciprocal_background(scene.image, ref, scene.static)
    contrast = _relative_contrast(stats + dark, pinv, pol, contrast / ref) * ref
    fill = _has_holes(stats + dark, pinv, pol, contrast / ref)
    c = scene.coefficients
    su, sv = float(c[1] / max(0.5 * (w - 1), 1.0)), float(c[2] / max(0.5 * (h - 1), 1.0))
    window = int(config.edge_window or 8)
    first = Calibration(polarity, polarity_from, background, contrast, su, sv, 1.5, window, 0.0, k, dark, fill,
                        scene, pinv)
    rows = measure_frames(sample, first.settings(config), pinv=pinv)
    ok = rows[:, 0] == 0
    if not ok.any():
        codes, counts = np.unique(rows[:, 0].astype(int), return_counts=True)
        names = {v: s for s, v in STATUS.items()}
        why = ", ".join(f"{names[int(cd)]} in {int(ct)}" for cd, ct in sorted(zip(codes, counts), key=lambda x: -x[1]))
        raise TrackingError(f"no dimer found: none of {k} frames sampled over the recording could be measured "
                            f"({why}; mostly: {STATUS_TEXT[names[int(codes[np.argmax(counts)])]]}); look at "
                            "python -m tracking inspect, and try --roi to exclude what is not the dimer")
    area = float(np.median(rows[ok, _C["area"]]))
    blur = float(np.median(rows[ok, _C["edge_width"]]))
    gap = rows[ok, _C["hinge_gap"]] / (2.0 * rows[ok, _C["half_side"]])
    tilt = tilt_from_gap(float(np.median(gap[np.isfinite(gap)]))) if np.isfinite(gap).any() else None
    if config.edge_window is None:
        window = int(np.clip(math.ceil(3.5 * blur + 2.0), 4, 25))
    cal = Calibration(polarity, polarity_from, background, contrast, su, sv, blur, window, area, int(ok.sum()),
                      dark, fill, scene, pinv, tilt)
    faces = faces_tilt(rows[ok])
    if tilt is not None and faces is not None and TILT_CORRECTION_DEG < faces and tilt <= MAX_TILT_DEG:
        cal = replace(cal, tilt=_refine_tilt(sample, cal.settings(config), pinv, tilt, faces))
    return cal


def faces_tilt(rows: NDArray) -> float | None:
    """The tilt [degrees] from the fitted squares' hinge corners placed with their sides from the faces (not from
    the area), :func:`tracking.tilt.tilt_from_faces` of the median gap over side; None without a fitted frame."""
    corners = []
    for u, v, g, side in (("u_a", "v_a", "gamma_a", "side_a"), ("u_b", "v_b", "gamma_b", "side_b")):
        g = rows[:, _C[g]]
        normals = g[:, None] - 0.5 * np.pi + 0.5 * np.pi * np.arange(4)[None, :]
        cx = np.cos(normals) + np.cos(normals + 0.5 * np.pi)
        cz = np.sin(normals) + np.sin(normals + 0.5 * np.pi)
        k = np.argmax(cx, axis=1) if u == "u_a" else np.argmin(cx, axis=1)  # the hinge corner: A's right, B's left
        i = np.arange(len(g))
        half = 0.5 * rows[:, _C[side]]
        corners.append((rows[:, _C[u]] + half * cx[i, k], -rows[:, _C[v]] + half * cz[i, k], rows[:, _C[side]]))
    (xa, za, sa), (xb, zb, sb) = corners
    ratio = np.hypot(xa - xb, za - zb) / (0.5 * (sa + sb))
    ratio = ratio[np.isfinite(ratio)]
    return tilt_from_faces(float(np.median(ratio))) if ratio.size else None


def _centres_tilt(rows: NDArray) -> tuple[NDArray, int]:
    """Each calibration frame's tilt [rad] from its cubes' centres and area (those with all eight faces fitted)."""
    use = (rows[:, 0] == 0) & (rows[:, _C["n_faces"]] == 8)
    r = rows[use]
    t = tilt_from_centres(r[:, _C["u_b"]] - r[:, _C["u_a"]], r[:, _C["v_b"]] - r[:, _C["v_a"]], r[:, _C["theta"]],
                          r[:, _C["tilt"]], r[:, _C["area"]])
    t = t[np.isfinite(t)]
    return t, int(t.size)


def _refine_tilt(sample: NDArray, settings: MeasureSettings, pinv: NDArray, gap_deg: float, faces_deg: float) -> dict:
    """The tilt the measurement undoes (module docstring): from the hinge gap's estimate, twice the median of the
    centres' estimates measured with the previous one undone; its error, the standard error of that median (1.25
    x the robust spread over the root of the frames) and :data:`tracking.tilt.TILT_FLOOR_DEG` in quadrature, and
    at least the difference from the faces' estimate (the area the centres' estimate uses reads large when the
    background's coverage is offset); and the RMS change of theta over the calibration frames with the tilt off by
    that error."""
    tau = math.radians(gap_deg)
    t, used = np.zeros(0), 0
    for _ in range(2):
        t_new, used_new = _centres_tilt(measure_frames(sample, replace(settings, hinge_tilt=tau), pinv=pinv))
        if used_new < 5:
            break
        t, used = t_new, used_new
        tau = float(np.median(t))
    spread = 1.4826 * float(np.median(np.abs(t - tau))) if used else math.radians(gap_deg)
    err = max(math.hypot(1.25 * spread / math.sqrt(max(used, 1)), math.radians(TILT_FLOOR_DEG)),
              abs(tau - math.radians(faces_deg)))
    rows = measure_frames(sample, replace(settings, hinge_tilt=tau), pinv=pinv)
    off = measure_frames(sample, replace(settings, hinge_tilt=tau + err), pinv=pinv)
    both = (rows[:, 0] == 0) & (off[:, 0] == 0)
    d_theta = off[both, _C["theta"]] - rows[both, _C["theta"]]
    return {"tilt_deg": math.degrees(tau), "error_deg": math.degrees(err),
            "theta_bias": float(np.sqrt(np.mean(d_theta ** 2))) if both.any() else 0.0,
            "from_hinge_gap_deg": float(gap_deg), "from_faces_deg": float(faces_deg), "frames": used}
