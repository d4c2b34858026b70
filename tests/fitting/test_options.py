"""The fit's options are generated from what the settings declare (fitting.options): a method registered with an
option of its own gets it on every command that fits, parsed and applied to its settings, and refused in one line by
the methods that do not declare it; the loader's options reach every command that loads a data set."""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import ClassVar

import pytest

from cubedimer.load_config import LOAD_OPTIONS, LoadConfig
from cubedimer.setting_options import SettingOption, positive_int
from fitting.config import FitConfig, MethodConfig
from fitting.methods import registry as methods
from fitting.options import fit_config_from_args, load_config_from_args
from fitting.refinement.long_time import RefineConfig


@dataclass(frozen=True)
class StencilConfig:
    """A nested stage of the dummy settings (the option sets a field two levels down)."""

    order: int = 3


@dataclass(frozen=True)
class DummyConfig(MethodConfig):
    """The dummy method's settings: a stencil whose order ``--stencil-order`` sets (odd only) and a switch."""

    name: ClassVar[str] = "dummy-options"
    options: ClassVar[tuple[SettingOption, ...]] = (
        SettingOption("--stencil-order", "stencil.order", type=positive_int, metavar="N",
                      valid=lambda v: v % 2 == 1, requirement="needs an odd order",
                      help="order of the dummy stencil (default {default})"),
        SettingOption("--no-stencil", "stencil", switch=None, help="fit without the dummy stencil"),
    )
    stencil: StencilConfig | None = field(default_factory=StencilConfig)
    joint: RefineConfig = field(default_factory=lambda: RefineConfig(max_evals=4, horizons=(1.0,)))


@dataclass(frozen=True)
class DummyMethod:
    """Registered for its options only: the tests never run its fit."""

    name: str = "dummy-options"
    summary: str = "a method with options of its own (test)"
    config_type: type = DummyConfig

    def fit(self, prepared, scales, config, context):
        raise AssertionError("the option tests never fit")

    def describe(self, result):
        raise AssertionError("the option tests never describe")


@pytest.fixture
def dummy_method():
    method = methods.register_method(DummyMethod())
    yield method
    del methods.METHODS[method.name]  # registered for this test only


def _command(parser, command):
    return next(a for a in parser._actions if a.__class__.__name__ == "_SubParsersAction").choices[command]


def _help(parser, command, flag):
    return next(a.help for a in _command(parser, command)._actions if flag in a.option_strings)


def _parsers():
    from fitting.cli import build_parser as fit_parser
    from validation.cli import build_parser as validation_parser

    return {"fit": fit_parser(), "report": validation_parser()}


def _parse(command, *extra):
    return _parsers()[command].parse_args([command, "data", "--out", "out", *extra])


@pytest.mark.parametrize("command", ["fit", "report"])
def test_a_registered_method_s_option_is_parsed_and_applied_by_every_command_that_fits(dummy_method, command):
    """``--stencil-order`` is offered with its declared help and the default read from the settings, and sets the
    nested field; ``--max-evals`` sets the dummy's main refinement (its joint re-optimisation, the base's
    ``max_evals_setting``), the switch sets its field, and the loader's options still reach the loader."""
    assert _help(_parsers()[command], command, "--stencil-order") == "dummy-options: order of the dummy stencil (default 3)"
    cfg = fit_config_from_args(_parse(command, "--method", "dummy-options", "--stencil-order", "5", "--max-evals", "7",
                                      "--min-periods", "2"))
    assert isinstance(cfg.method, DummyConfig)
    assert (cfg.method.stencil.order, cfg.method.joint.max_evals, cfg.load.min_periods) == (5, 7, 2.0)
    assert cfg.method.joint.horizons == (1.0,)  # the rest of the settings is the dummy's own default
    assert fit_config_from_args(_parse(command, "--method", "dummy-options", "--no-stencil")).method.stencil is None
    assert fit_config_from_args(_parse(command, "--method", "dummy-options")) == FitConfig.for_method("dummy-options")
    # the merged help of an option several methods declare names each method's meaning of it
    assert "dummy-options: objective evaluations of the joint re-optimisation (default 4)" in _help(
        _parsers()[command], command, "--max-evals")


