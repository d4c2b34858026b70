"""The force-model registry: one interface, one registry, and a new model through every command unchanged."""
from __future__ import annotations

import ast
import dataclasses
from pathlib import Path

import numpy as np
import pytest

from acousim import models
from acousim.static_model import StaticModel
from acousim.models import (ConditionError, ExperimentConditions, ForceModelType, ModelSpec, force_model_names,
                            register_force_model, static_model)

ROOT = Path(__file__).resolve().parents[2]


# the velocity coupling's trajectory test (on by default; trajectory_test=False below) is not what
# this module checks: it is checked in test_velocity_output_error.py and, end to end, in
# test_pipeline_twin.py, and costs 10-15 CPU-s per diagnosis

@pytest.fixture
def dummy_model():
    """A registered model "stiff_gorkov": the Gor'kov model at 1.2 times the pressure amplitude (a different trap,
    so that a mix-up with the Gor'kov model shows)."""

    def scaled(c: ExperimentConditions) -> ExperimentConditions:
        return dataclasses.replace(c, pressure_amplitude_pa=1.2 * c.pressure_amplitude_pa)

    t = ForceModelType("stiff_gorkov", "test model", "stiff Gor'kov", lambda c: models._gorkov_static(scaled(c)),
                       lambda c: models._gorkov_dynamic(scaled(c)), frozenset({"mesh_size_m"}))
    register_force_model(t)
    yield t
    models.FORCE_MODEL_TYPES.pop("stiff_gorkov")


@pytest.fixture
def pressure_factor_model():
    """A new model option, ``--pressure-factor`` (registered with acousim.models.register_model_option), and a model
    "scaled_gorkov" that takes it: the Gor'kov model at the option times the pressure amplitude (1 when unset)."""

    option = models.register_model_option(models.ModelOption(
        "pressure_factor", "--pressure-factor", "scale of the pressure amplitude of scaled_gorkov (test)", "FACTOR"))

    def scaled(c: ExperimentConditions) -> ExperimentConditions:
        factor = c.option("pressure_factor") or 1.0
        return dataclasses.replace(c, pressure_amplitude_pa=factor * c.pressure_amplitude_pa, extra_options=())

    t = register_force_model(ForceModelType(
        "scaled_gorkov", "test model", "scaled Gor'kov", lambda c: models._gorkov_static(scaled(c)),
        lambda c: models._gorkov_dynamic(scaled(c)), frozenset({"pressure_factor"})))
    yield t, option
    models.FORCE_MODEL_TYPES.pop(t.name)
    models.REGISTERED_MODEL_OPTIONS.pop(option.name)
    models.OPTION_NAMES.pop(option.name)


