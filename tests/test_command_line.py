"""The command line as a user meets it: console scripts beside ``python -m``, and a help text for every option and
argument of every command."""
import argparse
import importlib
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("acousim", "fitting", "validation", "tracking")


def _scripts() -> dict:
    if sys.version_info >= (3, 11):
        import tomllib
    else:  # pragma: no cover
        tomllib = pytest.importorskip("tomli")
    return tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["scripts"]


def test_one_console_script_per_package_runs_its_cli():
    scripts = _scripts()
    assert {f"cubedimer-{p}": f"{p}.cli:main" for p in PACKAGES}.items() <= scripts.items()
    for name, target in scripts.items():
        module, func = target.split(":")
        assert callable(getattr(importlib.import_module(module), func)), name


def _actions(parser: argparse.ArgumentParser, path: list[str]):
    for a in parser._actions:
        if isinstance(a, argparse._SubParsersAction):
            for name, sub in a.choices.items():
                yield from _actions(sub, path + [name])
        elif not isinstance(a, argparse._HelpAction):
            yield " ".join(path), "/".join(a.option_strings) or a.dest, a.help


@pytest.mark.parametrize("package", PACKAGES)
def test_every_option_and_argument_has_a_help_text(package):
    parser = importlib.import_module(f"{package}.cli").build_parser()
    missing = [f"{cmd} {opt}" for cmd, opt, text in _actions(parser, [package])
               if not text or text == argparse.SUPPRESS or not text.strip()]
    assert not missing, missing


@pytest.mark.parametrize("package", ["fitting", "validation"])
def test_help_points_to_the_repository_docs(package, capsys):
    main = importlib.import_module(f"{package}.cli").main
    with pytest.raises(SystemExit) as exit_:
        main(["--help"])
    assert exit_.value.code == 0
    out = capsys.readouterr().out
    assert "docs/formats.md" in out and "docs/conventions.md" in out


def _library_modules():
    for package in ("cubedimer", *PACKAGES):
        for f in sorted((ROOT / package).rglob("*.py")):
            # command modules: a package's cli.py or cli/ subpackage, its *_cli.py modules and __main__.py
            if not (f.name.endswith("cli.py") or f.name == "__main__.py" or f.parent.name == "cli"):
                yield f


def test_library_code_neither_configures_logging_nor_subclasses_the_command_line_errors():
    """Library code logs and raises its own errors; only the command modules configure logging and map errors to
    exit statuses (cubedimer.cli.run_cli)."""
    import ast

    bad = []
    for f in _library_modules():
        tree = ast.parse(f.read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            if isinstance(node, ast.Attribute) and node.attr == "basicConfig":
                bad.append(f"{f.relative_to(ROOT)}: logging.basicConfig")
            if isinstance(node, ast.ClassDef) and any(getattr(b, "id", None) == "UserInputError" for b in node.bases):
                bad.append(f"{f.relative_to(ROOT)}: {node.name}(UserInputError)")
    assert not bad, bad


@pytest.mark.parametrize("package", PACKAGES)
def test_every_command_module_builds_its_commands_from_add_parser_functions(package):
    """One command-line shape: every sub-command of a package is registered by an ``add_parser(subparsers)``
    function listed in the command module's ``COMMANDS`` and added by :func:`cubedimer.cli.command_parser`."""
    module = importlib.import_module(f"{package}.cli")
    parser = module.build_parser()
    subs = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    assert len(subs) == 1 and len(subs[0].choices) >= 2
    # every command comes from one add_parser function of COMMANDS: a parser built from COMMANDS alone has them all
    from cubedimer.cli import command_parser

    rebuilt = command_parser("x", "x", module.COMMANDS)
    assert [a for a in rebuilt._actions if isinstance(a, argparse._SubParsersAction)][0].choices.keys() == \
        subs[0].choices.keys()
