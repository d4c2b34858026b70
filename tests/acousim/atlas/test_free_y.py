"""The free-y attractor map (acousim.atlas.free_y): periodic orbits of the dimer with its cavity mode, their
multipliers, the cells' summary, the command and its resumption."""
import json
import math

import numpy as np
import pytest

from acousim.atlas.field_drops import AtlasDimer, AtlasError
from acousim.atlas.free_y import FreeYConfig, cell_summary, distinct_orbits, free_y_cell
from acousim.atlas.free_y_figures import cell_kind
from acousim.cli import main

#: The window dimer with a small cavity (30 mm^2) at Q 250: at x = -4 the start 50 um below rest with the hinge at
#: 0.3 settles near an unstable anti-phase orbit (a torus about it), at x = -3 the dimer escapes.
SMALL = dict(dimers=(AtlasDimer(500e-6, 0.02),), quality_factors=(250.0,), detunings=(-4.0, -3.0), area_m2=3e-5,
             amplitudes_m=(50e-6,), theta_starts=(0.3,), settle_time=16.0)


@pytest.fixture(scope="module")
def cell():
    config = FreeYConfig(**SMALL)
    return free_y_cell(config.dimers[0], 250.0, -4.0, config)


def test_the_orbit_found_with_y_free_is_periodic_with_a_trivial_multiplier(cell):
    """The shot orbit closes (scaled residual < 1e-10), it is locked at f_y, and its trivial multiplier is 1:
    |mu_trivial - 1| and |M f - f| / |f| measured 2e-8 to 1.1e-6 on this orbit over 370-2960 RK4 steps per period
    and difference steps 1e-4 to 1e-7 (scattered, not falling as RK4's h^4), checked to 1e-5.  The five others are
    the six-state system's: the mode's pair is damped to ~exp(-Gamma T) ~ 1e-9."""
    orbits = cell["orbits"]
    assert len(orbits) == 1 and cell["runs"][0]["orbit"] == 0
    o = orbits[0]
    assert o["residual"] < 1e-10 and o["lock_ratio"] == "1:1" and o["f_theta_over_f_y"] == pytest.approx(1.0)
    assert o["trivial_error"] < 1e-5 and o["flow_invariance"] < 1e-5
    assert len(o["multipliers"]) == 5 and min(o["multipliers"]) < 1e-6
    assert o["max_multiplier"] == max(o["multipliers"]) and o["stable"] == (o["max_multiplier"] < 1)
    assert o["e_fold_cycles"] == pytest.approx(1 / abs(math.log(o["max_multiplier"])))
    assert o["period_s"] * cell["f_y_hz"] == pytest.approx(1.0, abs=0.15)
    assert 0 < o["share_2fy"] < 1 and o["amp_y_m"] > 1e-6


def test_the_cell_summary_counts_runs_and_orbits(cell):
    row = cell_summary(cell)
    o = cell["orbits"][0]
    assert row["starts"] == 1 and row["orbits"] == 1 and row["stable"] + row["unstable"] == 1
    assert row["max_max_multiplier"] == o["max_multiplier"] and row["max_trivial_error"] == o["trivial_error"]
    assert cell_kind(row) in ("unstable orbits only", "stable anti-phase", "stable in phase", "stable, other class")
    both = {**cell, "orbits": [{**o, "stable": True, "class": "locked-in-phase"},
                               {**o, "stable": True, "class": "locked-anti-phase"}]}
    assert cell_kind(cell_summary(both)) == "stable in phase and anti-phase"


def test_orbits_reached_from_several_starts_count_once():
    a = {"period_s": 0.04, "amp_y_m": 1e-4, "amp_theta": 0.2, "theta_mean": 0.07}
    same = {**a, "amp_y_m": 1e-4 * (1 + 1e-6)}
    other = {**a, "amp_theta": 0.3}
    out = distinct_orbits([a, same, other])
    assert [d["starts"] for d in out] == [2, 1]


def test_the_command_writes_resumes_identically_and_refuses_bad_input(tmp_path, capsys):
    """The map's two cells; a rerun after a cell file is removed recomputes it identically (no random choice) and
    keeps the other."""
    out = tmp_path / "map"
    argv = ["free-y-map", "--out", str(out), "--dimers", "500e-6:0.02", "--qualities", "250", "--detunings", "-4,-3",
            "--area", "3e-5", "--amplitudes", "50e-6", "--theta-starts", "0.3", "--workers", "1", "--no-progress"]
    assert main(argv) == 0
    data = json.loads((out / "free_y.json").read_text())
    rows = {r["detuning"]: r for r in data["summary"]}
    assert rows[-4.0]["orbits"] == 1 and rows[-3.0]["escaped"] + rows[-3.0]["folded"] == 1
    assert (out / "free_y_map.png").stat().st_size > 0
    assert (out / "free_y.csv").read_text().splitlines()[0].startswith("dimer,side_m,gap_ratio,pressure_pa")
    files = sorted((out / "cells").glob("*.json"))
    first = [json.loads(f.read_text()) for f in files]
    kept = dict(first[1], seconds=-1.0)
    files[1].write_text(json.dumps(kept))
    files[0].unlink()
    assert main(argv) == 0
    again = [json.loads(f.read_text()) for f in files]
    assert again[1]["seconds"] == -1.0
    strip = lambda c: {k: v for k, v in c.items() if k != "seconds"}  # noqa: E731
    assert strip(again[0]) == strip(first[0])
    capsys.readouterr()
    for bad, fragment in ((["--detunings", "30"], "detuning"), (["--area", "1"], "area"),
                          (["--dimers", "500e-6:0.9"], "--dimers"), (["--settle-time", "0.1"], "--settle-time")):
        never = tmp_path / "never"
        assert main(["free-y-map", "--out", str(never), *bad, "--workers", "1", "--no-progress"]) == 2
        err = capsys.readouterr().err
        assert fragment in err and len(err.strip().splitlines()) == 1 and not never.exists()


def test_bad_settings_are_refused():
    with pytest.raises(AtlasError, match="--theta-starts"):
        FreeYConfig(**{**SMALL, "theta_starts": (1.2,)})
    with pytest.raises(AtlasError, match="quality factor"):
        FreeYConfig(**{**SMALL, "quality_factors": (-1.0,)})
