"""The one model.json reader (fitting.output.model_file.read_model_json): exact round trip, one-line errors on bad files."""
import json
from pathlib import Path

import numpy as np
import pytest

from cubedimer.errors import DatasetError
from fitting.config import FitConfig
from fitting.output.model_file import read_model_json, recorded_settings, settings_record


def test_reads_back_the_model_exactly(tmp_path, truth):
    doc = {**truth.to_json(), "scales": {"length_y_m": 1e-4, "length_theta": 0.1, "time_s": 0.01}}
    (tmp_path / "model.json").write_text(json.dumps(doc))
    mf = read_model_json(tmp_path / "model.json")
    np.testing.assert_array_equal(mf.model.coef, truth.coef)  # exact: JSON floats round-trip
    assert mf.document == doc and not mf.system.generic


@pytest.mark.parametrize("content,message", [
    ("{", "not valid JSON"), ("[1]", "no 'equations'"), ('{"a": 1}', "no 'equations'"),
    ('{"equations": {"xddot": {"y": 1}}}', "unknown equation 'xddot'"),
    ('{"equations": {"yddot": {"zz": 1}}}', "bad term or value 'zz'"),
    ('{"equations": {"yddot": {"y": "a"}}}', "bad term or value 'y'"),
    ('{"equations": {"yddot": {"y^4": 1}}}', "not in the cubic library"),
    ('{"equations": {"yddot": {"y": 1}}, "units": "cgs"}', "only SI"),
])
def test_bad_file_is_one_line_dataset_error(tmp_path, content, message):
    path = tmp_path / "model.json"
    path.write_text(content)
    with pytest.raises(DatasetError) as err:
        read_model_json(path)
    text = str(err.value)
    assert message in text and str(path) in text and "\n" not in text


def test_missing_file(tmp_path):
    with pytest.raises(DatasetError, match="cannot read"):
        read_model_json(tmp_path / "model.json")


#: model.json settings as the fit wrote them before each method owned its settings (one flat object): a default
#: discovery fit, and a paper fit with ``--max-evals 20 --joint-max-evals 20``
FLAT_SETTINGS = Path(__file__).parent / "data"


@pytest.mark.parametrize("name, config", [
    ("discovery", FitConfig()),
    ("paper", FitConfig.for_method("paper").with_max_evals(20, joint=True)),
])
def test_settings_of_the_flat_layout_read_as_the_method_layout(name, config):
    """The settings reader gives a file of the flat layout exactly the layout a fit of the same configuration writes
    today (the method's own settings under its name, the discovery's selection as ``selection``), and leaves
    today's layout as it is."""
    old = json.loads((FLAT_SETTINGS / f"model_settings_flat_{name}.json").read_text())
    flat = old["settings"]
    today = settings_record(config)
    assert set(today) == {"load", "smoothing", "classify", "method", name} and today["method"] == name
    got = recorded_settings(old)
    # the same layout as today's record; the values are the file's (defaults added since, such as the loader's
    # fill limit now read from meta.json, are not the file's to know)
    assert set(got) == set(today) and set(got[name]) == set(today[name]) and got["method"] == name
    assert all(got[k] == flat[k] for k in ("load", "smoothing", "classify"))
    assert recorded_settings({"method": name, "settings": today}) == today
    if name == "discovery":  # the discovery's own selection settings moved from settings["discovery"]
        assert got["discovery"]["selection"] == flat["discovery"]
        assert all(got["discovery"][k] == flat[k] for k in got["discovery"] if k != "selection")
        assert "refine" not in got["discovery"]  # the paper's per-run refinement is not the discovery's
    else:
        assert all(got["paper"][k] == flat[k] for k in got["paper"])
        assert got["paper"]["refine"]["max_evals"] == got["paper"]["joint"]["max_evals"] == 20


def test_settings_reader_takes_a_partial_or_missing_record():
    """What older or hand-written files hold: part of the discovery's selection settings, or none."""
    assert recorded_settings({"settings": {"discovery": {"keep_damping": False}}}) == {
        "method": "discovery", "discovery": {"selection": {"keep_damping": False}}}
    assert recorded_settings({"method": "paper"}) == {"method": "paper", "paper": {}}


@pytest.mark.parametrize("layout", ["flat", "today"])
def test_the_recorded_stages_are_the_fit_s_loading_smoothing_and_classification(layout):
    """A later step (``fitting compare``, a report made again from its files) prepares the runs as the fit did:
    every field of the shared stages a model.json records comes back, nested configs and tuples included, from
    either layout; a stage switched off (the glitch mask) stays off."""
    from dataclasses import replace

    from cubedimer.glitches import GlitchConfig
    from fitting.output.model_file import recorded_stages

    base = FitConfig()
    config = replace(base, load=replace(base.load, max_gap=25, min_periods=3.0, glitches=None),
                     smoothing=replace(base.smoothing, window_periods=0.5),
                     classify=replace(base.classify, coherence_min=0.9))
    record = settings_record(config)
    if layout == "flat":  # the shared stages sat at the same place before the per-method layout
        record = {**{k: record[k] for k in ("load", "smoothing", "classify")}, "method": "discovery",
                  "discovery": record["discovery"]["selection"]}
    stages = recorded_stages({"settings": record})
    assert (stages.load, stages.smoothing, stages.classify) == (config.load, config.smoothing, config.classify)
    assert stages.method_name == "discovery"
    # a file without settings, or with a nested stage on, gives the defaults
    assert recorded_stages({}).load == base.load
    on = recorded_stages({"settings": {"load": {"glitches": {"threshold": 9.0}}}}).load.glitches
    assert on == replace(GlitchConfig(), threshold=9.0)
