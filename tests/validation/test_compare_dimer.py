"""`validation compare` refuses a sweep of another dimer than the fitted data's, in one line, unless told."""
import json

import numpy as np
import pytest

from validation.cli import _check_same_dimer, main
from cubedimer.cli import UserInputError

MODEL = {"state": ["y", "ydot", "theta", "thetadot"], "units": "SI",
         "equations": {"yddot": {"y": -1.9e4}, "thetaddot": {"theta": -300.0}}}


@pytest.fixture(scope="module")
def sweep_csv(tmp_path_factory, default_model):
    from acousim import static_sweep

    path = tmp_path_factory.mktemp("sweep") / "sweep.csv"
    static_sweep(default_model, np.linspace(-0.3, 0.3, 5), np.linspace(-1e-4, 1e-4, 5)).to_csv(path)
    return path


def test_a_sweep_of_another_dimer_is_refused_in_one_line(tmp_path, sweep_csv, capsys):
    (tmp_path / "model.json").write_text(json.dumps(MODEL))
    data = tmp_path / "data"
    data.mkdir()
    (data / "meta.json").write_text(json.dumps({"side_length_m": 450e-6, "frequency_hz": 42000.0}))
    out = tmp_path / "out"
    code = main(["compare", "--model", str(tmp_path / "model.json"), "--sweep", str(sweep_csv), "--data", str(data),
                 "--out", str(out)])
    err = capsys.readouterr().err.strip()
    assert code == 2 and "\n" not in err and not out.exists()
    assert "another dimer" in err and "side 500 um against 450" in err and "--other-dimer" in err
    assert "frequency 4.565e+04 Hz against 4.2e+04" in err


def test_the_data_s_own_dimer_passes(sweep_csv):
    from acousim.statics.sweep import read_sweep_csv

    settings = read_sweep_csv(sweep_csv).settings
    _check_same_dimer(str(sweep_csv), settings, {}, "data")  # the defaults: the sweep's dimer
    with pytest.raises(UserInputError, match=r"side 500 um against 525, ks 0.418\d* against 0.439"):  # 5 % larger cubes
        _check_same_dimer(str(sweep_csv), settings, {"side_length_m": 525e-6}, "data")


def test_model_json_records_the_data_s_dimer_and_where_each_constant_came_from():
    from cubedimer.meta import META_DEFAULTS
    from fitting.output.model_file import dimer_record

    rec = dimer_record({"side_length_m": 450e-6, "frequency_hz": 42000.0, "comment": "lab B"})
    assert rec["side_length_m"] == 450e-6 and rec["frequency_hz"] == 42000.0
    assert rec["particle_density_kg_m3"] == META_DEFAULTS["particle_density_kg_m3"]  # not stated: the default
    assert rec["from_meta_json"] == ["side_length_m", "frequency_hz"]
    assert set(rec) == {*META_DEFAULTS, "from_meta_json"}


def test_a_sweep_of_another_dimer_is_refused_from_model_json_alone(tmp_path, sweep_csv, capsys):
    """No --data: the dimer model.json records (a fit of 450 um / 42 kHz data) is checked against the sweep's
    (the default 500 um / 45.65 kHz dimer), in one line naming model.json; --other-dimer compares anyway."""
    from fitting.output.model_file import dimer_record

    model = tmp_path / "model.json"
    model.write_text(json.dumps({**MODEL, "dimer": dimer_record({"side_length_m": 450e-6, "frequency_hz": 42000.0})}))
    out = tmp_path / "out"
    code = main(["compare", "--model", str(model), "--sweep", str(sweep_csv), "--out", str(out)])
    err = capsys.readouterr().err.strip()
    assert code == 2 and "\n" not in err and not out.exists()
    assert f"{model}'s dimer" in err and "side 500 um against 450" in err and "--other-dimer" in err
    # the same dimer as the sweep's passes the check (and the comparison is written)
    model.write_text(json.dumps({**MODEL, "dimer": dimer_record({})}))
    assert main(["compare", "--model", str(model), "--sweep", str(sweep_csv), "--out", str(out)]) == 0
    assert (out / "comparison.json").exists()
