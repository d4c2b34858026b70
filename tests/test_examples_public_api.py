"""The example gallery (examples/, executed by ``make docs``) uses only the public API: every name it takes from a
package of the suite is one that package's ``__init__`` re-exports (its ``__all__``), from a package the API
reference documents (docs/conf.py, ``API_PACKAGES``)."""
import ast
import importlib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SUITE = ("cubedimer", "acousim", "fitting", "validation", "tracking")
EXAMPLES = sorted((ROOT / "examples").glob("plot_*.py"))


def _api_packages() -> tuple[str, ...]:
    tree = ast.parse((ROOT / "docs" / "conf.py").read_text())
    for node in tree.body:
        if isinstance(node, ast.Assign) and any(getattr(t, "id", None) == "API_PACKAGES" for t in node.targets):
            return ast.literal_eval(node.value)
    raise AssertionError("docs/conf.py defines no API_PACKAGES")


def _suite_names_used(source: str) -> list[tuple[str, str]]:
    """(package, name) for every ``from package import name`` and ``package.name`` of the suite's packages."""
    tree = ast.parse(source)
    used, aliases = [], {}
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module and node.module.split(".")[0] in SUITE:
            used += [(node.module, a.name) for a in node.names]
        elif isinstance(node, ast.Import):
            for a in node.names:
                if a.name.split(".")[0] in SUITE:
                    aliases[a.asname or a.name] = a.name
    for node in ast.walk(tree):
        if isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name) and node.value.id in aliases:
            used.append((aliases[node.value.id], node.attr))
    return used


def test_there_are_examples_and_the_check_sees_private_names():
    assert len(EXAMPLES) >= 5
    # what the check below reports: a module path behind the public API, and a name outside __all__
    assert _suite_names_used("from fitting.synthetic import generate_runs\nimport fitting\nfitting.pipeline\n") == [
        ("fitting.synthetic", "generate_runs"), ("fitting", "pipeline")]


@pytest.mark.parametrize("example", EXAMPLES, ids=lambda p: p.name)
def test_an_example_uses_only_the_public_api(example):
    api = _api_packages()
    for package, name in _suite_names_used(example.read_text()):
        assert package in api, f"{example.name}: {package} is not a documented package ({', '.join(api)})"
        assert name in importlib.import_module(package).__all__, f"{example.name}: {package}.{name} is not public"
