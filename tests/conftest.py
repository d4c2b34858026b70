"""Shared fixtures for the whole suite."""
from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
import pytest

#: The test run's own caches and configuration folders, under the checkout (``make clean`` removes them), set before
#: any package of the suite is imported: kernels compiled here (some bind effects that only the tests register) and
#: tables built here never reach the caches that the installed commands read (``~/.cache/cubedimer``, or a
#: ``NUMBA_CACHE_DIR`` of the user's).
TEST_CACHE_ROOT = Path(__file__).resolve().parents[1] / ".pytest_cache" / "cubedimer-caches"
os.environ["XDG_CACHE_HOME"] = str(TEST_CACHE_ROOT / "xdg")
os.environ["XDG_CONFIG_HOME"] = str(TEST_CACHE_ROOT / "xdg-config")  # headless Chromium's profile and crash reports
os.environ["NUMBA_CACHE_DIR"] = str(TEST_CACHE_ROOT / "numba")
os.environ["MPLCONFIGDIR"] = str(TEST_CACHE_ROOT / "matplotlib")
os.environ.pop("ACOUSIM_FULLWAVE_CACHE", None)
os.environ.setdefault("MPLBACKEND", "Agg")
os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
# The boundary-element tests assemble on numba, whose kernels every process compiles once anyway (the flux and
# grid helpers need them); test_fullwave_dimer.py compares the OpenCL backend with it on the same mesh.
os.environ.setdefault("CUBEDIMER_BEM_DEVICE", "numba")

#: Test modules that solve boundary-element problems.  bempp-cl compiles its grid and assembly kernels at first use
#: in every process (about 37 s of CPU with one numba thread, 57 s with parallel kernels; they cannot be cached on
#: disk), so ``make test`` (``--dist loadfile``) sends these modules to one pytest-xdist worker as one unit and the
#: compilation happens once per session; solutions several modules check are session fixtures
#: (tests/acousim/fullwave/conftest.py).
BOUNDARY_ELEMENT_MODULES = frozenset({
    "tests/acousim/fullwave/test_fullwave_sphere.py", "tests/acousim/fullwave/test_fullwave_dimer.py",
    "tests/acousim/fullwave/test_fullwave_flux.py", "tests/acousim/cli/test_fullwave_cli.py",
    "tests/acousim/fullwave/test_fullwave_surrogate.py", "tests/acousim/fullwave/test_fullwave_interaction.py",
})

#: Test modules that run work on a real dask cluster (:func:`process_cluster`).  Its scheduler and two worker
#: processes take about 4 s of CPU to start and about 7 % of a core while they wait, so ``make test`` sends these modules
#: to one worker as one unit, which starts the cluster once and shuts it down when the unit ends
#: (:func:`pytest_runtest_teardown`) instead of leaving it idle beside the rest of the session.
CLUSTER_MODULES = frozenset({
    "tests/cubedimer/test_executor.py", "tests/acousim/cli/test_simulate_cli.py", "tests/fitting/test_cli.py",
    "tests/validation/test_cli.py",
})

#: The units of several modules (:func:`scheduling_unit`), by name.
GROUPED_UNITS = {"boundary-elements": BOUNDARY_ELEMENT_MODULES, "dask-cluster": CLUSTER_MODULES}

#: The module bempp-cl's solver API is imported with (``acousim.fullwave.solver``, at the first solve): its kernels
#: compile at the first assembly after it.
BEMPP_SOLVER_MODULE = "bempp_cl.api"


def boundary_elements_outside_their_unit(module: str, loaded, ran_boundary_elements: bool) -> str | None:
    """The one-line complaint when a test of ``module`` (not one of :data:`BOUNDARY_ELEMENT_MODULES`) has left
    bempp-cl's solver API in ``loaded`` (``sys.modules``) of a process that has run no boundary-element module: that
    process would compile bempp-cl's kernels a second time in the session (about 37 CPU-s).  None when all is well."""
    if ran_boundary_elements or module in BOUNDARY_ELEMENT_MODULES or BEMPP_SOLVER_MODULE not in loaded:
        return None
    return (f"{module} reaches bempp-cl's solver ({BEMPP_SOLVER_MODULE} imported) outside the boundary-element unit: "
            f"add it to BOUNDARY_ELEMENT_MODULES in tests/conftest.py so that the kernels compile once per session")


