"""No module of the suite exceeds 600 lines: a longer one holds more than one concept and is split along them."""
from __future__ import annotations

from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("cubedimer", "acousim", "fitting", "validation", "tracking", "benchmarks")
MAX_LINES = 600


@pytest.mark.parametrize("package", PACKAGES)
def test_no_module_exceeds_the_line_limit(package):
    long = {str(f.relative_to(ROOT)): n for f in sorted((ROOT / package).rglob("*.py"))
            if (n := len(f.read_text(encoding="utf-8").splitlines())) > MAX_LINES}
    assert not long, f"modules over {MAX_LINES} lines (split them along their concepts): {long}"



#: File names every package may repeat: the package markers and a package's entry point.
REPEATABLE = {"__init__.py", "__main__.py"}


def repeated_module_names(root: Path, package: str) -> dict[str, list[str]]:
    """The file names that more than one module of ``package`` (below ``root``) has, with their paths."""
    where: dict[str, list[str]] = {}
    for f in sorted((root / package).rglob("*.py")):
        if f.name not in REPEATABLE and "__pycache__" not in f.parts:
            where.setdefault(f.name, []).append(str(f.relative_to(root)))
    return {name: paths for name, paths in where.items() if len(paths) > 1}


@pytest.mark.parametrize("package", PACKAGES)
def test_no_two_modules_of_a_package_share_a_name(package):
    """Within a top-level package every module's file name is its own, so that a name says which module it is
    (a command module is ``<command>_command.py``, beside the physics module it runs)."""
    repeated = repeated_module_names(ROOT, package)
    assert not repeated, f"modules that share a name (rename them by what they are): {repeated}"


def test_a_repeated_module_name_is_found(tmp_path):
    """The check can fail: two modules of one package with one name, in different folders, are reported."""
    for sub in ("a", "b/c"):
        (tmp_path / "pkg" / sub).mkdir(parents=True)
        (tmp_path / "pkg" / sub / "same.py").write_text("")
        (tmp_path / "pkg" / sub / "__init__.py").write_text("")
    assert repeated_module_names(tmp_path, "pkg") == {"same.py": ["pkg/a/same.py", "pkg/b/c/same.py"]}
