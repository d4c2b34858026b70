"""The package layering contract, checked on the source (AST), so that it cannot regress.

* ``cubedimer`` (the shared core) imports none of ``acousim``, ``fitting``, ``validation``;
* ``acousim`` and ``fitting`` import neither each other nor ``validation`` (nor ``tracking``);
* ``tracking`` (camera frames to runs) imports only ``cubedimer`` from the suite;
* ``validation`` may import all of them.

Imports anywhere in a module count, including those inside functions.
"""
from __future__ import annotations

import ast
import functools
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


# ---- no import cycles inside a package ----------------------------------------------------------------------------
# Deferred imports (inside functions) count: a cycle hidden behind one still ties the modules together.  Imports under
# ``if TYPE_CHECKING:`` never run and do not count.

def _module_name(path: Path) -> str:
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


MODULES = {_module_name(f): f for p in PACKAGES for f in (ROOT / p).rglob("*.py")}


def _type_checking_nodes(tree: ast.AST) -> set[int]:
    skip: set[int] = set()
    for node in ast.walk(tree):
        test = getattr(node, "test", None)
        if isinstance(node, ast.If) and getattr(test, "id", getattr(test, "attr", None)) == "TYPE_CHECKING":
            skip.update(id(n) for stmt in node.body for n in ast.walk(stmt))
    return skip


