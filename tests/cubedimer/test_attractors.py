"""The one attractor classifier on synthetic locked, drifting and resting signals."""
import numpy as np
import pytest

from cubedimer.attractors import (ATTRACTOR_CLASSES, CLASS_COLORS, ClassifyConfig, classify_signal,
                                  classify_trajectory, lock_coherence, lock_ratios, section_phase)


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


def _ratio_signals(ratio, amp=0.4, harmonic=0.0, f_y=52.0, phase=0.3, seconds=4.0, fs=2000.0):
    """y = 100 um cos(w t); theta = amp cos(ratio w t + phase) + harmonic cos(3 ratio w t): a hinge at ratio f_y
    with its third harmonic (an anharmonic hinge), exact velocities."""
    t = np.arange(0, seconds, 1 / fs)
    w, wt = 2 * np.pi * f_y, 2 * np.pi * f_y * ratio
    th = amp * np.cos(wt * t + phase) + harmonic * np.cos(3 * wt * t + 3 * phase)
    thd = -amp * wt * np.sin(wt * t + phase) - 3 * harmonic * wt * np.sin(3 * wt * t + 3 * phase)
    return t, np.column_stack([1e-4 * np.cos(w * t), -1e-4 * w * np.sin(w * t), th, thd])


@pytest.mark.parametrize("p, q", [(3, 2), (2, 1), (1, 2), (2, 3), (3, 1)])
def test_a_p_q_lock_is_its_own_class(p, q):
    """A hinge at exactly q/p f_y (with a third harmonic: 2 f_y for the 3:2 lock) repeats every p periods of y."""
    att = classify_trajectory(*_ratio_signals(q / p, harmonic=0.05))
    assert att.label == "locked-p:q" and att.lock_ratio == f"{p}:{q}"
    # the states at crossings k and k + p coincide up to the section's linear interpolation between frames
    assert att.lock_coherence > 0.999


def test_a_drift_near_a_ratio_is_not_a_lock():
    """0.69 f_y is within 5 % of 2/3 f_y, but the hinge's phase slips by (0.69 - 2/3) x 52 Hz x 2 s ~ 2.4 turns over
    the 2 s analysed: the residues' phases spread and the coherence is small."""
    att = classify_trajectory(*_ratio_signals(0.69))
    assert att.lock_coherence < 0.5 and att.label == "independent" and att.lock_ratio == ""


def test_max_lock_order_one_reads_only_f_y_locks():
    att = classify_trajectory(*_ratio_signals(2 / 3), ClassifyConfig(max_lock_order=1))
    assert att.label == "independent"
    # a 1:1 lock keeps its phase class and reports its ratio
    att = classify_trajectory(*_signals(180.0))
    assert att.label == "locked-anti-phase" and att.lock_ratio == "1:1"
    assert att.lock_coherence == pytest.approx(att.coherence)


def test_lock_coherence_of_one_period_is_the_section_coherence():
    t, state = _signals(150.0)
    _, coh = section_phase(t, state)
    assert lock_coherence(t, state, 1, 21.5) == pytest.approx(coh, abs=1e-12)
    assert lock_ratios(3) == [(1, 2), (1, 3), (2, 1), (2, 3), (3, 1), (3, 2)]
