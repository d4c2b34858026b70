"""The report's first screen and the sentences beside its tables, each against the numbers it reads: the causes with
their uncertainty and shrink, the constants and where they came from, every data warning, which force model fits and
why, too few runs said first, a hinge a model does not hold, a long-time penalty said as what it is, and what each
compared simulation was given and fits."""
import dataclasses

import pytest

from validation.diagnosis import Diagnosis, EffectVerdict
from validation.diagnosis.summarise.uncertainty import ParameterInterval


def _diagnosis(effects=(), identified=(), n_runs=8, gap_before=0.286, gap_after=1.1e-5, warnings=(), **extra):
    settings = {"alpha": 0.01, "smallest_attainable_p": 0.5 ** n_runs, "identification_possible": 0.5 ** n_runs <= 0.01,
                "runs_needed": 7}
    return Diagnosis(model="gorkov", simulation={}, identified=tuple(identified), indistinguishable=(),
                     model_effects=tuple(e.name for e in effects if e.significant), dropped_by_backward_check=(),
                     greedy_identified=tuple(identified),
                     calibration={"pressure_amplitude_pa": 3000.6, "pressure_ratio": 1.0002,
                                  "y_origin_above_nominal_Z_eq_m": 2.3e-7},
                     gap_before=gap_before, gap_after=gap_after, gap_definition="", gap_components=(),
                     gap_component_forms={}, gap_per_run={"runs": [f"run{i}" for i in range(n_runs)]},
                     noise_floor=6.3e-4, noise_floor_note="", effects=tuple(effects), localization={}, long_time={},
                     remaining_gap={"statement": "a gap remains that no candidate effect explains; the localization "
                                                 "lists the library terms", "discovered_terms": {}},
                     identification_rounds=(), data_warnings=tuple(warnings), settings=settings, **extra)


def _named(name, params, gap_after, round_, std=None):
    unc = None if std is None else {p: ParameterInterval(v, std[p], (v - 2 * std[p], v + 2 * std[p]), 7)
                                    for p, v in params.items()}
    return EffectVerdict(name, params, gap_after, 0.0, True, 0.004, None, None, added_in_round=round_, named=True,
                         uncertainty=unc)


def test_the_causes_carry_their_uncertainty_and_how_far_the_gap_shrinks():
    """The demo's three causes: each with its parameters +- the jackknife standard error and the gap without and with
    it (the first from the calibrated simulation's 0.286), in the order added."""
    from validation.report.sections.answer import cause_rows, causes_text

    effects = [_named("pair_scattering", {"kappa": 19502.3}, 0.0016970, 1, {"kappa": 25.0}),
               _named("mirror_asymmetry", {"beta1": 999752.1}, 0.0014998, 2, {"beta1": 3000.0}),
               _named("linear_damping", {"gamma_y": 0.10106}, 1.1e-5, 3, {"gamma_y": 0.002})]
    diag = _diagnosis(effects, [e.name for e in effects])
    rows = cause_rows(diag)
    assert [r[0] for r in rows] == ["pair_scattering", "mirror_asymmetry", "linear_damping"]
    assert rows[0][1] == f"kappa = {effects[0].estimate('kappa').format()}" and "+-" in rows[0][1]
    assert rows[0][2:4] == [0.286, 0.0016970] and rows[1][2:4] == [0.0016970, 0.0014998]
    assert rows[0][4] == pytest.approx(1 - 0.0016970 / 0.286)
    text = causes_text(diag)
    assert text.startswith("The calibrated simulation alone leaves a gap of 0.286")
    assert f"pair_scattering (kappa = {effects[0].estimate('kappa').format()}; the gap 0.286 -> 0.0017)" in text
    assert "With them the gap is 1.1e-05." in text


