"""The resonator map (acousim.atlas.resonator_map): linear theory against the simulation, outcomes, resumption."""
import json

import pytest

from acousim.atlas.field_drops import AtlasError
from acousim.atlas.resonator_map import ResonatorMapConfig, run_resonator_map
from cubedimer.executor import ExecutorConfig

SMALL = dict(dimers=("gorkov:500e-6:3000",), quality_factors=(250.0,), areas_m2=(1e-4,), detunings=(-1.5, 2.0),
             growth_time=2.0, duration=4.0, window=1.0)


def test_a_small_map_agrees_with_the_linear_theory_and_resumes(tmp_path):
    """At 1 um the simulated growth rate is the linear theory's exact one (the point-body test's 1 %); the drive
    above the resonance (x = -1.5) feeds y past the air's damping, below it (x = 2) y decays.  A rerun reads the
    finished cells instead of simulating them."""
    config = ResonatorMapConfig(**SMALL)
    result = run_resonator_map(config, tmp_path / "m", ExecutorConfig(workers=1), progress=False, figures=True)
    rows = {r["detuning"]: r for r in result["rows"]}
    for r in rows.values():
        assert r["growth_simulated"] == pytest.approx(r["growth_exact"], rel=0.01)
    assert rows[-1.5]["growth_exact"] > 0 > rows[2.0]["growth_exact"]
    assert rows[-1.5]["band_low"] < -1.5 < rows[-1.5]["band_high"] < 0
    assert rows[2.0]["outcome"] in ("decayed", "decaying") and rows[-1.5]["outcome"] in ("growing", "escaped")
    assert (tmp_path / "m" / "resonator_map.png").stat().st_size > 0
    cell = next((tmp_path / "m" / "cells").iterdir())
    mark = json.loads(cell.read_text())
    mark["rows"][0]["seconds"] = -1.0  # a rerun keeps what is written
    cell.write_text(json.dumps(mark))
    again = run_resonator_map(config, tmp_path / "m", ExecutorConfig(workers=1), progress=False, figures=False)
    assert again["rows"][0]["seconds"] == -1.0


@pytest.mark.parametrize("kwargs, fragment", [
    (dict(dimers=("gorkov:500e-6",)), "--dimers"), (dict(detunings=(30.0,)), "detuning"),
    (dict(quality_factors=(-1.0,)), "quality factor"), (dict(duration=1.0), "the times"),
])
def test_bad_map_settings_are_refused(kwargs, fragment):
    with pytest.raises(AtlasError, match=fragment):
        ResonatorMapConfig(**{**SMALL, **kwargs})
