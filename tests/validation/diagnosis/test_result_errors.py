"""The typed result's errors and rejections as a reader meets them: the API, diagnosis.json and the report's
sentences and table (hand-made diagnoses; the numbers of a real one: test_joint_estimates.py)."""
from dataclasses import replace

import pytest

from validation.diagnosis import Diagnosis, EffectVerdict
from validation.diagnosis.summarise.result import RejectedCandidateError
from validation.diagnosis.summarise.uncertainty import interval_from_error


@pytest.fixture
def diagnosis(make_diagnosis):
    """pair_scattering named with kappa = 19,512 +- 213 (9 runs), and linear damping rejected: not significant and a
    negative gamma_theta."""
    named = make_diagnosis(["pair_scattering"], params={"pair_scattering": {"kappa": 19512.3}}, calibration={
        "pressure_amplitude_pa": 3001.2, "pressure_ratio": 1.0004, "y_origin_above_nominal_Z_eq_m": 1e-6,
        "uncertainty": {"pressure_amplitude_pa": interval_from_error(3001.2, 0.9, 8).to_dict()}},
        gap_per_run={"runs": ["a"] * 9, "before": [], "after": []},
        remaining_gap={"statement": "the calibrated simulation explains the data", "discovered_terms": {}})
    kappa = replace(named.effects[0], uncertainty={"kappa": interval_from_error(19512.3, 213.0, 8)})
    rejected = EffectVerdict("linear_damping", {"gamma_y": 0.2, "gamma_theta": -1.467}, 0.02, 0.8, False, 0.3, 0.4,
                             1e-3, note="not significant", rejected_because=(
                                 {"code": "not_significant", "reason": "not a significant held-out improvement (p = 0.3)"},
                                 {"code": "non_physical_sign", "reason": "a negative damping (gamma_theta = -1.47 < 0)"}))
    return replace(named, effects=(kappa, rejected))


def test_a_rejected_candidate_is_no_result(diagnosis):
    verdict = diagnosis.effect("linear_damping")
    assert verdict.rejected and verdict.status == "rejected"
    with pytest.raises(RejectedCandidateError, match="linear_damping is a rejected candidate .*negative damping"):
        verdict.estimate("gamma_theta")
    assert str(verdict) == ("linear_damping: rejected (not a significant held-out improvement (p = 0.3); a negative "
                            "damping (gamma_theta = -1.47 < 0))")


def test_named_parameters_carry_their_errors_through_json(diagnosis):
    back = Diagnosis.from_json(diagnosis.to_json())
    for d in (diagnosis, back):
        kappa = d.effect("pair_scattering").estimate("kappa")
        # t(0.975, 8) = 2.306: 19,512 +- 491
        assert kappa.std_error == 213.0 and kappa.interval_95 == pytest.approx((19512.3 - 491.2, 19512.3 + 491.2), abs=0.1)
        assert d.effect("pair_scattering").status == "named"
        assert d.effect("linear_damping").rejected
        assert d.calibration_estimate("pressure_amplitude_pa").std_error == 0.9
    assert str(back.effect("pair_scattering")) == "pair_scattering: named (kappa = 1.951e4 +- 0.021e4)"


def test_the_report_gives_errors_and_no_rejected_values(diagnosis):
    from validation.report.sections.gap_diagnosis import diagnosis_section

    section = diagnosis_section(diagnosis, [])
    assert "The gap is caused by pair_scattering (kappa = 1.951e4 +- 0.021e4)" in section.reading
    assert "Calibrated pressure 3001.20 Pa +- 0.90 Pa (standard error over runs)" in section.reading
    rows = {r[0]: r for r in section.tables[0].rows}
    assert rows["pair_scattering"][2] == "kappa = 1.951e4 +- 0.021e4"
    assert rows["linear_damping"][2] == "rejected: not significant, non physical sign"
    assert "-1.47" not in " ".join(str(c) for c in rows["linear_damping"])


def test_an_old_diagnosis_json_reads_back_with_statuses(diagnosis):
    """A diagnosis.json written before statuses and errors: the statuses follow from the flags, the errors are
    "not determined"."""
    doc = diagnosis.to_json()
    for e in doc["effects"]:
        for key in ("status", "rejected_because", "uncertainty"):
            e.pop(key, None)
    del doc["calibration"]["uncertainty"]
    back = Diagnosis.from_json(doc)
    assert back.effect("pair_scattering").status == "named" and back.effect("linear_damping").rejected
    assert not back.effect("pair_scattering").estimate("kappa").determined
    assert not back.calibration_estimate("pressure_amplitude_pa").determined