def test_a_new_model_option_runs_from_the_command_line_to_the_diagnosis(pressure_factor_model, tmp_path):
    """A model option registered once (no other change) is offered by the sweep's, the twin's and the diagnosis's
    command lines, builds the sweep's model, reaches the specs, builds the twin's model (the data are simulated at 1.2 x 3000 Pa), is recorded in
    truth.json, and builds the diagnosis's model: with the same option the diagnosis's trap at the data's nominal
    pressure is the twin's, and its calibration finds the pressure ratio 1."""
    import json

    from acousim.cli import main as acousim_main
    from acousim.cli.model_options import model_spec_from_args
    from acousim.statics.sweep import read_sweep_csv
    from validation.cli import build_parser as validation_parser
    from validation.diagnosis import DiagnoseConfig, diagnose_dataset

    model, option = pressure_factor_model
    sweep = tmp_path / "s.csv"
    assert acousim_main(["sweep", "--model", model.name, "--pressure-factor", "1.2", "--theta", "-0.3:0.3:3", "--y",
                         "-1e-4:1e-4:3", "--out", str(sweep), "--quiet"]) == 0
    assert read_sweep_csv(sweep).settings["pressure_amplitude_pa"] == pytest.approx(3600.0)  # the sweep's model too
    data = tmp_path / "twin"
    assert acousim_main(["simulate", "--model", model.name, "--pressure-factor", "1.2", "--runs", "3", "--duration",
                         "1.5", "--seed", "2", "--out", str(data), "--no-progress"]) == 0
    truth = json.loads((data / "truth.json").read_text())
    assert truth["force_model"] == model.name and truth[option.name] == 1.2
    assert truth["nominal_pressure_amplitude_pa"] == 3000.0
    # the data come from the option: the twin's trap is the Gor'kov one at 3600 Pa
    reference = static_model("gorkov", ExperimentConditions(pressure_amplitude_pa=3600.0))
    assert truth["equilibrium_height_m"] == pytest.approx(reference.equilibrium_height, rel=1e-6)
    args = validation_parser().parse_args(["diagnose", str(data), "--out", str(tmp_path / "d"), "--model", model.name,
                                           "--pressure-factor", "1.2"])
    spec = model_spec_from_args(args)
    assert spec == ModelSpec(model.name, {option.name: 1.2})
    d = diagnose_dataset(data, DiagnoseConfig(long_time=False, discover=False, candidates=("linear_damping",),
                                              trajectory_test=False),
                         progress=False, spec=spec)
    # the diagnosis's model carries the option: at the data's nominal 3000 Pa it is the 3600-Pa trap (3000 Pa without
    # the option), and the calibration needs no further factor (1.2 without it); 2e-3: the calibration's scatter on
    # 3 short runs with the computed air damping (as in the test above)
    assert d.calibration["nominal_pressure_amplitude_pa"] == pytest.approx(3600.0, rel=1e-12)
    assert d.calibration["pressure_ratio"] == pytest.approx(1.0, rel=2e-3)
    assert d.model == model.name


def test_registered_names_and_the_default():
    assert force_model_names()[:2] == ("gorkov", "fullwave")


def test_static_models_satisfy_the_protocol():
    for name in force_model_names():
        m = static_model(name, ExperimentConditions())
        assert isinstance(m, StaticModel)
        assert m.name == name and m.record()["model"] == name


def test_unknown_model_is_named_with_the_choices():
    with pytest.raises(ConditionError, match="unknown force model 'bem'; choose one of gorkov, fullwave"):
        static_model("bem", ExperimentConditions())


@pytest.mark.parametrize("field,value,message", [
    ("side_length_m", -1e-4, "--side = -0.0001 must be positive"),
    ("frequency_hz", float("inf"), "--frequency = inf is not finite"),
    ("gap_m", 3e-4, "more than half the side"),
    ("quadrature_degree", 1, "at least 2"),
])
def test_conditions_validate_themselves(field, value, message):
    with pytest.raises(ConditionError, match=message):
        ExperimentConditions(**{field: value})


def test_a_new_model_runs_through_sweep_twin_and_diagnosis(dummy_model, tmp_path):
    """One registry entry is all a new model needs: the sweep command offers it, the twin integrates it and the
    diagnosis calibrates it."""
    from acousim.cli import main as acousim_main
    from acousim.statics.sweep import read_sweep_csv
    from acousim.twin import TwinConfig, simulate_dataset
    from validation.diagnosis import DiagnoseConfig, diagnose_dataset

    out = tmp_path / "s.csv"
    assert acousim_main(["sweep", "--model", "stiff_gorkov", "--theta", "-0.3:0.3:5", "--y", "-1e-4:1e-4:5",
                         "--out", str(out), "--quiet"]) == 0
    sw = read_sweep_csv(out)
    ref = static_model("gorkov", ExperimentConditions(pressure_amplitude_pa=3600.0))
    assert sw.settings["pressure_amplitude_pa"] == pytest.approx(3600.0)
    assert sw.settings["equilibrium_height_m"] == pytest.approx(ref.equilibrium_height, rel=1e-9)

    data = tmp_path / "twin"
    truth = simulate_dataset(TwinConfig(runs=3, duration=1.5, seed=2, model_spec=ModelSpec("stiff_gorkov")), data,
                             progress=False)
    assert truth["force_model"] == "stiff_gorkov"
    d = diagnose_dataset(data, DiagnoseConfig(long_time=False, discover=False, candidates=("linear_damping",),
                                              trajectory_test=False),
                         progress=False, spec=ModelSpec("stiff_gorkov"))
    # the data come from the model itself: the calibration finds the model's own amplitude, 1.2 x 3000 Pa (a
    # mix-up with the Gor'kov model would give 3000 Pa)
    assert d.calibration["pressure_amplitude_pa"] == pytest.approx(3600.0, rel=2e-3)
    assert d.model == "stiff_gorkov"


