"""``python -m acousim simulate``: the command contract of docs/formats.md."""
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from acousim.cli import main
from cubedimer.dataset import load_dataset

REPO = Path(__file__).resolve().parents[3]
FAST = ["--workers", "1", "--no-progress", "--duration", "1", "--fps", "500"]


def test_simulate_writes_a_loadable_dataset_with_truth(tmp_path, capsys):
    out = tmp_path / "d"
    rc = main(["simulate", "--runs", "3", "--seed", "7", "--out", str(out), *FAST,
               "--effect", "pair_scattering:kappa=12000", "--effect", "linear_damping:gamma_y=0.3,gamma_theta=0.8",
               "--noise-y", "2e-6", "--noise-theta", "0.01", "--pressure-error", "0.1",
               "--t-off", "0.002:0.003", "--theta-drop", "-0.2:0.2"])
    assert rc == 0
    ds = load_dataset(out, strict=True)
    assert len(ds.runs) == 3 and ds.meta["pressure_amplitude_pa"] == 3000.0
    truth = json.loads((out / "truth.json").read_text())
    air = truth["effects"].pop("air_damping")  # the default: the air's computed drag, on top of the effects given
    assert truth["air_damping"] is True and air["gamma_y"] > 0 and air["gamma_theta"] > 0
    assert truth["effects"] == {"linear_damping": {"gamma_y": 0.3, "gamma_theta": 0.8},
                                "pair_scattering": {"kappa": 12000.0}}
    assert truth["seed"] == 7 and truth["camera"]["noise_y_m"] == 2e-6 and truth["camera"]["noise_theta"] == 0.01
    assert truth["protocol"]["t_off"] == [0.002, 0.003] and truth["protocol"]["theta_drop"] == [-0.2, 0.2]
    assert 2700 <= truth["pressure_amplitude_pa"] <= 3300 and truth["pressure_amplitude_pa"] != 3000.0
    assert all(0.002 <= r["t_off_s"] <= 0.003 for r in truth["runs_detail"])
    assert "wrote 3 runs" in capsys.readouterr().err


def test_without_effect_the_air_damping_alone_is_on_and_no_air_damping_switches_it_off(tmp_path):
    from acousim.dynamics.effects import air_damping_for
    from acousim.twin import TwinConfig, twin_dynamics

    assert main(["simulate", "--runs", "1", "--out", str(tmp_path / "d"), *FAST]) == 0
    truth = json.loads((tmp_path / "d" / "truth.json").read_text())
    dyn, _ = twin_dynamics(TwinConfig())
    # the twin's default damping is the air's drag computed from the default dimer (docs/damping.md)
    assert truth["air_damping"] is True
    assert truth["effects"] == {"air_damping": air_damping_for(dyn.force_model, TwinConfig().conditions).params()}
    assert main(["simulate", "--runs", "1", "--out", str(tmp_path / "e"), *FAST, "--no-air-damping"]) == 0
    truth = json.loads((tmp_path / "e" / "truth.json").read_text())
    assert truth["air_damping"] is False and truth["effects"] == {}  # the inviscid dimer: no effect at all


def test_preset_and_override(tmp_path):
    from acousim.twin import PAPER_LIKE

    assert main(["simulate", "--preset", "paper-like", "--runs", "1", "--out", str(tmp_path / "d"), *FAST,
                 "--effect", "linear_damping:gamma_y=1"]) == 0
    truth = json.loads((tmp_path / "d" / "truth.json").read_text())
    expected = PAPER_LIKE.effects.to_dict()
    expected["linear_damping"] = {"gamma_y": 1.0, "gamma_theta": 0.0}
    # paper-like's tuned linear damping is its total damping: no computed air damping on top
    assert truth["effects"] == expected and truth["preset"] == "paper-like" and truth["air_damping"] is False


@pytest.mark.parametrize(
    "extra, fragment",
    [
        (["--effect", "pair_scattering:kapa=1"], "unknown parameter 'kapa'"),
        (["--effect", "wind:speed=3"], "unknown effect 'wind'"),
        (["--runs", "0"], "runs must be"),
        (["--noise-y", "-1e-6"], "noise_y"),
        (["--pressure-error", "0.9"], "pressure error"),
        (["--t-off", "0.02:0.03"], "fell out of the trap"),
        (["--fps", "0"], "fps"),
        (["--duration", "1e9"], "frames per run (--duration x --fps) = 500,000,000,000 exceeds the limit"),
        (["--runs", "9000", "--duration", "10"], "frames in the data set"),
        (["--runs", "1000000"], "--runs = 1,000,000 exceeds the limit"),
        (["--pressure", "1e300"], "--pressure: pressure_amplitude_pa = 1e+300 is outside the plausible range"),
        (["--detuning", "nan"], "--detuning: the detuning must be finite"),
        (["--detuning", "25"], "--detuning: the detuning must be finite and within +-20"),
        (["--detuning", "1", "--cavity-area", "-1e-4"], "--cavity-area: the cavity area must lie in"),
        (["--cavity-area", "1e-4"], "--cavity-area needs the resonator: give --detuning"),
        (["--detuning", "1", "--transducer-q", "0"], "needs the cavity's quality factor: give --transducer-q > 0"),
        (["--detuning", "-1", "--cavity-area", "1e-5"], "--detuning -1: the cavity's response removes the trap's"),
    ],
)
def test_user_errors_are_one_line_exit_2_and_write_nothing(tmp_path, capsys, extra, fragment):
    out = tmp_path / "d"
    rc = main(["simulate", "--runs", "2", "--out", str(out), *FAST, *extra])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2
    assert len(err) == 1 and fragment in err[0] and err[0].startswith("error:")
    assert list(tmp_path.iterdir()) == []