#: Measured seconds of each scheduling unit (a module, or the boundary-element group), so that ``make test`` starts
#: the longest units first; refreshed from the last full run by ``make test-durations``.
UNIT_DURATIONS_FILE = Path(__file__).with_name("unit_durations.json")
_CACHE_KEY = "cubedimer/unit_seconds"


def scheduling_unit(module: str) -> str:
    """The unit ``make test`` sends to one worker: the module, or the name of its group in :data:`GROUPED_UNITS`
    (``"boundary-elements"`` for :data:`BOUNDARY_ELEMENT_MODULES`, ``"dask-cluster"`` for :data:`CLUSTER_MODULES`)."""
    return next((name for name, modules in GROUPED_UNITS.items() if module in modules), module)


def expected_seconds(unit: str, seconds: dict[str, float], counts: dict[str, int]) -> float:
    """The expected duration of ``unit``: its measured seconds; for a group without a record of its own, the sum of
    its modules' records; else 1 s per test (a module with no record is new or renamed, and usually small)."""
    if unit in seconds:
        return float(seconds[unit])
    members = [seconds[m] for m in GROUPED_UNITS.get(unit, ()) if m in seconds]
    return float(sum(members)) if members else float(counts.get(unit, 1))


def longest_first(units: list[str], seconds: dict[str, float], counts: dict[str, int]) -> list[str]:
    """``units`` by decreasing expected duration (:func:`expected_seconds`).  Longest-first keeps a long module
    from starting last while the other worker idles."""
    return sorted(units, key=lambda u: -expected_seconds(u, seconds, counts))


def _recorded_seconds(config) -> dict[str, float]:
    """This checkout's last full run (pytest's cache), over the committed measurement."""
    out: dict[str, float] = {}
    try:
        out.update(json.loads(UNIT_DURATIONS_FILE.read_text()))
    except (OSError, ValueError):
        pass
    cache = getattr(config, "cache", None)
    if cache is not None:
        out.update(cache.get(_CACHE_KEY, {}) or {})
    return out


@pytest.hookimpl(optionalhook=True)  # a plain pytest without pytest-xdist ignores it
def pytest_xdist_make_scheduler(config, log):
    """``--dist loadfile``, with the boundary-element modules as one unit (pytest-xdist's ``xdist_group`` marks
    would do this with ``--dist loadgroup``, but that mode silently stops grouping on pytest 9.2), and the units
    sent longest first (:func:`longest_first`)."""
    if config.getoption("dist") != "loadfile":
        return None
    from xdist.scheduler import LoadFileScheduling

    class _LongestFirst(LoadFileScheduling):
        _ordered = False

        def _split_scope(self, nodeid: str) -> str:
            return scheduling_unit(super()._split_scope(nodeid))

        def _assign_work_unit(self, node) -> None:
            if not self._ordered:
                self._ordered = True
                counts = {u: len(ids) for u, ids in self.workqueue.items()}
                order = longest_first(list(self.workqueue), _recorded_seconds(self.config), counts)
                for unit in order:
                    self.workqueue.move_to_end(unit)
            super()._assign_work_unit(node)

    return _LongestFirst(config, log)


_unit_seconds: dict[str, float] = {}


def pytest_runtest_logreport(report) -> None:
    """Sum each unit's test time (setup, call and teardown), on the controller of an xdist run or a plain run."""
    unit = scheduling_unit(report.nodeid.split("::", 1)[0])
    _unit_seconds[unit] = _unit_seconds.get(unit, 0.0) + float(report.duration)