def test_too_few_runs_is_said_first_and_no_candidate_is_said_to_fail():
    """With 4 runs (the old video demo) the held-out test's smallest p is 1/16 > 0.01: the answer starts with how many
    runs to record, and neither it nor section 6 says "no candidate effect explains" the gap."""
    from validation.report.sections.answer import causes_text
    from validation.report.sections.gap_diagnosis import diagnosis_section

    diag = _diagnosis(n_runs=4, gap_after=0.286)
    text = causes_text(diag)
    assert text.startswith("With 4 runs no effect can be named: the held-out test's smallest p is 0.0625, above "
                           "alpha = 0.01; record at least 7 runs.")
    reading = diagnosis_section(diag, []).reading
    assert "record at least 7 runs" in reading
    assert "no candidate effect explains" not in reading.lower() and "No candidate effect improves" not in reading
    # with 8 runs the same gap is a verdict: no candidate improves held-out runs
    assert "No candidate effect improves held-out runs" in diagnosis_section(_diagnosis(gap_after=0.286), []).reading


def test_too_few_runs_is_a_data_warning_of_the_diagnosis():
    from types import SimpleNamespace

    from validation.diagnosis.summarise.constants import data_set_warnings

    settings = {"identification_possible": False, "smallest_attainable_p": 0.0625, "alpha": 0.01, "runs_needed": 7}
    warnings = data_set_warnings(SimpleNamespace(meta={}), 4, settings)
    assert [w["code"] for w in warnings] == ["too_few_runs"]
    assert "with 4 runs no effect can be named" in warnings[0]["message"] and "record at least 7 runs" in \
        warnings[0]["message"]
    assert data_set_warnings(SimpleNamespace(meta={}), 8, {"identification_possible": True}) == []


def test_a_run_split_at_a_tracking_gap_is_a_data_warning():
    from types import SimpleNamespace

    from validation.diagnosis.summarise.constants import data_set_warnings

    runs = [SimpleNamespace(name="run01.csv", source=None),
            SimpleNamespace(name="run03_part1.csv", source="run03.csv", frames=(0, 500)),
            SimpleNamespace(name="run03_part2.csv", source="run03.csv", frames=(700, 2000))]
    (w,) = data_set_warnings(SimpleNamespace(meta={}, runs=runs), 3, {"identification_possible": True})
    assert w == {"code": "run_split", "message": "run03.csv split at a tracking gap longer than the fill limit into "
                                                 "run03_part1.csv (frames 0-499), run03_part2.csv (frames 700-1999)"}


def test_a_misspelt_meta_key_is_a_data_warning_with_the_key_it_misspells():
    """The lab's side_lenght_m: a data warning naming side_length_m (in diagnosis.json and on the first screen), and
    the default side is stated as a default among the constants."""
    from types import SimpleNamespace

    from acousim.models import ModelSpec
    from validation.diagnosis.summarise.constants import constants_used, data_set_warnings
    from validation.report.sections.answer import constant_rows, data_warnings

    meta = {"side_lenght_m": 450e-6, "frequency_hz": 42000.0}
    (warning,) = data_set_warnings(SimpleNamespace(meta=meta), 8, {"identification_possible": True})
    assert warning["code"] == "meta_unknown_keys" and "did you mean 'side_length_m'?" in warning["message"]
    cal = {"pressure_amplitude_pa": 3001.0, "uncertainty": {"pressure_amplitude_pa": {"std_error": 12.0}}}
    constants = constants_used(meta, ModelSpec(), cal)
    diag = _diagnosis(warnings=[warning], constants=tuple(constants),
                      skipped_files=({"file": "run09.csv", "reason": "200 consecutive missing values"},),
                      glitch_frames_masked=3)
    rows = {r[0]: r for r in constant_rows(diag)}
    assert rows["cube side"][1:3] == [pytest.approx(500.0), "um"] and "default" in rows["cube side"][4]
    assert rows["drive frequency"][1] == 42000.0 and "meta.json" in rows["drive frequency"][4]
    assert rows["calibrated pressure amplitude"][1:4] == [3001.0, "Pa", 12.0]
    said = data_warnings(diag, {"skipped_files": []})
    assert any("side_length_m" in w for w in said)
    assert "run09.csv skipped: 200 consecutive missing values" in said
    assert any(w.startswith("3 tracking-glitch frames masked") for w in said)


