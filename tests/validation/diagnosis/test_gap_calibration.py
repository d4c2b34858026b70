"""Calibrating the full-wave hinge gap from data (validation.diagnosis.calibrate.model_parameters and the pipeline)."""
from __future__ import annotations

import numpy as np
import pytest

from validation.diagnosis.calibrate import model_parameters as mp
from acousim.models import ModelSpec


def _fake_profile(monkeypatch, u0: float, sigma_u: float, n: int = 10_000, misfit: float = 1.0):
    """chi2(u) = misfit N + (u - u0)^2 / sigma_u^2 exactly (u = log value), in place of the hinge fit."""
    calls = []

    def chi2(problem):
        calls.append(problem)
        return misfit * n + (np.log(problem) - u0) ** 2 / sigma_u**2, n

    monkeypatch.setattr(mp, "_hinge_chi2", chi2)
    return calls


def test_profile_finds_the_minimum_and_its_standard_error(monkeypatch):
    """Quadratic chi2 in log g: the estimate is exp(u0) and the standard error exp(u0) sigma_u (delta method)."""
    u0, su = np.log(12e-6), 0.04
    _fake_profile(monkeypatch, u0, su)
    pc = mp.calibrate_model_parameter("gap_m", 5e-6, 25e-6, 5e-6, build_problem=lambda v: v)
    assert pc.calibrated
    assert pc.estimate == pytest.approx(12e-6, rel=0.01)  # the refinement's xatol 0.01 in log
    # central second difference of an exact parabola is exact: only the estimate's offset enters
    assert pc.std_error == pytest.approx(pc.estimate * su, rel=1e-6)
    assert pc.value == pc.estimate


def test_misfit_inflates_the_standard_error(monkeypatch):
    """A model that misses the data by chi2/N = 4 gets twice the standard error, never less."""
    u0, su = np.log(12e-6), 0.04
    _fake_profile(monkeypatch, u0, su, misfit=4.0)
    pc = mp.calibrate_model_parameter("gap_m", 5e-6, 25e-6, 5e-6, build_problem=lambda v: v)
    assert pc.std_error == pytest.approx(2 * pc.estimate * su, rel=1e-6)


@pytest.mark.parametrize("spread", [0.002, 0.05])
def test_run_to_run_scatter_widens_the_standard_error(monkeypatch, spread):
    """Runs whose own profiles are parabolas about scattered minima u_r (equal curvature): the profile's minimum is
    their mean, and the delete-one-run jackknife of a mean is exactly std(u_r) / sqrt(R).  The standard error is the
    larger of that and the curvature's, so scatter beyond the noise widens it, and small scatter leaves the
    curvature's in place."""
    rng = np.random.default_rng(3)
    runs, sigma_run, n = 8, 0.02, 10_000
    u_r = np.log(12e-6) + spread * rng.standard_normal(runs)

    def chi2(problem):
        return n / runs + (np.log(problem) - u_r) ** 2 / sigma_run**2, n

    monkeypatch.setattr(mp, "_hinge_chi2", chi2)
    pc = mp.calibrate_model_parameter("gap_m", 5e-6, 25e-6, 5e-6, build_problem=lambda v: v)
    assert pc.estimate == pytest.approx(np.exp(u_r.mean()), rel=0.01)  # the refinement's xatol 0.01 in log
    # R equal parabolas of width sigma_run, inflated by chi2_min / N (the scatter is a misfit too)
    inflation = 1 + np.sum((np.log(pc.estimate) - u_r) ** 2) / sigma_run**2 / n
    se_curvature = sigma_run / np.sqrt(runs) * np.sqrt(inflation)
    se_jackknife = np.std(u_r, ddof=1) / np.sqrt(runs)
    # the vertices of exact parabolas are exact: only round-off remains
    assert pc.std_error / pc.estimate == pytest.approx(max(se_curvature, se_jackknife), rel=1e-6)
    assert (se_jackknife > se_curvature) == (spread > sigma_run)


def test_jackknife_needs_a_minimum_without_each_run():
    """A run that alone carries the curvature leaves a profile without a minimum: no jackknife (nan)."""
    u = np.array([-0.05, 0.0, 0.05])
    per_run = np.column_stack([u**2, np.zeros(3), np.zeros(3), np.zeros(3)])
    assert np.isnan(mp.jackknife_log_error(u, per_run))
    per_run[:, 1:] = (u[:, None] - 0.01) ** 2
    assert np.isfinite(mp.jackknife_log_error(u, per_run))


