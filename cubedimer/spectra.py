"""Spectra of y and theta, dominant frequencies and the y-theta phase difference.

Amplitude spectra use a Hann window (one-sided, amplitude-corrected, mean removed).  Dominant
frequencies are refined by parabolic interpolation of the log-magnitude around the highest
bin (accuracy ~1 % of a bin for a clean sinusoid, vs. half a bin without).
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from numpy.typing import NDArray

__all__ = ["amplitude_spectrum", "dominant_frequency", "peak_frequency", "phase_difference", "SpectralFeatures",
           "spectral_features", "line_amplitude"]


@lru_cache(maxsize=16)
def _hann(n: int) -> tuple[NDArray[np.float64], float]:
    """The Hann window of ``n`` samples (read-only; the long-time loss asks for the same few lengths) and its sum."""
    w = np.hanning(n)
    w.flags.writeable = False
    return w, float(w.sum())


def amplitude_spectrum(x: NDArray, dt: float) -> tuple[NDArray, NDArray]:
    """One-sided amplitude spectrum of ``x`` sampled every ``dt`` [s].

    Returns
    -------
    f : ndarray [Hz]
    amplitude : ndarray (units of x); a sinusoid of amplitude A gives a peak ~A.
    """
    x = np.asarray(x, float)
    x = x - x.mean()
    w, wsum = _hann(x.size)
    spec = np.fft.rfft(x * w)
    return np.fft.rfftfreq(x.size, dt), 2.0 * np.abs(spec) / wsum


def _peak(f: NDArray, a: NDArray, fmin: float, refine: bool = True) -> float:
    a = a.copy()
    a[f < fmin] = 0.0
    i = int(np.argmax(a))
    if a[i] <= 0.0:
        return 0.0
    if refine and 0 < i < a.size - 1 and a[i - 1] > 0 and a[i + 1] > 0:
        l0, l1, l2 = np.log(a[i - 1]), np.log(a[i]), np.log(a[i + 1])
        den = l0 - 2 * l1 + l2
        d = 0.5 * (l0 - l2) / den if den != 0 else 0.0
        return float(f[i] + np.clip(d, -0.5, 0.5) * (f[1] - f[0]))
    return float(f[i])


def dominant_frequency(x: NDArray, dt: float, fmin: float = 0.0, *, prefer_above: float | None = None,
                       refine: bool = True) -> float:
    """Frequency [Hz] of the largest spectral peak of ``x`` sampled every ``dt`` [s]; 0 for a constant signal.

    Parameters
    ----------
    x : ndarray
        Signal (any units; the mean is removed).
    dt : float
        Sampling interval [s].
    fmin : float
        Lower frequency bound [Hz].  By default a hard bound: peaks below ``max(fmin, 1.5 bins)`` are
        ignored.
    prefer_above : float, optional
        Drift-robust rule instead of the hard bound: the largest peak above the zero-frequency bin is
        taken, unless it lies below ``fmin`` (e.g. a slow drift of the levitation height) and the largest
        peak at or above ``fmin`` reaches ``prefer_above`` times its height, in which case that one is
        taken; so noise above ``fmin`` is never taken for the oscillation.  A fraction in (0, 1].
    refine : bool
        Parabolic interpolation of the log-magnitude around the peak bin (otherwise the bin frequency).
    """
    f, a = amplitude_spectrum(x, dt)
    if prefer_above is None:
        f0 = max(fmin, 1.5 * (f[1] - f[0]) if f.size > 1 else 0.0)
        return _peak(f, a, f0, refine)
    if not 0.0 < prefer_above <= 1.0:
        raise ValueError(f"prefer_above must lie in (0, 1], got {prefer_above!r}")
    a = a.copy()
    a[0] = 0.0
    j = int(np.argmax(a))
    if fmin > 0 and f[j] < fmin:
        above = f >= fmin
        if above.any():
            k = int(np.argmax(np.where(above, a, 0.0)))
            if a[k] >= prefer_above * a[j]:
                return _peak(f, np.where(above, a, 0.0), fmin, refine)
    return _peak(f, a, 0.0, refine)


def peak_frequency(x: NDArray, dt: float, fmin: float = 0.0, pad: int = 16) -> tuple[float, float]:
    """The frequency [Hz] of the largest spectral peak of ``x`` (sampled every ``dt`` [s]) at or above ``fmin``,
    read from the Hann-windowed spectrum zero-padded to ``pad`` times the length (bins of 1/(pad T)) and
    refined by parabolic interpolation, with the record's resolution 1/T [Hz].

    Zero-padding interpolates the spectrum between the record's own bins, so the peak is not pinned to a bin
    centre (a 1.5 s record has bins 0.67 Hz apart); it does not make two peaks closer than about 2/T (the
    Hann main lobe) separable, which is why the resolution is returned beside it.  (0, resolution) for a
    constant signal.
    """
    x = np.asarray(x, float)
    x = x - x.mean()
    n = x.size
    duration = n * dt
    w, wsum = _hann(n)
    m = int(pad) * n
    a = 2.0 * np.abs(np.fft.rfft(x * w, m)) / wsum
    f = np.fft.rfftfreq(m, dt)
    # above the main lobe of the zero-frequency (mean-removed) leakage: 1/T
    return _peak(f, a, max(fmin, 1.0 / duration)), 1.0 / duration


def phase_difference(y: NDArray, theta: NDArray, dt: float, f: float | None = None) -> float:
    """Phase of theta relative to y [rad, in (-pi, pi]] at frequency ``f`` (default: y's dominant).

    Computed from the cross spectrum at the bin nearest ``f``; 0 means in phase, +-pi anti-phase.
    """
    y = np.asarray(y, float) - np.mean(y)
    th = np.asarray(theta, float) - np.mean(theta)
    w = np.hanning(y.size)
    Y, T = np.fft.rfft(y * w), np.fft.rfft(th * w)
    freqs = np.fft.rfftfreq(y.size, dt)
    if f is None:
        f = dominant_frequency(y, dt)
    i = int(np.argmin(np.abs(freqs - f)))
    return float(np.angle(T[i] * np.conj(Y[i])))


@dataclass(frozen=True)
class SpectralFeatures:
    """Dominant frequencies [Hz], amplitudes (half peak-to-peak of the 1-99 % quantiles) and phase."""

    f_y: float
    f_theta: float
    amp_y: float
    amp_theta: float
    phase: float
    theta_at_fy: float


def spectral_features(y: NDArray, theta: NDArray, dt: float) -> SpectralFeatures:
    """Features of one run: dominant y and theta frequencies, robust amplitudes, y-theta phase,
    and theta's spectral amplitude at the y frequency."""
    fy = dominant_frequency(y, dt)
    ft = dominant_frequency(theta, dt)
    f, a = amplitude_spectrum(theta, dt)
    q = lambda x: 0.5 * float(np.subtract(*np.quantile(x, [0.99, 0.01])))
    return SpectralFeatures(f_y=fy, f_theta=ft, amp_y=q(y), amp_theta=q(theta),
                            phase=phase_difference(y, theta, dt, fy),
                            theta_at_fy=float(np.interp(fy, f, a)))


def line_amplitude(x: NDArray, dt: float, f: float, half_width_bins: int = 2) -> float:
    """Amplitude of the spectral line of ``x`` (sampled every ``dt`` [s]) nearest ``f`` [Hz]: the largest
    Hann-window amplitude (:func:`amplitude_spectrum`) within ``half_width_bins`` bins of ``f`` (units of x;
    0 if ``f`` lies beyond the Nyquist frequency)."""
    freqs, a = amplitude_spectrum(x, dt)
    if not 0 <= f <= freqs[-1]:
        return 0.0
    df = freqs[1] - freqs[0]
    near = np.abs(freqs - f) <= half_width_bins * df
    return float(a[near].max()) if near.any() else 0.0
