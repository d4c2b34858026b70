"""Dominant frequency: the hard lower bound and the drift-robust rule the loader uses."""
import numpy as np
import pytest

from cubedimer.spectra import dominant_frequency

DT = 1e-3
T = np.arange(2000) * DT  # 2 s, bins of 0.5 Hz


def test_hard_bound_ignores_peaks_below_fmin():
    x = np.cos(2 * np.pi * 1.0 * T) + 0.01 * np.cos(2 * np.pi * 22 * T)
    assert dominant_frequency(x, DT) == pytest.approx(1.0, abs=0.1)
    assert dominant_frequency(x, DT, fmin=5.0) == pytest.approx(22.0, abs=0.05)


def test_drift_robust_rule_takes_a_prominent_peak_above_fmin_only():
    drift = 3.0 * T / T[-1]
    strong = drift + 0.5 * np.cos(2 * np.pi * 22 * T)
    weak = drift + 0.01 * np.cos(2 * np.pi * 22 * T)
    # the 22-Hz line is prominent next to the drift's spectrum: taken (bin frequency, no refinement)
    assert dominant_frequency(strong, DT, fmin=2.5, prefer_above=0.3, refine=False) == 22.0
    # too weak to be told from leakage: the drift's (low) frequency is returned, so a caller sees < fmin
    assert dominant_frequency(weak, DT, fmin=2.5, prefer_above=0.3, refine=False) < 2.5
    assert dominant_frequency(np.zeros(100), DT, fmin=2.5, prefer_above=0.3) == 0.0
    with pytest.raises(ValueError):
        dominant_frequency(strong, DT, fmin=2.5, prefer_above=1.5)
