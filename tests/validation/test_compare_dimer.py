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
