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
    d = diagnose_dataset(data, DiagnoseConfig(long_time=False, discover=False, candidates=("linear_damping",)),
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

    from acousim.cli.models import model_spec_from_args
    from cubedimer.cli import UserInputError

    args = argparse.Namespace(model="stiff_gorkov", mesh_size=80e-6, gap=None, edge_radius=None)
    assert model_spec_from_args(args) == ModelSpec("stiff_gorkov", {"mesh_size_m": 80e-6})
    with pytest.raises(UserInputError, match="--gap applies to --model fullwave only"):
        model_spec_from_args(argparse.Namespace(model="stiff_gorkov", gap=1e-5))
