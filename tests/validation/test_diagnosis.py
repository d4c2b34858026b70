"""Diagnosis core on synthetic accelerations with known calibration and effects."""
import numpy as np
import pytest

from validation.diagnosis import (CANDIDATE_EFFECTS, Calibration, RunAccelerations, _Physics, _residuals,
                                  effect_regressors, fit_gap_model, fit_gaps, identify_effects,
                                  localize_residuals)


@pytest.fixture(scope="module")
def fast_model():
    from acousim import GorkovDimer

    return GorkovDimer().interpolated()


def _synthetic_runs(model, cal, effects, n_runs=8, duration=1.6, fps=500, noise=(0.05, 50.0), seed=0, known_noise=False):
    """Trajectories of the calibrated model + effects from random starts (|y| <= 150 um, |theta| <= 0.4);
    exact accelerations plus noise of the size Savitzky-Golay differentiation leaves on realistic
    tracking (0.05 m/s^2 and 50 1/s^2).  ``known_noise``: the runs carry the noise variances, as
    :func:`validation.diagnose.prepare_runs` gives them, so that the gaps are in excess of the noise."""
    from validation.diagnosis import simulate_runs

    rng = np.random.default_rng(seed)
    x0 = np.column_stack([rng.uniform(-1.5e-4, 1.5e-4, n_runs), rng.uniform(-0.01, 0.01, n_runs),
                          rng.uniform(-0.4, 0.4, n_runs), rng.uniform(-5, 5, n_runs)])
    t = np.arange(int(duration * fps)) / fps
    states, n_valid = simulate_runs(model, cal, effects, x0, t)
    assert np.all(n_valid == len(t))
    runs = [RunAccelerations(f"run{i:02d}.csv", t, states[i], np.zeros((len(t), 2))) for i in range(n_runs)]
    _, pred = _residuals(_Physics(model, runs), runs, cal, effects)
    nv = np.array([noise[0] ** 2, noise[1] ** 2, 0.0, 0.0]) if known_noise else None
    return [RunAccelerations(r.name, r.t, r.state, p + rng.normal(0, noise, p.shape), nv) for r, p in zip(runs, pred)]


@pytest.mark.parametrize("name", list(CANDIDATE_EFFECTS))
def test_regressors_are_linear_in_parameters(name, rng):
    st = rng.normal(size=(20, 4))
    z = rng.uniform(-5e-4, 0, 20)
    reg = effect_regressors(name, st, z, 836.0)
    assert reg.shape == (20, 2, len(CANDIDATE_EFFECTS[name]))
    # PHYSICS.md section 5: which equation each parameter acts in
    acts_in_y = {"gamma_y", "c_y"}
    for j, p in enumerate(CANDIDATE_EFFECTS[name]):
        assert np.any(reg[:, 0, j] != 0) == (p in acts_in_y)


def test_calibration_and_effects_recovered(fast_model):
    truth = Calibration.at(fast_model, 1.08**2, fast_model.equilibrium_height + 15e-6)
    effects = {"pair_scattering": {"kappa": 1.2e4}, "linear_damping": {"gamma_y": 1.5, "gamma_theta": 0.8}}
    runs = _synthetic_runs(fast_model, truth, effects)
    fit = fit_gap_model(fast_model, runs, ["pair_scattering", "linear_damping"])
    # pressure and origin: determined by 4800 samples of the y equation with 0.05 m/s^2 noise
    np.testing.assert_allclose(fit.calibration.pressure_amplitude_pa, 3240.0, rtol=1e-3)
    np.testing.assert_allclose(fit.calibration.z_origin_m, truth.z_origin_m, atol=1e-7)
    np.testing.assert_allclose(fit.effects["pair_scattering"]["kappa"], 1.2e4, rtol=0.01)
    np.testing.assert_allclose(fit.effects["linear_damping"]["gamma_y"], 1.5, rtol=0.05)
    np.testing.assert_allclose(fit.effects["linear_damping"]["gamma_theta"], 0.8, rtol=0.25)  # thetadot noise dominates
    base = fit_gap_model(fast_model, runs, [])
    # the effects act on theta and on the energy: those gap components collapse (the y component is
    # floored by noise on small-amplitude runs and is the same for both fits)
    before, after = fit_gaps(runs, base).mean(axis=0), fit_gaps(runs, fit).mean(axis=0)
    assert before[1] > 50 * after[1] and before[2] > 50 * after[2]
    np.testing.assert_allclose(before[0], after[0], rtol=0.05)