def test_the_two_commands_make_the_same_settings_of_the_same_options(dummy_method):
    extra = ["--method", "dummy-options", "--stencil-order", "7", "--joint-max-evals", "9", "--no-glitch-mask"]
    assert fit_config_from_args(_parse("fit", *extra)) == fit_config_from_args(_parse("report", *extra))


@pytest.mark.parametrize("command", ["fit", "report"])
@pytest.mark.parametrize("extra, says", [
    (["--stencil-order", "5"], "error: --stencil-order applies to --method dummy-options"),  # the discovery's fit
    (["--method", "paper", "--no-stencil"], "error: --no-stencil applies to --method dummy-options"),
    (["--method", "dummy-options", "--stencil-order", "4"], "error: --stencil-order 4: needs an odd order"),
    (["--method", "dummy-options", "--heldout-tolerance", "0.002"], "error: --heldout-tolerance applies to --method "
                                                                    "discovery"),
])
def test_an_option_the_method_does_not_take_is_refused_in_one_line(dummy_method, tmp_path, capsys, command, extra,
                                                                   says):
    """Exit status 2, one line naming the option and the methods that take it (or what a valid value is), before
    any data are read: nothing is written."""
    from fitting.cli import main as fit_main
    from validation.cli import main as validation_main

    out = tmp_path / "out"
    main = fit_main if command == "fit" else validation_main
    assert main([command, str(tmp_path / "no-data"), "--out", str(out), "--quiet", *extra]) == 2
    err = capsys.readouterr().err.strip()
    assert err == says and "\n" not in err
    assert not out.exists()


def test_an_unregistered_method_s_option_is_gone_from_the_commands(dummy_method):
    assert any("--stencil-order" in a.option_strings for a in _command(_parsers()["fit"], "fit")._actions)
    del methods.METHODS[dummy_method.name]
    try:
        for command, parser in _parsers().items():
            assert not any("--stencil-order" in a.option_strings for a in _command(parser, command)._actions)
    finally:
        methods.METHODS[dummy_method.name] = dummy_method


@pytest.mark.parametrize("option, says", [
    (SettingOption("--max-gap", "joint.max_evals", type=positive_int, help="x"), "an option of the fit's loading"),
    (SettingOption("--stencil-width", "stencil.width", type=positive_int, help="x"), "which its settings do not have"),
    (SettingOption("--heldout-tolerance", "joint.max_evals", type=positive_int, metavar="FRACTION", help="x"),
     "declared by another method with another type"),
])
def test_registering_refuses_an_option_that_cannot_join_the_parser(option, says, monkeypatch):
    monkeypatch.setattr(DummyConfig, "options", (option,))
    with pytest.raises(TypeError, match=says):
        methods.register_method(DummyMethod())
    assert "dummy-options" not in methods.METHODS


def test_the_diagnosis_takes_the_loader_s_options_with_its_own_defaults():
    """``validation diagnose`` loads as the fit does: the loader's declared options, with LoadConfig's defaults
    (a levitated dimer only) in its help and under the given values."""
    from validation.cli import build_parser

    parser = build_parser()
    flags = {o for a in _command(parser, "diagnose")._actions for o in a.option_strings}
    assert {o.flag for o in LOAD_OPTIONS} <= flags
    args = parser.parse_args(["diagnose", "data", "--out", "out", "--min-periods", "8", "--max-gap", "3"])
    load = load_config_from_args(args, LoadConfig())
    assert (load.min_periods, load.max_gap, load.systems) == (8.0, 3, LoadConfig().systems)
    assert load.glitches == LoadConfig().glitches  # not given: the default mask
    assert "(default 5)" in _help(parser, "diagnose", "--min-periods")
