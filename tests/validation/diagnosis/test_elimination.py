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