def test_energy_balance_finds_weak_damping(fast_model):
    """gamma = 0.5 1/s changes accelerations by < 1e-4 of their variance but the energy by ~20 % per window."""
    truth = Calibration.at(fast_model, 1.0, fast_model.equilibrium_height)
    effects = {"pair_scattering": {"kappa": 1.2e4}, "linear_damping": {"gamma_y": 0.5, "gamma_theta": 0.5}}
    runs = _synthetic_runs(fast_model, truth, effects, duration=2.5, seed=4)
    fit = fit_gap_model(fast_model, runs, ["pair_scattering", "linear_damping"])
    np.testing.assert_allclose(fit.effects["linear_damping"]["gamma_y"], 0.5, rtol=0.1)
    np.testing.assert_allclose(fit.effects["linear_damping"]["gamma_theta"], 0.5, rtol=0.1)
    no_damping = fit_gap_model(fast_model, runs, ["pair_scattering"])
    energy_gap = lambda f: np.mean(fit_gaps(runs, f)[:, 2])  # noqa: E731
    assert energy_gap(no_damping) > 10 * energy_gap(fit)


def test_identification_finds_exactly_the_effects(fast_model):
    truth = Calibration.at(fast_model, 0.95**2, fast_model.equilibrium_height - 10e-6)
    # beta0 = 60 1/s^2: ~2 % of the hinge acceleration scale, above the 50 1/s^2 derivative noise
    effects = {"pair_scattering": {"kappa": 8e3}, "mirror_asymmetry": {"beta0": 60.0, "beta1": 0.0}}
    runs = _synthetic_runs(fast_model, truth, effects, seed=1, known_noise=True)
    result = identify_effects(fast_model, runs)
    assert set(result.identified) == {"pair_scattering", "mirror_asymmetry"}
    assert result.identified[0] == "pair_scattering"  # the larger gap goes first


def test_no_effect_names_nothing(fast_model):
    truth = Calibration.at(fast_model, 1.05**2, fast_model.equilibrium_height)
    runs = _synthetic_runs(fast_model, truth, {}, seed=2, known_noise=True)
    assert identify_effects(fast_model, runs).identified == []


def test_localization_points_at_the_missing_term(fast_model):
    truth = Calibration.at(fast_model, 1.0, fast_model.equilibrium_height)
    runs = _synthetic_runs(fast_model, truth, {"mirror_asymmetry": {"beta0": 0.0, "beta1": 5e4}}, seed=3, noise=(0.05, 1.0))
    base = fit_gap_model(fast_model, runs, [])
    loc = localize_residuals(runs, base.residuals)
    top = loc["terms"]["thetaddot"][0]
    assert top["term"] == "y" and top["explained_fraction_alone"] > 0.9  # beta1 * y
    assert set(loc["regions"]) == {"theta_y", "thetadot_ydot"}


def test_blind_draws_are_seeded_and_scored():
    from validation.blind import STRENGTHS, draw_case, score_case, summarize

    a, b = draw_case(7, 3), draw_case(7, 3)
    assert a == b and draw_case(8, 3) != a  # same seed, same hidden truth
    for name, params in a["effects"].items():
        for p, v in params.items():
            lo, hi, signed = STRENGTHS[name][p]
            assert lo <= abs(v) <= hi
    case = {"index": 0, "effects": {"pair_scattering": {"kappa": 1e4}}, "pressure_error": 0.05, "twin_seed": 1}
    diag = {"identified": ["pair_scattering", "linear_damping"], "gap_before": 0.4, "gap_after": 0.02,
            "effects": [{"name": "pair_scattering", "params": {"kappa": 1.1e4}},
                        {"name": "linear_damping", "params": {"gamma_y": 0.1, "gamma_theta": 0.1}}],
            "calibration": {"pressure_amplitude_pa": 3100.0}}
    r = score_case(case, {"pressure_amplitude_pa": 3150.0}, diag, None)
    assert not r["exact"] and r["parameter_relative_error"]["pair_scattering"]["kappa"] == pytest.approx(0.1)
    s = summarize([r])
    assert s["per_effect"]["linear_damping"]["fp"] == 1 and s["per_effect"]["pair_scattering"]["recall"] == 1.0
    assert s["median_shrink_with_effect"] == pytest.approx(0.95)


def test_sign_flip_pvalue_exact_cases():
    from validation.diagnosis import sign_flip_pvalue

    assert sign_flip_pvalue(np.ones(5)) == pytest.approx(1 / 32)  # only the observed pattern is as large
    assert sign_flip_pvalue(np.zeros(4)) == 1.0
    # one large positive and four tiny negatives: half of the sign patterns have a sum at least as large
    p = sign_flip_pvalue(np.array([1.0, -1e-3, -1e-3, -1e-3, -1e-3]))
    assert 0.5 <= p <= 0.5 + 1 / 32 + 1e-12
    # brute force on a random vector
    d = np.random.default_rng(3).normal(0.3, 1.0, 9)
    signs = np.array([[1 - 2 * ((k >> i) & 1) for i in range(9)] for k in range(2**9)])
    assert sign_flip_pvalue(d) == pytest.approx(np.mean(signs @ np.abs(d) >= d.sum() - 1e-12))


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
    assert err < 1e-3  # measured 2.6e-4 (step 1) to 3.8e-4 (step 4); the old smoothing-filter comparison: 19 %
