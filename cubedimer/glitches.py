"""Tracking glitches: isolated outlier frames found against a local smooth fit.

A camera tracker occasionally locks onto the wrong edge for a frame or two; the coordinate then jumps
by many times the tracking noise and comes back.  Such frames are found robustly and masked like
missing frames (the loader fills short gaps), so that they neither bias a regression nor blow up a
model.

Method.  The coordinate is smoothed with a short cubic Savitzky-Golay filter (about a tenth of the
dominant period, at least 5 frames), whose residual ``r = x - S x`` holds the tracking noise and
almost none of the signal.  For white noise of standard deviation sigma the residual's standard
deviation is ``sigma sqrt(1 - c0)`` (``c0`` the filter's centre weight; the filter is a projection),
so one robust scale (1.4826 times the median absolute residual) serves every frame.  A frame is a
glitch when its |r| exceeds ``threshold`` scales and is the largest |r| within one filter window; the
glitches are masked and the search repeats (the spike of a glitch leaks into its neighbours'
residuals, and masking the largest first keeps those neighbours unflagged).  With the default
threshold of 7 the false-alarm rate on Gaussian noise is ~3e-12 per frame, and a glitch of size h
leaves ``h (1 - c0)`` in the residual, so glitches from about 14 noise standard deviations on are
found with certainty (c0 ~ 0.42 for the 9-frame window of a 22 Hz oscillation at 2000 fps); smaller ones
are hard to tell from the noise and do little harm.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["GlitchConfig", "find_glitches"]


@dataclass(frozen=True)
class GlitchConfig:
    """Settings of :func:`find_glitches`.

    Parameters
    ----------
    threshold : float
        Robust standard deviations of the smoothing residual beyond which a frame is a glitch.
    period_fraction : float
        Smoothing window as a fraction of the dominant period (rounded to an odd number of frames).
    max_fraction : float
        At most this fraction of the frames is masked; a run with more outliers is not "glitchy" but
        broken, and is left to the loader's other checks.
    max_rounds : int
        Rounds of detection and masking.
    """

    threshold: float = 7.0
    period_fraction: float = 0.1
    max_fraction: float = 0.02
    max_rounds: int = 8

    def __post_init__(self) -> None:
        if not self.threshold > 3:
            raise ValueError(f"threshold must exceed 3 robust standard deviations, got {self.threshold!r}")
        if not 0 < self.period_fraction <= 0.5:
            raise ValueError(f"period_fraction must lie in (0, 0.5], got {self.period_fraction!r}")
        if not 0 < self.max_fraction < 0.5:
            raise ValueError(f"max_fraction must lie in (0, 0.5), got {self.max_fraction!r}")


def _window(frames_per_period: float, fraction: float) -> int:
    w = int(round(fraction * frames_per_period))
    w = max(w, 5)
    return w + 1 - w % 2  # odd


def _fill(x: NDArray, bad: NDArray) -> NDArray:
    """Linear interpolation over ``bad`` (and non-finite) samples, nearest value at the ends."""
    good = ~bad & np.isfinite(x)
    if good.sum() < 2:
        return np.where(good, x, 0.0)
    i = np.arange(x.size)
    return np.where(good, x, np.interp(i, i[good], x[good]))


def find_glitches(x: ArrayLike, frames_per_period: float, config: GlitchConfig = GlitchConfig()) -> NDArray[np.bool_]:
    """Frames of ``x`` that are isolated outliers (see the module docstring).

    Parameters
    ----------
    x : array_like (n,)
        A uniformly sampled coordinate; non-finite samples (missing frames) are allowed and never flagged.
    frames_per_period : float
        Frames per period of the coordinate's dominant oscillation (sets the smoothing window).
    config : GlitchConfig

    Returns
    -------
    ndarray of bool (n,)
        True at glitch frames.  None are returned when more than ``config.max_fraction`` of the
        frames would be flagged.
    """
    from scipy.ndimage import maximum_filter1d
    from scipy.signal import savgol_filter

    x = np.asarray(x, float)
    n = x.size
    w = _window(frames_per_period, config.period_fraction)
    glitch = np.zeros(n, bool)
    if n < 2 * w:
        return glitch
    missing = ~np.isfinite(x)
    # frames within half a window of a missing frame see the interpolation across the gap: never flagged
    near_gap = maximum_filter1d(missing.astype(np.uint8), w, mode="nearest").astype(bool)
    finite = x[~missing]
    # a scale below 1e-6 of the coordinate's range is round-off (noise-free synthetic data), not tracking noise
    floor = 1e-6 * float(np.ptp(finite)) if finite.size else 0.0
    for _ in range(config.max_rounds):
        filled = _fill(x, glitch | missing)
        r = filled - savgol_filter(filled, w, 3, mode="interp")
        r[glitch | near_gap] = 0.0
        scale = max(1.4826 * float(np.median(np.abs(r[~(glitch | near_gap)]))), floor)
        if not scale > 0:
            break
        a = np.abs(r)
        new = (a > config.threshold * scale) & (a >= maximum_filter1d(a, w, mode="nearest"))
        if not new.any():
            break
        glitch |= new
    if glitch.sum() > config.max_fraction * n:
        return np.zeros(n, bool)
    return glitch
