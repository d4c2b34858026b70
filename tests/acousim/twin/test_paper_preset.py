"""The paper preset: the paper's 13 ms field drop on the full-wave model with the air's computed damping."""
import json

import numpy as np
import pytest

from acousim.dynamics.effects import air_damping_for
from acousim.twin import PAPER, PAPER_LIKE, TwinConfig, simulate_dataset, twin_dynamics
from acousim.twin.simulation import simulate_field_drop_runs
from cubedimer.executor import ExecutorConfig


def test_the_preset_is_the_protocol_without_tuned_parameters():
    assert PAPER.model_spec.name == "fullwave" and PAPER.air_damping
    assert PAPER.protocol.t_off == (13.0e-3, 13.0e-3)                 # the paper's drop
    assert PAPER.protocol.thetadot_drop == (0.0, 0.0)                 # at rest before the drop
    assert len(PAPER.effects) == 0                                     # nothing but the computed air damping
    assert "tuned" in PAPER_LIKE.description                         # the Gor'kov preset says what it is
    cfg = TwinConfig.from_preset(PAPER, runs=1, duration=0.5)
    dyn, _ = twin_dynamics(cfg)
    # the damping the twin integrates is the one computed from the dimer, at the model's own frequencies
    assert dyn.effects.to_dict() == {"air_damping": air_damping_for(dyn.force_model, cfg.conditions).params()}
    theta_eq, _ = dyn.force_model.equilibrium()
    lo, hi = PAPER.protocol.theta_drop
    assert lo < theta_eq < hi and hi - lo == pytest.approx(0.04)     # the hinge starts within +-0.02 of theta*


def test_the_preset_runs_and_is_reproducible(tmp_path):
    cfg = TwinConfig.from_preset(PAPER, runs=2, duration=1.0, seed=5)
    a = simulate_dataset(cfg, tmp_path / "a", ExecutorConfig(workers=1), progress=False)
    b, _, _ = simulate_field_drop_runs(cfg, ExecutorConfig(workers=1), progress=False)
    truth = json.loads((tmp_path / "a" / "truth.json").read_text())
    assert truth["air_damping"] is True and set(truth["effects"]) == {"air_damping"}
    assert truth["effects"] == a["effects"]
    for detail, run in zip(truth["runs_detail"], b):
        assert detail["t_off_s"] == 13.0e-3
        np.testing.assert_array_equal(detail["state_at_field_on"], run.state[0])  # same seed, same numbers
    c, _, _ = simulate_field_drop_runs(TwinConfig.from_preset(PAPER, runs=2, duration=1.0, seed=6),
                                       ExecutorConfig(workers=1), progress=False)
    assert not np.array_equal(c[0].theta, b[0].theta)  # another seed, another start


def test_the_command_takes_the_preset_dimer(tmp_path):
    from acousim.cli import build_parser
    from acousim.cli.simulate_command import build_config

    args = build_parser().parse_args(["simulate", "--preset", "paper", "--out", str(tmp_path / "x")])
    cfg = build_config(args)
    assert (cfg.force_model, cfg.side, cfg.model_spec.option_values, cfg.pressure_amplitude_pa, cfg.air_damping) == (
        "fullwave", 700e-6, {"gap_m": 35e-6}, 6000.0, True)
    args = build_parser().parse_args(["simulate", "--preset", "paper", "--side", "600e-6", "--gap", "18e-6",
                                      "--out", str(tmp_path / "x")])
    assert (build_config(args).side, build_config(args).model_spec.option_values) == (600e-6, {"gap_m": 18e-6})
    plain = build_config(build_parser().parse_args(["simulate", "--out", str(tmp_path / "y")]))
    assert (plain.force_model, plain.side, plain.air_damping) == ("gorkov", 500e-6, True)  # air damping by default


@pytest.mark.parametrize("argv, air", [
    ([], True),                                             # the twin's default damping: the air's
    (["--no-air-damping"], False),                          # the inviscid dimer
    (["--preset", "paper"], True),
    (["--preset", "paper", "--no-air-damping"], False),
    (["--preset", "paper-like"], False),                    # its tuned linear damping is the total: not twice
    (["--preset", "paper-like", "--model", "fullwave"], False),
])
def test_the_command_adds_the_air_damping_unless_switched_off_or_tuned(tmp_path, argv, air):
    from acousim.cli import build_parser
    from acousim.cli.simulate_command import build_config

    cfg = build_config(build_parser().parse_args(["simulate", *argv, "--out", str(tmp_path / "x")]))
    assert cfg.air_damping is air and cfg.to_dict()["air_damping"] is air


def test_air_damping_is_the_default_of_the_configuration_and_of_presets():
    assert TwinConfig().air_damping and TwinConfig().to_dict()["air_damping"] is True
    assert TwinConfig(air_damping=False).to_dict()["air_damping"] is False
    assert PAPER.air_damping and not PAPER_LIKE.air_damping
    assert TwinConfig.from_preset(PAPER_LIKE).air_damping is False
    assert TwinConfig.from_preset(PAPER_LIKE, air_damping=True).air_damping is True  # an override still wins
