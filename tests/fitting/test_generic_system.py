"""Any two coordinates: a generic system declared in meta.json is loaded with its names and units, fitted, and
written in its declared names; bad declarations get one line; validation refuses the set; the levitated dimer stays
the default."""
import json

import numpy as np
import pytest

from cubedimer.dataset import DatasetError, LoadConfig, load_dataset, load_run
from cubedimer.meta import read_meta
from cubedimer.system import LEVITATED_DIMER, read_system
from fitting.cli import main
from fitting.output.model_file import read_model_json
from fitting.model import PolynomialModel
from fitting.synthetic import SyntheticConfig, generate_runs

W1, W2 = 2 * np.pi * 1.2, 2 * np.pi * 2.0
#: two coupled nonlinear oscillators (angles [rad]) at 1.2 and 2 Hz, in the library's slots (y = phi1, theta = phi2)
TRUTH = PolynomialModel.from_equations({
    "yddot": {"y": -W1**2, "ydot": -0.15, "y^3": 15.0, "theta": 12.0},
    "thetaddot": {"theta": -W2**2, "thetadot": -0.3, "y^2*theta": 20.0, "y": 25.0}})
CFG = SyntheticConfig(n_runs=5, duration=16.0, fps=200.0, noise_y=0.002, noise_theta=0.002, y_amplitude=(0.3, 0.6),
                      theta_amplitude=(0.1, 0.3), missing_frames=0, seed=3)
SYSTEM = {"kind": "generic", "coordinates": [{"name": "phi1", "unit": "rad", "velocity": "omega1"},
                                             {"name": "phi2", "unit": "rad"}], "frequency_range_hz": [0.5, 5]}
DEG = 180 / np.pi


def _write(path, raw, system=SYSTEM, header="t,phi1 [deg],phi2 [deg],omega1 [deg/s]", velocity_factor=DEG):
    """Runs in degrees (the header's labels), a measured phi1 rate with noise 0.02 rad/s, and meta.json."""
    path.mkdir()
    for i, r in enumerate(raw, 1):
        om = r["state"][:, 1] + 0.02 * np.random.default_rng(i).standard_normal(r["t"].size)
        rows = [header] + [f"{t:.5f},{a * DEG:.6f},{b * DEG:.6f},{c * velocity_factor:.6f}"
                           for t, a, b, c in zip(r["t"], r["y"], r["theta"], om)]
        (path / f"run{i:02d}.csv").write_text("\n".join(rows) + "\n")
    (path / "meta.json").write_text(json.dumps({"system": system}))
    return path


@pytest.fixture(scope="module")
def raw():
    return generate_runs(TRUTH, CFG)


def test_a_generic_system_is_fitted_end_to_end_in_its_declared_names(raw, tmp_path):
    data = _write(tmp_path / "data", raw)
    out = tmp_path / "out"
    assert main(["fit", str(data), "--out", str(out), "--no-plots", "--quiet", "--workers", "1", "--max-evals", "40"]) == 0
    m = json.loads((out / "model.json").read_text())
    assert m["state"] == ["phi1", "phi1dot", "phi2", "phi2dot"] and m["system"]["kind"] == "generic"
    assert m["selected_terms"] == {"phi1ddot": ["phi1", "phi1dot", "phi2", "phi1^3"],
                                   "phi2ddot": ["phi1", "phi2", "phi2dot", "phi1^2*phi2"]}
    # every coefficient of the discovery within 4 of its stated standard errors of the truth (8 comparisons)
    back = TRUTH.equations()
    for eq, internal in (("phi1ddot", "yddot"), ("phi2ddot", "thetaddot")):
        for term, est in m["discovery"][eq]["terms"].items():
            true = back[internal][{"phi1": "y", "phi1dot": "ydot", "phi2": "theta", "phi2dot": "thetadot",
                                   "phi1^3": "y^3", "phi1^2*phi2": "y^2*theta"}[term]]
            assert abs(est["value"] - true) < 4 * est["std_error"], (eq, term, est, true)
    # the file reads back into the library's model (the declared names translated)
    model_file = read_model_json(out / "model.json")
    assert model_file.system.generic and model_file.system.equation_names == ("phi1ddot", "phi2ddot")
    model = model_file.model
    assert (model.support == TRUTH.support).all()
    # the measured rate is used in place of the derivative of phi1: present, converted from deg/s
    ds = load_dataset(data, config=LoadConfig(systems=("levitated_dimer", "generic")))
    v = ds.runs[0].velocities
    assert np.isnan(v[:, 1]).all()
    np.testing.assert_allclose(v[:, 0], raw[0]["state"][:, 1], atol=0.1)  # 5 sigma of the 0.02 rad/s noise


