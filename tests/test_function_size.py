"""No function of the five packages is longer than 100 lines (from its ``def`` to its last line), unless the line
above its ``def`` (or above its first decorator) says why: ``# long: <reason>``.  A longer function is split along
its steps, one function per step named for what it does."""
from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("cubedimer", "acousim", "fitting", "tracking", "validation")
MAX_LINES = 100
MARKER = "# long:"


def long_functions(source: str, max_lines: int = MAX_LINES) -> list[tuple[str, int, int]]:
    """(qualified name, line of the ``def``, length in lines) of every function or method of ``source`` longer
    than ``max_lines`` without a ``# long: <reason>`` comment on the line above its ``def`` or its decorators."""
    lines = source.splitlines()
    out = []

    def visit(node: ast.AST, prefix: str) -> None:
        for child in ast.iter_child_nodes(node):
            if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef)):
                name = f"{prefix}{child.name}"
                length = child.end_lineno - child.lineno + 1
                first = min([child.lineno] + [d.lineno for d in child.decorator_list])
                above = {lines[k - 2].strip() for k in (first, child.lineno) if k >= 2}
                if length > max_lines and not any(a.startswith(MARKER) and a[len(MARKER):].strip() for a in above):
                    out.append((name, child.lineno, length))
                visit(child, name + ".")
            elif isinstance(child, ast.ClassDef):
                visit(child, f"{prefix}{child.name}.")
            else:
                visit(child, prefix)

    visit(ast.parse(source), "")
    return out


def _function(n_body: int, above: str = "", decorator: str = "") -> str:
    """Line 1 ``x = 0``, then ``above`` and ``decorator`` when given, then ``def f`` with ``n_body`` body lines."""
    head = "".join(f"{ln}\n" for ln in ("x = 0", above, decorator) if ln)
    return head + "def f(x):\n" + "".join(f"    x = x + {i}\n" for i in range(n_body - 1)) + "    return x\n"


def test_the_counter_on_known_functions():
    # a def line plus 100 body lines is 101 lines: flagged; one line fewer is not
    assert long_functions(_function(100)) == [("f", 2, 101)]
    assert long_functions(_function(99)) == []
    assert long_functions(_function(100, above="# long: one table of coefficients")) == []
    assert long_functions(_function(100, above="# long: reason", decorator="@staticmethod")) == []
    assert long_functions(_function(100, above="# long:")) == [("f", 3, 101)]  # a reason is required
    assert long_functions(_function(100, above="# long: reason\n")) == [("f", 4, 101)]  # not on the line above
    nested = "class C:\n    def m(self):\n" + "".join(f"        y = {i}\n" for i in range(101))
    assert long_functions(nested) == [("C.m", 2, 102)]


def test_no_function_exceeds_the_line_limit():
    found = []
    for package in PACKAGES:
        for f in sorted((ROOT / package).rglob("*.py")):
            for name, line, length in long_functions(f.read_text(encoding="utf-8")):
                found.append(f"{f.relative_to(ROOT)}:{line} {name} ({length} lines)")
    print("\n".join(found))
    assert not found, (f"{len(found)} functions over {MAX_LINES} lines (split them along their steps, or say why on "
                       f"the line above the def with '{MARKER} <reason>'):\n" + "\n".join(found))
