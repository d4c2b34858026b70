"""The attractor atlas in the report (validation report --atlas)."""
import pytest

from acousim.atlas.field_drops import AtlasConfig, AtlasDimer, run_atlas
from cubedimer.executor import ExecutorConfig
from validation.cli import main
from validation.report.sections.atlas import AtlasSectionError, atlas_section
from validation.report.html import write_report


def test_the_atlas_becomes_a_section(tmp_path):
    config = AtlasConfig(dimers=(AtlasDimer(700e-6, 0.05),), t_off=(5e-3, 25e-3), theta_drop=(0.0,), duration=1.0)
    run_atlas(config, tmp_path / "atlas", ExecutorConfig(workers=1), progress=False)
    sec = atlas_section(tmp_path / "atlas")
    assert sec.id == "atlas" and len(sec.figures) == 2            # one basin map and the phase histogram
    (row,) = sec.tables[0].rows
    assert row[0] == "s700um_g0.05" and row[1] == 1              # the 25 ms drop leaves the trap
    assert sum(row[1:8]) == 2                                     # every drop is counted once
    html = write_report([sec], tmp_path / "report", "atlas").read_text()
    assert "The attractor atlas of the simulation" in html and html.count("<img") == 2


def test_a_missing_atlas_is_refused_before_anything_runs(tmp_path, capsys):
    with pytest.raises(AtlasSectionError, match="no readable atlas.json"):
        atlas_section(tmp_path)
    out = tmp_path / "report"
    assert main(["report", str(tmp_path), "--out", str(out), "--atlas", str(tmp_path / "none")]) == 2
    assert "--atlas" in capsys.readouterr().err and not out.exists()
