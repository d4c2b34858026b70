"""Command-line options of the force-model registry (:mod:`acousim.models`), shared by every command with ``--model``.

The one path from a command's options to what it simulates: :func:`model_spec_from_args` (the model and its own
options, :func:`~acousim.models.model_options`) and :func:`experiment_from_args` (the experiment, the
:class:`~acousim.models.ExperimentConditions` fields of meta.json), each read by the options' command-line names
(:data:`~acousim.models.OPTION_NAMES`) over a default (a preset's, or a data set's meta.json), so that a command
names no option of a model itself.
"""
from __future__ import annotations

import argparse
from dataclasses import replace

from cubedimer.cli import UserInputError
from cubedimer.meta import check_meta_value

from ..models import (OPTION_NAMES, REGISTERED_MODEL_OPTIONS, ExperimentConditions, ModelSpec, force_model_names,
                      force_model_type, model_options, static_model)

__all__ = ["add_model_arguments", "conditions_from_args", "static_model_from_args", "model_help",
           "model_spec_from_args", "experiment_from_args"]


def _option(args: argparse.Namespace, name: str):
    """The value of the command-line option of the condition ``name`` (:data:`OPTION_NAMES`), None when the command
    does not offer it or it is not given."""
    return getattr(args, OPTION_NAMES[name].lstrip("-").replace("-", "_"), None)


def model_help() -> str:
    """One line per registered model, for ``--help``."""
    return "; ".join(f"{t.name}: {t.summary}" for t in map(force_model_type, force_model_names()))


def add_model_arguments(parser: argparse.ArgumentParser, unset_default: bool = False) -> None:
    """``--model`` (the registry's choices; default the registry's first model, or None with ``unset_default``, for a
    command whose preset may choose it), the hinge options ``--gap`` / ``--edge-radius`` and every registered model
    option (:func:`acousim.models.register_model_option`)."""
    parser.add_argument("--model", choices=force_model_names(), default=None if unset_default else force_model_names()[0],
                        help=f"force model ({model_help()})")
    parser.add_argument("--gap", type=float, default=None, metavar="METRES",
                        help="hinge gap g [m] of the full-wave model (default 0.01 x side; the shipped family covers "
                             "0.01-0.05 x side). validation diagnose/report calibrate it from the data when it is not "
                             "given")
    parser.add_argument("--edge-radius", type=float, default=None, metavar="METRES",
                        help="edge radius r_e [m] of the full-wave model (only sharp edges, 0, are tabulated)")
    for option in REGISTERED_MODEL_OPTIONS.values():  # every registered model option (acousim.models)
        parser.add_argument(option.flag, type=float, default=None, metavar=option.metavar, help=option.help)


def conditions_from_args(args: argparse.Namespace, meta: dict | None = None, **extra) -> ExperimentConditions:
    """The experiment of ``meta`` (or the defaults) with the options that are set (side, frequency, pressure,
    density, every model option the command offers: :func:`~acousim.models.model_options`) and ``extra`` (which
    wins, None included); one-line :class:`UserInputError` on a bad value."""
    names = ("side_length_m", "frequency_hz", "pressure_amplitude_pa", "particle_density_kg_m3", *model_options())
    options = {**{k: _option(args, k) for k in names}, **extra}
    try:
        return ExperimentConditions.from_meta(meta, **options)
    except ValueError as exc:
        raise UserInputError(str(exc)) from None


def _checked(build, args: argparse.Namespace, conditions: ExperimentConditions):
    try:
        return build(args.model, conditions)
    except ValueError as exc:  # ConditionError, FamilyRangeError, a field that cannot levitate the dimer
        raise UserInputError(str(exc)) from None


def static_model_from_args(args: argparse.Namespace, conditions: ExperimentConditions):
    """The static model of ``--model`` for ``conditions`` (one-line errors)."""
    return _checked(static_model, args, conditions)


def model_spec_from_args(args: argparse.Namespace, default: ModelSpec | None = None) -> ModelSpec:
    """The :class:`~acousim.models.ModelSpec` of ``--model`` with every model option the command offers that is set
    (``--gap``, ``--edge-radius``, ``--mesh-size``...: the :func:`~acousim.models.model_options` by their
    command-line names), over ``default`` (a preset's model and options; None: the registry's first model); one-line
    :class:`UserInputError` when the model does not take one."""
    name = args.model if getattr(args, "model", None) is not None else (default.name if default is not None else None)
    options = {**(default.option_values if default is not None else {}),
               **{k: v for k in model_options() if (v := _option(args, k)) is not None}}
    try:
        return ModelSpec(name, options)
    except ValueError as exc:
        raise UserInputError(str(exc)) from None


def experiment_from_args(args: argparse.Namespace, default: ExperimentConditions | None = None) -> ExperimentConditions:
    """The experiment (:class:`~acousim.models.ExperimentConditions` without the model's own options) of ``default``
    (a preset's; None: the defaults of docs/conventions.md) with the experiment's options the command offers that are
    set (``--side``, ``--frequency``, ``--pressure``, ``--density``...: the meta.json fields by their command-line
    names), each checked against the range meta.json allows; one-line :class:`UserInputError` on a bad value."""
    given = {k: v for k in ExperimentConditions.META_FIELDS if k in OPTION_NAMES and (v := _option(args, k)) is not None}
    for key, value in given.items():
        check_meta_value(key, value, OPTION_NAMES[key])
    try:
        return replace(default if default is not None else ExperimentConditions(), **given)
    except ValueError as exc:
        raise UserInputError(str(exc)) from None
