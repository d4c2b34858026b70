"""The tracking noise a run records: the white-noise estimate, or one that survives temporally correlated errors.

Every measured frame carries standard errors from its own image (:mod:`tracking.measure`): for y the image noise
of the border ring through the centre of mass, for theta the edge residuals through the face fits.  Their RMS is
right when the errors are white, as in an uncompressed recording.  A compressed video (H.264, with its
frame-to-frame prediction) or a rolling illumination gives errors that are correlated from frame to frame and
larger than the image's own noise suggests (its codec smooths the background on which the pixel noise is
measured).

The correlated estimate: the fourth differences of the series, ``d4 = x[i-2] - 4 x[i-1] + 6 x[i] - 4 x[i+1] +
x[i+2]``, have the variance ``sigma^2 (70 - 112 rho1 + 56 rho2 - 16 rho3 + 2 rho4)`` for errors of standard
deviation sigma and lag correlations ``rho_k`` (the motion adds ``(omega dt)^4`` of its amplitude: nothing at
camera rates).  The lag correlations of the errors are read from a cross-check that contains the errors and
not the motion: the difference between two measurements of the same quantity (y from the centre of mass and
from the fitted squares' centres; theta from all faces and from the faces at the hinge alone).  The fourth
differences enter by their RMS (:mod:`cubedimer.noise`'s robust scale would miss the heavy tails of compression
errors; a glitch is an unmeasured frame here).  When those
differences are correlated (``rho1 > 0.3``), the recorded noise is the larger of the white estimate and the
corrected fourth-difference one; otherwise the white estimate.
"""
from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

__all__ = ["noise_estimate", "lag_correlations", "CORRELATED_RHO1"]

_FOURTH_DIFFERENCE = np.array([1.0, -4.0, 6.0, -4.0, 1.0])

#: Lag-1 correlation of the cross-check beyond which the errors count as correlated.
CORRELATED_RHO1 = 0.3


def lag_correlations(x: NDArray, lags: int = 4) -> NDArray[np.float64]:
    """Correlations at lags 1..``lags`` of a series about its mean (NaN frames left out of each product)."""
    a = np.asarray(x, float)
    a = a - np.nanmean(a)
    var = np.nanmean(a * a)
    if not var > 0:
        return np.zeros(lags)
    return np.array([np.nanmean(a[:-k] * a[k:]) / var for k in range(1, lags + 1)])


def noise_estimate(series: NDArray, cross_check: NDArray, white: float) -> dict:
    """The noise of one tracked coordinate (module docstring).

    Parameters
    ----------
    series : ndarray (n,)
        The coordinate per frame (NaN where not measured).
    cross_check : ndarray (n,)
        The difference of two measurements of it per frame (NaN where unavailable).
    white : float
        The white-noise estimate (RMS of the per-frame standard errors).

    Returns
    -------
    dict
        ``value`` (the recorded noise), ``white``, ``correlated`` (the corrected fourth-difference estimate, or
        None), ``lag_correlations`` and ``estimator`` ("white" or "correlated").
    """
    ok = np.isfinite(cross_check)
    if ok.sum() < 50 or np.sum(np.isfinite(series)) < 50:
        return {"value": white, "white": white, "correlated": None, "lag_correlations": None, "estimator": "white"}
    rho = lag_correlations(cross_check)
    den = 70.0 - 112.0 * rho[0] + 56.0 * rho[1] - 16.0 * rho[2] + 2.0 * rho[3]
    d4 = np.convolve(np.asarray(series, float), _FOURTH_DIFFERENCE, mode="valid")
    d4 = d4[np.isfinite(d4)]
    # the RMS, not a robust scale: compression errors are heavy-tailed, and a glitch is an unmeasured frame here
    corr = float(np.sqrt(np.mean(d4 ** 2) / max(den, 2.0))) if d4.size >= 20 else None
    use = corr is not None and rho[0] > CORRELATED_RHO1 and corr > white
    return {"value": corr if use else white, "white": white, "correlated": corr,
            "lag_correlations": [round(float(r), 3) for r in rho], "estimator": "correlated" if use else "white"}
