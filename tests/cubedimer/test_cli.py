"""The shared command-line layer: one-line errors, output checks before computing, size limits."""
import argparse

import pytest

from cubedimer.cli import (OneLineParser, UserInputError, add_executor_arguments, check_limit, executor_config,
                           prepare_output_dir, prepare_output_file, run_cli)
from cubedimer.dataset import DatasetError
from cubedimer.executor import ExecutorError


def _parser(exc):
    p = OneLineParser(prog="t")
    sub = p.add_subparsers(dest="command", required=True)
    c = sub.add_parser("go")
    add_executor_arguments(c)

    def func(args):
        raise exc

    c.set_defaults(func=func)
    return p


@pytest.mark.parametrize("exc", [UserInputError("bad --x"), DatasetError("f.csv: bad"),
                                 ExecutorError("cannot reach the dask scheduler at tcp://h:1")])
def test_user_errors_are_one_line_exit_2(capsys, exc):
    assert run_cli(_parser(exc), ["go"]) == 2
    assert capsys.readouterr().err == f"error: {exc}\n"


def test_executor_options(monkeypatch):
    args = _parser(None).parse_args(["go", "--workers", "3", "--scheduler", "tcp://h:8786"])
    cfg = executor_config(args)
    assert cfg.workers == 3 and cfg.resolved_scheduler() == "tcp://h:8786"
    monkeypatch.setenv("CUBEDIMER_SCHEDULER", "tcp://env:8786")
    assert executor_config(_parser(None).parse_args(["go"])).resolved_scheduler() == "tcp://env:8786"
    with pytest.raises(SystemExit):
        _parser(None).parse_args(["go", "--workers", "0"])


def test_output_dir_checks_create_nothing_unless_asked(tmp_path):
    target = tmp_path / "a" / "b"
    assert prepare_output_dir(target, create=False) == target and not (tmp_path / "a").exists()
    prepare_output_dir(target)
    assert target.is_dir() and list(target.iterdir()) == []  # the probe file is removed
    prepare_output_file(tmp_path / "x" / "f.csv")
    assert not (tmp_path / "x").exists()


@pytest.mark.parametrize("kind", ["under a file", "is a file", "file is a directory", "moved into place"])
def test_unwritable_outputs_name_the_option(tmp_path, kind):
    blocker = tmp_path / "file"
    blocker.write_text("x")
    with pytest.raises(UserInputError) as err:
        if kind == "under a file":
            prepare_output_dir(blocker / "sub" / "deeper", "--out", create=False)
        elif kind == "is a file":
            prepare_output_dir(blocker, "--out")
        elif kind == "file is a directory":
            prepare_output_file(tmp_path, "--out")
        else:
            prepare_output_dir(blocker / "d", "--out", moved_into_place=True)
    msg = str(err.value)
    assert msg.startswith("--out ") and "\n" not in msg
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file"]


def test_check_limit():
    check_limit("--runs", 10, 10)
    with pytest.raises(UserInputError, match=r"--runs = 11 exceeds the limit of 10; fewer"):
        check_limit("--runs", 11, 10, "fewer")
    with pytest.raises(UserInputError):
        check_limit("frames", float("nan"), 10)


@pytest.mark.parametrize("argv0,expected", [
    ("/home/lab/.venv/bin/cubedimer-acousim", "cubedimer-acousim"),
    ("cubedimer-tracking", "cubedimer-tracking"),
    ("/work/acousim/__main__.py", "python -m acousim"),
    ("-c", "python -m acousim"),
])
def test_the_usage_line_names_the_command_as_typed(argv0, expected):
    from cubedimer.cli import invoked_as

    assert invoked_as("python -m acousim", argv0) == expected
