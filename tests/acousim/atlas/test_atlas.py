"""The attractor atlas (acousim.atlas.field_drops, python -m acousim atlas) on a tiny grid."""
import json

import numpy as np
import pytest

from acousim.atlas.field_drops import (AtlasConfig, AtlasDimer, AtlasError, atlas_dynamics, drop_and_settle, observations,
                           settled_outcome)
from acousim.cli import main

DIMER = ["--dimers", "700e-6:0.05"]


def test_settled_outcome_reads_the_lock_and_the_2fy_line():
    """y = A cos(w t), theta = B cos(w t) + C cos(2 w t): locked in phase, 2 f_y share C / B."""
    f, fs, dur = 20.0, 1000.0, 12.0
    t = np.arange(int(dur * fs)) / fs
    w = 2 * np.pi * f
    y, yd = 1e-4 * np.cos(w * t), -1e-4 * w * np.sin(w * t)
    th = 0.2 * np.cos(w * t) + 0.02 * np.cos(2 * w * t)
    thd = -0.2 * w * np.sin(w * t) - 0.04 * w * np.sin(2 * w * t)
    r = settled_outcome(t, np.column_stack([y, yd, th, thd]))
    assert r["outcome"] == "locked-in-phase" and r["amplitude_class"] == "medium"
    # exact-bin lines (20 and 40 Hz on a 1/6 Hz grid): the Hann amplitudes are exact to round-off
    assert r["share_2fy"] == pytest.approx(0.1, rel=1e-6)
    assert r["long_lived"] and r["cycles"] == pytest.approx(120, rel=0.01)   # 6 s at 20 Hz
    # anti-phase
    r = settled_outcome(t, np.column_stack([y, yd, -th, -thd]))
    assert r["outcome"] == "locked-anti-phase"


def test_observations_count_the_papers_criteria():
    cells = ([{"outcome": "locked-in-phase", "share_2fy": 0.08, "long_lived": True, "amplitude_class": "large"}] * 3
             + [{"outcome": "locked-anti-phase", "share_2fy": 0.01, "long_lived": True, "amplitude_class": "small"}] * 3
             + [{"outcome": "folded"}] * 4)
    o = observations(cells)
    assert (o["runs"], o["trapped"], o["locked_at_fy"], o["with_2fy"], o["folded"]) == (10, 6, 6, 3, 4)
    assert o["both_phase_classes"] and o["n_attractors"] == 2


def test_the_2fy_line_is_counted_for_every_lock():
    """A 3:2 lock's third harmonic sits at 2 f_y: it counts in with_2fy, not in with_2fy_at_fy nor as locked at f_y."""
    cells = ([{"outcome": "locked-p:q", "lock_ratio": "3:2", "share_2fy": 0.3, "long_lived": True,
               "amplitude_class": "large"}] * 2
             + [{"outcome": "locked-in-phase", "lock_ratio": "1:1", "share_2fy": 0.01, "long_lived": True,
                 "amplitude_class": "medium"}])
    o = observations(cells)
    assert (o["locked_at_fy"], o["locked_ratio"], o["with_2fy"], o["with_2fy_at_fy"]) == (1, 2, 2, 0)
    assert o["lock_ratios"] == {"3:2": 2}
    assert o["attractors"] == [["locked-in-phase", "medium"], ["locked-p:q 3:2", "large"]]


def test_settled_outcome_reads_a_3_2_lock():
    """theta = B cos(2/3 w t) + C cos(2 w t) with y at w: a 3:2 lock whose 2 f_y line is C over theta's f_y line."""
    f, fs, dur = 21.0, 1000.0, 12.0     # 2/3 f, f and 2 f on the 1/6 Hz grid of the 6 s analysed
    t = np.arange(int(dur * fs)) / fs
    w = 2 * np.pi * f
    y, yd = 1e-4 * np.cos(w * t), -1e-4 * w * np.sin(w * t)
    th = 0.4 * np.cos(2 / 3 * w * t) + 0.05 * np.cos(w * t) + 0.02 * np.cos(2 * w * t)
    thd = -0.4 * 2 / 3 * w * np.sin(2 / 3 * w * t) - 0.05 * w * np.sin(w * t) - 0.04 * w * np.sin(2 * w * t)
    r = settled_outcome(t, np.column_stack([y, yd, th, thd]))
    assert r["outcome"] == "locked-p:q" and r["lock_ratio"] == "3:2" and r["long_lived"]
    # exact-bin lines: the Hann amplitudes are exact to round-off
    assert r["share_2fy"] == pytest.approx(0.4, rel=1e-6)


