"""Every sentence of the report true: frequencies with their resolution, statistics stated as bounds where they are
bounds, no JSON keys in prose, no sentence about effects or an origin that are not there, agreement verdicts with
the uncertainty behind them, and each numeric claim equal to numbers.json."""
import html
import json
import re

import numpy as np
import pytest

from cubedimer.spectra import peak_frequency
from validation.diagnosis.statistics import format_p
from validation.report.diagnosis_section import diagnosis_section


def test_p_values_are_bounds_below_double_precision():
    assert format_p(0.0) == "p < 1e-16" and format_p(3e-20) == "p < 1e-16"
    assert format_p(0.0123) == "p = 0.012" and format_p(0.5, 3) == "p = 0.5"


def test_a_short_record_gives_a_zero_padded_peak_and_its_resolution():
    """A 1.68-Hz hinge over 1.5 s (2.5 periods; bins 0.67 Hz apart, so the bin centres nearest are 1.33 and 2.0 Hz).
    The zero-padded peak is not pinned to a bin: within 0.1 Hz (the Hann window's leakage from the mean-removed
    slow end of 2.5 periods shifts it by a few per cent), and the resolution 1/T is returned beside it."""
    dt = 1 / 2000
    t = np.arange(3000) * dt
    f, resolution = peak_frequency(0.2 * np.cos(2 * np.pi * 1.68 * t + 0.4), dt)
    assert resolution == pytest.approx(1 / 1.5)
    assert abs(f - 1.68) < 0.1
    f_y, _ = peak_frequency(1e-4 * np.cos(2 * np.pi * 21.83 * t), dt)
    assert abs(f_y - 21.83) < 0.01  # 33 periods: the parabolic refinement is good to ~1 % of a padded bin


def _diagnosis(identified=(), p_drift=0.3, drift_amplitude=0.0, statement="the calibrated simulation explains the "
               "data within its derivative noise"):
    effects = [{"name": n, "params": {"kappa": 15000.0}, "gap_after": 0.01, "shrink": 0.9, "significant": True,
                "p_value": 0.004} for n in identified]
    return {"identified": list(identified), "effects": effects, "gap_before": 0.3, "gap_after": 0.01 if identified else 0.3,
            "noise_floor": 0.003, "gap_per_run": {"runs": ["a", "b", "c", "d"]},
            "calibration": {"pressure_amplitude_pa": 3010.0, "pressure_ratio": 1.0033,
                            "y_origin_above_nominal_Z_eq_m": 2e-7,
                            "drift": {"tested": True, "detected": False, "p_value": p_drift, "alpha": 1e-6,
                                      "relative_amplitude": drift_amplitude, "min_relative_amplitude": 0.005}},
            "remaining_gap": {"statement": statement, "discovered_terms": {}}, "settings": {}, "skipped_files": [],
            "data_warnings": []}


def test_no_sentence_about_identified_effects_when_there_are_none():
    reading = diagnosis_section(_diagnosis(), []).reading
    assert "With them" not in reading and "identified effects" not in reading
    assert "No candidate effect improves held-out runs significantly." in reading
    reading = diagnosis_section(_diagnosis(identified=["pair_scattering"]), []).reading
    assert "With them the gap is 1.0 %" in reading  # numbers.json gap_after 0.01


def test_a_significant_but_negligible_drift_is_not_called_no_drift():
    """An F-test p below double precision on a drift below the threshold that counts: both are said, as bounds."""
    reading = diagnosis_section(_diagnosis(p_drift=0.0, drift_amplitude=0.001), []).reading
    assert "No drift" not in reading and "p = 0" not in reading
    assert "varies within runs by 0.1 %, below the 0.5 % counted as a drift (F-test p < 1e-16)" in reading
    assert "No drift of the pressure within runs (F-test p = 0.3)" in diagnosis_section(_diagnosis(), []).reading


# ------------------------------------------------------------------------------- the report on small data sets
def _twin(path, runs, duration, effects):
    from acousim.effects import EffectSet
    from acousim.twin import DropProtocol, TwinConfig, simulate_dataset

    # no air damping: the cases' effects are the only ones ("damping-free" is the inviscid dimer)
    cfg = TwinConfig(runs=runs, duration=duration, seed=4, effects=EffectSet.from_dict(effects), air_damping=False,
                     protocol=DropProtocol(theta_drop=(-0.2, 0.2), thetadot_drop=(-2.0, 2.0)))
    simulate_dataset(cfg, path, progress=False)
    (path / "truth.json").rename(path.parent / "truth.json")
    return path


