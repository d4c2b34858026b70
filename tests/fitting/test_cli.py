"""End-to-end CLI on a small synthetic data set: outputs, resume, bad input, compare."""
import json
import subprocess
import sys

import pytest

from fitting.cli import main

FAST = ["--method", "paper", "--max-evals", "40", "--joint-max-evals", "40", "--workers", "2", "--quiet"]


@pytest.fixture(scope="module")
def fitted(small_dataset, tmp_path_factory):
    out = tmp_path_factory.mktemp("fit_out")
    assert main(["fit", str(small_dataset), "--out", str(out), *FAST]) == 0
    return out


def test_fit_writes_model_json_and_plots(fitted):
    d = json.loads((fitted / "model.json").read_text())
    assert d["state"] == ["y", "ydot", "theta", "thetadot"] and d["units"] == "SI"
    assert set(d["zscores"]) == {"yddot", "thetaddot"} and len(d["zscores"]["yddot"]) == 35
    assert [r["file"] for r in d["per_run"]] == ["run01.csv", "run02.csv", "run03.csv"]
    assert "ydot" in d["equations"]["yddot"] and "thetadot" in d["equations"]["thetaddot"]  # damping kept
    assert d["method"] == "paper" and d["selection"]["rule"] == "significance" and "discovery" not in d
    # a paper fit records the shared stages and its own settings, under its name
    assert set(d["settings"]) == {"load", "smoothing", "classify", "method", "paper"}
    assert "polish" not in d["settings"]["paper"] and d["settings"]["paper"]["selection"]["rule"] == "significance"
    for p in ("zscores.png", "coefficients.png", "optimisation.png", "phase_portraits.png", "poincare.png"):
        assert (fitted / p).stat().st_size > 1000


def test_model_json_records_the_box_the_data_span(small_dataset, fitted):
    """``data_range`` is the largest |theta| and |y| of the runs the fit saw (what ``validation compare`` fits the
    static coefficients over): the loader's runs, exactly."""
    from cubedimer import load_dataset

    runs = load_dataset(small_dataset).runs
    rng = json.loads((fitted / "model.json").read_text())["data_range"]
    assert rng == {"theta_abs_max": max(float(abs(r.theta).max()) for r in runs),
                   "y_abs_max_m": max(float(abs(r.y).max()) for r in runs)}
    assert 0.05 < rng["theta_abs_max"] < 0.9 and 1e-5 < rng["y_abs_max_m"] < 1e-3  # a dimer's range, in SI units
    # and the dimer the data are of: no meta.json, so every constant is docs/conventions.md's default
    dimer = json.loads((fitted / "model.json").read_text())["dimer"]
    assert dimer["side_length_m"] == 500e-6 and dimer["frequency_hz"] == 45650.0 and dimer["from_meta_json"] == []


def test_fit_resumes_from_cached_runs(small_dataset, fitted, capsys):
    before = {p.name: p.stat().st_mtime_ns for p in (fitted / "runs").glob("*.json")}
    assert len(before) == 3
    assert main(["fit", str(small_dataset), "--out", str(fitted), "--no-plots", *FAST]) == 0
    after = {p.name: p.stat().st_mtime_ns for p in (fitted / "runs").glob("*.json")}
    assert before == after
    assert "3 of 3 run refinements loaded" in capsys.readouterr().err


def test_bad_input_clear_error_no_output(tmp_path, small_dataset):
    bad = tmp_path / "bad"
    bad.mkdir()
    (bad / "run01.csv").write_text((small_dataset / "run01.csv").read_text().replace("t,y,theta", "t,y,phi"))
    out = tmp_path / "out"
    r = subprocess.run([sys.executable, "-m", "fitting", "fit", str(bad), "--out", str(out), "--strict"],
                       capture_output=True, text=True)
    assert r.returncode == 2
    err = [ln for ln in r.stderr.splitlines() if ln.strip()]
    assert len(err) == 1 and "run01.csv" in err[0] and "missing column" in err[0]
    assert not out.exists()


