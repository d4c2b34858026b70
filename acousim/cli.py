"""Command line of acousim: ``python -m acousim {sweep,simulate,force,family,table,convergence,atlas} ...``.

Each subcommand lives in its own module and registers itself through an ``add_parser(subparsers)``
function; the runner is :func:`cubedimer.cli.run_cli`.
"""
from __future__ import annotations

import argparse

from cubedimer.cli import OneLineParser, run_cli

__all__ = ["main", "build_parser"]


def build_parser() -> argparse.ArgumentParser:
    from . import atlas_cli, simulate_cli, sweep_cli
    from .fullwave import cli as fullwave_cli
    from .fullwave import convergence, family_cli, table_cli

    parser = OneLineParser(
        prog="python -m acousim",
        description="The physics of a levitated cube dimer (the Gor'kov and the full-wave force models): static "
        "force/torque sweeps, synthetic experiments (digital twin), full-wave forces and tables.",
    )
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND", parser_class=OneLineParser)
    sweep_cli.add_parser(sub)
    simulate_cli.add_parser(sub)
    fullwave_cli.add_parser(sub)
    family_cli.add_parser(sub)
    table_cli.add_parser(sub)
    convergence.add_parser(sub)
    atlas_cli.add_parser(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    return run_cli(build_parser(), argv)
