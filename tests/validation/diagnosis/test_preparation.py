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


def test_every_entry_point_leaves_the_cavity_ring_up_out_where_the_start_is_made(small_oscillating_dataset):
    """With the cavity among the candidates the first RING_UP_S of every run are left out by start_diagnosis itself,
    from a data set and from a preparation alike (prepared again with its own smoothing), so that the report's start
    and diagnose() read the same runs; a start made without it is refused for such a diagnosis."""
    from validation.diagnosis import DiagnoseConfig, diagnose, load_for_diagnosis, start_diagnosis
    from validation.diagnosis.prepare.cavity_lag import RING_UP_S
    from fitting.derivatives.preparation import prepare_dataset

    dataset = load_for_diagnosis(small_oscillating_dataset, progress=False)
    cavity = ("linear_damping", "cavity_lag")
    plain = start_diagnosis(dataset)
    from_data = start_diagnosis(dataset, candidates=cavity)
    from_prepared = start_diagnosis(prepare_dataset(dataset), candidates=cavity)
    assert plain.ring_up_left_out == 0.0 and from_data.ring_up_left_out == RING_UP_S
    for run, a, b in zip(dataset.runs, from_data.prepared.dataset.runs, from_prepared.prepared.dataset.runs):
        dt = float(np.median(np.diff(run.t)))
        # the first frame at or after RING_UP_S (one frame's tolerance: the cut is on the frame grid)
        assert RING_UP_S <= a.t[0] - run.t[0] < RING_UP_S + dt
        np.testing.assert_array_equal(a.t, b.t)
        np.testing.assert_array_equal(a.y, run.y[run.t.size - a.t.size:])
    assert [r.t.size for r in plain.prepared.dataset.runs] == [r.t.size for r in dataset.runs]
    with pytest.raises(ValueError, match="ring-up"):
        diagnose(plain, DiagnoseConfig(candidates=cavity), progress=False)
