"""The fit's command-line options, generated from what the settings declare, and the one path from them to a
:class:`~fitting.config.FitConfig`.

Every command that fits (``python -m fitting fit``, ``python -m validation report``) adds the same options with
:func:`add_fit_options` and turns them into its configuration with :func:`fit_config_from_args`.  No option is
written here: ``--method`` offers the registered methods (:data:`fitting.method_names.METHODS`), the loading
options are those the loader's settings declare (:data:`cubedimer.load_config.LOAD_OPTIONS`), and every other
option is declared by the settings of the methods that take it (``MethodConfig.command_options``: the refinement's
``--max-evals`` and ``--joint-max-evals``, then the method's own, such as ``--heldout-tolerance`` or ``--selection``),
each with its flag, the field it sets, its type or choices and its help, the default read from the field.  An option
several methods declare is one argument whose help gives each method's meaning; a method whose settings do not
declare a given option refuses it in one line naming the methods that take it.  So a newly registered method's
options reach both commands with no other change.
"""
from __future__ import annotations

import argparse
from dataclasses import replace

from cubedimer.cli import UserInputError
from cubedimer.load_config import LOAD_OPTIONS, LoadConfig
from cubedimer.setting_options import SettingOption
from .config import FitConfig
from .method_names import DEFAULT_METHOD, METHODS, methods_help

__all__ = ["add_fit_options", "fit_config_from_args", "add_load_options", "load_config_from_args",
           "method_options_by_flag"]


def method_options_by_flag() -> dict[str, dict[str, SettingOption]]:
    """flag -> {method name: its declaration} over the registered methods' settings, in the order of the methods and
    of their declarations."""
    out: dict[str, dict[str, SettingOption]] = {}
    for name, method in METHODS.items():
        for option in method.config_type.command_options():
            out.setdefault(option.flag, {})[name] = option
    return out


def _merged_help(declared: dict[str, SettingOption]) -> str:
    """The help of an option as every method that declares it means it: one line when they all declare the same
    (with the same default), else ``method: line`` per meaning; the methods that take it are named unless all do."""
    lines: dict[str, list[str]] = {}
    for name, option in declared.items():
        lines.setdefault(option.help_text(METHODS[name].config_type()), []).append(name)
    if len(lines) == 1 and len(declared) == len(METHODS):
        return next(iter(lines))
    return "; ".join(f"{', '.join(names)}: {text}" for text, names in lines.items())


def add_load_options(parser: argparse.ArgumentParser | argparse._ArgumentGroup,
                     defaults: LoadConfig | None = None) -> None:
    """The loader's options (:data:`cubedimer.load_config.LOAD_OPTIONS`: ``--no-glitch-mask``, ``--min-periods``,
    ``--max-gap``), their defaults read from ``defaults`` (default: the fit's loading rules)."""
    defaults = FitConfig().load if defaults is None else defaults
    for option in LOAD_OPTIONS:
        option.add_to(parser, defaults)


def add_fit_options(parser: argparse.ArgumentParser | argparse._ArgumentGroup) -> None:
    """The fit's options: ``--method`` (the registered methods), every option the registered methods' settings
    declare (``MethodConfig.command_options``), then the loader's (:func:`add_load_options`)."""
    parser.add_argument("--method", choices=tuple(METHODS), default=DEFAULT_METHOD, help=methods_help())
    for flag, declared in method_options_by_flag().items():
        first = next(iter(declared.values()))
        first.add_to(parser, None, help=_merged_help(declared))
    add_load_options(parser)


def _applied(option: SettingOption, settings, value):
    try:
        return option.applied(settings, value)
    except ValueError as exc:
        raise UserInputError(f"{option.flag} {exc}") from None


def load_config_from_args(args: argparse.Namespace, load: LoadConfig) -> LoadConfig:
    """``load`` with the loader's options that are given (:func:`add_load_options`; one-line
    :class:`~cubedimer.cli.UserInputError` naming the option for a value the settings refuse)."""
    for option in LOAD_OPTIONS:
        if (value := option.given(args)) is not None:
            load = _applied(option, load, value)
    return load


def fit_config_from_args(args: argparse.Namespace) -> FitConfig:
    """The :class:`FitConfig` of the options of :func:`add_fit_options`: the method's default settings
    (``FittingMethod.config_type``) with the options applied to them and to the loading rules;
    :class:`cubedimer.cli.UserInputError` (one line naming the option) for an option the method's settings do not
    declare or a value out of range."""
    cfg = FitConfig.for_method(args.method)
    settings = cfg.method
    for flag, declared in method_options_by_flag().items():
        value = next(iter(declared.values())).given(args)
        if value is None:
            continue
        if args.method not in declared:
            raise UserInputError(f"{flag} applies to --method {', '.join(declared)}")
        settings = _applied(declared[args.method], settings, value)
    return replace(cfg, load=load_config_from_args(args, cfg.load), method=settings)
