"""Calibration and effect fit on synthetic accelerations with known calibration and effects."""
import numpy as np
import pytest

from validation.diagnosis import Calibration, DiagnosisProblem
from validation.diagnosis.calibrate.gap_model import fit_gap_model
from validation.diagnosis.calibrate.metrics import fit_gaps


def _fit(model, runs, effects=()):
    return fit_gap_model(DiagnosisProblem(model, runs), effects)


def test_calibration_and_effects_recovered(fast_model, synthetic_runs):
    truth = Calibration.at(fast_model, 1.08**2, fast_model.equilibrium_height + 15e-6)
    effects = {"pair_scattering": {"kappa": 1.2e4}, "linear_damping": {"gamma_y": 1.5, "gamma_theta": 0.8}}
    runs = synthetic_runs(fast_model, truth, effects)
    fit = _fit(fast_model, runs, ["pair_scattering", "linear_damping"])
    # pressure and origin: determined by 4800 samples of the y equation with 0.05 m/s^2 noise
    np.testing.assert_allclose(fit.calibration.pressure_amplitude_pa, 3240.0, rtol=1e-3)
    np.testing.assert_allclose(fit.calibration.z_origin_m, truth.z_origin_m, atol=1e-7)
    np.testing.assert_allclose(fit.effects["pair_scattering"]["kappa"], 1.2e4, rtol=0.01)
    np.testing.assert_allclose(fit.effects["linear_damping"]["gamma_y"], 1.5, rtol=0.05)
    np.testing.assert_allclose(fit.effects["linear_damping"]["gamma_theta"], 0.8, rtol=0.25)  # thetadot noise dominates
    base = _fit(fast_model, runs, [])
    # the effects act on theta and on the energy: those gap components collapse (the y component is
    # floored by noise on small-amplitude runs and is the same for both fits)
    before, after = fit_gaps(runs, base).mean(axis=0), fit_gaps(runs, fit).mean(axis=0)
    assert before[1] > 50 * after[1] and before[2] > 50 * after[2]
    np.testing.assert_allclose(before[0], after[0], rtol=0.05)


def test_energy_balance_finds_weak_damping(fast_model, synthetic_runs):
    """gamma = 0.5 1/s changes accelerations by < 1e-4 of their variance but the energy by ~20 % per window."""
    truth = Calibration.at(fast_model, 1.0, fast_model.equilibrium_height)
    effects = {"pair_scattering": {"kappa": 1.2e4}, "linear_damping": {"gamma_y": 0.5, "gamma_theta": 0.5}}
    runs = synthetic_runs(fast_model, truth, effects, duration=2.5, seed=4)
    fit = _fit(fast_model, runs, ["pair_scattering", "linear_damping"])
    np.testing.assert_allclose(fit.effects["linear_damping"]["gamma_y"], 0.5, rtol=0.1)
    np.testing.assert_allclose(fit.effects["linear_damping"]["gamma_theta"], 0.5, rtol=0.1)
    no_damping = _fit(fast_model, runs, ["pair_scattering"])
    energy_gap = lambda f: np.mean(fit_gaps(runs, f)[:, 2])  # noqa: E731
    assert energy_gap(no_damping) > 10 * energy_gap(fit)


def test_a_registered_effect_is_fitted_by_the_diagnosis(registered_push, fast_model, synthetic_runs):
    """A dummy effect registered in acousim.dynamics.effects.EFFECT_TYPES (a constant hinge push) is a candidate of the
    diagnosis's effect fit with no further code: runs whose hinge feels it give back its parameter."""
    from validation.diagnosis.prepare.runs import RunAccelerations

    truth = Calibration.at(fast_model, 1.0, fast_model.equilibrium_height)
    runs = synthetic_runs(fast_model, truth, {}, n_runs=4, duration=0.8)
    push = 40.0  # [1/s^2]: 0.8 times the thetaddot noise (50 1/s^2) on each of the 1600 samples
    pushed = [RunAccelerations(r.name, r.t, r.state, r.accel + np.array([0.0, push])) for r in runs]
    fit = fit_gap_model(DiagnosisProblem(fast_model, pushed), ["constant_push"])
    # the standard error of a mean of 1600 samples at noise 50 is 1.25 1/s^2: 4 of them
    assert fit.effects["constant_push"]["push"] == pytest.approx(push, abs=5.0)
