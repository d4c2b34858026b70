"""The one preparation of a data set (fitting.derivatives.preparation): the frequency rule on analytic signals, the
fit's view of it, and the exact y -> -y preparation."""
import numpy as np
import pytest

from cubedimer.dataset import Dataset, Run
from cubedimer.spectra import dominant_frequency
from fitting.config import FitConfig
from fitting.derivatives.preparation import (PreparedDataset, flipped_y, integral_form_states, oscillation_frequencies,
                                             prepare_dataset)
from fitting.derivatives.savitzky_golay import SmoothingConfig
from fitting.fit import prepare_runs

DT = 1 / 2000
T = np.arange(6000) * DT  # 3 s: bins of 1/3 Hz
BIN = 1 / (T[-1] + DT)
# the refined peak of a clean sinusoid is within ~1 % of a bin (cubedimer.spectra); a second line's Hann leakage
# moves it a little more: 2 % of a bin (measured 0.8 % for y and 1.2 % for theta below)
TOLERANCE = 0.02 * BIN


def _run(y, theta, name="r.csv"):
    return Run(name=name, t=T.copy(), y=np.asarray(y, float), theta=np.asarray(theta, float))


def _oscillating(k: int, rng) -> Run:
    """A run with a 21.7-Hz y oscillation and a 9.2-Hz hinge (both with a second line), white tracking noise."""
    phase = rng.uniform(0, 2 * np.pi, 2)
    y = 1e-4 * np.sin(2 * np.pi * 21.7 * T + phase[0]) + 3e-5 * np.sin(2 * np.pi * 43.4 * T) + rng.normal(0, 1e-6, T.size)
    theta = (0.2 * np.sin(2 * np.pi * 9.2 * T + phase[1]) + 0.05 * np.sin(2 * np.pi * 21.7 * T)
             + rng.normal(0, 1e-3, T.size))
    return _run(y, theta, f"run{k}.csv")


@pytest.fixture(scope="module")
def dataset():
    rng = np.random.default_rng(11)
    return Dataset(path="synthetic", runs=tuple(_oscillating(k, rng) for k in range(3)))


@pytest.mark.parametrize("second, f_y", [(0.5, 21.7), (2.0, 51.3)])
def test_the_frequency_of_a_sum_of_two_sinusoids_is_the_larger_line(second, f_y):
    y = 1e-4 * np.sin(2 * np.pi * 21.7 * T) + second * 1e-4 * np.sin(2 * np.pi * 51.3 * T + 0.4)
    theta = 0.2 * np.sin(2 * np.pi * 9.2 * T) + 0.1 * np.sin(2 * np.pi * 21.7 * T)
    fy, ft = oscillation_frequencies(_run(y, theta))
    assert abs(fy - f_y) < TOLERANCE and abs(ft - 9.2) < TOLERANCE


def test_a_drifting_mean_is_not_taken_for_the_oscillation():
    """A levitation height drifting by 3 times the oscillation's amplitude over the run (a ramp and a 0.4-Hz swing):
    the largest peak of the whole spectrum is the drift (the fit's former rule read 0.67 Hz, and removing the mean
    changes nothing); the rule reads the 21.7-Hz oscillation, and a 1.7-Hz hinge (5 cycles) under a drift of theta."""
    y = 1e-4 * np.sin(2 * np.pi * 21.7 * T) + 3e-4 * T / T[-1] + 2e-4 * np.sin(2 * np.pi * 0.4 * T)
    theta = 0.2 * np.sin(2 * np.pi * 1.7 * T) + 0.3 * T / T[-1]
    assert dominant_frequency(y, DT) < 1.0 and dominant_frequency(y - y.mean(), DT) < 1.0  # the drift's peak
    fy, ft = oscillation_frequencies(_run(y, theta))
    assert abs(fy - 21.7) < TOLERANCE and abs(ft - 1.7) < TOLERANCE


def test_a_run_that_only_drifts_keeps_its_slow_frequency():
    """Nothing at five or more cycles per run reaches a tenth of the drift's peak: the slow peak is kept (the noise
    above it is never read as the oscillation)."""
    rng = np.random.default_rng(3)
    y = 3e-4 * T / T[-1] + 2e-4 * np.sin(2 * np.pi * 0.4 * T) + rng.normal(0, 1e-6, T.size)
    fy, _ = oscillation_frequencies(_run(y, 0.2 * np.sin(2 * np.pi * 9.2 * T)))
    assert fy < 5 * BIN


def test_the_fit_reads_the_one_preparation(dataset):
    """prepare_runs of a PreparedDataset is a view: the very arrays, no second smoothing; of the runs themselves it
    prepares them by the same rules, to the same numbers."""
    prepared = prepare_dataset(dataset)
    view, scales = prepare_runs(prepared)
    again, scales_again = prepare_runs(dataset.runs)
    for v, p, a in zip(view, prepared.runs, again):
        assert v.derivs is p.derivs and v.preparation is p and v.f_y == p.f_y
        np.testing.assert_array_equal(a.derivs.state, p.derivs.state)
        np.testing.assert_array_equal(a.preparation.columns, p.columns)
    assert scales == scales_again
    with pytest.raises(ValueError, match="prepared with"):
        prepare_runs(prepared, FitConfig(smoothing=SmoothingConfig(window_periods=0.5)))


def test_integral_form_states_are_the_prepared_ones(dataset):
    """The discovery's frequencies and column states: read from the preparation, or made by the same rules."""
    prepared = prepare_dataset(dataset)
    runs, derivs = [p.run for p in prepared.runs], [p.derivs for p in prepared.runs]
    read = integral_form_states(runs, derivs, prepared.runs)
    made = integral_form_states(runs, derivs)
    assert read[0] == made[0] == [(p.f_y, p.f_theta) for p in prepared.runs] and read[2] == made[2]
    for a, b in zip(read[1], made[1]):
        np.testing.assert_array_equal(a, b)
    for f_y, f_theta in read[0]:
        assert abs(f_y - 21.7) < TOLERANCE and abs(f_theta - 9.2) < TOLERANCE


def test_the_flipped_preparation_is_the_preparation_of_the_flipped_data(dataset):
    """Every step is linear in y and blind to its sign: PreparedDataset.flipped_y (sign changes only) equals preparing
    the data set with y -> -y, bit for bit."""
    prepared = prepare_dataset(dataset)
    flipped = prepared.flipped_y()
    direct = prepare_dataset(Dataset(path="synthetic", runs=tuple(flipped_y(r) for r in dataset.runs)))
    assert isinstance(flipped, PreparedDataset)
    for a, b in zip(flipped.runs, direct.runs):
        assert (a.f_y, a.f_theta, a.windows, a.noise_var, a.column_edge) == (b.f_y, b.f_theta, b.windows, b.noise_var,
                                                                            b.column_edge)
        for x, z in ((a.derivs.state, b.derivs.state), (a.derivs.accel, b.derivs.accel), (a.columns, b.columns),
                     (a.run.y, b.run.y)):
            np.testing.assert_array_equal(x, z)
    np.testing.assert_array_equal(flipped.dataset.runs[0].y, -dataset.runs[0].y)