def pytest_sessionfinish(session, exitstatus) -> None:
    """Shut down a cluster still running (an interrupted session); keep the units' seconds of a whole-suite run (not
    of a selection) in pytest's cache for the next schedule."""
    _close_cluster()
    config = session.config
    if getattr(config, "workerinput", None) is not None or getattr(config, "cache", None) is None:
        return
    if any(a.rstrip("/") != "tests" for a in config.args) or config.getoption("markexpr", "") \
            or config.getoption("keyword", "") or exitstatus not in (0, 1):
        return
    if session.testscollected and _unit_seconds:
        config.cache.set(_CACHE_KEY, {u: round(s, 1) for u, s in sorted(_unit_seconds.items())})


#: Results of the expensive pipeline steps (twin data sets, fits, diagnoses, reports) the end-to-end tests share,
#: kept between test runs below the checkout's pytest cache (``make clean`` removes them), never in a user's home.
PIPELINE_CACHE_ROOT = TEST_CACHE_ROOT / "pipeline"


#: The installed distributions whose numbers the pipeline's results depend on (their versions are in the fingerprint).
PIPELINE_DEPENDENCIES = ("numpy", "scipy", "numba", "nlopt", "pysindy", "scikit-learn", "bempp-cl", "trimesh")


def pipeline_fingerprint(root: Path = Path(__file__).resolve().parents[1]) -> str:
    """The version of everything that makes the pipeline's results: the suite's sources
    (``cubedimer.compile_cache.source_fingerprint``), the packages' data files (the shipped full-wave tables) and the
    versions of Python and of :data:`PIPELINE_DEPENDENCIES`; 16 hex digits.  ``root``: the checkout."""
    import hashlib
    import platform
    from importlib.metadata import PackageNotFoundError, version

    from cubedimer.compile_cache import SUITE_PACKAGES, source_fingerprint

    root = Path(root)
    digest = hashlib.sha1(source_fingerprint(root).encode())
    for package in SUITE_PACKAGES:
        for path in sorted((root / package).rglob("*")):
            if path.is_file() and path.suffix not in (".py", ".pyc") and "__pycache__" not in path.parts:
                digest.update(path.relative_to(root).as_posix().encode() + b"\0" + path.read_bytes())
    digest.update(platform.python_version().encode())
    for name in PIPELINE_DEPENDENCIES:
        try:
            digest.update(f"{name}={version(name)}".encode())
        except PackageNotFoundError:
            digest.update(f"{name}=absent".encode())
    return digest.hexdigest()[:16]


