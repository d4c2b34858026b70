"""End-to-end CLI on a small synthetic data set: outputs, resume, bad input, compare."""
import json
import subprocess
import sys

import pytest

from fitting.cli import main

FAST = ["--max-evals", "40", "--joint-max-evals", "40", "--workers", "2", "--quiet"]


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
    for p in ("zscores.png", "coefficients.png", "optimisation.png", "phase_portraits.png", "poincare.png"):
        assert (fitted / p).stat().st_size > 1000


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