CASES = {
    # the suite's own 4 runs of 1.5 s without damping: nothing can be identified with 4 runs
    "damping-free": (4, 1.5, {}),
    # 7 runs (the fewest the held-out test can identify with at alpha 0.01) with pair scattering
    "pair scattering": (7, 1.0, {"pair_scattering": {"kappa": 15000.0}}),
}


@pytest.fixture(scope="module", params=list(CASES))
def report(request, tmp_path_factory):
    from validation.report import build_report

    runs, duration, effects = CASES[request.param]
    base = tmp_path_factory.mktemp("true_sentences")
    data = _twin(base / "data", runs, duration, effects)
    path = build_report(data, base / "report", workers=1, progress=False, max_evals=60)
    text = path.read_text()
    readings = {sid: html.unescape(r) for sid, r in re.findall(
        r'<section id="([^"]+)">.*?<p class="reading">(.*?)</p>', text, re.S)}
    numbers = json.loads((base / "report" / "numbers.json").read_text())
    # the second case must exercise the sentences about identified effects
    assert bool(numbers["diagnosis"]["identified"]) == bool(effects), numbers["diagnosis"]["identified"]
    return readings, numbers, text


def _number(pattern, text):
    m = re.search(pattern, text)
    assert m, (pattern, text[:400])
    return float(m.group(1))


@pytest.mark.slow
def test_each_numeric_claim_is_the_number_in_numbers_json(report):
    readings, numbers, _ = report
    data = numbers["data"]
    d = readings["data"]
    # frequencies: zero-padded peaks with the resolution, as in numbers.json (2 decimals in the prose)
    assert _number(r"spectrum peaks at a median ([\d.]+) Hz", d) == pytest.approx(data["median_f_y_hz"], abs=0.005)
    assert _number(r"hinge's spectrum peaks at a median ([\d.]+) Hz", d) == pytest.approx(data["median_f_theta_hz"],
                                                                                          abs=0.005)
    assert _number(r"resolve ([\d.]+) Hz", d) == pytest.approx(data["frequency_resolution_hz"], rel=0.01)
    diag, g = numbers["diagnosis"], readings["diagnosis"]
    assert _number(r"leaves ([\d.]+) % of the acceleration variance", g) == pytest.approx(100 * diag["gap_before"],
                                                                                           abs=0.05)
    assert _number(r"noise floor ([\d.]+) %", g) == pytest.approx(100 * diag["noise_floor"], abs=0.05)
    assert _number(r"Calibrated pressure ([\d.]+) Pa", g) == pytest.approx(diag["pressure_amplitude_pa"], abs=0.5)
    if diag["identified"]:
        assert _number(r"With them the gap is (-?[\d.]+) %", g) == pytest.approx(100 * diag["gap_after"], abs=0.05)
        for name, params in diag["effects"].items():
            for p, v in params.items():
                assert float(re.search(rf"{name} \([^)]*{p} = ([-\d.e+]+)", g).group(1)) == pytest.approx(v, rel=5e-3)
    else:
        assert "With them" not in g and "identified effects" not in g
    sim = numbers["simulation"]
    assert _number(r"calibrated pressure ([\d.]+) Pa", readings["simulation"]) == pytest.approx(
        sim["calibrated_pressure_pa"], abs=0.5)


@pytest.mark.slow
def test_no_json_keys_no_false_bounds_and_verdicts_with_their_uncertainty(report):
    readings, numbers, text = report
    prose = " ".join(readings.values())
    assert not re.search(r"\b[a-z]+(_[a-z]+)*\.[a-z_]+\b(?<!\.md)", re.sub(r"docs/\w+\.md|\d+\.\d+|e\.g\.|i\.e\.", "",
                                                                           prose)), "a JSON key path in the prose"
    assert not re.search(r"\bp = 0(?![.\d])", prose)
    assert "user-given" not in prose  # the report's origin comes from the calibration
    cmp = numbers["model-vs-simulation"]
    for row in cmp["terms"]:
        if row["within_uncertainty"] is None:
            continue
        # "within n sigma: no" only with the deviation shown above n sigma, "yes" at or below
        assert (row["deviation_sigma"] <= cmp["n_sigma"]) == row["within_uncertainty"], row
    assert "<th>deviation [combined sigma]</th>" in text


@pytest.mark.slow
def test_the_minimal_model_agrees_with_the_stated_selection_rule(report):
    readings, numbers, _ = report
    eqs = numbers["fit"]["equations"]
    damping = [t for eq, t in (("yddot", "ydot"), ("thetaddot", "thetadot")) if t in eqs[eq]]
    if damping:  # kept whatever their z: the text must say so
        assert "kept as physical damping whatever their significance" in readings["fit"]