class PipelineCache:
    """Fingerprinted, disk-cached results of the pipeline for the tests (:func:`pipeline_cache`).

    An entry is a folder below the digest of the suite's sources, data files and dependencies
    (:func:`pipeline_fingerprint`: any change to a module of the five packages, a shipped table or an installed
    dependency's version makes every entry stale, and the session removes the stale ones)
    named by a digest of the step's key (its settings, in a ``repr`` that names every one), made once by
    ``build(folder)`` into a temporary folder and renamed into place, so that a parallel worker never sees half an
    entry.  A pytest-xdist worker that needs an entry another worker is making waits for it
    (``cubedimer.cache_lock``, a lock file beside the entry) instead of making it too.  An
    entry that cannot be read is made again: the cache can make a test run faster, never different.  The key must
    name everything the build depends on outside the five packages (a test's own settings and data edits)."""

    def __init__(self, root: Path):
        self.root = Path(root)
        self._fingerprint: str | None = None

    #: :func:`pipeline_fingerprint`, for the cache's own tests
    fingerprint_of = staticmethod(pipeline_fingerprint)

    @property
    def fingerprint(self) -> str:
        if self._fingerprint is None:
            self._fingerprint = pipeline_fingerprint()
        return self._fingerprint

    def entry(self, name: str, key: str) -> Path:
        import hashlib

        digest = hashlib.sha1(f"{name}\0{key}".encode()).hexdigest()[:16]
        return self.root / self.fingerprint / f"{name}-{digest}"

    def prune(self) -> None:
        """Remove the entries of other versions of the sources (best effort)."""
        import shutil

        for old in (self.root.iterdir() if self.root.is_dir() else ()):
            if old.name != self.fingerprint:
                shutil.rmtree(old, ignore_errors=True)

    def folder(self, name: str, key: str, build) -> Path:
        """The folder of entry (``name``, ``key``), made by ``build(folder)`` when missing or unreadable."""
        import shutil
        import tempfile

        from cubedimer.cache_lock import cache_entry_lock

        path = self.entry(name, key)
        done = path / ".complete"
        if done.is_file():
            return path
        path.parent.mkdir(parents=True, exist_ok=True)
        # one builder per entry: a parallel worker that needs the same entry waits for it instead of making it too
        with cache_entry_lock(path, f"the tests' {name}"):
            if done.is_file():  # made by another worker while this one waited
                return path
            tmp = Path(tempfile.mkdtemp(prefix=f".{path.name}-", dir=path.parent))
            try:
                build(tmp)
                (tmp / ".complete").write_text(key)
            except BaseException:
                shutil.rmtree(tmp, ignore_errors=True)  # a build that failed leaves nothing behind
                raise
            if path.exists() and not done.is_file():  # a broken entry: made again
                shutil.rmtree(path, ignore_errors=True)
            try:
                tmp.rename(path)
            except OSError:  # another worker's entry came first (no lock on this file system): use it
                shutil.rmtree(tmp, ignore_errors=True)
        return path

    def value(self, name: str, key: str, build):
        """The pickled value of entry (``name``, ``key``), computed by ``build()`` when missing or unreadable."""
        import pickle

        def make(folder: Path) -> None:
            (folder / "value.pickle").write_bytes(pickle.dumps(build()))

        path = self.folder(name, key, make)
        try:
            return pickle.loads((path / "value.pickle").read_bytes())
        except Exception:  # noqa: BLE001 - an unreadable entry is recomputed, never fatal
            (path / ".complete").unlink(missing_ok=True)
            return pickle.loads((self.folder(name, key, make) / "value.pickle").read_bytes())

    def twin_dataset(self, config, protocol_note: str = "") -> Path:
        """The folder ``data/`` (the runs and meta.json) of the twin data set of ``config`` (an
        ``acousim.twin.TwinConfig``), with its ``truth.json`` beside it, out of the data set's folder."""
        from acousim.twin import simulate_dataset
        from cubedimer.executor import ExecutorConfig

        def build(folder: Path) -> None:
            # in this process: the runs' seeds make them the same on any executor (tests/acousim/twin/test_twin.py),
            # and a pool of one process per core beside the pytest-xdist workers only competes with them for the cores
            simulate_dataset(config, folder / "data", ExecutorConfig(workers=1), progress=False)
            (folder / "data" / "truth.json").rename(folder / "truth.json")

        return self.folder("twin", repr(config) + protocol_note, build) / "data"


@pytest.fixture(scope="session")
def pipeline_cache() -> PipelineCache:
    """The session's :class:`PipelineCache` (twin data sets, fits, diagnoses and reports the end-to-end tests share)."""
    cache = PipelineCache(PIPELINE_CACHE_ROOT)
    cache.prune()
    return cache


@pytest.fixture(scope="session")
def default_wave():
    from acousim.field import StandingWave

    return StandingWave()


@pytest.fixture(scope="session")
def default_model():
    """The Gor'kov dimer at the docs/conventions.md defaults (500 um NaCl, 3 kPa, default mesh)."""
    from acousim.gorkov.forces import GorkovDimer

    return GorkovDimer()


@pytest.fixture(scope="session")
def raw_model():
    """The default model without the symmetrised quadrature: the bare mesh."""
    from acousim.gorkov.forces import GorkovDimer

    return GorkovDimer(symmetrize=False)


@pytest.fixture
def rng():
    return np.random.default_rng(12345)


@pytest.fixture
def chromium_required():
    """Skip when no Chromium is installed, unless the run promised one (make test sets
    CUBEDIMER_REQUIRE_BROWSER=1 after installing it), in which case its absence is a failure."""
    from validation.report.browser_check import find_chromium

    if find_chromium() is None:
        if os.environ.get("CUBEDIMER_REQUIRE_BROWSER") == "1":
            pytest.fail("Chromium is required for this run but was not found")
        pytest.skip("Chromium not installed")


