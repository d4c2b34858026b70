"""The one estimate of white tracking noise from a tracked coordinate: robust scale of its fourth differences.

The fourth difference ``x[i-2] - 4 x[i-1] + 6 x[i] - 4 x[i+1] + x[i+2]`` of white noise has the standard
deviation ``sqrt(70) sigma``, while that of the motion is ``(omega dt)^4`` times its amplitude (7e-5 at 22 Hz
and 1500 fps: 0.007 um on 100 um), so the scaled fourth differences are the noise; sigma is their median
absolute deviation times 1.4826 / sqrt(70), robust to isolated tracking glitches (a glitch touches five
differences).  A tracked data set records each run's own noise, measured from the images, in meta.json
(:func:`recorded_run_noise`).  Used by the cross-run consistency checks (:mod:`cubedimer.consistency`) and the oracle
(:func:`fitting.uncertainty.oracle.estimate_tracking_noise`).
"""
from __future__ import annotations

import math
from typing import Sequence

import numpy as np
from numpy.typing import ArrayLike

__all__ = ["white_noise_std", "recorded_run_noise"]

_FOURTH_DIFFERENCE = np.array([1.0, -4.0, 6.0, -4.0, 1.0]) / np.sqrt(70.0)


def white_noise_std(parts: Sequence[ArrayLike]) -> float:
    """Standard deviation of white noise on the coordinate, pooled over ``parts`` (e.g. the runs of a data set).

    Parameters
    ----------
    parts : sequence of array_like
        Samples at a uniform frame rate, gaps filled (NaN differences are left out).

    Returns
    -------
    float
        sigma in the units of the samples; the standard deviation of the scaled fourth differences where their
        MAD is 0 (quantised data).

    Raises
    ------
    ValueError
        No part has five finite consecutive frames.
    """
    diffs = [np.convolve(np.asarray(p, float), _FOURTH_DIFFERENCE, mode="valid") for p in parts]
    x = np.concatenate(diffs) if diffs else np.zeros(0)
    x = x[np.isfinite(x)]
    if x.size == 0:
        raise ValueError("no frames to estimate the tracking noise from")
    mad = 1.4826 * float(np.median(np.abs(x - np.median(x))))
    return mad if mad > 0 else max(float(np.std(x)), 1e-300)


def recorded_run_noise(meta: dict) -> dict[str, tuple[float, float]]:
    """``{file: (noise_y_m, noise_theta)}`` of the runs meta.json's ``tracking.runs`` records (``tracking track``
    writes each run's own noise there); a run whose record is incomplete, not positive or not finite is left out."""
    block = meta.get("tracking")
    entries = block.get("runs") if isinstance(block, dict) else None
    out: dict[str, tuple[float, float]] = {}
    for e in entries if isinstance(entries, list) else ():
        try:
            noise = (float(e["noise_y_m"]), float(e["noise_theta"]))
            name = str(e["file"])
        except (KeyError, TypeError, ValueError):
            continue
        if all(math.isfinite(v) and v > 0 for v in noise):
            out[name] = noise
    return out
