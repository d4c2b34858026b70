"""The one command-line runner of the suite (``python -m acousim|fitting|validation ...``).

Each package's ``cli`` module builds an :class:`OneLineParser` with one sub-parser per command
(``add_parser(subparsers)`` functions that set ``func``) and calls :func:`run_cli`, which

* configures logging (library code logs; progress bars stay on stderr),
* turns errors a user can fix (:class:`UserInputError`, :class:`~cubedimer.dataset.DatasetError`,
  :class:`~cubedimer.executor.ExecutorError`) into one line ``error: ...`` on stderr and exit status 2, with no traceback,
* turns Ctrl-C into exit status 130 with a line on what was kept.

Shared options live here too, so that every command spells them the same way:
:func:`add_executor_arguments` (``--workers``, ``--scheduler``), :func:`prepare_output_dir` and
:func:`prepare_output_file` (checked before any computation starts, so an unwritable ``--out`` costs
nothing) and :func:`check_limit` (sizes refused before anything is allocated).
"""
from __future__ import annotations

import argparse
import logging
import math
import os
import re
import sys
import tempfile
from pathlib import Path
from typing import Callable, Sequence

from .dataset import DatasetError
from .distribution import DISTRIBUTION, __version__
from .executor import ExecutorConfig, ExecutorError, single_blas_thread
from .setting_options import positive_float, positive_int

__all__ = ["UserInputError", "OneLineParser", "command_parser", "run_cli", "configure_logging", "join_negative_values",
           "add_executor_arguments", "executor_config", "prepare_output_dir", "prepare_output_file", "check_limit",
           "positive_int", "positive_float", "float_list", "invoked_as", "field_default"]

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


def configure_logging(quiet: bool = False, verbose: bool = False) -> None:
    """Send the suite's log records (loggers ``acousim``, ``fitting``, ``validation``, ``tracking``, ``cubedimer``) to
    stderr as plain lines; ``quiet`` keeps warnings and errors only, ``verbose`` adds debug lines."""
    level = logging.WARNING if quiet else (logging.DEBUG if verbose else logging.INFO)
    handler = logging.StreamHandler(sys.stderr)
    handler.setFormatter(logging.Formatter("[%(name)s] %(message)s"))
    for name in ("acousim", "fitting", "validation", "cubedimer", "tracking"):
        log = logging.getLogger(name)
        log.handlers[:] = [handler]
        log.setLevel(level)
        log.propagate = False


def field_default(config_class: type, name: str):
    """The default of the field ``name`` of the dataclass ``config_class``: a command's option reads its default (and
    the default its help names) from the config it fills, never a copy."""
    f = config_class.__dataclass_fields__[name]
    return f.default_factory() if callable(f.default_factory) else f.default


def float_list(text: str, option: str) -> list[float]:
    """Comma-separated finite, non-negative numbers of the option ``option``; one-line :class:`UserInputError`."""
    try:
        values = [float(x) for x in text.split(",")]
    except ValueError:
        raise UserInputError(f"{option} {text!r}: expected comma-separated numbers") from None
    if not all(math.isfinite(v) and v >= 0 for v in values):
        raise UserInputError(f"{option} {text!r}: values must be finite and non-negative")
    return values


def add_executor_arguments(parser: argparse.ArgumentParser, note: str | None = None) -> None:
    """``--workers N`` and ``--scheduler ADDRESS``, the same on every parallel command.

    ``note`` is added to the group's description (e.g. which part of the command runs in parallel).
    """
    description = ("Work that runs inside a parallel task (a worker process or a dask worker) runs serially "
                   "there; results are the same wherever the work ran.")
    g = parser.add_argument_group("where parallel work runs", f"{description} {note}" if note else description)
    g.add_argument("--workers", type=positive_int, default=None, metavar="N",
                   help="local worker processes (default: one per core; 1 runs everything in this process)")
    g.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="address of a running dask.distributed scheduler, e.g. tcp://host:8786 (overrides "
                        "--workers; default: $CUBEDIMER_SCHEDULER if set). Needs pip install 'cubedimer[dask]'")


def executor_config(args: argparse.Namespace) -> ExecutorConfig:
    """The :class:`ExecutorConfig` of the options added by :func:`add_executor_arguments`."""
    return ExecutorConfig(workers=getattr(args, "workers", None), scheduler=getattr(args, "scheduler", None))


def _probe(directory: Path, label: str) -> None:
    """Write and remove a probe file in the existing ``directory``."""
    try:
        fd, probe = tempfile.mkstemp(dir=directory, prefix=".write-check.")
        os.close(fd)
        os.unlink(probe)
    except OSError as exc:
        raise UserInputError(f"{label}: cannot write in {directory} ({exc.strerror or exc}); "
                             f"choose another location") from None