def test_a_long_drop_throws_the_dimer_out():
    """A 25 ms free fall (3.1 mm) goes past the potential barrier (less than a quarter wavelength, 1.9 mm)."""
    dyn = atlas_dynamics(700e-6, 0.05, 6000.0, 45_650.0)
    assert drop_and_settle(dyn, 25e-3, 0.0, 1.0, 1000.0)["outcome"] == "escaped"


def test_bad_settings_are_one_line_errors():
    with pytest.raises(AtlasError, match="--t-off"):
        AtlasConfig(dimers=(AtlasDimer(500e-6, 0.03),), t_off=(0.05,), theta_drop=(0.0,))
    with pytest.raises(AtlasError, match="--dimers"):
        AtlasDimer(500e-6, 0.9)


def test_the_command_writes_and_resumes(tmp_path, capsys):
    out = tmp_path / "atlas"
    argv = ["atlas", "--out", str(out), *DIMER, "--t-off", "5e-3,25e-3", "--theta-drop", "0.0,0.1",
            "--duration", "1.5", "--workers", "1", "--no-progress"]
    assert main(argv) == 0
    data = json.loads((out / "atlas.json").read_text())
    counts = data["dimers"]["s700um_g0.05"]["counts"]
    assert sum(counts.values()) == 4 and counts["escaped"] == 2          # the 25 ms drops leave the trap
    assert (out / "basin_s700um_g0.05.png").stat().st_size > 0 and (out / "phase_histogram.png").exists()
    lines = (out / "atlas.csv").read_text().splitlines()
    assert len(lines) == 5 and lines[0].startswith("dimer,side_m,gap_ratio,t_off_s,theta_drop,outcome")
    # resume: finished cells are kept, not recomputed
    cell = sorted((out / "cells").glob("*.json"))[0]
    kept = json.loads(cell.read_text())
    kept["outcome"] = "theta-at-rest"
    cell.write_text(json.dumps(kept))
    assert main(argv) == 0
    assert json.loads((out / "atlas.json").read_text())["cells"][0]["outcome"] == "theta-at-rest"
    # other settings in the same folder: refused, exit 2
    assert main([*argv[:-5], "--duration", "2", "--workers", "1", "--no-progress"]) == 2
    assert "other settings" in capsys.readouterr().err


def test_bad_input_exits_2_and_writes_nothing(tmp_path, capsys):
    out = tmp_path / "never"
    assert main(["atlas", "--out", str(out), "--t-off", "5e-3:40e-3:3"]) == 2
    assert "--t-off" in capsys.readouterr().err and not out.exists()
    assert main(["atlas", "--out", str(out), "--dimers", "100e-6:0.03"]) == 2   # outside the full-wave family
    assert "--dimers" in capsys.readouterr().err and not out.exists()


def test_force_discards_the_study_in_the_folder(tmp_path):
    """The pinned settings refuse a study with other settings; ``force`` discards the folder's study (its pin and
    its finished cells) instead, so that nothing of the old one is taken for the new one."""
    from acousim.atlas.field_drops import check_pinned_settings

    pinned = tmp_path / "atlas_settings.json"
    pinned.write_text(json.dumps({"duration": 1.5}))
    (tmp_path / "cells").mkdir()
    (tmp_path / "cells" / "c0.json").write_text("{}")
    with pytest.raises(AtlasError, match="other settings"):
        check_pinned_settings(pinned, {"duration": 2.0}, "an atlas")
    assert pinned.exists() and (tmp_path / "cells" / "c0.json").exists()  # refused: nothing touched
    check_pinned_settings(pinned, {"duration": 2.0}, "an atlas", force=True)
    assert not pinned.exists() and not (tmp_path / "cells").exists()
