"""``make test``'s schedule: the boundary-element modules travel as one unit, so do the modules that use a dask
cluster, and units start longest first."""
import json
import re

from tests.conftest import (BEMPP_SOLVER_MODULE, BOUNDARY_ELEMENT_MODULES, CLUSTER_MODULES, GROUPED_UNITS,
                            UNIT_DURATIONS_FILE, boundary_elements_outside_their_unit, longest_first, scheduling_unit)


def test_boundary_element_modules_are_one_unit():
    assert {scheduling_unit(m) for m in BOUNDARY_ELEMENT_MODULES} == {"boundary-elements"}
    assert scheduling_unit("tests/fitting/test_recovery.py") == "tests/fitting/test_recovery.py"


def test_a_module_outside_the_boundary_element_unit_that_reaches_bempp_is_named():
    """bempp-cl's kernels compile once per session only if its solver is reached in the boundary-element unit alone:
    a test of another module that leaves bempp-cl's solver API imported in a process that has run no boundary-element
    module fails its teardown (tests/conftest.py ``pytest_runtest_teardown``), naming the module and the fix."""
    fullwave = sorted(BOUNDARY_ELEMENT_MODULES)[0]
    other = "tests/validation/diagnosis/test_pipeline_twin.py"
    complaint = boundary_elements_outside_their_unit(other, {BEMPP_SOLVER_MODULE: None}, False)
    assert other in complaint and "BOUNDARY_ELEMENT_MODULES" in complaint
    assert boundary_elements_outside_their_unit(other, {"bempp_cl": None}, False) is None  # importorskip alone
    assert boundary_elements_outside_their_unit(fullwave, {BEMPP_SOLVER_MODULE: None}, False) is None
    assert boundary_elements_outside_their_unit(other, {BEMPP_SOLVER_MODULE: None}, True) is None  # compiled here


def test_cluster_modules_are_one_unit_and_every_user_of_the_cluster_is_in_it():
    from pathlib import Path

    assert {scheduling_unit(m) for m in CLUSTER_MODULES} == {"dask-cluster"}
    root = Path(__file__).resolve().parents[1]
    asks = re.compile(r"def \w+\([^)]*\bprocess_cluster\b")  # a test or fixture that takes the cluster
    users = {p.relative_to(root).as_posix() for p in (root / "tests").rglob("test_*.py") if asks.search(p.read_text())}
    assert users == CLUSTER_MODULES  # a module outside the unit would start a cluster of its own


def test_a_group_without_a_record_is_expected_to_take_its_modules_seconds():
    seconds = {"tests/cubedimer/test_executor.py": 5.0, "tests/fitting/test_cli.py": 13.0, "big.py": 15.0}
    assert longest_first(["big.py", "dask-cluster"], seconds, {"big.py": 3, "dask-cluster": 40}) == ["dask-cluster",
                                                                                                      "big.py"]


def test_longest_first_uses_seconds_then_test_counts():
    seconds = {"a.py": 5.0, "b.py": 120.0, "c.py": 0.5}
    counts = {"a.py": 40, "b.py": 4, "c.py": 10, "new.py": 30}
    # b by its seconds first; a new module without a record counts 1 s per test (30 s), ahead of a (5 s)
    assert longest_first(["a.py", "b.py", "c.py", "new.py"], seconds, counts) == ["b.py", "new.py", "a.py", "c.py"]


def test_committed_durations_name_existing_units():
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    recorded = json.loads(UNIT_DURATIONS_FILE.read_text())
    assert recorded and all(v >= 0 for v in recorded.values())
    stale = [u for u in recorded if u not in GROUPED_UNITS and not (root / u).exists()]
    assert not stale, f"{stale}: refresh with make test-durations"
