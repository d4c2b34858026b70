"""The candidates' run planner (validation.planner): its oracle standard errors against a Monte-Carlo of the estimator,
the 1/sqrt(n) law, the alias z of a candidate with itself, the drop amplitudes, truth.json and the command's errors."""
from dataclasses import replace

import numpy as np
import pytest

from acousim.dynamics.effects import EffectSet
from acousim.twin import TwinConfig, simulate_field_drop_runs
from cubedimer.executor import ExecutorConfig
from fitting.derivatives.integral_form import detrend_windows, window_starts
from fitting.uncertainty.oracle import NoiseLevels, covariance_diagonal, integral_design
from validation.cli import main
from validation.planner import CandidatePlanConfig, RunDesign, pair_alias_z, plan_candidates, reference_runs
from validation.planner.candidate_plan import joint_information, target_z
from validation.planner.reference_runs import EQUATIONS, _columns, drop_time, twin_from_truth

NOISE = NoiseLevels(1e-6, 0.005)
FITTED = ("velocity_coupling", "linear_damping")
#: a strong coupling (the blind strengths' upper third) beside the air's damping
TWIN = TwinConfig(effects=EffectSet.from_dict({"velocity_coupling": {"c5": 3000.0, "c6": 1.0e6}}))
DESIGN = RunDesign(duration=1.0, fps=1000.0, n_reference=4, seed=3)


@pytest.fixture(scope="module")
def ref():
    return reference_runs(TWIN, DESIGN, FITTED)


def test_oracle_standard_errors_match_a_monte_carlo_of_the_estimator():
    """400 draws of white position noise on the twin's exact runs, each fitted by least squares of the detrended
    windows (the integral form) on the pressure scale, the origin, the coupling and linear damping: the spread of the
    estimates is the planner's standard error.  The sample standard deviation of 400 draws has a relative standard
    error of 1/sqrt(2 * 399) = 3.5 %, so 12 % is 3.4 of them."""
    from acousim.twin import twin_dynamics

    runs, _, _ = simulate_field_drop_runs(replace(TWIN, runs=3, duration=1.0, seed=3,
                                                  camera=replace(TWIN.camera, fps=1000.0, missing_frames=0)),
                                          ExecutorConfig(workers=1), progress=False)
    ref = reference_runs(TWIN, replace(DESIGN, n_reference=3), FITTED)
    fm = twin_dynamics(TWIN)[0].force_model
    rng = np.random.default_rng(11)
    for q, eq in enumerate(EQUATIONS):
        designs, noise = [], []
        for r in runs:
            X, w = integral_design(_columns(r.state, fm, None, None, FITTED)[q], r.state[:, 2 * q], 1e-3)
            e = NOISE.of(eq) * rng.standard_normal((r.state.shape[0], 400))
            designs.append(X)
            noise.append(detrend_windows(e, window_starts(r.state.shape[0], w), w))
        X, b = np.concatenate(designs), np.concatenate(noise)
        scale = np.linalg.norm(X, axis=0)
        estimates = np.linalg.lstsq(X / scale, b, rcond=None)[0] / scale[:, None]
        planned = NOISE.of(eq) * np.sqrt(covariance_diagonal(ref.information[q].sum(axis=0)))
        np.testing.assert_allclose(estimates.std(axis=1, ddof=1), planned, rtol=0.12)


def test_standard_errors_fall_as_one_over_sqrt_runs(ref):
    """Runs add information: the same runs twice halve the variance exactly, and the runs needed for a target
    follow 1/sqrt(n) from the table's largest row."""
    cfg = CandidatePlanConfig(FITTED, run_counts=(4, 8), n_draws=1)
    once = {p.label: p for p in plan_candidates(ref, NOISE, cfg).parameters}
    doubled = replace(ref, information=tuple(np.concatenate([m, m]) for m in ref.information),
                      heights=np.concatenate([ref.heights, ref.heights]),
                      amplitudes=np.concatenate([ref.amplitudes, ref.amplitudes]))
    twice = {p.label: p for p in plan_candidates(doubled, NOISE, cfg).parameters}
    c6 = "velocity_coupling.c6"
    assert twice[c6].std_error_reference == pytest.approx(once[c6].std_error_reference / np.sqrt(2), rel=1e-9)
    # the doubled pool's row of 8 runs draws every run: its SE is the pooled one, and the runs needed extrapolate it
    assert twice[c6].table[1][1] == pytest.approx(twice[c6].std_error_reference, rel=1e-9)
    se8, n = twice[c6].std_error_reference, 8
    need = int(np.ceil(n * (target_z(0.2, 0.95) * se8 / abs(1.0e6)) ** 2))
    assert twice[c6].runs_needed == need or twice[c6].table[-1][2] >= target_z(0.2, 0.95)
    assert target_z(0.2, 0.95) == pytest.approx(1.959964 / 0.2, rel=1e-6)


