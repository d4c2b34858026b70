"""The diagnosis on digital-twin data sets: each single effect, none, and a partly corrupt data set (causes
outside the candidates: test_drift.py and test_discovery.py)."""
import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from validation.diagnosis import EXPLAINED_GAP, DiagnoseConfig, Diagnosis, diagnose_dataset

#: single effects at moderate strength (velocity coupling in the middle of the blind range of
#: validation.blind.STRENGTHS; the theta equation is fitted in its integral form, whose noise is the
#: tracking noise itself, see docs/diagnosis.md)
SINGLE = {
    "linear_damping": {"gamma_y": 1.5, "gamma_theta": 1.5},
    "quadratic_drag": {"c_y": 200.0, "c_theta": 0.3},
    "pair_scattering": {"kappa": 15000.0},
    "mirror_asymmetry": {"beta0": 10.0, "beta1": 3.0e4},  # beta0/omega_theta^2 = 0.09 on the soft hinge
    "velocity_coupling": {"c5": 5.0e3, "c6": 1.0e6},  # measured: c5 +3 %, c6 -5 %, p = 0.006
}


def _twin(cache, effects, seed=3, pressure_error=0.06, runs=10, duration=3.0):
    """The twin data set (its folder in the pipeline cache: read it, never write into it) and its truth."""
    from acousim.dynamics.effects import EffectSet
    from acousim.twin import DropProtocol, TwinConfig

    # drops of moderate angle and rate: the soft Gor'kov hinge plus an effect must not reach theta = +-1; no air
    # damping: the drawn effect is the only one, so the diagnosis must name it alone (and nothing on no effect)
    cfg = TwinConfig(runs=runs, duration=duration, seed=seed, pressure_error=pressure_error,
                     effects=EffectSet.from_dict(effects), air_damping=False,
                     protocol=DropProtocol(theta_drop=(-0.2, 0.2), thetadot_drop=(-2.0, 2.0)))
    data = cache.twin_dataset(cfg)  # truth.json beside the data set: the diagnosis is blind
    return data, json.loads((data.parent / "truth.json").read_text())


#: the two corrupt files added to the pair-scattering data set (test_partly_corrupt_dataset): a copy of its first run
#: whose time goes backwards (lines 20-49 again after line 50), and a file without a theta column
CORRUPT_FILES = ("run11.csv", "run12.csv")


def _partly_corrupt_twin(cache):
    """The pair-scattering twin data set with :data:`CORRUPT_FILES` beside its ten runs (in the pipeline cache: read
    it, never write into it), and its truth."""
    clean, truth = _twin(cache, {"pair_scattering": SINGLE["pair_scattering"]})

    def build(folder):
        data = Path(shutil.copytree(clean, folder / "data"))
        text = (data / "run01.csv").read_text().splitlines()
        (data / CORRUPT_FILES[0]).write_text("\n".join([text[0]] + text[1:50] + text[20:]) + "\n")  # time goes backwards
        (data / CORRUPT_FILES[1]).write_text("t,y\n0,0\n")  # no theta column

    return cache.folder("partly-corrupt-twin", f"{clean.parent.name} {CORRUPT_FILES}", build) / "data", truth


def _diagnosis(cache, data, config):
    """The diagnosis of a cached twin data set (made once per version of the sources, tests/conftest.py)."""
    return cache.value("diagnosis", f"{data.parent.name} {config!r}",
                       lambda: diagnose_dataset(data, config, progress=False))


FAST = DiagnoseConfig(long_time=False)


@pytest.mark.slow
@pytest.mark.parametrize("name", list(SINGLE))
def test_single_effect_identified_with_parameters(pipeline_cache, name):
    # pair scattering's ten runs come with two corrupt files beside them, which the diagnosis skips: the one diagnosis
    # of test_partly_corrupt_dataset
    data, truth = (_partly_corrupt_twin(pipeline_cache) if name == "pair_scattering"
                   else _twin(pipeline_cache, {name: SINGLE[name]}))
    diag = _diagnosis(pipeline_cache, data, FAST)
    assert diag.identified == (name,)
    assert not diag.calibration["drift"]["detected"]  # no false alarm at a constant pressure with an effect
    fitted = next(e for e in diag.effects if e.name == name).params
    for p, v in SINGLE[name].items():
        # acceptance: parameters within 25 %
        assert abs(fitted[p] - v) <= 0.25 * abs(v), (p, fitted[p], v)
    # the calibrated pressure recovers the hidden pressure error (Savitzky-Golay bias ~1 %, see docs)
    np.testing.assert_allclose(diag.calibration["pressure_amplitude_pa"], truth["pressure_amplitude_pa"], rtol=0.02)
    if diag.gap_before > EXPLAINED_GAP:
        assert diag.gap_after < 0.3 * diag.gap_before
    else:
        # a gap already below the "explained" level lies within the estimate of the noise floor, where a
        # shrink ratio means nothing (velocity coupling at 5e3 / 1e6: 1.2e-4 -> 5.4e-5): it must not grow
        assert diag.gap_after <= diag.gap_before and diag.remaining_gap["explained_within_noise"]