def _write_csv(path, t, y, theta, header="t,y,theta", comment=True):
    lines = (["# test file"] if comment else []) + [header]
    lines += [f"{a:.10g},{b:.10g},{c:.10g}" for a, b, c in zip(t, y, theta)]
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.fixture
def write_csv():
    """Writer of a CSV run: ``write_csv(path, t, y, theta, header=...)``."""
    return _write_csv


@pytest.fixture
def sine_run():
    """A clean 22-Hz y / 9-Hz theta signal, 2 s at 1000 fps."""
    t = np.arange(2000) / 1000.0
    return t, 1e-4 * np.cos(2 * np.pi * 22 * t), 0.2 * np.sin(2 * np.pi * 9 * t)


def field_drop_heights(n: int, fps: float, rest: float, t_off: float, f_y: float = 22.0, decay: float = 0.5):
    """The height [m] of a field drop as a lab records it, analytic: at rest (0) until the drive stops after ``rest``
    frames (fractional), the free fall ``-g t^2 / 2`` for ``t_off`` [s], then the trap's damped oscillation at ``f_y``
    from that height and velocity (continuous in both).  Returns (t [s] from the first frame, y, the field's return
    [frames])."""
    g = 9.80665
    t = np.arange(n) / fps
    t_d = rest / fps
    t_on = t_d + t_off
    y = np.zeros(n)
    fall = (t >= t_d) & (t < t_on)
    y[fall] = -0.5 * g * (t[fall] - t_d) ** 2
    on = t >= t_on
    tau = t[on] - t_on
    w = 2 * np.pi * f_y
    y0, v0 = -0.5 * g * t_off ** 2, -g * t_off
    y[on] = np.exp(-decay * tau) * (y0 * np.cos(w * tau) + (v0 + decay * y0) / w * np.sin(w * tau))
    return t, y, t_on * fps


@pytest.fixture
def drop_heights():
    """:func:`field_drop_heights`: ``drop_heights(n, fps, rest, t_off)`` -> (t, y, field-on frame)."""
    return field_drop_heights


#: The running cluster of :func:`process_cluster` in this process: {"address": str, "stack": ExitStack}, or empty.
_CLUSTER: dict = {}


@pytest.fixture
def process_cluster():
    """The address of a real dask cluster on the loopback: a scheduler and two daemonic worker processes (as every
    normal deployment has), started at the first test that asks for it and shared by the tests that follow in the
    same scheduling unit (:data:`CLUSTER_MODULES`); shut down when the unit ends (:func:`pytest_runtest_teardown`)."""
    pytest.importorskip("dask.distributed")
    if "address" not in _CLUSTER:
        from contextlib import ExitStack

        from cubedimer.executor import loopback_cluster

        stack = ExitStack()
        _CLUSTER["address"] = stack.enter_context(loopback_cluster(2))
        _CLUSTER["stack"] = stack
    return _CLUSTER["address"]


def _close_cluster() -> None:
    stack = _CLUSTER.pop("stack", None)
    _CLUSTER.pop("address", None)
    if stack is not None:
        stack.close()


#: Whether this process has run a test of :data:`BOUNDARY_ELEMENT_MODULES` (bempp-cl's kernels compile there).
_BOUNDARY_ELEMENTS_RAN: dict[str, bool] = {"ran": False}


@pytest.hookimpl(wrapper=True)
def pytest_runtest_teardown(item, nextitem):
    """After a test's own teardown: shut :func:`process_cluster`'s cluster down when the next test of this process
    belongs to another scheduling unit, or there is none (an idle cluster costs a share of a core); and fail the
    teardown of a test outside the boundary-element unit that reached bempp-cl's solver
    (:func:`boundary_elements_outside_their_unit`)."""
    import sys

    module = item.nodeid.split("::", 1)[0]
    try:
        result = yield
    finally:  # also after a teardown that failed
        if _CLUSTER and (nextitem is None or scheduling_unit(nextitem.nodeid.split("::", 1)[0])
                         != scheduling_unit(module)):
            _close_cluster()
    _BOUNDARY_ELEMENTS_RAN["ran"] |= module in BOUNDARY_ELEMENT_MODULES
    complaint = boundary_elements_outside_their_unit(module, sys.modules, _BOUNDARY_ELEMENTS_RAN["ran"])
    if complaint:
        _BOUNDARY_ELEMENTS_RAN["ran"] = True  # said once per process
        pytest.fail(complaint, pytrace=False)
    return result


