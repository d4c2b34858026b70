"""The installed distribution: one version everywhere (``__version__`` of each package, ``--version`` of every
console script), and the warning when another installation claims one of the suite's top-level names."""
import importlib
import importlib.metadata
import sys
import warnings
from pathlib import Path

import pytest

from cubedimer import distribution
from cubedimer.distribution import IMPORT_NAMES, ImportNameWarning, foreign_import_names, warn_foreign_import_names

ROOT = Path(__file__).resolve().parents[2]


def _scripts() -> dict:
    if sys.version_info >= (3, 11):
        import tomllib
    else:  # pragma: no cover
        tomllib = pytest.importorskip("tomli")
    return tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["scripts"]


@pytest.mark.parametrize("package", IMPORT_NAMES)
def test_every_package_reports_the_distributions_version(package):
    expected = importlib.metadata.version("cubedimer")
    assert importlib.import_module(package).__version__ == expected == distribution.distribution_version()


@pytest.mark.parametrize("script", sorted(_scripts()))
def test_every_console_script_answers_version(script, capsys, monkeypatch):
    module, func = _scripts()[script].split(":")
    monkeypatch.setattr(sys, "argv", [f"/somewhere/bin/{script}"])  # as the console script runs
    with pytest.raises(SystemExit) as stop:
        getattr(importlib.import_module(module), func)(["--version"])
    assert stop.value.code == 0
    assert capsys.readouterr().out.strip() == f"{script} {importlib.metadata.version('cubedimer')} (cubedimer)"


def _fake_distribution(site: Path, name: str, files: list[str]) -> None:
    """An installed distribution ``name`` whose RECORD lists ``files`` (what pip leaves in site-packages)."""
    info = site / f"{name}-1.0.dist-info"
    info.mkdir(parents=True)
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {name}\nVersion: 1.0\n")
    (info / "RECORD").write_text("".join(f"{f},,\n" for f in files + [f"{info.name}/METADATA", f"{info.name}/RECORD"]))
    for f in files:
        (site / f).parent.mkdir(parents=True, exist_ok=True)
        (site / f).write_text("")


def test_a_distribution_that_ships_a_same_named_package_is_found_and_warned(tmp_path, monkeypatch):
    """Two unrelated distributions in an environment: one ships ``validation/``, one a module ``tracking.py``."""
    site = tmp_path / "site-packages"
    _fake_distribution(site, "validation", ["validation/__init__.py", "validation/core.py"])
    _fake_distribution(site, "trackpkg", ["tracking.py"])
    monkeypatch.syspath_prepend(str(site))  # the suite's own packages still come first on the path
    clashes = {c.name: c for c in foreign_import_names()}
    assert set(clashes) == {"validation", "tracking"}
    assert clashes["validation"].distributions == ("validation",) and clashes["tracking"].distributions == ("trackpkg",)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        warn_foreign_import_names()
    messages = [str(w.message) for w in caught if issubclass(w.category, ImportNameWarning)]
    assert len(messages) == 2 and all("environment of its own" in m for m in messages)


def test_a_name_that_resolves_outside_the_suite_is_found(tmp_path, monkeypatch):
    """A same-named package earlier on the path shadows the suite's: where it resolves is named."""
    other = tmp_path / "elsewhere"
    (other / "fitting").mkdir(parents=True)
    (other / "fitting" / "__init__.py").write_text("")
    monkeypatch.delitem(sys.modules, "fitting", raising=False)  # as in a fresh interpreter (restored afterwards)
    sys.path.insert(0, str(other))
    try:
        importlib.invalidate_caches()
        clashes = foreign_import_names(owners={})
    finally:
        sys.path.remove(str(other))
        importlib.invalidate_caches()
    assert [(c.name, c.distributions) for c in clashes] == [("fitting", ())]
    assert clashes[0].location == str(other / "fitting")


def test_the_suite_alone_gives_no_warning():
    """This environment holds the suite alone: no clash (the check does not flag the suite's own distribution)."""
    assert foreign_import_names() == []
    assert foreign_import_names(owners={"fitting": ["cubedimer"], "acousim": ["CubeDimer"]}) == []
