"""The pressure calibrated in time: a drift within runs is detected, measured and followed by the simulation;
none is reported on data at a constant pressure."""
import numpy as np
import pytest

from validation.diagnosis import EXPLAINED_GAP, DiagnoseConfig, DiagnosisProblem, PressureDrift, diagnose_dataset
from validation.diagnosis.calibrate.drift import DriftSettings, detect_pressure_drift, drift_basis
from validation.diagnosis.prepare.runs import prepare_diagnosis_runs

FAST = DiagnoseConfig(long_time=False)


def test_pressure_drift_factor_is_the_spline_through_the_nodes():
    # three nodes: their parabola (1 + 0.25 t - 0.15 t^2 through (0, 1), (1, 1.1), (2, 0.9)); constant beyond
    drift = PressureDrift({"a.csv": (np.array([0.0, 1.0, 2.0]), np.array([1.0, 1.1, 0.9]))})
    np.testing.assert_allclose(drift.factor("a.csv", [-1.0, 0.0, 0.5, 1.5, 2.0, 3.0]),
                               [1.0, 1.0, 1.0875, 1.0375, 0.9, 0.9], rtol=1e-14)
    assert drift.factor("other.csv", [0.0]) is None  # a run without nodes keeps the constant pressure


def test_drift_basis_reproduces_cubics_and_follows_a_sinusoid():
    nodes = np.linspace(0.0, 3.0, 11)  # a 3 s run at the default 0.3 s window: 11 nodes
    t = np.linspace(0.0, 3.0, 601)
    basis = drift_basis(t, nodes)
    np.testing.assert_allclose(basis.sum(axis=1), 1.0, atol=1e-13)  # a constant pressure stays constant
    cubic = lambda x: 1 + 0.1 * x - 0.03 * x**2 + 0.004 * x**3
    np.testing.assert_allclose(basis @ cubic(nodes), cubic(t), atol=1e-13)  # not-a-knot is exact on cubics
    # drifts of the blind study's periods (1.5-4 s), sampled at the nodes: the spline's rms error against that of
    # straight lines between the same nodes.  Measured over 12 phases: 0.016 (at most 0.023) against 0.098 of the
    # amplitude at T = 1.5 s (5 nodes per period), 0.0020 against 0.036 at 2.5 s, 3e-4 against 0.014 at 4 s
    # (errors ~h^4 against ~h^2); the bounds leave a factor 1.3-1.5 over the worst phase
    for period, spline_max, linear_min in [(1.5, 0.03, 0.07), (2.5, 0.004, 0.025), (4.0, 0.0006, 0.01)]:
        for phase in (0.3, 2.0, 4.4):
            drift = np.sin(2 * np.pi * t / period + phase)
            at_nodes = np.sin(2 * np.pi * nodes / period + phase)
            rms = lambda e: float(np.sqrt(np.mean(e**2)))
            assert rms(basis @ at_nodes - drift) < spline_max
            assert rms(np.interp(t, nodes, at_nodes) - drift) > linear_min


@pytest.mark.parametrize("kwargs", [{"window_s": 0.0}, {"alpha": 1.0}, {"min_relative_amplitude": -0.1}])
def test_drift_settings_validate(kwargs):
    with pytest.raises(ValueError):
        DriftSettings(**kwargs)


def _problem(data_dir):
    from cubedimer.dataset import load_dataset
    from cubedimer.meta import read_meta

    from validation.simulation import model_from_meta

    model = model_from_meta(read_meta(data_dir)).interpolated()
    return DiagnosisProblem.from_recorded(model, prepare_diagnosis_runs(load_dataset(data_dir)), 1500)


@pytest.mark.slow
def test_no_drift_at_constant_pressure(clean_dataset):
    """Measured (seed 1): F = 1.03 on (79, 41392) degrees of freedom, p = 0.40, pressure nodes within 0.03 %
    of each other: the integral-form residual is the white tracking noise the F-test assumes."""
    data, truth = clean_dataset
    test = detect_pressure_drift(_problem(data))
    assert test.tested and not test.detected
    assert test.p_value > 0.01  # far from the 1e-6 level: a constant pressure is not near the threshold
    assert test.relative_amplitude < 0.1 * DriftSettings().min_relative_amplitude
    p = np.concatenate([n[1] for n in test.nodes.values()])
    np.testing.assert_allclose(p, truth["pressure_amplitude_pa"], rtol=1e-3)  # each node within 0.1 %


@pytest.mark.slow
def test_drift_detected_then_effects_on_top(drift_dataset):
    """A 4 % drift (periods 1.5-4 s): before, the calibration came out several per cent off and no cause could be
    named (the vertical equation stayed unexplained).  Now: the drift is detected with its amplitude (measured 3.9 %
    against a true median half range of 4.0 %), the simulation follows it, and the data are explained within
    the noise with nothing named."""
    data, truth = drift_dataset
    diag = diagnose_dataset(data, FAST, progress=False)
    drift = diag.calibration["drift"]
    assert drift["detected"] and drift["p_value"] < 1e-6
    # the node pressures are each window's least-squares value; their half range within a run is the drift's
    # (noise per node ~0.2 Pa, 0.01 %); 15 %: the nodes sample a sinusoid 0.3 s apart and miss its peaks by a few %
    assert drift["relative_amplitude"] == pytest.approx(np.median(truth["relative_half_range"]), rel=0.15)
    assert 0.1 < drift["time_scale_s"] < 1.0  # T / 2 pi for periods of 1.5-4 s: 0.24-0.64 s
    assert len(drift["times_s"]) == len(drift["pressure_amplitude_pa"]) == len(drift["run"]) > 0
    assert diag.calibration["pressure_amplitude_pa"] == pytest.approx(truth["pressure_amplitude_pa"], rel=0.01)
    assert diag.identified == () and diag.remaining_gap["withheld"] == []
    assert diag.gap_after < EXPLAINED_GAP and diag.remaining_gap["explained_within_noise"]
    assert diag.remaining_gap["discovered_terms"] == {"yddot": [], "thetaddot": []}
    assert "drifts" in diag.remaining_gap["statement"]
    assert diag.skipped_files == ()


def test_a_run_too_long_for_its_windows_is_refused_before_any_fit():
    """The per-node fit has one dense column per node and run: a run needing more than ``max_nodes_per_run``
    nodes (a time in milliseconds makes a 3-s run 3000 "s" long: 9,999 windows of 0.3 s) is refused with a
    message before any fit, instead of building a design of that size.  Only the runs' names and integral-form
    times are looked at before the refusal, so a stand-in problem carries just those."""
    from types import SimpleNamespace

    times = np.arange(6000) / 2.0  # 3 s of 2,000 fps written in milliseconds
    run = SimpleNamespace(name="run01.csv", integral=SimpleNamespace(times=times, usable=True))
    problem = SimpleNamespace(runs=[run])
    with pytest.raises(ValueError, match="run01.csv: a time span of 3000 s needs 9999 pressure-drift windows .* "
                                         "is t in seconds"):
        detect_pressure_drift(problem)
    with pytest.raises(ValueError):
        DriftSettings(max_nodes_per_run=1)