#: The synthetic family's analytic dependence: the interpolated quantities (dimensionless coefficients, F_Z's over ks)
#: of the default table times (1 + KS_SLOPE (ks - ks0) + KS_CURV (ks - ks0)^2) for every component, and times
#: (1 + GAP_SLOPE L + GAP_CURV L^2), L = log(g / g0), for Q_theta only (the gap sets the hinge stiffness: softer as
#: the gap opens, as in the full wave).  Quadratic in ks and log g: the family's interpolant is exact.
#: The ks slope is negative so that the lowest node (ks 0.28, lift ~ ks) still levitates the dimer at 3 kPa.
SYNTHETIC_FAMILY = {"ks_slope": -0.5, "ks_curv": -1.5, "gap_slope": -0.3, "gap_curv": 0.02}


def synthetic_reduced(ks: float, gap_ratio: float) -> dict:
    """The synthetic family's dimensionless coefficients at (ks, g/s)."""
    from acousim.fullwave import default_fullwave_surrogate
    from acousim.fullwave.family import dimensionless_coefficients

    sur0 = default_fullwave_surrogate()
    ks0 = sur0.wavenumber * sur0.settings["side_m"]
    base = dimensionless_coefficients(sur0)
    p = SYNTHETIC_FAMILY
    fk = 1 + p["ks_slope"] * (ks - ks0) + p["ks_curv"] * (ks - ks0) ** 2
    lg = np.log(gap_ratio / 0.01)
    fg = 1 + p["gap_slope"] * lg + p["gap_curv"] * lg**2
    return {"fz": base["fz"] / ks0 * ks * fk, "qt": base["qt"] * fk * fg}


def write_synthetic_family(directory, ks_nodes=None, gap_nodes=None, edge_graded: bool = False) -> list:
    """Node tables of the synthetic family in ``directory`` (the family's node grid by default); no solve.
    ``edge_graded``: the tables claim the edge-graded meshes of the family's levels (else the hinge-graded mesh)."""
    from dataclasses import replace as dc_replace

    from acousim.fullwave.family import (FAMILY_GAP_RATIOS, FAMILY_KS, REFERENCE, FamilyNode, node_path,
                                         scaled_surrogate)
    from acousim.fullwave.family_grid import family_mesh_level

    from acousim.fullwave import default_fullwave_surrogate

    n_half = default_fullwave_surrogate().settings["n_half"]
    paths = []
    for g in gap_nodes or FAMILY_GAP_RATIOS:
        for k in ks_nodes or FAMILY_KS:
            node = FamilyNode(k, g, n_half=n_half, theta_max=0.9,
                              mesh_level=family_mesh_level(g) if edge_graded else None)
            s = REFERENCE["side_m"]
            sur = scaled_surrogate(synthetic_reduced(k, g), 0.9, s, g * s, node.medium,
                                   REFERENCE["particle_density_kg_m3"], REFERENCE["pressure_amplitude_pa"])
            sur = dc_replace(sur, settings={**sur.settings, **node.expected_settings()},
                             build_accuracy={"ks": k, "gap_ratio": g, "dofs": 0, "wall_s": 0.0})
            path = node_path(directory, node)
            sur.save(path)
            paths.append(path)
    return paths


@pytest.fixture(scope="session")
def synthetic_family_dir(tmp_path_factory):
    """A complete synthetic table family (no boundary-element solve) with a known dependence on (ks, g/s)."""
    d = tmp_path_factory.mktemp("synthetic_family")
    write_synthetic_family(d)
    return d


@pytest.fixture
def use_synthetic_family(synthetic_family_dir, monkeypatch):
    """Point the full-wave model at the synthetic family for this test."""
    from acousim.fullwave.family import FAMILY_ENV

    monkeypatch.setenv(FAMILY_ENV, str(synthetic_family_dir))
    return synthetic_family_dir
