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
