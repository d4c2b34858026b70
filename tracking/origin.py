"""Where y = 0 is: the levitation height as an image row, and how it was found.

In this order: the row given with ``--origin-row``; the levitation row the file records; else from the frames.
From the frames, the recording should start with the dimer levitating at rest before the field drop: the origin
is the median centre-of-mass row of the measured frames among the first ``origin_frames``.  Those frames are
checked for motion: their spread (standard deviation of the row) against the tracking's own noise there.  When
they move (spread above ``3 x noise`` and above 0.1 px), the recording did not start at rest, and the origin is
the centre of the oscillation in its late part (the mean row of the last quarter of the measured frames, at
least 200), where the amplitude has decayed: accepted when the spread there is below 1 px, so that the mean
over a few periods is within a tenth of it; otherwise the origin is refused with a line that names
``--origin-row``.
"""
from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from .recording import TrackingError

__all__ = ["find_origin", "REST_SPREAD_FLOOR_PX", "LATE_SPREAD_MAX_PX"]

#: Spread of the origin frames' rows [px] always counted as rest (sub-micrometre jitter at 10 um/px).
REST_SPREAD_FLOOR_PX = 0.1
#: Largest spread [px] of the late frames whose mean is taken as the oscillation's centre.
LATE_SPREAD_MAX_PX = 1.0


def find_origin(v_com: NDArray, sigma_v: NDArray, ok: NDArray, origin_frames: int, path: str,
                why: str = "") -> dict:
    """The origin row from the frames (module docstring).

    Parameters
    ----------
    v_com, sigma_v : ndarray (n,)
        Centre-of-mass row and its standard error per frame [px].
    ok : ndarray (n,) bool
        Measured frames.
    origin_frames : int
        The first frames that should show the dimer at rest.
    path : str
        The recording (for the messages).
    why : str
        What kept the origin frames from being measured (for the message), e.g. ``"poor_fit in 50"``.

    Returns
    -------
    dict
        ``row_px``, ``from`` (how), ``at_rest`` (bool), ``method`` ("rest frames" or "late oscillation centre"),
        ``spread_px`` and ``noise_px`` of the origin frames.

    Raises
    ------
    TrackingError
        No measured origin frame, or a recording that neither starts at rest nor settles.
    """
    first = np.flatnonzero(ok[:origin_frames])
    if first.size == 0:
        raise TrackingError(f"{path}: none of the first {origin_frames} frames could be measured ({why}), so the "
                            "levitation height is unknown; give --origin-row or more --origin-frames")
    rows = v_com[first]
    spread = float(np.std(rows)) if first.size > 1 else 0.0
    noise = float(np.sqrt(np.mean(sigma_v[first] ** 2)))
    out = {"spread_px": spread, "noise_px": noise}
    if spread <= max(3.0 * noise, REST_SPREAD_FLOOR_PX):
        return {"row_px": float(np.median(rows)), "at_rest": True, "method": "rest frames",
                "from": f"median centre-of-mass row of the {first.size} measured frames among the first "
                        f"{origin_frames} (at rest: spread {spread:.3g} px, noise {noise:.3g} px)", **out}
    meas = np.flatnonzero(ok)
    late = meas[-max(200, meas.size // 4):]
    late_spread = float(np.std(v_com[late]))
    if late.size >= 100 and late_spread <= LATE_SPREAD_MAX_PX and late[0] > first[-1]:
        return {"row_px": float(np.mean(v_com[late])), "at_rest": False, "method": "late oscillation centre",
                "from": f"mean centre-of-mass row of the last {late.size} measured frames (the first {origin_frames} "
                        f"move: spread {spread:.3g} px against a noise of {noise:.3g} px; late spread "
                        f"{late_spread:.3g} px)", "late_spread_px": late_spread, **out}
    raise TrackingError(f"{path}: the recording does not start at rest (the first {origin_frames} frames move by "
                        f"{spread:.2g} px RMS against a tracking noise of {noise:.2g} px) and its last {late.size} "
                        f"measured frames still move by {late_spread:.2g} px RMS, so the levitation height is unknown; "
                        "give --origin-row (the levitation row, px from the top)")
