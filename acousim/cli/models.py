"""Command-line options of the force-model registry (:mod:`acousim.models`), shared by every command with ``--model``."""
from __future__ import annotations

import argparse

from cubedimer.cli import UserInputError

from ..models import (MODEL_OPTIONS, OPTION_NAMES, ExperimentConditions, ModelSpec, force_model_names, force_model_type,
                      static_model)

__all__ = ["add_model_arguments", "conditions_from_args", "static_model_from_args", "model_help",
           "model_spec_from_args"]


def model_help() -> str:
    """One line per registered model, for ``--help``."""
    return "; ".join(f"{t.name}: {t.summary}" for t in map(force_model_type, force_model_names()))


def add_model_arguments(parser: argparse.ArgumentParser, unset_default: bool = False) -> None:
    """``--model`` (the registry's choices; default the registry's first model, or None with ``unset_default``, for a
    command whose preset may choose it) and the hinge options ``--gap`` / ``--edge-radius``."""
    parser.add_argument("--model", choices=force_model_names(), default=None if unset_default else force_model_names()[0],
                        help=f"force model ({model_help()})")
    parser.add_argument("--gap", type=float, default=None, metavar="METRES",
                        help="hinge gap g [m] of the full-wave model (default 0.01 x side; the shipped family covers "
                             "0.01-0.05 x side). validation diagnose/report calibrate it from the data when it is not "
                             "given")
    parser.add_argument("--edge-radius", type=float, default=None, metavar="METRES",
                        help="edge radius r_e [m] of the full-wave model (only sharp edges, 0, are tabulated)")


def conditions_from_args(args: argparse.Namespace, meta: dict | None = None, **extra) -> ExperimentConditions:
    """The experiment of ``meta`` (or the defaults) with the options that are set (side, frequency, pressure,
    density, gap, edge radius and ``extra``); one-line :class:`UserInputError` on a bad value."""
    options = {"side_length_m": getattr(args, "side", None), "frequency_hz": getattr(args, "frequency", None),
               "pressure_amplitude_pa": getattr(args, "pressure", None),
               "particle_density_kg_m3": getattr(args, "density", None),
               "gap_m": getattr(args, "gap", None), "edge_radius_m": getattr(args, "edge_radius", None), **extra}
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


def model_spec_from_args(args: argparse.Namespace) -> ModelSpec:
    """The :class:`~acousim.models.ModelSpec` of ``--model`` with every model option the command offers that is set
    (``--gap``, ``--edge-radius``, ``--mesh-size``...: the :data:`~acousim.models.MODEL_OPTIONS` by their
    command-line names); one-line :class:`UserInputError` when the model does not take one."""
    options = {name: getattr(args, OPTION_NAMES[name].lstrip("-").replace("-", "_"), None) for name in MODEL_OPTIONS}
    try:
        return ModelSpec(args.model, options)
    except ValueError as exc:
        raise UserInputError(str(exc)) from None
