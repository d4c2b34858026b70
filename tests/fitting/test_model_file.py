"""The one model.json reader (fitting.output.model_file.read_model_json): exact round trip, one-line errors on bad files."""
import json

import numpy as np
import pytest

from cubedimer.errors import DatasetError
from fitting.output.model_file import read_model_json


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
