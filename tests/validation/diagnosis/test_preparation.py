"""The model's accelerations filtered as the data's (RunAccelerations.smooth)."""
import numpy as np
import pytest

from validation.diagnosis.prepare.runs import RunAccelerations


@pytest.mark.parametrize("step", [1, 2, 4])
def test_model_filter_matches_the_data_filter_on_thinned_frames(step):
    """RunAccelerations.smooth applied to the true accelerations reproduces the data's Savitzky-Golay second
    derivative, also on thinned frames (kernel sampled every step taps)."""
    from scipy.signal import savgol_filter

    dt, window = 1 / 2000, 71
    t = np.arange(6000) * dt
    w1, w2 = 2 * np.pi * 22.0, 2 * np.pi * 50.6
    x = np.sin(w1 * t) + 0.3 * np.cos(w2 * t)
    xdd = -w1**2 * np.sin(w1 * t) - 0.3 * w2**2 * np.cos(w2 * t)
    data = savgol_filter(x, window, 5, deriv=2, delta=dt)
    run = RunAccelerations("r", t, np.zeros((len(t), 4)), np.column_stack([data, data]), None, (window * dt, 5), dt)
    thin = run.subsample(step)
    inner = slice(100 // step, -100 // step)
    err = np.max(np.abs(thin.smooth(xdd[::step]) - data[::step])[inner]) / np.max(np.abs(data))
    assert err < 1e-3  # measured 2.6e-4 (step 1) to 3.8e-4 (step 4); a plain smoothing filter instead of the matched kernel: 19 %


def test_the_calibration_reads_the_one_preparation_with_y_flipped_from_it(small_oscillating_dataset, monkeypatch):
    """The diagnosis's first step (with the check of y's orientation, which compares the data with y -> -y) prepares
    no run again: the flipped runs are the prepared ones with their y columns' signs changed."""
    import fitting.derivatives.preparation as preparation
    from validation.diagnosis import DiagnoseConfig, load_for_diagnosis, start_diagnosis
    from validation.diagnosis.calibrate.calibration_step import calibration_step

    start = start_diagnosis(load_for_diagnosis(small_oscillating_dataset, progress=False))
    calls = []
    real = preparation.prepare_run
    monkeypatch.setattr(preparation, "prepare_run", lambda *a, **k: calls.append(a) or real(*a, **k))
    config = DiagnoseConfig(drift=None, check_orientation=True)
    cal = calibration_step(start.prepared, start.conditions, start.model, start.spec, config, lambda *a: None)
    assert calls == [] and not cal.data_warnings  # y points up in these data
    for run, p in zip(cal.problem.recorded_runs, start.prepared.runs):
        d = p.derivs
        np.testing.assert_array_equal(run.state, d.state[d.trim:len(d.t) - d.trim])
