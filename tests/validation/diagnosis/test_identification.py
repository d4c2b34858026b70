"""Held-out identification on synthetic accelerations: exactly the effects present, nothing without one."""
from validation.diagnosis import Calibration, DiagnosisProblem
from validation.diagnosis.identify.identification import identify_effects


def test_identification_finds_exactly_the_effects(fast_model, synthetic_runs):
    truth = Calibration.at(fast_model, 0.95**2, fast_model.equilibrium_height - 10e-6)
    # beta0 = 60 1/s^2: ~2 % of the hinge acceleration scale, above the 50 1/s^2 derivative noise
    effects = {"pair_scattering": {"kappa": 8e3}, "mirror_asymmetry": {"beta0": 60.0, "beta1": 0.0}}
    runs = synthetic_runs(fast_model, truth, effects, seed=1, known_noise=True)
    result = identify_effects(DiagnosisProblem(fast_model, runs))
    assert set(result.identified) == {"pair_scattering", "mirror_asymmetry"}
    assert result.identified[0] == "pair_scattering"  # the larger gap goes first


def test_no_effect_names_nothing(fast_model, synthetic_runs):
    truth = Calibration.at(fast_model, 1.05**2, fast_model.equilibrium_height)
    runs = synthetic_runs(fast_model, truth, {}, seed=2, known_noise=True)
    assert identify_effects(DiagnosisProblem(fast_model, runs)).identified == []