def test_a_calibrated_hinge_gap_is_a_constant_with_its_error_and_source():
    from acousim.models import ModelSpec
    from validation.diagnosis.summarise.constants import constants_used

    cal = {"pressure_amplitude_pa": 2824.3, "gap_m": 41.2e-6, "gap_calibrated": True, "gap_std_m": 0.3e-6,
           "gap_note": "calibrated from the hinge motion", "uncertainty": {"gap_m": {"std_error": 0.3e-6}}}
    by_key = {c["key"]: c for c in constants_used({}, ModelSpec("fullwave"), cal)}
    assert by_key["gap_m"]["source"] == "calibrated" and by_key["gap_m"]["std_error"] == 0.3e-6
    given = {c["key"]: c for c in constants_used({}, ModelSpec("fullwave", {"gap_m": 40e-6}),
                                                 {**cal, "gap_m": 40e-6, "gap_calibrated": False})}
    assert given["gap_m"]["source"] == "option" and given["gap_m"]["value"] == 40e-6


@pytest.mark.parametrize("theta_gap, said, not_said", [
    # the lab's full-wave theta equation of 1.557: worse than predicting no hinge acceleration, never "holds the hinge"
    (1.557, "does not hold these data's hinge: its theta equation leaves 1.56 of the hinge accelerations' variance "
            "unexplained, more than predicting no hinge acceleration at all would (1)", "holds the hinge with"),
    (0.4, "explains part of the hinge motion: its theta equation leaves 0.4", "does not hold"),
    (0.02, "it holds the hinge with no fitted stiffness: its theta equation leaves 0.02", "does not hold"),
])
def test_a_model_is_said_to_hold_the_hinge_only_when_its_theta_equation_does(theta_gap, said, not_said):
    from validation.report.sections.simulated_forces import hinge_reading

    text = hinge_reading("full wave", theta_gap, "Gor'kov", 0.853, 0.00143)
    assert said in text and not_said not in text
    # why, beside it: the reference model alone and with the fitted pair scattering
    assert "the Gor'kov model leaves 0.853, and 0.00143 with the pair scattering fitted" in text
    # a reference gap below the subtracted noise floor (the 4-run twin's -4.16e-05) is never a negative number
    below = hinge_reading("full wave", theta_gap, "Gor'kov", -4.16e-5, -4.1e-5)
    assert "the Gor'kov model leaves below the noise floor, and below the noise floor with the pair" in below
    assert "-4" not in below


def test_a_long_time_penalty_is_said_as_what_it_is():
    """The Gor'kov model alone scored 1714 where "about 1 for no motion" stood beside it: its simulation stops where
    the cube faces touch in 7 of 8 runs, and the lost frames are a penalty, not a distance."""
    from types import SimpleNamespace

    from validation.report.sections.scattering import long_time_value

    stopped = SimpleNamespace(long_time_total=1714.5, long_time_stopped=(7, 8, "theta reached +-1 (the cube faces touch)"))
    assert long_time_value(stopped) == ("1.71e+03: the simulation stops early in 7 of 8 runs (theta reached +-1 (the cube "
                                        "faces touch)); a penalty for the lost frames, worse than no motion")
    assert long_time_value(SimpleNamespace(long_time_total=0.343, long_time_stopped=None)) == 0.343
    # the full wave's 201.8 on the 4-run twin, with every run simulated to its end: far from the data, said so
    assert long_time_value(SimpleNamespace(long_time_total=201.8, long_time_stopped=None)) == (
        "202: worse than no motion (the simulated motion lies far from the data's attractor)")


def test_each_simulation_says_what_it_was_given_and_what_it_fits():
    from validation.report.sections.scattering import model_description

    assert model_description("gorkov", "gorkov") == ("given the experiment's constants; fits the pressure amplitude and "
                                                      "the height origin")
    assert model_description("gorkov+pair_scattering", "gorkov").endswith(
        "fits the pressure amplitude and the height origin, and the pair scattering stiffness kappa")
    full = model_description("fullwave", "gorkov", {"gap_m": (41.2e-6, "calibrated")})
    assert full == ("given the experiment's constants, the hinge gap 41.20 um (calibrated); fits the pressure amplitude "
                    "and the height origin; no fitted stiffness: its hinge comes from its own physics")