@pytest.mark.slow
def test_no_effect_names_nothing(pipeline_cache):
    data, truth = _twin(pipeline_cache, {}, seed=5)
    diag = _diagnosis(pipeline_cache, data, FAST)
    assert diag.identified == ()
    assert diag.remaining_gap["explained_within_noise"]
    assert not diag.calibration["drift"]["detected"]
    assert diag.remaining_gap["discovered_terms"] == {"yddot": [], "thetaddot": []}
    # twin runs carry integral data: the theta component is computed, and described, in its integral form
    assert diag.gap_component_forms == {"yddot": "acceleration", "thetaddot": "integral", "energy": "energy balance"}
    assert "thetaddot (integral form)" in diag.gap_definition


@pytest.mark.slow
def test_partly_corrupt_dataset(pipeline_cache):
    """The single-effect case's data set with two corrupt files beside its ten runs: the two are skipped, each with its
    reason, and the ten runs diagnosed (pair scattering named with its parameter:
    test_single_effect_identified_with_parameters reads the same diagnosis)."""
    data, _ = _partly_corrupt_twin(pipeline_cache)
    diag = _diagnosis(pipeline_cache, data, FAST)
    assert diag.identified == ("pair_scattering",)
    assert len(diag.skipped_files) == 2
    assert set(CORRUPT_FILES) == {s["file"] for s in diag.skipped_files}  # docs/formats.md: {file, reason}
    assert all(s["reason"] for s in diag.skipped_files)
    assert len(diag.gap_per_run["runs"]) == 10
    # diagnosis.json round trip: the typed result reads back its own document, key for key and value for value
    doc = json.loads(json.dumps(diag.to_json()))
    assert list(doc)[:3] == ["model", "simulation", "identified"]
    assert Diagnosis.from_json(doc).to_json() == doc
    assert Diagnosis.from_json(doc) == diag  # equal fields (internals are not compared)
    assert diag.effect("pair_scattering") is diag.effects[0] and diag.effect("pair_scattering").named
    with pytest.raises(KeyError):
        diag.effect("not_a_candidate")


def test_diagnose_cli_bad_directory(tmp_path, capsys):
    """The command's entry point in this process (``python -m validation`` itself runs in
    tests/validation/test_coefficients.py): exit 2, one line naming the folder, nothing written."""
    from validation.cli import main

    assert main(["diagnose", str(tmp_path / "nope"), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "nope" in err
    assert not (tmp_path / "o").exists()


@pytest.mark.slow
def test_strong_velocity_coupling_identified(pipeline_cache):
    """Strong coupling (c5 = 3e4, c6 = 6e6, six times the single-effect case): identified alone, measured
    c5 +13 %, c6 -11 % (asserted at the acceptance level of 25 %).  The bias grows with the strength (+3 % / -5 % at
    5e3 / 1e6): the hinge columns are evaluated at theta smoothed over half a hinge period, which
    leaves out the fast response the coupling itself drives.  At 1.5e4 / 3e6 this bias makes the diagnosis name
    pair_scattering after velocity_coupling (a known limitation, measured by ``make bench``:
    benchmarks/bench_diagnosis.py)."""
    effects = {"velocity_coupling": {"c5": 3.0e4, "c6": 6.0e6}}
    data, _ = _twin(pipeline_cache, effects)
    diag = _diagnosis(pipeline_cache, data, FAST)
    assert diag.identified == ("velocity_coupling",)
    fitted = diag.effects[0].params
    for p, v in effects["velocity_coupling"].items():
        assert abs(fitted[p] - v) <= 0.25 * abs(v), (p, fitted[p], v)


@pytest.mark.slow
def test_diagnose_cli_writes_diagnosis_report_and_logs_progress(tmp_path, pipeline_cache, capsys):
    """The command end to end on a small twin data set (its entry point in this process, which configures the logging
    as ``python -m validation`` does: tests/validation/test_coefficients.py runs that): diagnosis.json with the
    docs/formats.md keys, the report section with its figures, and the progress logged on stderr."""
    from validation.cli import main

    data, _ = _twin(pipeline_cache, {"pair_scattering": {"kappa": 15000.0}}, runs=3, duration=2.0)
    out = tmp_path / "out"
    code = main(["diagnose", str(data), "--out", str(out), "--candidates", "pair_scattering", "--no-long-time"])
    r = capsys.readouterr()
    assert code == 0, r.err
    doc = json.loads((out / "diagnosis.json").read_text())
    assert {"identified", "calibration", "gap_before", "gap_after", "effects", "localization", "skipped_files",
            "remaining_gap", "gap_definition", "gap_components"} <= set(doc)
    diag = Diagnosis.from_json(doc)
    assert [e.name for e in diag.effects] == ["pair_scattering"]
    assert (out / "report.html").exists()
    assert {p.name for p in (out / "figures").iterdir()} >= {"gap_by_effect.png", "residual_maps.png", "residual_terms.png"}
    assert "[validation.diagnosis.steps] 3 runs; calibrating" in r.err
    assert "[validation.diagnosis.identify.identification] testing pair_scattering on top of calibration" in r.err
    # three runs cannot make any held-out test significant (smallest one-sided p 2^-3 = 0.125 > alpha 0.01):
    # the command says so, and the file records it, instead of a bare "identified: none"
    assert diag.identified == ()
    assert diag.settings["smallest_attainable_p"] == 0.125
    assert diag.settings["identification_possible"] is False and diag.settings["runs_needed"] == 7
    assert "with 3 runs no effect can be identified at --alpha 0.01" in r.err
    assert "record at least 7 runs" in r.err
    page = (out / "report.html").read_text()
    assert "With 3 runs no effect can be named" in page and "record at least 7 runs" in page