def test_refuses_non_empty_output_without_force(tmp_path, capsys):
    out = tmp_path / "d"
    out.mkdir()
    (out / "keep.csv").write_text("t,y,theta\n")
    assert main(["simulate", "--runs", "1", "--out", str(out), *FAST]) == 2
    assert "not empty" in capsys.readouterr().err
    assert (out / "keep.csv").exists()
    assert main(["simulate", "--runs", "1", "--out", str(out), *FAST, "--force"]) == 0
    assert sorted(p.name for p in out.iterdir()) == ["meta.json", "run01.csv", "truth.json", "truth_states.npz"]


@pytest.mark.slow
def test_python_dash_m_entry_point(tmp_path):
    out = tmp_path / "d"
    proc = subprocess.run([sys.executable, "-m", "acousim", "simulate", "--runs", "2", "--seed", "3", "--out", str(out),
                           "--duration", "1", "--workers", "2"], cwd=REPO, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    ds = load_dataset(out, strict=True)
    assert len(ds.runs) == 2 and ds.runs[0].t.size == 2000
    # default noise: 1 um on y, 0.005 on theta, 3 missing frames per run
    assert all(r.n_filled == 3 for r in ds.runs)
    assert np.all(np.abs(ds.runs[0].theta) < 1)


def test_executor_options_are_the_shared_ones(tmp_path, capsys):
    with pytest.raises(SystemExit) as exc:
        main(["simulate", "--runs", "1", *FAST, "--workers", "0", "--out", str(tmp_path / "d")])
    assert exc.value.code == 2 and "--workers: must be at least 1" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(["simulate", "--help"])
    assert "--scheduler ADDRESS" in capsys.readouterr().out


def test_unwritable_output_is_refused_before_simulating(tmp_path, capsys):
    """--out under a file cannot be created, even by root (who ignores permission bits)."""
    blocker = tmp_path / "file"
    blocker.write_text("x")
    for option, target in (("--out", blocker / "d"), ("--figures", blocker / "figs")):
        extra = [] if option == "--out" else ["--out", str(tmp_path / "d")]
        rc = main(["simulate", "--runs", "1", *FAST, *extra, option, str(target)])
        err = capsys.readouterr().err.strip().splitlines()
        assert rc == 2 and len(err) == 1 and err[0].startswith(f"error: {option}") and "not a directory" in err[0]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file"]


@pytest.mark.skipif(hasattr(os, "geteuid") and os.geteuid() == 0, reason="root may write into a read-only directory")
def test_read_only_parent_is_refused(tmp_path, capsys):
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o500)
    try:
        assert main(["simulate", "--runs", "1", *FAST, "--out", str(ro / "d")]) == 2
        assert "cannot write" in capsys.readouterr().err
    finally:
        ro.chmod(0o700)


@pytest.mark.parametrize("mask, mode", [(0o022, 0o644), (0o077, 0o600)])
def test_data_set_files_respect_the_umask(tmp_path, mask, mode):
    import stat

    old = os.umask(mask)
    try:
        assert main(["simulate", "--runs", "1", *FAST, "--out", str(tmp_path / "d")]) == 0
    finally:
        os.umask(old)
    for f in (tmp_path / "d").iterdir():
        assert stat.S_IMODE(f.stat().st_mode) == mode, f.name


@pytest.mark.slow
def test_identical_data_sets_serially_on_local_processes_and_on_a_cluster(tmp_path, process_cluster):
    common = ["simulate", "--runs", "3", "--seed", "5", "--no-progress", "--duration", "1", "--fps", "500",
              "--effect", "pair_scattering:kappa=12000"]
    outs = {"serial": ["--workers", "1"], "local": ["--workers", "2"],
            "cluster": ["--scheduler", process_cluster]}
    files = {}
    for name, extra in outs.items():
        assert main([*common, *extra, "--out", str(tmp_path / name)]) == 0
        files[name] = {p.name: p.read_bytes() for p in sorted((tmp_path / name).iterdir())}
    assert sorted(files["serial"]) == ["meta.json", "run01.csv", "run02.csv", "run03.csv", "truth.json",
                                       "truth_states.npz"]
    assert files["local"] == files["serial"] and files["cluster"] == files["serial"]


