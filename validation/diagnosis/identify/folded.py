"""Runs whose hinge ended folded: outside the mirror-symmetric model's domain, left out of the diagnosis.

The hinge's restoring acceleration has a largest value (on the default dimer at 3 kPa, 26 1/s^2 at
|theta| = 0.4 on the Gor'kov hinge): a constant hinge acceleration beyond it (a strong mirror asymmetry
beta0), or a drop that throws the hinge over that top, closes the dimer until the cube faces nearly touch
(theta = +-1).  With the air between the closing faces (its squeeze film, docs/damping.md) the hinge then
creeps toward contact and stays within a few per cent of it for the rest of the run: on the twin with
beta0 = -27.5 1/s^2 every run ended at theta = -0.98 to -0.99, still with the tracking noise alone on it.

Such a run carries no hinge dynamics: its measured theta is noise about a constant, so the integral form's
normalisation (the detrended theta) is the noise itself and the run's gap is tens to hundreds of times the
others' (89 and 38 against 0.2-0.5 there), which outweighs every held-out comparison and hid every effect
(the mirror asymmetry that folded the hinge included).  A real dimer whose cubes stuck face to face looks the
same.  :func:`leave_out_folded_runs` moves such runs to the data set's skipped files, with the reason, so
that the fit and the diagnosis of a report see the same runs and the report lists them.
"""
from __future__ import annotations

from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from cubedimer.dataset import Dataset, Run

__all__ = ["FOLDED_THETA", "FOLDED_TAIL_S", "TOUCHING_THETA", "folded_angle", "leave_out_folded_runs"]

#: |theta| beyond which the hinge counts as folded (the faces touch at 1; on the default dimer the hinge's restoring
#: acceleration peaks at 26 1/s^2 at 0.4 and is down to 7.5 1/s^2 at 0.85).
FOLDED_THETA = 0.9
#: Length of the run's end [s] whose median |theta| decides whether the run ended folded.
FOLDED_TAIL_S = 0.1
#: |theta| of a run's last frames beyond which the faces touch as the run ends (a run stopped at the fold).
TOUCHING_THETA = 0.95


def folded_angle(run: "Run") -> float | None:
    """The angle at which ``run`` ended folded, else None: the median theta [-] over its last :data:`FOLDED_TAIL_S`
    seconds when its |theta| exceeds :data:`FOLDED_THETA` (a hinge that stays closed), or the median of its last 5
    frames when their |theta| exceeds :data:`TOUCHING_THETA` (a run that ends as the faces touch, as the inviscid
    twin's runs stop at a fold: the final plunge from the top of the restoring acceleration takes about 0.15 s)."""
    n = max(10, int(round(FOLDED_TAIL_S / run.dt)))
    median = float(np.median(run.theta[-n:]))
    if abs(median) > FOLDED_THETA:
        return median
    last = float(np.median(run.theta[-5:]))
    return last if abs(last) > TOUCHING_THETA else None


def leave_out_folded_runs(dataset: "Dataset") -> "Dataset":
    """The data set without its runs that ended folded (:func:`folded_angle`), each moved to ``skipped`` with a
    one-line reason that names the angle."""
    from cubedimer.dataset import SkippedFile

    kept, skipped = [], list(dataset.skipped)
    for run in dataset.runs:
        angle = folded_angle(run)
        if angle is None:
            kept.append(run)
            continue
        skipped.append(SkippedFile(run.name, (
            f"the hinge ended folded (theta {angle:+.3f} at the end of the run, beyond +-{FOLDED_THETA:g}; the faces "
            "touch at +-1): the mirror-symmetric model does not describe a closed dimer, so the run is left out")))
    if len(kept) == len(dataset.runs):
        return dataset
    return replace(dataset, runs=tuple(kept), skipped=tuple(skipped))