def test_alias_z_of_a_candidate_with_itself_is_zero(ref):
    """A candidate's own columns fit its contribution exactly; another candidate's leave a residual no larger than
    dropping the candidate altogether (the alias z against nothing)."""
    labels, joint = joint_information(ref, NOISE)
    args = (joint.sum(axis=0), labels, ref.truth)
    self_z = pair_alias_z(*args, "velocity_coupling", "velocity_coupling", FITTED)
    drop_z = pair_alias_z(*args, "velocity_coupling", "no_such_candidate", ())
    rival_z = pair_alias_z(*args, "velocity_coupling", "linear_damping", FITTED)
    # the Schur complement of scaled Gram matrices cancels to ~1e-12 of the signal's sum of squares
    assert self_z < 1e-5 * drop_z
    assert 0 < rival_z <= drop_z * (1 + 1e-9)


def test_drop_amplitudes_set_the_runs_amplitude():
    """Runs dropped for 50 um start oscillating with an amplitude of 50 um: the linear trap's field-off time; the
    twin's trap is nonlinear and damped by the air (0.6 1/s), which over 0.3 s changes the largest |y| by a few per
    cent (10 % allowed)."""
    assert drop_time(0.0, 140.0) == 0.0
    t = drop_time(50e-6, 140.0)
    assert np.hypot(9.81 * t * t / 2, 9.81 * t / 140.0) == pytest.approx(50e-6, rel=1e-9)
    ref = reference_runs(TWIN, RunDesign(duration=0.3, fps=1000.0, n_reference=2, amplitudes=(50e-6,)), FITTED)
    np.testing.assert_allclose(ref.amplitudes, 50e-6, rtol=0.1)


def test_truth_json_gives_back_the_twin_configuration():
    twin = replace(TWIN, seed=77, runs=5, duration=2.0, transducer_q=250.0, cavity_detuning=1.5)
    truth = {**twin.to_dict(), "pressure_amplitude_pa": 3100.0}
    back = twin_from_truth(truth)
    assert (back.seed, back.runs, back.duration, back.protocol) == (77, 5, 2.0, twin.protocol)
    assert back.pressure_amplitude_pa == 3100.0 and back.effects.to_dict() == twin.effects.to_dict()
    assert back.cavity_mode.quality_factor == 250.0 and back.cavity_mode.detuning == 1.5
    with pytest.raises(ValueError, match="'seed'"):
        twin_from_truth({"pressure_amplitude_pa": 3000.0})


def _one_line_error(capsys) -> str:
    err = [ln for ln in capsys.readouterr().err.splitlines() if ln.strip()]
    assert len(err) == 1, err
    return err[0]


QUICK = ["plan", "--duration", "0.3", "--fps", "1000", "--reference-runs", "2", "--runs", "2", "4", "--draws", "5"]


def test_plan_command_prints_the_tables(capsys):
    assert main(QUICK + ["--effect", "velocity_coupling:c5=3000,c6=1e6", "--pair",
                         "velocity_coupling:linear_damping"]) == 0
    out = capsys.readouterr().out
    assert "velocity_coupling.c6 = 1e+06" in out and "runs needed for z >= 9.80" in out
    assert "velocity_coupling replaced by linear_damping" in out and "alias z" in out
    assert "trajectory test: c6 = 1e+06" in out


@pytest.mark.parametrize("extra, fragment", [
    (["--effect", "bogus:x=1"], "--effect"),
    (["--truth", "/no/such/truth.json"], "--truth /no/such/truth.json"),
    (["--amplitudes", "0.02"], "--amplitudes"),
    (["--fit", "bogus"], "--fit/--pair"),
    (["--relative-error", "2"], "--relative-error"),
    (["--theta-drop", "1.2"], "--theta-drop"),
    (["--preset", "bogus"], "--preset"),
    (["--pair", "cavity_lag:linear_damping"], "no cavity_lag"),
    (["--data", "/no/such/dir"], "--data /no/such/dir"),
])
def test_plan_command_refuses_bad_input_in_one_line(capsys, extra, fragment):
    assert main(QUICK + extra) == 2
    line = _one_line_error(capsys)
    assert fragment in line


