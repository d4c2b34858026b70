"""The package layering contract, checked on the source (AST), so that it cannot regress.

* ``cubedimer`` (the shared core) imports none of ``acousim``, ``fitting``, ``validation``;
* ``acousim`` and ``fitting`` import neither each other nor ``validation`` (nor ``tracking``);
* ``tracking`` (camera frames to runs) imports only ``cubedimer`` from the suite;
* ``validation`` may import all of them.

Imports anywhere in a module count, including those inside functions.
"""
from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("cubedimer", "acousim", "fitting", "validation", "tracking")
FORBIDDEN = {
    "cubedimer": {"acousim", "fitting", "validation", "tracking"},
    "acousim": {"fitting", "validation", "tracking"},
    "fitting": {"acousim", "validation", "tracking"},
    "tracking": {"acousim", "fitting", "validation"},
    "validation": set(),
}


def imported_packages(path: Path) -> set[str]:
    """Top-level names of every absolute import in the file."""
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    names: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names.update(a.name.split(".")[0] for a in node.names)
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            names.add(node.module.split(".")[0])
    return names


def test_imported_packages_sees_nested_imports(tmp_path):
    f = tmp_path / "m.py"
    f.write_text("import os\ndef g():\n    from fitting.model import X\n    import acousim.twin as t\n")
    assert imported_packages(f) == {"os", "fitting", "acousim"}


@pytest.mark.parametrize("package", PACKAGES)
def test_package_imports_respect_the_layers(package):
    files = sorted((ROOT / package).rglob("*.py"))
    assert files, f"no modules found for {package}"
    bad = {str(f.relative_to(ROOT)): sorted(imported_packages(f) & FORBIDDEN[package]) for f in files}
    bad = {k: v for k, v in bad.items() if v}
    assert not bad, f"{package} imports packages above or beside it: {bad}"
