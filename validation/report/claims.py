"""The report's claims that depend on a threshold, each stated with it, so that a sentence says only what its number
supports.

* :func:`long_time_reading`: "reproduces the long-time behaviour" only when every long-time error lies below
  :data:`REPRODUCES_BELOW`; otherwise the errors with what they mean.
* :func:`run_phase`: the phase of theta relative to y at f_y only where theta has a line at f_y of at least
  :data:`PHASE_LINE_FRACTION` of its largest line (else there is no phase to give).
* :func:`anti_damping_text` (from :mod:`fitting.description`, where the fitting methods' descriptions use it too): a
  fitted velocity coefficient that feeds energy in (anti-damping) is flagged, with what may cause it.
* :func:`not_significant_text`: beside a test that is not significant, the smallest p its number of runs allows.
* :func:`gap_value`: a gap (an unexplained fraction with the noise floor subtracted) below zero is "below the noise
  floor (< floor)", never a negative number.
* :func:`ratio_value`: a ratio whose denominator is within its stated number of standard errors of zero is "not
  determined (denominator at noise level)", never a number.
"""
from __future__ import annotations

from typing import Mapping

import numpy as np
from numpy.typing import NDArray

from fitting.description import anti_damping_text

from ..diagnosis.identify.statistics import format_p

__all__ = ["REPRODUCES_BELOW", "PHASE_LINE_FRACTION", "long_time_reading", "run_phase", "anti_damping_text",
           "smallest_wilcoxon_p", "not_significant_text", "gap_value",
           "RATIO_NOT_DETERMINED", "ratio_value"]

#: what the report says in place of a ratio whose denominator is not significantly different from zero
RATIO_NOT_DETERMINED = "not determined (denominator at noise level)"

#: A long-time error (attractor shape, Poincare map, frequency: 0 for a perfect model, about 1 for one that predicts no
#: motion) below this is called reproduced: a tenth of the error of predicting no motion.
REPRODUCES_BELOW = 0.1

#: theta's line at f_y must reach this fraction of theta's largest spectral line for a phase at f_y to be given
#: (below it the cross spectrum's phase is that of leakage and noise).
PHASE_LINE_FRACTION = 0.1

_LONG_TIME_NAMES = {"shape": "attractor-shape", "poincare": "Poincare", "frequency": "frequency"}


def long_time_reading(loss: Mapping[str, float], subject: str = "The minimal model") -> str:
    """The sentence on a model's long-time errors: "reproduces" only when all three lie below
    :data:`REPRODUCES_BELOW`, otherwise the errors and which of them exceed it.

    Parameters
    ----------
    loss : mapping with ``shape``, ``poincare`` and ``frequency`` (0 perfect, about 1 for a model predicting no motion)
    subject : the sentence's subject
    """
    errors = ", ".join(f"{_LONG_TIME_NAMES[k]} error {float(loss[k]):.3g}" for k in _LONG_TIME_NAMES)
    meaning = "each 0 for a perfect model and about 1 for one that predicts no motion"
    above = [_LONG_TIME_NAMES[k] for k in _LONG_TIME_NAMES if not float(loss[k]) < REPRODUCES_BELOW]
    if not above:
        return (f"{subject}, integrated from each run's first measured state, reproduces the long-time behaviour: mean "
                f"{errors} ({meaning}; all below the {REPRODUCES_BELOW:g} counted as reproducing).")
    return (f"{subject}, integrated from each run's first measured state, has a mean {errors} ({meaning}); the "
            f"{' and '.join(above)} error{'s' if len(above) > 1 else ''} exceed{'' if len(above) > 1 else 's'} the "
            f"{REPRODUCES_BELOW:g} counted as reproducing the long-time behaviour, so it does not reproduce it there.")


