"""The orientation of y, told by the physics: does the data set measure y positive up?

A tracker that reports image rows measures y positive *down*.  Nothing in the file says so, and the fit and the
diagnosis run as usual: the y*theta coupling changes sign, and the diagnosis finds a gap that no candidate
effect explains, which reads like new physics.  The physics can tell, however.  The vertical force of the trap,
``F_Z = -F0 sin(2 k Z)`` with the levitation height ``Z_eq`` below the pressure node (gravity pulls the dimer
there at any pressure), is not symmetric about ``Z_eq``: expanded in y, its ``y^2`` coefficient
``2 k^2 F0 sin(2 k Z_eq) / M`` is negative whatever the pressure (docs/conventions.md).  A calibration can move
the pressure and the origin, but not that sign: with y inverted the vertical equation keeps a gap.

:func:`check_y_orientation` calibrates the simulation (pressure and origin, no effects) to the data as they
are and with ``y -> -y``, and compares the vertical equation's gap per run.  Every term that is odd in y (the
linear restoring force, linear damping) fits both orientations equally, so any unmodelled odd effect leaves the
same gap in both; the difference is the trap's asymmetry.  y is judged inverted when the flipped data fit
better in every run and the flipped vertical gap is at most :data:`FAR_BETTER` of the original's, with the
original's above :data:`MIN_VERTICAL_GAP` (a gap the noise cannot make).
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray

from ..prepare.problem import DiagnosisProblem
from ..prepare.runs import prepare_diagnosis_runs
from .gap_model import fit_gap_model
from .metrics import fit_gaps

__all__ = ["OrientationTest", "check_y_orientation", "judge_inverted", "flip_y", "FAR_BETTER", "MIN_VERTICAL_GAP"]

#: The flipped data's vertical gap must be at most this fraction of the original's ("far better").
FAR_BETTER = 1.0 / 3.0
#: Smallest vertical gap of the original orientation (fraction of the acceleration variance in excess of the
#: noise floor) that can be told from noise; the twin's correctly oriented data sit at 2e-5, the same data
#: inverted at 1e-3 (4 runs of 1.5 s).
MIN_VERTICAL_GAP = 2e-4

@dataclass(frozen=True)
class OrientationTest:
    """Result of :func:`check_y_orientation`: per-run vertical gaps as recorded and with y inverted."""

    inverted: bool
    vertical_gap: NDArray[np.float64]
    vertical_gap_flipped: NDArray[np.float64]

    @property
    def ratio(self) -> float:
        """Mean flipped vertical gap over the mean recorded one."""
        g = float(np.mean(self.vertical_gap))
        return float(np.mean(self.vertical_gap_flipped)) / g if g > 0 else float("nan")

    def warning(self) -> dict | None:
        """The ``data_warnings`` entry (code ``y_inverted``), or None when y is not evidently inverted."""
        if not self.inverted:
            return None
        return {"code": "y_inverted",
                "message": (f"y evidently points down (image rows?): the trap's vertical equation fits "
                            f"{1 / self.ratio:.0f} times better with y -> -y (vertical gap "
                            f"{np.mean(self.vertical_gap_flipped):.2g} against {np.mean(self.vertical_gap):.2g}, "
                            f"better in all {self.vertical_gap.size} runs); the diagnosis uses -y. Write y positive "
                            f"up (docs/conventions.md)"),
                "vertical_gap": float(np.mean(self.vertical_gap)),
                "vertical_gap_flipped": float(np.mean(self.vertical_gap_flipped))}

def flip_y(dataset):
    """The data set with y -> -y in every run (a :class:`cubedimer.dataset.Dataset`)."""
    return replace(dataset, runs=tuple(replace(r, y=-r.y) for r in dataset.runs))

def _vertical_gaps(problem: DiagnosisProblem) -> NDArray[np.float64]:
    return fit_gaps(problem.runs, fit_gap_model(problem, []))[:, 0]

def check_y_orientation(problem: DiagnosisProblem, dataset, max_frames_per_run: int) -> tuple[OrientationTest,
                                                                                              DiagnosisProblem]:
    """Compare the calibrated vertical equation on ``problem`` (the data set as recorded) and on the data set
    with y inverted (module docstring).

    Returns
    -------
    (OrientationTest, DiagnosisProblem)
        The test and the problem of the flipped data (to diagnose instead when ``inverted``).
    """
    flipped = DiagnosisProblem.from_recorded(problem.model, prepare_diagnosis_runs(flip_y(dataset)),
                                             max_frames_per_run)
    g, gf = _vertical_gaps(problem), _vertical_gaps(flipped)
    return OrientationTest(judge_inverted(g, gf), g, gf), flipped


def judge_inverted(gap: NDArray, gap_flipped: NDArray) -> bool:
    """y is inverted when the per-run vertical gaps with y -> -y (``gap_flipped``) are smaller in every run, at
    most :data:`FAR_BETTER` of the recorded ones on average, and the recorded ones exceed :data:`MIN_VERTICAL_GAP`."""
    g, gf = np.asarray(gap, float), np.asarray(gap_flipped, float)
    return bool(np.all(gf < g) and np.mean(g) > MIN_VERTICAL_GAP and np.mean(gf) <= FAR_BETTER * np.mean(g))