def test_which_force_model_fits_and_why():
    """One sentence per compared simulation from its gap components (the demo's rows)."""
    from types import SimpleNamespace

    from validation.diagnosis.summarise.model_comparison import ModelGap
    from validation.report.sections.answer import model_sentences

    rows = [ModelGap("gorkov", 3000.6, 1e-8, (8.5e-5, 0.853, 0.0045), 0.286, 1714.5),
            ModelGap("gorkov+pair_scattering", 3000.6, 1e-8, (8.5e-5, 0.00143, 0.0036), 0.0017, 0.343,
                     {"pair_scattering": {"kappa": 19320.0}}),
            ModelGap("fullwave", 2824.3, -1.5e-6, (2.8e-4, 1.146, 0.0072), 0.384, 0.5)]
    context = SimpleNamespace(models=SimpleNamespace(rows=rows), diagnosis=SimpleNamespace(noise_floor=6.3e-4),
                              unavailable=lambda: {})
    gorkov, scattering, full = model_sentences(context)
    assert gorkov == "Gor'kov: gap 0.286; it misses the hinge: its theta equation leaves 0.853 unexplained (y equation 8.5e-05)."
    assert scattering.startswith("Gor'kov + fitted pair scattering: gap 0.0017; it fits")
    assert full.startswith("full wave (no fitted stiffness): gap 0.384; it does not fit the hinge: its theta equation "
                           "leaves 1.15")


def test_stored_comparison_rows_read_back():
    from validation.diagnosis.summarise.model_comparison import ModelComparison, ModelGap

    rows = [ModelGap("gorkov", 3000.6, 1e-8, (8.5e-5, 0.853, 0.0045), 0.286, 1714.5, {},
                     (7, 8, "theta reached +-1 (the cube faces touch)")),
            ModelGap("gorkov+pair_scattering", 3000.6, 1e-8, (8.5e-5, 0.00143, 0.0036), 0.0017, 0.343,
                     {"pair_scattering": {"kappa": 19320.0}})]
    doc = ModelComparison(rows, {}, {}, {"fullwave": "outside the table"}).to_dict()
    back = ModelComparison.from_dict(doc)
    assert back.rows == rows and back.unavailable == {"fullwave": "outside the table"}
    assert back.to_dict() == doc


def test_a_stored_diagnosis_keeps_its_report_records():
    """diagnosis.json's new keys (constants, model_comparison, overlay, data_set) survive a round trip, and a document
    written before them still reads (they are additive)."""
    diag = _diagnosis(constants=({"key": "frequency_hz", "value": 45650.0},), model_comparison={"rows": []},
                      overlay={"run": "run01.csv"}, data_set={"path": "/data", "meta": {}})
    doc = diag.to_json()
    assert list(doc)[-4:] == ["constants", "model_comparison", "overlay", "data_set"]
    assert Diagnosis.from_json(doc) == diag
    old = {k: v for k, v in doc.items() if k not in ("constants", "model_comparison", "overlay", "data_set")}
    assert Diagnosis.from_json(old).model_comparison is None


@pytest.mark.parametrize("broken, message", [
    ("missing", "diagnosis.json: missing"),
    ("not json", "diagnosis.json: unreadable"),
    ("diagnose", "no model_comparison, data_set: not written by `python -m validation report`"),
])
def test_a_report_from_stored_results_refuses_a_missing_or_unreadable_file_in_one_line(tmp_path, capsys, broken,
                                                                                      message):
    """``validation report --from DIR``: one line naming the file and what to do, exit 2, nothing written."""
    import json

    from validation.cli import main

    if broken == "not json":
        (tmp_path / "diagnosis.json").write_text("{not json")
    elif broken == "diagnose":  # a diagnosis.json of `validation diagnose`: no report records
        (tmp_path / "diagnosis.json").write_text(json.dumps(dataclasses.replace(_diagnosis()).to_json()))
    before = sorted(p.name for p in tmp_path.iterdir())
    assert main(["report", "--from", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and "\n" not in err and "Traceback" not in err
    assert sorted(p.name for p in tmp_path.iterdir()) == before  # nothing partial
