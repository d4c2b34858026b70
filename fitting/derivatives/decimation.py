"""Block averaging of runs filmed at many frames per period (the fit's first step at high frame rates).

A run with more than ``SmoothingConfig.max_frames_per_period`` frames per period of its fastest dominant coordinate
(the larger of the y and theta frequencies) is replaced by the means of consecutive blocks of ``q`` frames, ``q``
the smallest whole factor that brings it to at most that many frames per period, each mean at the mean time of
its block (a frame left over at the end is dropped).

Why a block mean.  It keeps the information: white tracking noise of standard deviation sigma becomes white noise
of sigma / sqrt(q) at the new rate (the blocks do not overlap), so the integral form, the noise estimate of
:mod:`cubedimer.noise` and the oracle see exactly the noise they assume; a low-pass filter followed by
subsampling would leave coloured noise that the fourth-difference estimate under-reads.  The mean attenuates an
oscillation of frequency f by sinc(pi f q dt) ~ 1 - (pi f q dt)^2 / 6, 4e-5 at the fundamental and 4e-4 at its
third harmonic at 250 frames per period after averaging.  The smoothing windows, the model-state segments and the
long-time polish then cost what they cost at ordinary frame rates.
"""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from cubedimer.dataset import Run

__all__ = ["decimation_factor", "block_average"]


def decimation_factor(dt: float, frequency: float, max_frames_per_period: float | None) -> int:
    """The smallest whole ``q`` with ``1 / (q dt frequency) <= max_frames_per_period`` (1 when None or the
    frequency is not positive).

    Parameters
    ----------
    dt : float
        Frame interval [s].
    frequency : float
        The fastest dominant frequency of the run [Hz].
    max_frames_per_period : float or None
    """
    if max_frames_per_period is None or not frequency > 0:
        return 1
    return max(1, math.ceil(1.0 / (dt * frequency * max_frames_per_period) - 1e-9))


def block_average(run: Run, q: int) -> Run:
    """``run`` with every ``q`` consecutive frames replaced by their mean (times included); ``q = 1`` returns it.

    The counts of filled and glitch frames (``n_filled``, ``glitch_frames``) are those of the recorded frames; the
    recorded white noise (``noise``) of a mean of q frames is 1/sqrt(q) of the frames'.
    """
    if q == 1:
        return run
    n = run.t.size // q * q
    mean = lambda x: np.asarray(x[:n], float).reshape(-1, q).mean(axis=1)  # noqa: E731
    v = None if run.velocities is None else np.column_stack([mean(run.velocities[:, k]) for k in range(2)])
    noise = getattr(run, "noise", None)
    noise = None if noise is None else (noise[0] / math.sqrt(q), noise[1] / math.sqrt(q))
    return replace(run, t=mean(run.t), y=mean(run.y), theta=mean(run.theta), velocities=v, noise=noise)