def test_compare_cli(small_dataset, fitted, tmp_path):
    assert main(["compare", str(small_dataset), "--model", str(fitted / "model.json"), "--out", str(tmp_path),
                 "--no-reoptimise", "--no-plots"]) == 0
    d = json.loads((tmp_path / "compare.json").read_text())
    assert len(d["per_run"]) == 3 and 0.0 <= d["wilcoxon_shape"]["p_greater"] <= 1.0


def _one_line_error(capsys) -> str:
    err = [ln for ln in capsys.readouterr().err.splitlines() if ln.strip()]
    assert len(err) == 1, err
    return err[0]


@pytest.mark.parametrize("meta, fragment", [
    ('{"side_length_m": -5e-4}', "side_length_m = -0.0005 is outside the plausible range"),
    ('{"side_length_m": true}', "side_length_m must be a number"),
    ('{"pressure_amplitude_pa": 1e300}', "pressure_amplitude_pa = 1e+300 is outside the plausible range"),
    ('{"pressure_amplitude_pa": "3 kPa"}', "pressure_amplitude_pa must be a number"),
])
def test_fit_refuses_bad_meta_json_naming_it(tmp_path, small_dataset, capsys, meta, fragment):
    data = tmp_path / "data"
    data.mkdir()
    (data / "run01.csv").write_text((small_dataset / "run01.csv").read_text())
    (data / "meta.json").write_text(meta)
    assert main(["fit", str(data), "--out", str(tmp_path / "out"), *FAST]) == 2
    line = _one_line_error(capsys)
    assert "meta.json" in line and fragment in line
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("command", ["fit", "compare", "synth"])
def test_unwritable_out_is_refused_before_computing(tmp_path, small_dataset, fitted, capsys, command):
    """A path under a file cannot be created, even by root (who ignores permission bits)."""
    blocker = tmp_path / "file"
    blocker.write_text("x")
    target = str(blocker / "out")
    argv = {"fit": ["fit", str(small_dataset), "--out", target, *FAST],
            "compare": ["compare", str(small_dataset), "--model", str(fitted / "model.json"), "--out", target],
            "synth": ["synth", target, "--runs", "2"]}[command]
    assert main(argv) == 2
    line = _one_line_error(capsys)
    assert target.split("/")[-2] in line and "not a directory" in line
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file"]


def test_synth_size_limit(tmp_path, capsys):
    assert main(["synth", str(tmp_path / "d"), "--duration", "1e9"]) == 2
    assert "exceeds the limit" in _one_line_error(capsys) and not (tmp_path / "d").exists()


@pytest.mark.slow
def test_fit_identical_serially_on_local_processes_and_on_a_cluster(small_dataset, fitted, tmp_path, process_cluster):
    """Byte-identical model.json wherever the per-run refinements ran; a fit begun serially
    finishes on the cluster from its per-run caches."""
    opts = [a for a in FAST if a not in ("--workers", "2")] + ["--no-plots"]
    serial, cluster = tmp_path / "serial", tmp_path / "cluster"
    assert main(["fit", str(small_dataset), "--out", str(serial), *opts, "--workers", "1"]) == 0
    # resume across executors: keep two of the three serial run caches, refine the third on the cluster
    cluster.mkdir()
    (cluster / "runs").mkdir()
    for name in ("run01.json", "run02.json"):
        (cluster / "runs" / name).write_bytes((serial / "runs" / name).read_bytes())
    assert main(["fit", str(small_dataset), "--out", str(cluster), *opts,
                 "--scheduler", process_cluster]) == 0
    reference = (fitted / "model.json").read_bytes()  # the module's fit on 2 local processes
    assert (serial / "model.json").read_bytes() == reference
    assert (cluster / "model.json").read_bytes() == reference
    assert (cluster / "runs" / "run03.json").read_bytes() == (serial / "runs" / "run03.json").read_bytes()