def test_a_folded_run_is_an_outcome_recorded_up_to_the_fold(tmp_path, capsys):
    """The 500 um, g = 10 um dimer at 3 kPa: a 7 ms drop folds its hinge 72 ms after the field is back (run 3 of
    seed 2); the data set is written, that run up to the fold, the event in truth.json."""
    out = tmp_path / "d"
    argv = ["simulate", "--model", "fullwave", "--side", "500e-6", "--gap", "10e-6", "--pressure", "3000",
            "--runs", "4", "--t-off", "0.002:0.008", "--seed", "2", "--out", str(out), "--workers", "1",
            "--no-progress", "--duration", "0.5", "--fps", "1000"]
    assert main(argv) == 0
    assert "1 of 4 runs folded" in capsys.readouterr().err
    truth = json.loads((out / "truth.json").read_text())
    assert truth["folded_runs"] == 1 and truth["field_switching"]["transducer_q"] == 0.0
    folded = [r for r in truth["runs_detail"] if r["event"]]
    assert len(folded) == 1 and folded[0]["t_off_s"] > 6e-3 and folded[0]["event"]["event"] == "folded"
    frames = folded[0]["frames"]
    assert 0 < frames < 500 and folded[0]["event"]["t_s"] == pytest.approx((frames - 1) / 1000)
    rows = [ln for ln in (out / folded[0]["file"]).read_text().splitlines() if ln and not ln.startswith("#")]
    assert len(rows) == frames + 1                           # header + the frames up to the fold
    states = np.load(out / "truth_states.npz")
    x = states[Path(folded[0]["file"]).stem]
    assert x.shape == (500, 4) and np.all(np.isfinite(x[:frames])) and np.all(np.isnan(x[frames:]))
    # the last recorded hinge angle is close to contact: it reaches +-1 within the next frame
    assert 0.9 < abs(x[frames - 1, 2]) < 1
    # the loader keeps the other runs
    assert len(load_dataset(out, strict=False).runs) >= 3


def test_the_ring_time_is_recorded_and_checked(tmp_path, capsys):
    out = tmp_path / "d"
    assert main(["simulate", "--runs", "2", "--seed", "1", "--out", str(out), *FAST, "--transducer-q", "250"]) == 0
    truth = json.loads((out / "truth.json").read_text())
    assert truth["field_switching"]["transducer_q"] == 250.0
    # tau = Q / (pi f) at 45.65 kHz
    assert truth["field_switching"]["ring_time_s"] == pytest.approx(250 / (np.pi * 45_650.0), rel=1e-12)
    assert all(r["pressure_at_field_on"] == pytest.approx(np.exp(-r["t_off_s"] / truth["field_switching"]["ring_time_s"]))
               for r in truth["runs_detail"])
    assert main(["simulate", "--out", str(tmp_path / "bad"), *FAST, "--transducer-q", "-1"]) == 2
    assert "transducer quality factor" in capsys.readouterr().err and not (tmp_path / "bad").exists()


def test_the_resonator_is_recorded_and_off_by_default(tmp_path):
    """--detuning switches the cavity mode on: truth.json records its settings, each run's |A|/p0 when the drive is
    back is the mode's (its ring-down, exp(-t_off / tau) as the plain ring: the drive is off, the detuning only turns
    the phase) and truth_mode.npz holds A/p0 at the frames, near 1 in modulus after the ring-up.  Without it nothing
    of the resonator appears."""
    out = tmp_path / "d"
    assert main(["simulate", "--runs", "2", "--seed", "3", "--out", str(out), *FAST, "--detuning", "1.5",
                 "--cavity-area", "2e-4"]) == 0
    truth = json.loads((out / "truth.json").read_text())
    res = truth["resonator"]
    assert res["quality_factor"] == 250.0 and res["detuning_half_widths"] == 1.5 and res["cavity_area_m2"] == 2e-4
    assert res["detuning_hz"] == pytest.approx(1.5 * 45_650.0 / 500.0)
    tau = res["ring_time_s"]
    # the ring-down is integrated (RK4 at h Gamma = 0.03: ~1e-8)
    assert all(r["pressure_at_field_on"] == pytest.approx(np.exp(-r["t_off_s"] / tau), rel=1e-7)
               for r in truth["runs_detail"])
    modes = np.load(out / "truth_mode.npz")
    assert sorted(modes.files) == ["run01", "run02", "t"]
    assert abs(np.abs(modes["run01"][-1]) - 1.0) < 0.01  # back at the steady amplitude, detuned by the motion
    plain = tmp_path / "plain"
    assert main(["simulate", "--runs", "1", "--out", str(plain), *FAST]) == 0
    assert "resonator" not in json.loads((plain / "truth.json").read_text())
    assert not (plain / "truth_mode.npz").exists()
