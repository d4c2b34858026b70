"""The oscillation frequencies of a run, the one rule by which the fit and the diagnosis set their windows
(:func:`oscillation_frequencies`)."""
from __future__ import annotations

from cubedimer.consistency import Y_MIN_CYCLES, oscillation_frequency
from cubedimer.dataset import Run

__all__ = ["oscillation_frequencies", "Y_MIN_CYCLES", "THETA_MIN_CYCLES"]

#: The fewest cycles per run of the hinge's oscillation (a hinge may swing at a tenth of f_y: 2 cycles of a 1.7-Hz
#: hinge fit in 1.2 s).
THETA_MIN_CYCLES = 2.0


def oscillation_frequencies(run: Run) -> tuple[float, float]:
    """The run's oscillation frequencies (f_y, f_theta) [Hz]: the one rule of the fit and the diagnosis.

    Each is the largest peak of the coordinate's Hann-windowed amplitude spectrum
    (:func:`cubedimer.spectra.dominant_frequency`, its mean removed there, refined by parabolic interpolation) at
    :data:`Y_MIN_CYCLES` (y) or :data:`THETA_MIN_CYCLES` (theta) or more cycles per run, unless nothing there reaches
    :data:`cubedimer.consistency.SLOW_PEAK_FRACTION` of a slower peak (then the slower one: a run that only drifts
    keeps its slow frequency).  Why this rule:

    * the frequencies set the smoothing window (0.75 of the y period) and the integral form's windows, so they must
      be those of the oscillation.  A drifting mean (the levitation height following a slowly drifting pressure)
      puts its power in the lowest bins, where the largest peak of the whole spectrum would take it for the
      oscillation; removing the mean does not help (a linear drift has no mean to remove), a lower bound of a
      few cycles per run does, and the fraction keeps a run whose only motion is slow from being read as noise;
    * it is the loader's and the consistency check's rule for f_y (:func:`cubedimer.consistency.run_features`), so
      a data set is judged and prepared at the same frequency;
    * both are read from the whole run (as recorded, raw): the longest record, the finest bins.
    """
    duration = max(run.duration, 1e-9)
    return tuple(oscillation_frequency(x, run.dt, duration, cycles)
                 for x, cycles in ((run.y, Y_MIN_CYCLES), (run.theta, THETA_MIN_CYCLES)))