def test_flat_profile_is_not_called_calibrated(monkeypatch):
    """sigma_u = 1 (a factor e): the data do not determine the gap; the default is kept and the note says why."""
    _fake_profile(monkeypatch, np.log(10e-6), 1.0)
    pc = mp.calibrate_model_parameter("gap_m", 5e-6, 25e-6, 5e-6, build_problem=lambda v: v)
    assert not pc.calibrated and pc.value == 5e-6
    assert "do not determine" in pc.note and np.isfinite(pc.std_error)


def test_minimum_at_the_range_edge_is_not_called_calibrated(monkeypatch):
    _fake_profile(monkeypatch, np.log(40e-6), 0.05)
    pc = mp.calibrate_model_parameter("gap_m", 5e-6, 25e-6, 5e-6, build_problem=lambda v: v)
    assert not pc.calibrated and "edge of the range" in pc.note


@pytest.fixture(scope="module")
def fullwave_twin(tmp_path_factory, synthetic_family_dir):
    """8 runs of 2 s on the full wave (synthetic family) of the default dimer with a 10 um gap (between the nodes
    7.5 and 16.7 um) and linear damping as the only damping, the true pressure 5 % off the nominal one."""
    from acousim.dynamics.effects import EffectSet
    from acousim.fullwave.family import FAMILY_ENV
    from acousim.twin import TwinConfig, simulate_dataset
    from cubedimer.executor import ExecutorConfig

    mpatch = pytest.MonkeyPatch()
    mpatch.setenv(FAMILY_ENV, str(synthetic_family_dir))
    out = tmp_path_factory.mktemp("fw_twin")
    # no air damping: the linear damping is the only effect, the one the diagnosis must name alone
    cfg = TwinConfig(runs=8, duration=2.0, seed=11, model_spec=ModelSpec("fullwave", {"gap_m": 10e-6}), pressure_error=0.05,
                     effects=EffectSet.parse(["linear_damping:gamma_y=0.5,gamma_theta=2.0"]), air_damping=False)
    simulate_dataset(cfg, out, ExecutorConfig(workers=1), force=True, progress=False)
    yield out
    mpatch.undo()


def test_diagnosis_calibrates_the_gap_and_names_only_the_true_effect(fullwave_twin, use_synthetic_family):
    from validation.diagnosis import DiagnoseConfig, diagnose_dataset

    d = diagnose_dataset(fullwave_twin, DiagnoseConfig(long_time=False), progress=False, spec=ModelSpec("fullwave"))
    cal = d.calibration
    assert cal["gap_calibrated"] is True
    # the target is 20 %; on noise-free physics (the twin is the family itself) it is far better
    assert cal["gap_m"] == pytest.approx(10e-6, rel=0.2)
    assert abs(cal["gap_m"] - 10e-6) < 4 * cal["gap_std_m"] + 0.001 * 10e-6  # the refinement's own resolution
    assert cal["gap_model_error_m"] is None  # the synthetic family states no mesh error
    assert d.identified == ("linear_damping",)
    assert d.model == "fullwave"
    # the report states the calibrated gap with its uncertainty
    from validation.report.sections.gap_diagnosis import diagnosis_section

    reading = diagnosis_section(d, []).reading
    assert f"g = {cal['gap_m'] * 1e6:.2f} +- {cal['gap_std_m'] * 1e6:.2g} um" in reading
    assert "model's own stated accuracy" not in reading
    cal["gap_model_error_m"] = 0.8e-6  # as a family with a mesh study states it
    assert "+- 0.8 um more from the model's own stated accuracy" in diagnosis_section(d, []).reading


def test_a_given_gap_is_used_not_calibrated(fullwave_twin, use_synthetic_family):
    from validation.diagnosis import DiagnoseConfig, diagnose_dataset

    # the calibration only: one candidate, no discovery
    d = diagnose_dataset(fullwave_twin, DiagnoseConfig(long_time=False, discover=False,
                                                          candidates=("linear_damping",)), progress=False,
                            spec=ModelSpec("fullwave", {"gap_m": 13e-6}))
    cal = d.calibration
    assert cal["gap_m"] == 13e-6 and cal["gap_calibrated"] is False and cal["gap_std_m"] is None
    assert "gap_profile" not in cal
    from validation.report.sections.gap_diagnosis import diagnosis_section

    assert "Hinge gap g = 13.00 um: the gap given by the user" in diagnosis_section(d, []).reading
