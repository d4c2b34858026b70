"""Command line of acousim: ``python -m acousim {sweep,simulate,force,family,table,convergence,atlas,held-y,resonator-map,free-y-map} ...``.

Each subcommand lives in its own module of this package, ``<command>_command.py``, and registers itself through an
``add_parser(subparsers)`` function; the runner is :func:`cubedimer.cli.run_cli`.
"""
from __future__ import annotations

import argparse

from cubedimer.cli import command_parser, run_cli

from ..fullwave.solver import AssemblyBackendError
from . import (atlas_command, convergence_command, family_command, force_command, free_y_command, held_y_command,
               resonator_map_command, simulate_command, sweep_command, table_command)

__all__ = ["main", "build_parser", "COMMANDS"]

#: The commands of ``python -m acousim``, in the order of the help.
COMMANDS = (sweep_command.add_parser, simulate_command.add_parser, force_command.add_parser,
            family_command.add_parser, table_command.add_parser, convergence_command.add_parser,
            atlas_command.add_parser, held_y_command.add_parser, resonator_map_command.add_parser,
            free_y_command.add_parser)


def build_parser() -> argparse.ArgumentParser:
    """The parser of ``python -m acousim`` (one ``add_parser`` function per command)."""
    return command_parser("python -m acousim",
                          "The physics of a levitated cube dimer (the Gor'kov and the full-wave force models): static "
                          "force/torque sweeps, synthetic experiments (digital twin), full-wave forces and tables. "
                          "Conventions: docs/conventions.md; files: docs/formats.md.", COMMANDS)


def main(argv: list[str] | None = None) -> int:
    return run_cli(build_parser(), argv, errors=(AssemblyBackendError,))
