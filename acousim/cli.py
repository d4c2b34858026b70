"""Command line of acousim: ``python -m acousim {sweep,simulate} ...``.

Each subcommand lives in its own module and registers itself through an ``add_parser(subparsers)``
function; errors a user can fix (``UserInputError``) print one line and exit with status 2.
"""
from __future__ import annotations

import argparse
import sys

__all__ = ["main", "UserInputError"]


class UserInputError(Exception):
    """A problem with the user's arguments or files; printed as one line, exit status 2."""


def build_parser() -> argparse.ArgumentParser:
    from . import sweep_cli

    parser = argparse.ArgumentParser(
        prog="python -m acousim",
        description="Gor'kov acoustic model of a levitated cube dimer: static force/torque sweeps "
        "and synthetic experiments (digital twin).",
    )
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    sweep_cli.add_parser(sub)
    try:
        from . import simulate_cli
    except ImportError:  # the twin is optional while it is being built
        simulate_cli = None
    if simulate_cli is not None:
        simulate_cli.add_parser(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except UserInputError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130