def _own_files(name: str) -> str:
    """Where a model may name itself: its static model's package (a subpackage of acousim) or module."""
    module = type(static_model(name, ExperimentConditions())).__module__
    package, _, leaf = module.rpartition(".")
    return package.replace(".", "/") + "/" if package.count(".") >= 1 else module.replace(".", "/") + ".py"


def test_no_module_names_a_model_outside_the_registry_and_its_own_files():
    """No module but the registry (acousim/models.py) and a model's own implementation holds a registered model's
    name as a string: no comparison (`x == "gorkov"`), no dictionary key or lookup (`rows["fullwave"]`,
    `.get("fullwave")`), no default or keyword (`model="gorkov"`). Every other module reaches a model through the
    registry, a ModelSpec or the constant of the model's own package."""
    names = set(force_model_names())
    own = {n: _own_files(n) for n in names}
    offenders = []
    for pkg in ("acousim", "fitting", "validation", "cubedimer", "tracking"):
        for path in (ROOT / pkg).rglob("*.py"):
            rel = path.relative_to(ROOT).as_posix()
            if rel == "acousim/models.py":
                continue
            offenders += [f"{rel}:{node.lineno} {node.value!r}" for node in ast.walk(ast.parse(path.read_text()))
                          if isinstance(node, ast.Constant) and isinstance(node.value, str)
                          and (node.value.split("+")[0] in names)
                          and not rel.startswith(own[node.value.split("+")[0]])]
    assert not offenders, offenders


def test_a_model_spec_checks_its_options_on_construction():
    """The spec carries the model and its own options: None values are left out, the default is the registry's first
    model, and an option the model does not take is refused in one line naming the option."""
    assert ModelSpec().name == force_model_names()[0]
    spec = ModelSpec("fullwave", {"gap_m": 10e-6, "edge_radius_m": None})
    assert spec.option_values == {"gap_m": 10e-6} and spec == ModelSpec("fullwave", (("gap_m", 10e-6),))
    assert spec.label == "full wave" and spec.type.name == "fullwave"
    c = spec.conditions({"side_length_m": 600e-6}, pressure_amplitude_pa=2500.0)
    assert (c.side_length_m, c.gap_m, c.pressure_amplitude_pa) == (600e-6, 10e-6, 2500.0)
    with pytest.raises(ConditionError, match="--gap applies to --model fullwave only"):
        ModelSpec("gorkov", {"gap_m": 10e-6})
    with pytest.raises(ConditionError, match="unknown force model 'nope'"):
        ModelSpec("nope")
    with pytest.raises(ConditionError, match="not a model option"):
        ModelSpec("gorkov", {"side_length_m": 1e-3})


def test_a_new_model_option_reaches_the_spec_from_the_command_line(dummy_model):
    """Every model option a command offers reaches the spec by its command-line name, with no per-model code."""
    import argparse

    from acousim.cli.model_options import model_spec_from_args
    from cubedimer.cli import UserInputError

    args = argparse.Namespace(model="stiff_gorkov", mesh_size=80e-6, gap=None, edge_radius=None)
    assert model_spec_from_args(args) == ModelSpec("stiff_gorkov", {"mesh_size_m": 80e-6})
    with pytest.raises(UserInputError, match="--gap applies to --model fullwave only"):
        model_spec_from_args(argparse.Namespace(model="stiff_gorkov", gap=1e-5))
