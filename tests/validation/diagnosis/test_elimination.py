"""The backward check: an effect the greedy rounds chose that is not needed given the others is dropped, and two
effects that only work as either one are one verdict naming both."""
from validation.diagnosis import Calibration, DiagnosisProblem
from validation.diagnosis.identify.elimination import backward_check
from validation.diagnosis.identify.identification import held_out_gaps


def test_an_effect_not_needed_given_the_others_is_dropped(fast_model, synthetic_runs):
    """Pair scattering alone in the data; a greedy set that also holds mirror asymmetry keeps pair scattering
    only, with its held-out test given the others reported."""
    truth = Calibration.at(fast_model, 0.95**2, fast_model.equilibrium_height - 10e-6)
    runs = synthetic_runs(fast_model, truth, {"pair_scattering": {"kappa": 8e3}}, seed=1, known_noise=True)
    problem = DiagnosisProblem(fast_model, runs)
    cache = {}
    result = backward_check(problem, ["mirror_asymmetry", "pair_scattering"], cache=cache)
    assert result.named == ["pair_scattering"] and result.model_effects == ["pair_scattering"]
    assert result.dropped == ["mirror_asymmetry"] and result.indistinguishable == []
    assert not result.dropped_tests["mirror_asymmetry"].significant
    test = result.tests["pair_scattering"]
    assert test.significant and test.p_value < 0.01
    # the held-out gaps are shared with the caller (the greedy rounds): the full set and each set without one
    assert {("mirror_asymmetry", "pair_scattering"), ("pair_scattering",), ("mirror_asymmetry",), ()} <= set(cache)
    assert (cache[("pair_scattering",)] == held_out_gaps(problem, ["pair_scattering"])).all()


def test_two_copies_of_one_effect_are_one_verdict(fast_model, synthetic_runs, registered_push):
    """A constant hinge torque is mirror asymmetry's beta0 and the dummy effect constant_push at once: neither
    improves held-out runs given the other, both together do, so neither is named alone and both are named as
    indistinguishable, with the evidence; one of them stays in the fitted model."""
    truth = Calibration.at(fast_model, 0.95**2, fast_model.equilibrium_height - 10e-6)
    # beta0 = 60 1/s^2: ~2 % of the hinge acceleration scale, above the 50 1/s^2 derivative noise
    # (with pair scattering, which keeps the soft hinge open under the torque)
    effects = {"pair_scattering": {"kappa": 8e3}, "mirror_asymmetry": {"beta0": 60.0, "beta1": 0.0}}
    runs = synthetic_runs(fast_model, truth, effects, seed=1, known_noise=True)
    problem = DiagnosisProblem(fast_model, runs)
    result = backward_check(problem, ["pair_scattering", "mirror_asymmetry", "constant_push"])
    assert result.named == ["pair_scattering"] and result.dropped == []
    (pair,) = result.indistinguishable
    assert pair.effects == ("mirror_asymmetry", "constant_push")
    assert result.model_effects == ["pair_scattering", pair.kept_in_model]
    assert all(p >= 0.01 for p in pair.p_given_other.values()) or \
        all(m <= 5e-6 for m in pair.median_improvement_given_other.values())
    assert pair.p_together < 0.01  # with 8 runs the smallest attainable p is 2^-8 = 0.0039
    assert pair.p_difference > 0.01  # the data prefer neither
    d = pair.to_dict()
    assert d["effects"] == ["mirror_asymmetry", "constant_push"] and d["kept_in_model"] == pair.kept_in_model


def _damped_runs(model, amplitudes_m, seed=3, n_runs=8, duration=1.6, fps=500, noise=(0.05, 50.0)):
    """Runs of the calibrated model with a weak linear damping (gamma_y = 0.8, gamma_theta = 1 1/s), each dropped from
    rest at one of ``amplitudes_m`` (cycled; random sign) with a random hinge start, plus noise of the size the
    Savitzky-Golay accelerations leave (the runs carry its variances)."""
    import numpy as np

    from validation.diagnosis.calibrate.gap_model import predicted_accelerations
    from validation.diagnosis.prepare.runs import RunAccelerations

    from .conftest import _calibrated_runs

    truth = Calibration.at(model, 0.95**2, model.equilibrium_height - 10e-6)
    effects = {"linear_damping": {"gamma_y": 0.8, "gamma_theta": 1.0}}
    rng = np.random.default_rng(seed)
    x0 = np.column_stack([np.resize(amplitudes_m, n_runs) * rng.choice([-1, 1], n_runs), np.zeros(n_runs),
                          rng.uniform(-0.3, 0.3, n_runs), rng.uniform(-3, 3, n_runs)])
    t = np.arange(int(duration * fps)) / fps
    states, _ = _calibrated_runs(truth, effects, x0, t)
    runs = [RunAccelerations(f"run{i:02d}.csv", t, states[i], np.zeros((len(t), 2))) for i in range(n_runs)]
    pred = predicted_accelerations(DiagnosisProblem(model, runs), truth, effects)
    variances = np.array([noise[0] ** 2, noise[1] ** 2, 0.0, 0.0])
    return [RunAccelerations(r.name, r.t, r.state, p + rng.normal(0, noise, p.shape), variances)
            for r, p in zip(runs, pred)]


def test_dampings_at_one_amplitude_are_one_verdict(fast_model):
    """Linear damping and quadratic drag differ in how the loss scales with the amplitude (A^2 against A^3): on runs
    all dropped from 60 um neither improves held-out runs given the other (p = 0.07 and 0.97), both together do
    (p = 2^-8, the smallest 8 runs give), so the verdict names the pair as indistinguishable with that evidence,
    and neither alone.  Dropped from 20-150 um, the same damping is linear damping alone (next test)."""
    result = backward_check(DiagnosisProblem(fast_model, _damped_runs(fast_model, [6e-5])),
                            ["linear_damping", "quadratic_drag"])
    assert result.named == [] and result.dropped == []
    (pair,) = result.indistinguishable
    assert set(pair.effects) == {"linear_damping", "quadratic_drag"}
    assert all(p >= 0.01 for p in pair.p_given_other.values())
    assert pair.p_together < 0.01
    assert result.model_effects == [pair.kept_in_model]
    d = pair.to_dict()
    assert {"p_given_other", "p_together", "median_difference", "p_difference"} <= set(d)


def test_dampings_at_several_amplitudes_are_told_apart(fast_model):
    """The same damping on runs dropped from 20, 40, 80 and 150 um: the amplitude dependence names linear damping
    and drops quadratic drag (measured: no pair)."""
    result = backward_check(DiagnosisProblem(fast_model, _damped_runs(fast_model, [2e-5, 4e-5, 8e-5, 1.5e-4])),
                            ["linear_damping", "quadratic_drag"])
    assert result.named == ["linear_damping"] and result.dropped == ["quadratic_drag"]
    assert result.indistinguishable == []
