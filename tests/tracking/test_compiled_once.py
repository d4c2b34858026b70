"""The tracking's compiled functions compile once per first run: no compiled call passes an integer constant.

numba types an integer or boolean constant argument as a literal of its value, and compiles the called function (and
everything it calls) once per value: two call sites of the face fit with sides -1 and +1 compiled the fit's whole
chain twice, about a fifth of the measurement kernel's compile time that a first ``tracking track`` pays.  The
check reads the sources (nothing is compiled here)."""
from __future__ import annotations

import ast
from pathlib import Path

TRACKING = Path(__file__).resolve().parents[2] / "tracking"


def _compiled_functions(tree: ast.Module) -> dict[str, ast.FunctionDef]:
    """The functions of ``tree`` decorated with ``njit`` (bare or called)."""
    def is_njit(d: ast.expr) -> bool:
        return getattr(d.func if isinstance(d, ast.Call) else d, "id", None) == "njit"

    return {n.name: n for n in ast.walk(tree) if isinstance(n, ast.FunctionDef) and any(map(is_njit, n.decorator_list))}


def constant_arguments(folder: Path) -> list[str]:
    """Each call from a compiled function of ``folder``'s modules to a compiled function of them that passes an
    integer or boolean constant (``-1`` too), as ``"module.py:line callee(argument)"``."""
    trees = {path: ast.parse(path.read_text()) for path in sorted(folder.glob("*.py"))}
    compiled = set().union(*(_compiled_functions(tree) for tree in trees.values()))
    found = []
    for path, tree in trees.items():
        for function in _compiled_functions(tree).values():
            for call in ast.walk(function):
                if not (isinstance(call, ast.Call) and getattr(call.func, "id", None) in compiled):
                    continue
                for arg in call.args:
                    value = arg.operand if isinstance(arg, ast.UnaryOp) else arg
                    if isinstance(value, ast.Constant) and isinstance(value.value, (bool, int)):
                        found.append(f"{path.name}:{call.lineno} {call.func.id}({ast.unparse(arg)})")
    return found


def test_no_compiled_call_of_the_tracking_passes_an_integer_constant():
    assert constant_arguments(TRACKING) == []


def test_the_check_finds_a_constant_side(tmp_path):
    """The check itself: the two constant sides of a fit are found, an integer known at run time is not."""
    (tmp_path / "fits.py").write_text(
        "from numba import njit\n\n@njit(cache=True)\ndef fit(x, side):\n    return side * x\n\n"
        "@njit\ndef both(x):\n    return fit(x, -1) + fit(x, True)\n\n"
        "@njit(cache=True)\ndef loop(x):\n    s = 0.0\n    for k in range(2):\n        s += fit(x, 2 * k - 1)\n    return s\n")
    assert constant_arguments(tmp_path) == ["fits.py:9 fit(-1)", "fits.py:9 fit(True)"]
