"""``python -m acousim sweep``: documented columns on good input, one-line errors and no file on bad input."""
import subprocess
import sys

import numpy as np
import pytest

COLUMNS = ["theta", "y", "potential", "force_z", "q_y", "q_theta", "yddot", "thetaddot"]


@pytest.fixture
def run(capsys):
    """``python -m acousim ARGS`` in this process (its ``main``, with argparse's exits caught): the same code path
    as the command line without a Python start and the imports for every case (the first test runs the real
    command in a subprocess)."""
    from acousim.cli import main

    def _run(*args: str) -> subprocess.CompletedProcess:
        capsys.readouterr()
        try:
            code = main(list(args))
        except SystemExit as exc:  # argparse: --help and usage errors
            code = exc.code if isinstance(exc.code, int) else 1
        cap = capsys.readouterr()
        return subprocess.CompletedProcess(["acousim", *args], code, cap.out, cap.err)

    return _run


def test_sweep_writes_documented_columns(tmp_path):
    out = tmp_path / "s.csv"
    r = subprocess.run([sys.executable, "-m", "acousim", "sweep", "--theta", "-0.5:0.5:5", "--y", "-1e-4:1e-4:3",
                        "--out", str(out), "--quiet"], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    rows = [l for l in out.read_text().splitlines() if not l.startswith("#")]
    header = rows[0].split(",")
    assert header[: len(COLUMNS)] == COLUMNS
    data = np.array([[float(v) for v in r.split(",")] for r in rows[1:]])
    assert data.shape[0] == 15
    assert np.all(np.isfinite(data))
    np.testing.assert_allclose(np.unique(data[:, 0]), np.linspace(-0.5, 0.5, 5))


def test_sweep_with_all_outputs(run, tmp_path):
    r = run("sweep", "--theta", "-0.6:0.6:9", "--y", "-1e-4:1e-4:9", "--out", str(tmp_path / "s.csv"),
            "--coefficients", str(tmp_path / "c.json"), "--plots", str(tmp_path / "fig"), "--quiet")
    assert r.returncode == 0, r.stderr
    assert (tmp_path / "c.json").exists()
    assert sorted(p.name for p in (tmp_path / "fig").iterdir()) == ["restoring_force.png", "restoring_torque.png", "thetaddot_map.png"]


@pytest.mark.parametrize(
    "args,message",
    [
        (["--theta", "-1:0.5:3"], "inside (-1, 1)"),
        (["--theta", "-0.5:1.0:3"], "inside (-1, 1)"),
        (["--theta", "0.5:-0.5:3"], "greater than STOP"),
        (["--y", "1e-4:-1e-4:3"], "greater than STOP"),
        (["--side", "-5e-4"], "must be positive"),
        (["--theta", "a:b:c"], "must be numbers"),
        (["--pressure", "100"], "cannot levitate"),
        (["--nonsense"], "unrecognized"),
    ],
)
def test_bad_arguments_fail_cleanly(run, tmp_path, args, message):
    out = tmp_path / "s.csv"
    cov = tmp_path / "c.json"
    r = run("sweep", *args, "--out", str(out), "--coefficients", str(cov))
    assert r.returncode != 0
    lines = [l for l in r.stderr.strip().splitlines() if l.strip()]
    assert len(lines) == 1, r.stderr  # one line, no traceback
    assert message in lines[0]
    assert not out.exists() and not cov.exists()
    assert list(tmp_path.iterdir()) == []


def test_help_explains_units(run):
    r = run("sweep", "--help")
    assert r.returncode == 0 and "q_theta [N m]" in r.stdout


@pytest.mark.parametrize(
    "args,message",
    [
        (["--theta", "-0.5:0.5:100000", "--y", "-1e-4:1e-4:100000"], "exceeds the limit"),
        (["--pressure", "1e300"], "pressure_amplitude_pa = 1e+300 is outside the plausible range"),
        (["--frequency", "inf"], "must be positive"),
        (["--density", "1e9"], "particle_density_kg_m3"),
    ],
)
def test_sizes_and_implausible_values_are_refused_in_one_line(run, tmp_path, args, message):
    r = run("sweep", *args, "--out", str(tmp_path / "s.csv"))
    lines = [l for l in r.stderr.strip().splitlines() if l.strip()]
    assert r.returncode == 2 and len(lines) == 1 and message in lines[0], r.stderr
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("option", ["--out", "--coefficients", "--render", "--plots"])
def test_unwritable_output_is_refused_before_computing(run, tmp_path, option):
    """A path under a file cannot be created, even by root (who ignores permission bits)."""
    blocker = tmp_path / "file"
    blocker.write_text("x")
    target = blocker / "sub" / ("figs" if option == "--plots" else "x.out")
    args = ["--out", str(tmp_path / "s.csv")] if option != "--out" else []
    r = run("sweep", *args, option, str(target), "--theta", "-0.5:0.5:3", "--y", "-1e-4:1e-4:3")
    lines = [l for l in r.stderr.strip().splitlines() if l.strip()]
    assert r.returncode == 2 and len(lines) == 1, r.stderr
    assert lines[0].startswith("error: " + option) and "not a directory" in lines[0]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file"]  # nothing computed or written


def test_fullwave_sweep_is_the_surrogate(run, tmp_path):
    """``--model fullwave`` sweeps the shipped full-wave surrogate: its values on the grid, an empty potential
    column, the model named in the header, and static coefficients whose small-box limit is the surrogate's own
    Taylor expansion."""
    from acousim.fullwave import default_fullwave_surrogate
    from acousim.statics.sweep import read_sweep_csv

    out, cof = tmp_path / "s.csv", tmp_path / "c.json"
    r = run("sweep", "--model", "fullwave", "--theta", "-0.3:0.3:7", "--y", "-1e-4:1e-4:5", "--out", str(out),
            "--coefficients", str(cof), "--quiet")
    assert r.returncode == 0, r.stderr
    assert '"model": "fullwave"' in out.read_text()
    sweep = read_sweep_csv(out)
    assert np.all(np.isnan(sweep["potential"]))
    sur = default_fullwave_surrogate(3000.0)
    tt, yy = np.meshgrid(sweep.theta_grid, sweep.y_grid, indexing="ij")
    q_y, q_t = sur.generalized_forces(tt, yy)
    # the CSV keeps 10 significant digits
    np.testing.assert_allclose(sweep["q_theta"], q_t, rtol=1e-9, atol=1e-9 * np.abs(q_t).max())
    np.testing.assert_allclose(sweep["yddot"], q_y / sur.mass, rtol=1e-9, atol=1e-9 * np.abs(q_y / sur.mass).max())
    np.testing.assert_allclose(sweep["thetaddot"], q_t / sur.hinge_inertia(tt), rtol=1e-9,
                               atol=1e-9 * np.abs(q_t / sur.hinge_inertia(tt)).max())
    import json

    taylor = json.loads(cof.read_text())["taylor_at_equilibrium"]
    # the sweep's small-box fit against the surrogate's analytic derivatives: both are the same Chebyshev
    # series, so they agree to the fit's truncation (degree 5 on a 20 um x 0.05 box)
    for term in ("theta", "y*theta", "y^2*theta"):
        np.testing.assert_allclose(taylor["thetaddot"][term], sur.taylor_coefficients()["thetaddot"][term], rtol=1e-3)


@pytest.mark.parametrize("args,message", [
    (["--mesh-size", "1e-4"], "--mesh-size applies to --model gorkov only"),
    (["--render", "x.png"], "does not apply to --model fullwave"),
    (["--side", "1e-3"], "outside the full-wave family"),  # ks = 0.84
    (["--gap", "-1e-6"], "--gap = -1e-06 must be positive"),
    (["--gap", "nan"], "--gap = nan is not finite"),
    (["--edge-radius", "1e-5"], "only sharp-edged tables"),
    (["--theta", "-0.95:0.95:3"], "covers |theta| <= 0.9"),
])
def test_fullwave_sweep_refuses_what_the_table_does_not_cover(run, tmp_path, args, message):
    out = tmp_path / "s.csv"
    r = run("sweep", "--model", "fullwave", *args, "--out", str(out))
    assert r.returncode != 0
    lines = [l for l in r.stderr.strip().splitlines() if l.strip()]
    assert len(lines) == 1 and message in lines[0], r.stderr
    assert not out.exists()
