"""Command line of acousim: ``python -m acousim {sweep,simulate} ...``.

Each subcommand lives in its own module and registers itself through an ``add_parser(subparsers)``
function; errors a user can fix (``UserInputError``) print one line and exit with status 2.
"""
from __future__ import annotations

import argparse
import re
import sys

__all__ = ["main", "run_cli", "UserInputError", "OneLineParser"]

_NEGATIVE_VALUE = re.compile(r"^-(\d|\.\d|inf)")


class UserInputError(Exception):
    """A problem with the user's arguments or files; printed as one line, exit status 2."""


class OneLineParser(argparse.ArgumentParser):
    """argparse parser whose errors are one line (no usage dump), exit status 2."""

    def error(self, message: str):  # noqa: D401 - argparse API
        self.exit(2, f"{self.prog}: error: {message} (see --help)\n")


def join_negative_values(argv: list[str]) -> list[str]:
    """Rewrite ``--opt -1:0.5:3`` as ``--opt=-1:0.5:3`` so negative numbers and ranges parse as values."""
    out: list[str] = []
    i = 0
    while i < len(argv):
        a = argv[i]
        if a.startswith("--") and "=" not in a and i + 1 < len(argv) and _NEGATIVE_VALUE.match(argv[i + 1]):
            out.append(f"{a}={argv[i + 1]}")
            i += 2
            continue
        out.append(a)
        i += 1
    return out


def build_parser() -> argparse.ArgumentParser:
    from . import sweep_cli

    parser = OneLineParser(
        prog="python -m acousim",
        description="Gor'kov acoustic model of a levitated cube dimer: static force/torque sweeps "
        "and synthetic experiments (digital twin).",
    )
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND", parser_class=OneLineParser)
    sweep_cli.add_parser(sub)
    from .fullwave import cli as fullwave_cli; fullwave_cli.add_parser(sub)  # noqa: E702
    try:
        from . import simulate_cli
    except ImportError:  # the twin is optional while it is being built
        simulate_cli = None
    if simulate_cli is not None:
        simulate_cli.add_parser(sub)
    return parser


def run_cli(parser: argparse.ArgumentParser, argv: list[str] | None = None) -> int:
    """Parse ``argv`` and run the chosen subcommand's ``func``: user errors become one line and exit 2."""
    args = parser.parse_args(join_negative_values(list(sys.argv[1:] if argv is None else argv)))
    try:
        return int(args.func(args) or 0)
    except UserInputError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130


def main(argv: list[str] | None = None) -> int:
    return run_cli(build_parser(), argv)