def test_the_default_is_the_levitated_dimer_and_other_commands_refuse_a_generic_set(raw, tmp_path):
    data = _write(tmp_path / "data", raw[:2])
    assert read_system({}) is LEVITATED_DIMER and read_system({"system": {"kind": "levitated_dimer"}}) is LEVITATED_DIMER
    with pytest.raises(DatasetError, match="meta.json: declares a generic system .phi1, phi2.; this command reads "
                                           "levitated_dimer data sets only"):
        load_dataset(data)  # the default LoadConfig: what validation's diagnosis loads with
    from validation.simulation import model_from_meta
    with pytest.raises(DatasetError, match="validation is for levitated dimers only") as info:
        model_from_meta(read_meta(data))
    assert "\n" not in str(info.value)


@pytest.mark.parametrize("system, message", [
    ({"kind": "generic", "coordinates": [{"name": "phi1", "unit": "rad"}], "frequency_range_hz": [0.5, 5]},
     "system.coordinates must list exactly two coordinates"),
    ({"kind": "generic", "coordinates": [{"name": "a", "unit": "rad"}, {"name": "adot", "unit": "rad"}],
      "frequency_range_hz": [0.5, 5]}, "must be distinct"),
    ({"kind": "generic", "coordinates": [{"name": "phi1", "unit": "furlong"}, {"name": "phi2", "unit": "rad"}],
      "frequency_range_hz": [0.5, 5]}, r"system.coordinates\[0\].unit 'furlong' cannot be read"),
    ({"kind": "generic", "coordinates": [{"name": "phi1", "unit": "rad"}, {"name": "phi2", "unit": "rad"}],
      "frequency_range_hz": [5, 0.5]}, "frequency_range_hz must be"),
    ({"kind": "robot"}, "system.kind 'robot' is not one of"),
])
def test_bad_declarations_get_one_line(tmp_path, system, message):
    (tmp_path / "meta.json").write_text(json.dumps({"system": system}))
    with pytest.raises(DatasetError, match=message) as info:
        read_meta(tmp_path)
    assert str(info.value).startswith(str(tmp_path / "meta.json")) and "\n" not in str(info.value)


@pytest.mark.parametrize("header, factor, message", [
    ("t,phi1 [mm],phi2 [deg],omega1 [deg/s]", DEG, r"column 'phi1 \[mm\]': unit label not read for a coordinate "
                                                   "declared in rad"),
    ("t,phi1 [deg],phi2 [deg],omega1 [deg]", DEG, r"column 'omega1 \[deg\]' is a velocity"),
    ("t,phi1 [deg],phi2 [deg],omega1 [rad/s]", DEG, "column 'omega1': its integral over one period disagrees"),
    ("t,phi1 [deg],phi2 [deg],omega1 [deg/s]", -DEG, "column 'omega1': its integral over one period disagrees"),
    ("t,phi1 [deg],theta [deg],omega1 [deg/s]", DEG, "missing column 'phi2'"),
])
def test_bad_columns_get_one_line_naming_file_and_column(raw, tmp_path, header, factor, message):
    # a velocity in rad/s labelled as such but written in deg/s (57 times too large), or of the wrong sign, misses
    # the positions' increments by the size of the motion
    data = _write(tmp_path / "data", raw[:1], header=header, velocity_factor=factor)
    with pytest.raises(DatasetError, match=message) as info:
        load_run(data / "run01.csv", system=read_system(read_meta(data)))
    assert str(info.value).startswith(str(data / "run01.csv")) and "\n" not in str(info.value)
    assert main(["fit", str(data), "--out", str(tmp_path / "out"), "--strict", "--quiet"]) == 2
    assert not (tmp_path / "out" / "model.json").exists()


def test_minimum_periods_is_an_option(raw, tmp_path, capsys):
    # 16 s at 1.2 Hz hold 19 periods: refused when 25 are required, read with the default 5
    data = _write(tmp_path / "data", raw[:2])
    system = read_system(read_meta(data))
    with pytest.raises(DatasetError, match="too short to hold 25 oscillation periods .* dominant phi1 frequency"):
        load_run(data / "run01.csv", LoadConfig(min_periods=25), system=system)
    assert load_run(data / "run01.csv", system=system).t.size == CFG.duration * CFG.fps
    capsys.readouterr()
    assert main(["fit", str(data), "--out", str(tmp_path / "out"), "--min-periods", "25", "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "every file fails the same check" in err[0] and "too short to hold 25" in err[0]


def test_compare_reads_a_generic_model_and_data_set(raw, tmp_path):
    data = _write(tmp_path / "data", raw[:3])
    out = tmp_path / "out"
    assert main(["fit", str(data), "--out", str(out), "--no-plots", "--quiet", "--max-evals", "10"]) == 0
    assert main(["compare", str(data), "--model", str(out / "model.json"), "--out", str(out), "--no-plots",
                 "--drop", "phi2ddot:phi1^2*phi2", "--no-reoptimise"]) == 0
    assert json.loads((out / "compare.json").read_text())["variant_label"] == "without phi2ddot:phi1^2*phi2"