@functools.lru_cache(maxsize=None)
def imported_modules(name: str, path: Path) -> frozenset[str]:
    """The suite's modules that the module ``name`` (file ``path``) imports (``from . import x`` imports x only)."""
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    skip = _type_checking_nodes(tree)
    base = name.split(".") if path.name == "__init__.py" else name.split(".")[:-1]
    out: set[str] = set()
    for node in ast.walk(tree):
        if id(node) in skip:
            continue
        if isinstance(node, ast.Import):
            out.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            module = ".".join(base[:len(base) - node.level + 1] + [node.module] if node.module else
                              base[:len(base) - node.level + 1]) if node.level else node.module
            submodules = {f"{module}.{a.name}" for a in node.names} & MODULES.keys()
            out.update(submodules)
            if len(submodules) < len(node.names):
                out.add(module)
    return frozenset(out & MODULES.keys())


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one node (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    out: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in graph:
        if v not in index:
            visit(v)
    return out


def test_cycle_finder_sees_deferred_imports_and_ignores_type_checking(tmp_path):
    graph = {"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}
    assert _cycles(graph) == [["a", "b", "c"]] and _cycles({"a": {"b"}, "b": set()}) == []
    f = tmp_path / "m.py"
    f.write_text("from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from .config import X\n"
                 "def g():\n    from .meta import Y\n")
    assert {m.split(".")[-1] for m in imported_modules("cubedimer.m", f)} == {"meta"}


@pytest.mark.parametrize("package", PACKAGES)
def test_no_import_cycles_between_modules_of_a_package(package):
    graph = {m: {i for i in imported_modules(m, f) if i.split(".")[0] == package}
             for m, f in MODULES.items() if m.split(".")[0] == package}
    assert not _cycles(graph), f"import cycles in {package}: {_cycles(graph)}"


def _packages_below(package: str) -> list[str]:
    """Every package of the suite at or below ``package`` (a folder with an ``__init__.py``), dotted."""
    return sorted(_module_name(init) for init in (ROOT / package).rglob("__init__.py"))


def subpackage_graph(parent: str) -> dict[str, set[str]]:
    """Import arrows between the direct subpackages of the package ``parent``: a module anywhere inside subpackage A
    that imports a module inside subpackage B is an arrow A -> B.  The parent's own modules are left out: they are
    built on the subpackages (``fitting.fit`` runs every step) and may import any of them."""
    depth = len(parent.split(".")) + 1

    def group(m: str) -> str | None:
        parts = m.split(".")
        if len(parts) < depth or parts[:depth - 1] != parent.split("."):
            return None
        head = ".".join(parts[:depth])
        return head if (ROOT / Path(*parts[:depth]) / "__init__.py").exists() else None

    graph: dict[str, set[str]] = {}
    for m, f in MODULES.items():
        g = group(m)
        if g is None:
            continue
        graph.setdefault(g, set()).update(h for i in imported_modules(m, f) if (h := group(i)) not in (None, g))
    for deps in list(graph.values()):
        for d in deps:
            graph.setdefault(d, set())
    return graph


def test_subpackage_graph_groups_nested_modules():
    """fitting.methods is built on fitting.selection (the methods select terms), never the other way."""
    graph = subpackage_graph("fitting")
    assert "fitting.selection" in graph["fitting.methods"]
    assert "fitting.methods" not in graph["fitting.selection"]
    assert all(k.count(".") == 1 for k in graph)


@pytest.mark.parametrize("parent", [p for package in PACKAGES for p in _packages_below(package)])
def test_no_import_cycles_between_subpackages(parent):
    """At every level: validation.diagnosis and validation.report, say, or the steps inside validation.diagnosis
    (calibrate, identify, ...) and the roles inside fitting (derivatives, selection, refinement, ...): one of them is
    built on the other, not both ways."""
    graph = subpackage_graph(parent)
    assert not _cycles(graph), f"import cycles between subpackages of {parent}: {_cycles(graph)}"


#: What opens a pool of workers (processes, threads or a cluster): modules, and names imported or used as attributes.
POOL_MODULES = {"multiprocessing", "concurrent", "dask", "joblib"}
POOL_NAMES = {"ProcessPoolExecutor", "ThreadPoolExecutor", "ThreadPool", "Pool", "Thread"}


def pools_opened(source: str) -> list[str]:
    """The pool modules ``source`` imports and the pool classes it imports or uses (``threading.Thread``,
    ``concurrent.futures.ThreadPoolExecutor``), sorted."""
    tree = ast.parse(source)
    modules = {n.module for n in ast.walk(tree) if isinstance(n, ast.ImportFrom) and n.module}
    modules |= {a.name for n in ast.walk(tree) if isinstance(n, ast.Import) for a in n.names}
    names = {a.name for n in ast.walk(tree) if isinstance(n, ast.ImportFrom) for a in n.names}
    names |= {n.attr for n in ast.walk(tree) if isinstance(n, ast.Attribute)}
    return sorted({m.split(".")[0] for m in modules} & POOL_MODULES | names & POOL_NAMES)


def test_the_pool_scanner_sees_thread_pools_too():
    assert pools_opened("from concurrent.futures import ThreadPoolExecutor\n") == ["ThreadPoolExecutor", "concurrent"]
    assert pools_opened("import threading\nt = threading.Thread(target=print)\n") == ["Thread"]
    assert pools_opened("from multiprocessing.pool import ThreadPool\n") == ["ThreadPool", "multiprocessing"]
    assert pools_opened("import threading\nlock = threading.Lock()\n") == []  # a lock opens no pool


def test_parallel_work_goes_through_the_executor_seam():
    """Processes, threads and clusters are opened by cubedimer.executor only (map_ordered), so work inside a task
    never opens a pool of its own; the tracking's compiled per-frame work runs on the compiled kernel's own threads
    (numba prange, one to a task), which is not a pool the suite opens."""
    seam = ROOT / "cubedimer" / "executor.py"
    bad = {}
    for f in sorted(f for p in PACKAGES for f in (ROOT / p).rglob("*.py")):
        if f != seam and (hits := pools_opened(f.read_text(encoding="utf-8"))):
            bad[str(f.relative_to(ROOT))] = hits
    assert not bad, f"parallel work outside cubedimer.executor.map_ordered: {bad}"


#: The documented order of the steps (docs/architecture.md): a subpackage imports only the ones after it in its list.
STEP_ORDER = {
    "fitting": ("methods", "output", "uncertainty", "selection", "refinement", "derivatives"),
    "validation.diagnosis": ("summarise", "discover", "identify", "calibrate", "prepare"),
}


@pytest.mark.parametrize("parent", list(STEP_ORDER))
def test_the_steps_are_built_in_their_documented_order(parent):
    """fitting: methods -> output -> uncertainty -> selection -> refinement -> derivatives; the diagnosis: each step
    on the steps before it (prepare <- calibrate <- identify <- discover <- summarise)."""
    order = [f"{parent}.{s}" for s in STEP_ORDER[parent]]
    graph = subpackage_graph(parent)
    assert set(graph) == set(order), f"{parent} has subpackages the order does not list: {set(graph) ^ set(order)}"
    upward = sorted(f"{a} -> {b}" for a in order for b in graph[a] if order.index(b) < order.index(a))
    assert not upward, f"imports against the documented order of {parent}: {upward}"


@pytest.mark.parametrize("package", sorted({m for m, f in MODULES.items() if f.name == "__init__.py"}))
def test_every_public_name_of_a_package_resolves(package):
    """Every name of a package's ``__all__`` (the lazy ones included, cubedimer.lazy) is there: a module moved or
    renamed cannot leave a public name pointing at nothing."""
    import importlib

    module = importlib.import_module(package)
    missing = [name for name in getattr(module, "__all__", ()) if not hasattr(module, name)]
    assert not missing, f"{package}.__all__ names what it cannot give: {missing}"