def run_phase(theta: NDArray, dt: float, f_y: float, phase: float) -> float | None:
    """The phase [deg] of theta relative to y at f_y, or None where theta has no line at f_y: its line amplitude there
    (:func:`cubedimer.spectra.line_amplitude`) below :data:`PHASE_LINE_FRACTION` of its largest line.

    Parameters
    ----------
    theta : the hinge angle over the stretch the phase was measured on [-]
    dt : sample interval [s]
    f_y : the vertical frequency [Hz]
    phase : the measured phase [rad]
    """
    from cubedimer.spectra import amplitude_spectrum, line_amplitude

    theta = np.asarray(theta, float)
    theta = theta[np.isfinite(theta)]
    if theta.size < 8 or not np.isfinite(phase) or not f_y > 0:
        return None
    _, amp = amplitude_spectrum(theta - theta.mean(), dt)
    largest = float(amp[1:].max()) if amp.size > 1 else 0.0
    if not largest > 0 or line_amplitude(theta - theta.mean(), dt, f_y) < PHASE_LINE_FRACTION * largest:
        return None
    return float(np.degrees(phase))


def smallest_wilcoxon_p(n: int) -> float:
    """The smallest one-sided p-value the exact Wilcoxon signed-rank test reaches with ``n`` non-zero differences:
    2^-n (every difference of one sign). 1 for none."""
    return 0.5 ** int(n) if n > 0 else 1.0


def not_significant_text(p: float, n: int, alpha: float, test: str = "one-sided Wilcoxon",
                         smallest: float | None = None) -> str:
    """``"(test p = ...)"`` for a significant result; beside a non-significant one also the smallest p that ``n``
    runs allow (2^-n unless ``smallest`` is given), and, when that is not below ``alpha``, that no number of
    differences this size could have been significant."""
    floor = smallest_wilcoxon_p(n) if smallest is None else smallest
    if p < alpha:
        return f"({test} {format_p(p, 3)})"
    text = f"({test} {format_p(p, 3)}; with {n} runs the smallest attainable p is {floor:.3g}"
    if not floor < alpha:
        text += f", not below {alpha:g}: {n} runs cannot show a significant difference"
    return text + ")"


def gap_value(gap: float, noise_floor: float | None, percent: bool = False) -> float | str:
    """A gap as the report shows it: the number where it is not negative, else ``"below the noise floor (< X)"``
    with X the noise floor that was subtracted from it (a negative gap is an unexplained fraction below the floor).

    Parameters
    ----------
    gap : the unexplained fraction beyond the noise floor [-]
    noise_floor : the floor subtracted from it [-] (None: not stated)
    percent : return the gap in per cent, rounded to 0.1 %, and state the floor in per cent
    """
    if not gap < 0:
        return round(100 * gap, 1) + 0.0 if percent else gap  # + 0.0: never a signed zero
    if noise_floor is None or not np.isfinite(noise_floor):
        return "below the noise floor"
    return f"below the noise floor (< {100 * noise_floor:.2g} %)" if percent else \
        f"below the noise floor (< {noise_floor:.3g})"


def ratio_value(ratio: float, denominator: float, denominator_std: float, n_sigma: float) -> float | str:
    """A ratio as the report shows it: :data:`RATIO_NOT_DETERMINED` where its denominator is zero or within
    ``n_sigma`` of its standard error of zero (the ratio of a number to noise is no result), else the ratio (a signed
    zero made 0).

    Parameters
    ----------
    ratio : numerator / denominator
    denominator, denominator_std : the denominator and its standard error (same units)
    n_sigma : how many standard errors from zero make the denominator significant (the report's verdict threshold)
    """
    if denominator == 0 or not np.isfinite(ratio) or (
            np.isfinite(denominator_std) and abs(denominator) <= n_sigma * denominator_std):
        return RATIO_NOT_DETERMINED
    return float(ratio) + 0.0


#: The shrink column's entry for a gap taken below the noise floor (where 1 - after/before exceeds 1).
SHRINK_TO_FLOOR = "all of it (to below the noise floor)"


def shrink_value(shrink: float, gap_after: float) -> float | str:
    """A shrink ``1 - gap_after / gap_before`` as the report shows it: the number, or :data:`SHRINK_TO_FLOOR` where the
    gap after lies below the noise floor (a negative gap, so a shrink above 1, which no fraction of a gap can be)."""
    if gap_after < 0 or shrink > 1:
        return SHRINK_TO_FLOOR
    return float(shrink) + 0.0