def test_a_pair_needs_the_colon(capsys):
    with pytest.raises(SystemExit) as exc:
        main(QUICK + ["--pair", "cavity_lag"])
    assert exc.value.code == 2
    assert "TRUE:RIVAL" in capsys.readouterr().err


def test_trajectory_oracle_pools_runs_as_the_joint_fit(ref):
    """The trajectory test's information per run, its initial state marginalised, summed over runs, is the joint
    Gauss-Newton covariance of the trajectory test on all the runs at once (the same simulations and differences:
    the sums of the normal equations are exact; 1e-6 for the inversions)."""
    from acousim.twin import twin_dynamics
    from validation.diagnosis.identify.output_error import RunTrajectories, fit_trajectories
    from validation.planner.trajectory_oracle import _law, trajectory_information

    runs, _, _ = simulate_field_drop_runs(replace(TWIN, runs=2, duration=0.5, seed=3,
                                                  camera=replace(TWIN.camera, fps=1000.0, missing_frames=0)),
                                          ExecutorConfig(workers=1), progress=False)
    dynamics, pressure = twin_dynamics(TWIN)
    states = [r.state for r in runs]
    labels, info, truth = trajectory_information(TWIN, dynamics, states, 1e-3, NOISE)
    assert truth["trajectory test: c6"] == 1.0e6 and labels[-1] == "trajectory test: y_offset"
    pooled = np.sqrt(covariance_diagonal(info.sum(axis=0)))
    law, shape, rates = _law(dynamics)
    data = RunTrajectories(1e-3, [s[:, [0, 2]] for s in states], np.full((2, 2), [NOISE.sigma_y, NOISE.sigma_theta]),
                           np.array([s[0] for s in states]))
    joint = fit_trajectories(data, dynamics.force_model, law, shape, {}, {"pressure_pa": pressure, **rates,
                                                                           "c5": 3000.0, "c6": 1.0e6}, True,
                             iterations=0)
    for k, name in enumerate(joint.shared_names + ("y_offset",)):
        assert pooled[k] == pytest.approx(joint.std_errors[name], rel=1e-6), name
    # the reference runs of a c6 plan carry it; a twin with a resonator has none (no trajectory test there)
    assert ref.trajectory is None
    assert trajectory_information(replace(TWIN, transducer_q=250.0, cavity_detuning=1.5), dynamics, states, 1e-3,
                                  NOISE) is None


def test_a_parameter_acting_in_both_equations_is_one_parameter():
    """The cavity's gains act in y and theta: the joint information adds both equations' (each over its noise), so
    its standard error is below either equation's alone; and the alias z of the cavity against itself is 0."""
    twin = TwinConfig(air_damping=False, transducer_q=250.0, cavity_detuning=1.5)
    ref = reference_runs(twin, RunDesign(duration=0.5, fps=1000.0, n_reference=2, amplitudes=(100e-6,)),
                         ("cavity_lag", "linear_damping"))
    labels, joint = joint_information(ref, NOISE)
    assert labels.count("cavity_lag.lag_gain") == 1
    k = labels.index("cavity_lag.lag_gain")
    se_joint = np.sqrt(covariance_diagonal(joint.sum(axis=0))[k])
    for q, eq in enumerate(EQUATIONS):
        own = NOISE.of(eq) * np.sqrt(covariance_diagonal(ref.information[q].sum(axis=0))[list(ref.labels[q]).index(
            "cavity_lag.lag_gain")])
        assert se_joint < own
    assert pair_alias_z(joint.sum(axis=0), labels, ref.truth, "cavity_lag", "cavity_lag", ("cavity_lag",)) < 1e-4


def test_plan_takes_a_data_sets_experiment_and_recorded_noise(tmp_path, sine_run, write_csv, capsys):
    """--data: the noise its meta.json records (the tracking's block); a meta.json the reader refuses is one line
    naming it."""
    import json

    data = tmp_path / "data"
    data.mkdir()
    write_csv(data / "run01.csv", *sine_run)
    (data / "meta.json").write_text(json.dumps({"tracking": {"noise_y_m": 2e-6, "noise_theta": 0.004}}))
    assert main(QUICK + ["--data", str(data), "--runs", "2"]) == 0
    out = capsys.readouterr().out
    assert "sigma_y = 2e-06 m, sigma_theta = 0.004" in out
    (data / "meta.json").write_text(json.dumps({"pressure_amplitude_pa": -5.0}))
    assert main(QUICK + ["--data", str(data)]) == 2
    assert "meta.json" in _one_line_error(capsys)
