"""The one attractor classifier on synthetic locked, drifting and resting signals."""
import numpy as np
import pytest

from cubedimer.attractors import (ATTRACTOR_CLASSES, CLASS_COLORS, ClassifyConfig, classify_signal,
                                  classify_trajectory, section_phase)


def _signals(phase_deg, f_theta=21.5, amp=0.2, offset=0.0):
    """Exact states: y = 100 um cos(w t), theta = offset + amp cos(w_theta t + phase), 4 s at 1 kHz."""
    t = np.arange(0, 4, 1e-3)
    w, wt = 2 * np.pi * 21.5, 2 * np.pi * f_theta
    p = np.radians(phase_deg)
    state = np.column_stack([1e-4 * np.cos(w * t), -1e-4 * w * np.sin(w * t),
                             offset + amp * np.cos(wt * t + p), -amp * wt * np.sin(wt * t + p)])
    return t, state


@pytest.mark.parametrize("phase, label", [(0.0, "locked-in-phase"), (-20.0, "locked-in-phase"),
                                          (180.0, "locked-anti-phase"), (150.0, "locked-anti-phase"),
                                          (90.0, "locked-quadrature")])
def test_locked_signals_get_their_phase_class(phase, label):
    att = classify_trajectory(*_signals(phase))
    assert att.label == label and att.coherence > 0.999
    # the section phase is exact up to the linear interpolation between frames (~0.1 deg at 1 kHz)
    assert np.cos(att.section_phase - np.radians(phase)) > np.cos(np.radians(1.0))
    # and the spectral phase agrees to within the Hann window's bin leakage
    assert np.cos(att.phase - np.radians(phase)) > np.cos(np.radians(5.0))
    assert att.f_theta == pytest.approx(21.5, rel=1e-3) and att.amp_theta == pytest.approx(0.2, rel=0.01)


def test_a_mean_bend_does_not_bias_the_phase():
    """mirror asymmetry moves theta's mean; the phase is that of the oscillation about it."""
    att = classify_trajectory(*_signals(180.0, offset=0.3))
    assert att.label == "locked-anti-phase"
    assert np.cos(att.section_phase - np.pi) > np.cos(np.radians(1.0))


def test_other_frequency_and_rest():
    assert classify_trajectory(*_signals(0.0, f_theta=23.0)).label == "independent"
    assert classify_trajectory(*_signals(0.0, amp=0.005)).label == "theta-at-rest"


def test_slow_drift_within_the_frequency_tolerance_is_not_a_lock():
    """22.3 vs 21.5 Hz is within the 5 % frequency tolerance, but the phase drifts by ~1.6 turns over
    the 2 s analysed: the section coherence tells it from a lock, a frequency comparison cannot."""
    t, state = _signals(0.0, f_theta=22.3)
    att = classify_trajectory(t, state)
    assert abs(att.f_theta / att.f_y - 1) < ClassifyConfig().lock_tol
    assert att.coherence < 0.5 and att.label == "independent"


def test_positions_only_use_the_same_classifier():
    t, state = _signals(180.0)
    a = classify_signal(state[:, 0], state[:, 2], 1e-3)
    b = classify_trajectory(t, state)
    assert a.label == b.label == "locked-anti-phase"
    # central differences at 1 kHz change the velocities by ~(w dt)^2 / 6 = 0.3 %: the phase by far less than 1 deg
    assert np.cos(a.section_phase - b.section_phase) > np.cos(np.radians(1.0))


def test_section_phase_needs_crossings():
    t = np.arange(100) * 1e-3
    state = np.column_stack([np.full(100, 1e-4), np.zeros(100), 0.1 * np.ones(100), np.zeros(100)])
    assert all(np.isnan(v) for v in section_phase(t, state))


def test_every_class_has_a_colour():
    assert set(CLASS_COLORS) == set(ATTRACTOR_CLASSES)


def test_bad_thresholds():
    with pytest.raises(ValueError):
        ClassifyConfig(coherence_min=1.5)
