"""Cross-run consistency (cubedimer.consistency): a file in the wrong units is named with its cause."""
import numpy as np
import pytest

from acousim.analytic import nominal_trap_frequency
from cubedimer.consistency import check_consistency, run_features

FPS, F_Y = 2000.0, 21.8


def _run(rng, name, amp=None, noise=1e-6, duration=3.0, f=F_Y):
    t = np.arange(int(duration * FPS)) / FPS
    amp = rng.uniform(5e-5, 3e-4) if amp is None else amp
    y = amp * np.exp(-0.2 * t) * np.cos(2 * np.pi * f * t + rng.uniform(0, 6)) + noise * rng.standard_normal(t.size)
    return name, t, y


def _features(runs):
    return [run_features(*r) for r in runs]


@pytest.mark.parametrize("n_runs", [4, 12])
@pytest.mark.parametrize("noise", [0.0, 1e-6, 2e-6])
def test_clean_sets_have_no_findings(n_runs, noise):
    rng = np.random.default_rng(n_runs)
    runs = [_run(rng, f"run{i:02d}.csv", noise=noise, duration=rng.uniform(2.5, 4.0)) for i in range(n_runs)]
    assert check_consistency(_features(runs), meta={}) == []


@pytest.mark.parametrize("n_runs", [4, 12])
@pytest.mark.parametrize("kind, cause", [
    ("micrometres", "y looks like micrometres"),
    ("milliseconds", "t looks like milliseconds"),
    ("noise", "looks like pure noise"),
    ("constant", "y is constant"),
    ("other_experiment", "another experiment"),
    ("bad_track", "tracking noise"),
])
def test_one_bad_file_is_named_with_its_cause(n_runs, kind, cause):
    rng = np.random.default_rng(5)
    runs = [_run(rng, f"run{i:02d}.csv") for i in range(n_runs)]
    name, t, y = runs[1]
    if kind == "micrometres":
        y = y * 1e6
    elif kind == "milliseconds":
        t = t * 1e3
    elif kind == "noise":
        y = 1e-6 * rng.standard_normal(t.size)
    elif kind == "constant":
        y = np.full_like(t, 1e-4)
    elif kind == "other_experiment":
        _, t, y = _run(rng, name, f=3.1 * F_Y)
    elif kind == "bad_track":
        _, t, y = _run(rng, name, amp=2e-4, noise=1.5e-5)  # 15 times the others' noise, still 10x below the signal
    runs[1] = (name, t, y)
    # without meta, so that the cross-run rules themselves are tested
    found = check_consistency(_features(runs))
    assert [x.file for x in found] == [name], found
    assert cause in found[0].reason, found[0].reason


def test_micrometre_message_gives_the_numbers():
    rng = np.random.default_rng(2)
    runs = [_run(rng, f"r{i}.csv", amp=2e-4) for i in range(5)]
    name, t, y = runs[0]
    runs[0] = (name, t, y * 1e6)
    (x,) = check_consistency(_features(runs))
    assert x.reason.startswith("y looks like micrometres: amplitude 1")
    assert "m in the other runs" in x.reason and str(x).startswith("r0.csv: ")


def test_meta_checks_work_for_a_single_run():
    rng = np.random.default_rng(4)
    name, t, y = _run(rng, "only.csv")
    assert check_consistency(_features([(name, t, y)]), meta={}) == []
    (x,) = check_consistency(_features([(name, t, y * 1e6)]), meta={})
    assert "quarter wavelength" in x.reason and "micrometres" in x.reason
    # the Gor'kov estimate is passed in by the caller that has the physics (the core carries none)
    (x,) = check_consistency(_features([(name, t, y)]), meta={"pressure_amplitude_pa": 12000.0},
                             trap_frequency=nominal_trap_frequency)
    assert "trap frequency" in x.reason
    assert check_consistency(_features([(name, t, y)]), meta={"pressure_amplitude_pa": 12000.0}) == []


def test_nominal_trap_frequency_against_the_mesh_model():
    # the small-particle estimate ignores the cube's finite size (ks ~ 0.42): within 5 % of the
    # Gor'kov mesh model's 21.83 Hz for the default 500 um dimer at 3 kPa
    from acousim import cached_surrogate

    f_y, _ = cached_surrogate().linear_frequencies()
    np.testing.assert_allclose(nominal_trap_frequency({}), f_y, rtol=0.05)
    assert np.isnan(nominal_trap_frequency({"pressure_amplitude_pa": 100.0}))  # cannot levitate


@pytest.mark.parametrize("n_runs", [4, 12])
def test_a_slowly_drifting_height_is_not_another_experiment(n_runs):
    """A pressure drifting within a run moves the levitation height slowly (periods of seconds, amplitude up to
    a few times the oscillation's): its f_y is still the trap's oscillation, and the run is not flagged."""
    rng = np.random.default_rng(n_runs)
    runs = [_run(rng, f"run{i:02d}.csv") for i in range(n_runs)]
    name, t, y = runs[1]
    amp = 0.5 * np.ptp(y)
    runs[1] = (name, t, y + 2.0 * amp * np.sin(2 * np.pi * t / 2.5))  # a drift larger than the oscillation
    features = _features(runs)
    np.testing.assert_allclose(features[1].f_y, F_Y, rtol=0.02)  # two bins of 0.33 Hz: the oscillation's peak
    assert check_consistency(features, meta={}) == []
