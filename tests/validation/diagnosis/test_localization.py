"""Localisation of the residual of the calibrated simulation."""
from validation.diagnosis import Calibration, DiagnosisProblem
from validation.diagnosis.calibrate.gap_model import fit_gap_model
from validation.diagnosis.summarise.localization import localize_residuals


def test_localization_points_at_the_missing_term(fast_model, synthetic_runs):
    truth = Calibration.at(fast_model, 1.0, fast_model.equilibrium_height)
    runs = synthetic_runs(fast_model, truth, {"mirror_asymmetry": {"beta0": 0.0, "beta1": 5e4}}, seed=3, noise=(0.05, 1.0))
    base = fit_gap_model(DiagnosisProblem(fast_model, runs), [])
    loc = localize_residuals(runs, base.residuals)
    top = loc["terms"]["thetaddot"][0]
    assert top["term"] == "y" and top["explained_fraction_alone"] > 0.9  # beta1 * y
    assert set(loc["regions"]) == {"theta_y", "thetadot_ydot"}
