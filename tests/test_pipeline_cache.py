"""The tests' pipeline cache (tests/conftest.py PipelineCache): made once per key and version of the sources, made
again when broken, and never a different result."""
from __future__ import annotations

import pytest


@pytest.fixture
def cache(tmp_path, pipeline_cache):
    c = type(pipeline_cache)(tmp_path / "cache")  # the class of the suite's cache, on a folder of its own
    c._fingerprint = "sources-a"
    return c


def test_a_folder_is_built_once_per_key(cache):
    calls = []

    def build(folder):
        calls.append(folder)
        (folder / "x.txt").write_text(str(len(calls)))

    first = cache.folder("twin", "k1", build)
    assert cache.folder("twin", "k1", build) == first and len(calls) == 1
    assert (first / "x.txt").read_text() == "1"
    assert cache.folder("twin", "k2", build) != first and len(calls) == 2
    assert not [p for p in first.parent.iterdir() if p.name.startswith(".")]  # no temporary folder left


def test_another_version_of_the_sources_builds_anew_and_prunes_the_old(cache):
    calls = []
    old = cache.folder("fit", "k", lambda f: calls.append(1))
    cache._fingerprint = "sources-b"
    new = cache.folder("fit", "k", lambda f: calls.append(2))
    assert new != old and calls == [1, 2]
    cache.prune()
    assert not old.exists() and new.exists()


def test_a_broken_entry_is_made_again(cache):
    value = cache.value("diagnosis", "k", lambda: {"a": 1.5})
    path = cache.entry("diagnosis", "k")
    (path / "value.pickle").write_bytes(b"not a pickle")
    assert cache.value("diagnosis", "k", lambda: {"a": 1.5}) == value == {"a": 1.5}
    (path / ".complete").unlink()  # an entry whose build did not finish
    assert cache.value("diagnosis", "k", lambda: {"a": 2.5}) == {"a": 2.5}


def test_a_worker_that_needs_an_entry_being_made_waits_for_it(cache):
    """Two workers (threads here; pytest-xdist's are processes, the lock is the same) ask for one entry at once: the
    entry is made once, and both get the same folder."""
    import threading

    calls, started = [], threading.Event()

    def build(folder):
        calls.append(folder)
        started.set()
        threading.Event().wait(0.3)  # still making it when the second worker asks
        (folder / "x.txt").write_text("made")

    got = {}
    first = threading.Thread(target=lambda: got.setdefault("first", cache.folder("twin", "k", build)))
    first.start()
    assert started.wait(60)
    second = cache.folder("twin", "k", build)  # asked while the first worker holds the entry's lock
    first.join(60)
    assert len(calls) == 1 and second == got["first"] and (second / "x.txt").read_text() == "made"


def test_a_build_that_fails_leaves_no_entry_and_is_tried_again(cache):
    def broken(folder):
        (folder / "half.txt").write_text("")
        raise RuntimeError("interrupted")

    with pytest.raises(RuntimeError):
        cache.folder("fit", "k", broken)
    assert not cache.entry("fit", "k").exists()
    assert not [p for p in cache.entry("fit", "k").parent.iterdir() if p.name.startswith(".")]
    made = cache.folder("fit", "k", lambda f: (f / "x.txt").write_text("ok"))
    assert (made / "x.txt").read_text() == "ok"


def test_the_fingerprint_changes_with_the_code_and_the_data_that_make_the_results(tmp_path, cache):
    """A change of any module or data file of the five packages gives another fingerprint (a new set of entries);
    a file outside them does not."""
    pipeline_fingerprint = cache.fingerprint_of
    for package in ("cubedimer", "acousim", "fitting", "tracking", "validation"):
        (tmp_path / package).mkdir()
        (tmp_path / package / "__init__.py").write_text("x = 1\n")
    (tmp_path / "acousim" / "data").mkdir()
    (tmp_path / "acousim" / "data" / "table.json").write_text("{}")
    (tmp_path / "tests").mkdir()
    first = pipeline_fingerprint(tmp_path)
    assert pipeline_fingerprint(tmp_path) == first and len(first) == 16
    (tmp_path / "tests" / "other.py").write_text("y = 2\n")
    assert pipeline_fingerprint(tmp_path) == first
    seen = {first}
    for path, text in ((tmp_path / "fitting" / "__init__.py", "x = 2\n"),
                       (tmp_path / "acousim" / "data" / "table.json", '{"a": 1}')):
        path.write_text(text)
        seen.add(pipeline_fingerprint(tmp_path))
    assert len(seen) == 3
