"""The blind check's further case kinds: draws are seeded, the data carry what they should, and each score can fail."""
import json

import pytest

from validation.blind import (KINDS, OUT_OF_CANDIDATE, BlindConfig, blind_table, draw_extended_case, insert_glitches,
                              score_drift, score_glitches, score_out_of_candidate, score_unit_slip,
                              slip_units, summarize_kind, write_twin_like_dataset, TwinLikeConfig)


def _diag_factory(make_diagnosis):
    """Diagnoses with what the blind scores read: the identified effects, discovered terms, a drift, skipped files
    and masked glitches."""
    def diag(identified=(), discovered=None, drift=False, amplitude=0.0, skipped=(), params=None, masked=0):
        return make_diagnosis(identified, params=params,
                              calibration={"pressure_amplitude_pa": 3000.0,
                                           "drift": {"detected": drift, "relative_amplitude": amplitude}},
                              remaining_gap={"discovered_terms": discovered or {"yddot": [], "thetaddot": []}},
                              skipped_files=tuple(skipped), glitch_frames_masked=masked)
    return diag


def test_extended_draws_are_seeded():
    for kind in KINDS[1:]:
        a = draw_extended_case(kind, 7, 3)
        assert a == draw_extended_case(kind, 7, 3) and a != draw_extended_case(kind, 8, 3)
        json.dumps(a)  # every hidden choice is stored with the result
    assert {draw_extended_case("out_of_candidate", 0, i)["effect"] for i in range(2)} == set(OUT_OF_CANDIDATE)
    with pytest.raises(ValueError):
        BlindConfig(kinds=("candidates", "typo"))


def test_out_of_candidate_forced_onto_a_candidate_scores_as_forced(make_diagnosis):
    _diag = _diag_factory(make_diagnosis)
    case = draw_extended_case("out_of_candidate", 0, 0)  # cubic hinge
    truth = {"pressure_amplitude_pa": 3000.0}
    right = {"yddot": [], "thetaddot": [{"term": "theta^3", "coefficient": -1.05 * case["strength"]}]}
    good = score_out_of_candidate(case, truth, _diag(discovered=right), None)
    assert not good["forced"] and good["leading_right"]
    assert good["coefficient_relative_error"] == pytest.approx(0.05)
    wrong = {"yddot": [], "thetaddot": [{"term": "theta", "coefficient": -300.0}]}
    bad = score_out_of_candidate(case, truth, _diag(["pair_scattering"], wrong), None)
    assert bad["forced"] and not bad["leading_right"] and bad["coefficient_relative_error"] is None
    s = summarize_kind("out_of_candidate", [good, bad])
    assert s["not_forced_rate"] == 0.5 and s["leading_term_right_rate"] == 0.5
    assert "cubic_hinge" in blind_table({"out_of_candidate": s}, BlindConfig(cases=2))


def test_drift_missed_or_forced_scores_as_such(make_diagnosis):
    _diag = _diag_factory(make_diagnosis)
    case = draw_extended_case("drift", 0, 1)
    truth = {"pressure_amplitude_pa": 3000.0, "relative_half_range": [0.03, 0.03]}
    hit = score_drift(case, truth, _diag(case["effects"], drift=True, amplitude=0.033), None)
    assert hit["drift_detected"] and hit["exact"] and not hit["forced"]
    assert hit["amplitude_relative_error"] == pytest.approx(0.1)
    miss = score_drift(case, truth, _diag(sorted(case["effects"]) + ["velocity_coupling"]), None)
    assert not miss["drift_detected"] and miss["forced"] and not miss["exact"]
    assert summarize_kind("drift", [hit, miss])["detected_rate"] == 0.5


def test_glitch_case_that_loses_accuracy_scores_as_lost(tmp_path, make_diagnosis):
    _diag = _diag_factory(make_diagnosis)
    """Glitches are inserted where the loader can find them (all masked on short twin-like runs), and a glitched
    diagnosis that names an extra effect counts against its clean twin."""
    from cubedimer.dataset import load_dataset

    write_twin_like_dataset(tmp_path, TwinLikeConfig(runs=3, duration=1.0, seed=4))
    assert load_dataset(tmp_path).n_glitches == 0
    inserted = insert_glitches(tmp_path, seed=5)
    assert 9 <= inserted <= 24 and load_dataset(tmp_path).n_glitches == inserted
    case = draw_extended_case("glitches", 0, 0) | {"effects": {"pair_scattering": {"kappa": 1e4}}}
    truth = {"pressure_amplitude_pa": 3000.0}
    clean = _diag(["pair_scattering"], params={"pair_scattering": {"kappa": 1.0e4}})
    worse = _diag(["pair_scattering", "linear_damping"], params={"pair_scattering": {"kappa": 1.3e4}}, masked=inserted)
    r = score_glitches(case, truth, clean, None, worse, None, inserted)
    assert r["accuracy_lost"] and not r["same_identified"] and r["max_parameter_error"] == pytest.approx(0.3)
    same = score_glitches(case, truth, clean, None, clean, None, inserted)
    assert not same["accuracy_lost"] and same["same_identified"]
    s = summarize_kind("glitches", [r, same])
    assert s["accuracy_lost"] == 1 and s["same_identified_rate"] == 0.5


# a t in milliseconds is caught first by the physics bound on the vertical frequency (5-200 Hz), which names it
@pytest.mark.parametrize("slip, word", [("y_micrometres", "micrometres"), ("t_milliseconds", "milliseconds")])
def test_unit_slip_file_is_skipped_by_name(tmp_path, slip, word, make_diagnosis):
    _diag = _diag_factory(make_diagnosis)
    """The loader names the slipped file; a diagnosis that skipped another file (or none) scores as not named."""
    from cubedimer.dataset import load_dataset

    write_twin_like_dataset(tmp_path, TwinLikeConfig(runs=4, duration=1.0, seed=6))
    name = slip_units(tmp_path, slip, 5)
    assert name == "run01.csv"
    skipped = load_dataset(tmp_path).skipped_files()
    assert [s["file"] for s in skipped] == [name] and word in skipped[0]["reason"]
    case = draw_extended_case("unit_slip", 0, 0) | {"slip": slip}
    truth = {"pressure_amplitude_pa": 3000.0}
    good = score_unit_slip(case, truth, _diag(case["effects"], skipped=skipped, params=case["effects"]), None, name)
    assert good["skipped_by_name"] and good["unit_named"] and good["exact"]
    bad = score_unit_slip(case, truth, _diag(case["effects"], skipped=[{"file": "run02.csv", "reason": word}],
                                             params=case["effects"]), None, name)
    assert not bad["skipped_by_name"] and not bad["unit_named"]
