"""The recording's background: its illumination and the static structures in view, from calibration frames.

A levitator recording shows more than the dimer: the illumination is uneven (a gradient, vignetting) and may
flicker, and the reflector and transducer edges, or dirt on the window, stay in view.  What does not move is
estimated once per recording and removed before segmentation (:mod:`tracking.segmentation`):

1. **Light levels.**  Each calibration frame's light level is the mean of its background-like pixels (coverage
   below 0.3 against the recording's background level) relative to the median over the frames; every frame is
   divided by its level (the light multiplies the scene: a flicker scales background and cube alike).
2. **The median image** ``M`` of the normalised frames (at most ``MEDIAN_FRAMES`` of them), per pixel: what is
   there in most frames.
3. **The illumination** ``S``: a plane in (column, row) fitted to the background-like pixels of
   ``M``, with those more than 4 robust standard deviations off left out (twice).  Where the dimer is, ``M``
   shows the dimer; the smooth surface reaches under it.
4. **Static structures.**  The pixels of ``M`` that look like a cube (coverage above 1/2 against ``S``),
   joined in 8-connected components: those that touch the frame's border ring are static (the dimer never
   does: a dimer at the border is out of view), widened by 3 px for their blurred edges.  They are left out of
   every frame (coverage 0), so a dimer passing in front of one is partly hidden and its frames fail the area
   check.  Static structures that do not touch the border are excluded with ``--roi``.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

__all__ = ["Background", "estimate_background", "STATIC_MARGIN_PX"]

#: Calibration frames (at most, spread over them) whose per-pixel median is the median image.
MEDIAN_FRAMES = 50
#: Widening of a static structure for its blurred edge [px].
STATIC_MARGIN_PX = 3


@dataclass(frozen=True, eq=False)
class Background:
    """A recording's background (module docstring).

    Attributes
    ----------
    image : ndarray (height, width)
        The background's grey levels at the recording's typical light level (the smooth illumination ``S``).
    static : ndarray (height, width) bool
        Static structures, left out of every frame.
    levels : ndarray (k,)
        The calibration frames' light levels relative to their median.
    coefficients : ndarray (3,)
        ``S = c0 + c1 x + c2 y`` with ``x, y`` the column and row about the frame's
        centre, divided by half the width and height.
    """

    image: NDArray[np.float64]
    static: NDArray[np.bool_]
    levels: NDArray[np.float64]
    coefficients: NDArray[np.float64]

    @property
    def gradient(self) -> float:
        """The illumination's largest relative change across the frame (max - min over mean)."""
        return float((self.image.max() - self.image.min()) / self.image.mean())

    @property
    def static_rows(self) -> list[int]:
        """Rows with a static structure across at least half the frame."""
        return np.flatnonzero(self.static.mean(axis=1) > 0.5).tolist()


def _design(h: int, w: int) -> NDArray[np.float64]:
    x = (np.arange(w) - 0.5 * (w - 1)) / max(0.5 * (w - 1), 1.0)
    y = (np.arange(h) - 0.5 * (h - 1)) / max(0.5 * (h - 1), 1.0)
    X, Y = np.meshgrid(x, y)
    return np.stack([np.ones_like(X), X, Y], axis=-1).reshape(-1, 3)


def _border_touching(mask: NDArray[np.bool_], ring: int) -> NDArray[np.bool_]:
    from scipy import ndimage

    lab, n = ndimage.label(mask, structure=np.ones((3, 3), bool))
    if n == 0:
        return np.zeros_like(mask)
    edge = np.zeros_like(mask)
    edge[:ring] = edge[-ring:] = True
    edge[:, :ring] = edge[:, -ring:] = True
    touching = np.unique(lab[edge & mask])
    return np.isin(lab, touching[touching > 0])


def estimate_background(sample: NDArray, polarity: float, background: float, contrast: float,
                        ring: int = 2) -> Background:
    """The background of a recording from its calibration frames (module docstring).

    Parameters
    ----------
    sample : ndarray (k, height, width)
        Calibration frames spread over the recording (grey levels, any offset already added).
    polarity : float
        -1 for dark cubes on a bright background, +1 for bright on dark.
    background, contrast : float
        The recording's background grey level and |cube - background| (grey levels).
    ring : int
        Width of the border ring [px].

    Returns
    -------
    Background
    """
    from scipy import ndimage

    k, h, w = sample.shape
    like_bg = polarity * (sample - background) / contrast < 0.3
    n_bg = like_bg.sum(axis=(1, 2))
    levels = np.where(n_bg > 0.05 * h * w, np.sum(np.where(like_bg, sample, 0.0), axis=(1, 2)) / np.maximum(n_bg, 1),
                      np.nan)
    levels = levels / np.nanmedian(levels) if np.all(np.nan_to_num(levels, nan=1.0) > 0) else np.ones(k)
    levels = np.nan_to_num(levels, nan=1.0)
    sub = np.unique(np.linspace(0, k - 1, min(k, MEDIAN_FRAMES)).round().astype(int))
    med = np.median(sample[sub] / levels[sub, None, None].astype(np.float32), axis=0)
    A = _design(h, w)
    z = med.reshape(-1)
    use = (polarity * (z - background) / contrast < 0.3) & np.isfinite(z)
    coef = np.array([background, 0.0, 0.0])
    for _ in range(3):
        if use.sum() < 8:
            break
        coef = np.linalg.lstsq(A[use], z[use], rcond=None)[0]
        r = z - A @ coef
        s = 1.4826 * np.median(np.abs(r[use]))
        use = use & (np.abs(r) <= max(4.0 * s, 1e-9 * abs(background)))
    smooth = (A @ coef).reshape(h, w)
    smooth = np.maximum(smooth, 0.2 * background)
    kappa = contrast / background
    cube_like = polarity * (med / smooth - 1.0) / kappa > 0.5
    static = _border_touching(cube_like, ring)
    if static.any():
        static = ndimage.binary_dilation(static, iterations=STATIC_MARGIN_PX)
    return Background(smooth, static, levels, coef)
