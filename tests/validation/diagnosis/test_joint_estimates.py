"""The final model's parameters: an identified effect fitted beside discovered terms is re-estimated with them,
and no discovered term repeats the effect's own column."""
import numpy as np
import pytest

from validation.diagnosis import DiagnoseConfig, diagnose_dataset


# the velocity coupling's trajectory test (on by default; trajectory_test=False below) is not what
# this module checks: it is checked in test_velocity_output_error.py and, end to end, in
# test_pipeline_twin.py, and costs 10-15 CPU-s per diagnosis

def test_pair_scattering_beside_a_discovered_hardening_keeps_its_stiffness(tmp_path):
    """8 runs of 2 s with pair scattering (kappa 15,000 1/s^2) and a hinge hardening -5e4 theta^3 that is no
    candidate.  Pair scattering fitted alone absorbs part of the hardening (measured: kappa 17,720, 18 % high);
    the discovery then needs a linear theta (+2,350 1/s^2) beside theta^3 to undo it.  In the final joint model
    that theta is pair scattering's own column: it is folded into the effect, and kappa and the theta^3
    coefficient are fitted together (measured: 15,006 and -50,250)."""
    from validation.blind.twin_like import TwinLikeConfig, write_twin_like_dataset

    truth = write_twin_like_dataset(tmp_path / "data", TwinLikeConfig(
        runs=8, duration=2.0, seed=5, cubic_hinge=5.0e4, effects={"pair_scattering": {"kappa": 15000.0}}))
    diag = diagnose_dataset(tmp_path / "data", DiagnoseConfig(long_time=False, trajectory_test=False), progress=False)
    assert diag.identified == ("pair_scattering",)
    effect = diag.effects[0]
    # within 3 % (the noise of 8 short runs: the theta^3 standard error is 0.5 % of the coefficient, kappa's similar)
    np.testing.assert_allclose(effect.params["kappa"], truth["effects"]["pair_scattering"]["kappa"], rtol=0.03)
    # the effects-only fit, kept for reference, is the biased one
    assert effect.params_without_discovered_terms["kappa"] > 1.1 * truth["effects"]["pair_scattering"]["kappa"]
    found = {t["term"]: t for t in diag.remaining_gap["discovered_terms"]["thetaddot"]}
    assert "theta" not in found and diag.remaining_gap["folded_into_effects"] == {"thetaddot": ["theta"]}
    np.testing.assert_allclose(found["theta^3"]["coefficient"], -truth["cubic_hinge"], rtol=0.03)
    # the named effect's interval (the jackknife of the joint model over the 8 runs, with kappa's systematic part)
    # covers the truth; measured kappa = 15,006 +- 16 from the jackknife
    from validation.diagnosis.summarise.uncertainty import EFFECT_MODEL_ERROR

    kappa = diag.effect("pair_scattering").estimate("kappa")
    assert kappa.determined and kappa.covers(truth["effects"]["pair_scattering"]["kappa"])
    assert kappa.std_error < 0.01 * kappa.value  # 8 runs of 2 s determine kappa to 0.1 % (measured)
    assert kappa.model_std_error == pytest.approx(EFFECT_MODEL_ERROR["pair_scattering"]["kappa"] * abs(kappa.value))
    assert kappa.std_error == pytest.approx(np.hypot(kappa.statistical_std_error, kappa.model_std_error))
    unc = next(e for e in diag.to_json()["effects"] if e["name"] == "pair_scattering")["uncertainty"]["kappa"]
    assert unc["statistical_std_error"] == kappa.statistical_std_error and unc["model_std_error"] > 0
    pressure = diag.calibration_estimate("pressure_amplitude_pa")
    # measured: 0.075 Pa from the jackknife, 0.90 Pa with the systematic 0.03 % (PRESSURE_MODEL_ERROR); truth 3000.0
    assert pressure.determined and pressure.std_error < 1.0 and pressure.covers(truth["pressure_amplitude_pa"])
    _check_rejected_candidates(diag)


def _check_rejected_candidates(diag):
    """Every candidate outside the model is rejected with its reasons, in the API and the JSON; a rejected
    candidate's parameters are refused as a result.  Measured on this data set: the dampings fitted on top of the
    model come out negative (gamma_y = -4.5e-4 1/s, c_y = -2.7e-3 1/m), a non-physical sign."""
    from validation.diagnosis import Diagnosis
    from validation.diagnosis.summarise.result import RejectedCandidateError

    doc = diag.to_json()
    back = Diagnosis.from_json(doc)
    for verdict in (diag.effect("linear_damping"), back.effect("linear_damping")):
        assert verdict.rejected and verdict.status == "rejected"
        codes = [r["code"] for r in verdict.rejected_because]
        assert codes[0] == "not_significant"
        if verdict.params["gamma_y"] < 0 or verdict.params["gamma_theta"] < 0:
            assert "non_physical_sign" in codes
        with pytest.raises(RejectedCandidateError, match="rejected candidate"):
            verdict.estimate("gamma_y")
        assert str(verdict).startswith("linear_damping: rejected")
    by_name = {e["name"]: e for e in doc["effects"]}
    assert by_name["pair_scattering"]["status"] == "named" and by_name["pair_scattering"]["rejected_because"] == []
    assert by_name["pair_scattering"]["uncertainty"]["kappa"]["determined"]
    assert all(e["status"] == "rejected" and e["rejected_because"] for n, e in by_name.items() if n != "pair_scattering")
    assert "uncertainty" not in by_name["linear_damping"]  # a rejected candidate carries no result