def _check_writable(directory: Path, label: str, create: bool) -> None:
    """Check that files can be written into ``directory``: created first if ``create``; otherwise,
    if it is absent, its nearest existing ancestor must be a writable directory (nothing is created)."""
    if directory.exists() and not directory.is_dir():
        raise UserInputError(f"{label}: {directory} exists and is not a directory")
    if create:
        try:
            directory.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise UserInputError(f"{label}: cannot create {directory} ({exc.strerror or exc}); "
                                 f"choose another location") from None
        _probe(directory, label)
        return
    ancestor = directory.absolute()
    while not ancestor.exists() and ancestor != ancestor.parent:
        ancestor = ancestor.parent
    if not ancestor.is_dir():
        raise UserInputError(f"{label}: {ancestor} is a file, not a directory; choose another location")
    _probe(ancestor, label)


def prepare_output_dir(path: str | os.PathLike, what: str = "--out", create: bool = True,
                       moved_into_place: bool = False) -> Path:
    """Check, before any computation, that results can be written into the directory ``path``.

    Parameters
    ----------
    path : path-like
        Output directory.
    what : str
        How the user named it (an option such as ``--out``), for the message.
    create : bool
        True: create the directory if needed and check it is writable.  False: create nothing (so
        that a command refusing its input leaves no trace); an absent directory must be creatable,
        i.e. its nearest existing ancestor is a writable directory.
    moved_into_place : bool
        The writer builds the directory beside ``path`` and renames it into place (implies
        ``create=False``): the parent is what must be writable.

    Raises
    ------
    UserInputError
        One line naming the directory when it is a file, lies under a file, cannot be created or is
        not writable.
    """
    out = Path(path)
    if out.exists() and not out.is_dir():
        raise UserInputError(f"{what} {out}: exists and is not a directory")
    if moved_into_place:
        _check_writable(out.absolute().parent, f"{what} {out}", create=False)
    else:
        _check_writable(out, f"{what} {out}", create)
    return out


def prepare_output_file(path: str | os.PathLike, what: str = "--out") -> Path:
    """Check, before any computation, that the file ``path`` can be written (nothing is created).

    Raises
    ------
    UserInputError
        One line when ``path`` is a directory, or its directory is not writable or cannot be created.
    """
    out = Path(path)
    if out.is_dir():
        raise UserInputError(f"{what} {out}: is a directory; give a file name")
    _check_writable(out.absolute().parent, f"{what} {out}", create=False)
    return out


def check_limit(what: str, value: float, limit: float, hint: str = "") -> None:
    """Refuse a size beyond ``limit`` (frames, grid points, runs) before anything is allocated.

    Raises
    ------
    UserInputError
        ``"<what> = <value> exceeds the limit of <limit>[; hint]"``.
    """
    if not value <= limit:
        raise UserInputError(f"{what} = {value:,.0f} exceeds the limit of {limit:,.0f}" + (f"; {hint}" if hint else ""))


def invoked_as(module_prog: str, argv0: str | None = None) -> str:
    """The command as the user typed it, for usage lines: the console script's name (``cubedimer-acousim``) when
    the package runs as one, else ``module_prog`` (``python -m acousim``)."""
    name = Path(sys.argv[0] if argv0 is None else argv0).name
    return name if name.startswith("cubedimer-") else module_prog


def command_parser(prog: str, description: str,
                   commands: Sequence[Callable[[argparse._SubParsersAction], None]]) -> OneLineParser:
    """The parser of a package's command line: one sub-parser per ``add_parser(subparsers)`` function in ``commands``,
    named as it was invoked (:func:`invoked_as`; ``prog`` is the ``python -m`` form), with ``--version``.

    Every package's command module has this one shape: each command is a function that adds its sub-parser to
    ``subparsers`` and sets ``func`` (the function :func:`run_cli` calls with the parsed arguments).
    """
    parser = OneLineParser(prog=invoked_as(prog), description=description)
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__} ({DISTRIBUTION})",
                        help="print the installed version of the suite and exit")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND", parser_class=OneLineParser)
    for add_parser in commands:
        add_parser(sub)
    return parser


def run_cli(parser: argparse.ArgumentParser, argv: list[str] | None = None,
            errors: tuple[type[BaseException], ...] = ()) -> int:
    """Parse ``argv`` and run the chosen subcommand's ``func``: user errors become one line and exit 2.

    ``errors``: the package's library errors that mean "nothing can be written for this input" (e.g. the fit's
    :class:`fitting.uncertainty.final_checks.NoSaneModelError`); they are reported like user errors, one line and exit
    status 2.  The command runs with one BLAS thread (:func:`cubedimer.executor.single_blas_thread`), as every
    executor task does: its numbers are then the same whether it runs here or inside a task, and the
    many small factorisations are faster so (parallel work goes through the executor's processes)."""
    args = parser.parse_args(join_negative_values(list(sys.argv[1:] if argv is None else argv)))
    configure_logging(quiet=bool(getattr(args, "quiet", False)), verbose=bool(getattr(args, "verbose", False)))
    try:
        with single_blas_thread():
            return int(args.func(args) or 0)
    except (UserInputError, DatasetError, ExecutorError, *errors) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("interrupted (finished work is kept; rerun the same command to resume where it applies)", file=sys.stderr)
        return 130
