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

A change of acceleration is not a glitch: the onset of a free fall when the field drops (the acceleration jumps by
g) or the field's return leave a residual of a few noise standard deviations at the kink, over several frames.  Each
candidate is therefore predicted from its neighbours by a cubic plus up to two
breaks of the acceleration near it; a candidate the breaks predict within the threshold is a kink and is kept.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .config_checks import check_above, check_positive, check_that

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
        check_above(self, "threshold", 3.0)  # robust standard deviations
        check_positive(self, "period_fraction")
        check_that(self, self.period_fraction <= 0.5, f"period_fraction must lie in (0, 0.5], got {self.period_fraction!r}")
        check_positive(self, "max_fraction")
        check_that(self, self.max_fraction < 0.5, f"max_fraction must lie in (0, 0.5), got {self.max_fraction!r}")


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


def _explained_by_acceleration_change(x: NDArray, candidates: NDArray, excluded: NDArray, w: int,
                                      bound: float) -> NDArray[np.bool_]:
    """For each candidate frame: whether changes of acceleration explain it (kinks, not a glitch).

    Around the candidate (``w // 2 + 2`` frames either side), a cubic plus up to two breaks of the acceleration,
    ``(t - b1)_+^2`` and ``(t - b2)_+^2`` (a field drop's fall and the field's return may lie a few frames apart), is
    fitted to the other frames not ``excluded`` (earlier glitches, missing frames), the breaks on
    a grid of half frames at the least residual sum; the candidate is explained when that fit predicts it within
    ``bound``.  A glitch is a frame off the smooth motion, which its neighbours do not predict; the onset of a fall or
    the field's return is a jump of the acceleration, which a break takes up.
    """
    out = np.zeros(candidates.size, bool)
    half = w // 2 + 2
    grid = np.arange(-half + 1.0, half - 0.99, 0.5)
    pairs = np.array([(b1, b2) for b1 in grid for b2 in grid if b2 > b1])
    for j, i in enumerate(candidates):
        idx = np.arange(max(0, i - half), min(x.size, i + half + 1))
        use = idx[~excluded[idx] & (idx != i)]
        if use.size < 9:
            continue
        s = (use - i).astype(float)
        design = np.concatenate([np.broadcast_to(np.stack([np.ones_like(s), s, s ** 2, s ** 3], axis=1),
                                                 (len(pairs), s.size, 4)),
                                 np.maximum(s[None, :, None] - pairs[:, None, :], 0.0) ** 2], axis=2)
        gram = np.einsum("pmk,pml->pkl", design, design) + 1e-9 * np.eye(6)
        coef = np.linalg.solve(gram, np.einsum("pmk,m->pk", design, x[use])[..., None])[..., 0]
        rss = np.sum((x[use][None, :] - np.einsum("pmk,pk->pm", design, coef)) ** 2, axis=1)
        k = int(np.argmin(rss))
        pred = coef[k, 0] + coef[k, 4] * max(-pairs[k, 0], 0.0) ** 2 + coef[k, 5] * max(-pairs[k, 1], 0.0) ** 2
        out[j] = abs(x[i] - pred) <= bound
    return out


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
        over = a > config.threshold * scale
        new = over & (a >= maximum_filter1d(a, w, mode="nearest"))
        cand = np.flatnonzero(new)
        new[cand[_explained_by_acceleration_change(filled, cand, glitch | missing, w, config.threshold * scale)]] = False
        if not new.any():
            break
        glitch |= new
    if glitch.sum() > config.max_fraction * n:
        return np.zeros(n, bool)
    return glitch
