"""numba's cache folder follows the suite's sources (cubedimer.compile_cache)."""
import os
import time
from pathlib import Path

import pytest

from cubedimer.compile_cache import STALE_AFTER_DAYS, compile_cache_dir, prune_stale_caches, source_fingerprint


@pytest.fixture
def tree(tmp_path):
    """A two-package source tree: a kernel in one file, the function it inlines in another."""
    (tmp_path / "core").mkdir()
    (tmp_path / "physics").mkdir()
    (tmp_path / "core" / "kernel.py").write_text("from physics.terms import force\n")
    (tmp_path / "physics" / "terms.py").write_text("def force(x):\n    return -x\n")
    return tmp_path


def test_a_change_in_an_inlined_file_gives_a_new_cache_folder(tree):
    """The defect this prevents: numba checks only the kernel's own file, so an edited dependency would
    reuse a stale kernel.  Any source's content changes the fingerprint, and so the folder."""
    before = source_fingerprint(tree, ("core", "physics"))
    assert source_fingerprint(tree, ("core", "physics")) == before  # deterministic
    (tree / "physics" / "terms.py").write_text("def force(x):\n    return -2 * x\n")
    after = source_fingerprint(tree, ("core", "physics"))
    assert after != before
    assert compile_cache_dir(after) != compile_cache_dir(before)


def test_a_new_file_changes_the_fingerprint(tree):
    before = source_fingerprint(tree, ("core", "physics"))
    (tree / "physics" / "extra.py").write_text("")
    assert source_fingerprint(tree, ("core", "physics")) != before


def test_the_suite_caches_into_the_folder_of_its_sources(monkeypatch, tmp_path):
    from numba.core import config

    import acousim  # noqa: F401  (any package of the suite sets the cache up on import)

    assert Path(config.CACHE_DIR).name == f"cubedimer-{source_fingerprint()}"
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    assert compile_cache_dir() == tmp_path / f"cubedimer-{source_fingerprint()}"


def test_folders_of_other_versions_unused_for_a_week_are_removed(tmp_path):
    now = time.time()
    day = 86400.0
    folders = {}
    for name, age_days in (("cubedimer-current", 30), ("cubedimer-old", STALE_AFTER_DAYS + 1),
                           ("cubedimer-recent", STALE_AFTER_DAYS - 1), ("someone-else", 30)):
        d = tmp_path / name
        (d / "sub").mkdir(parents=True)
        (d / "sub" / "kernel.nbi").write_bytes(b"x")
        os.utime(d, (now - age_days * day, now - age_days * day))
        folders[name] = d
    removed = prune_stale_caches(folders["cubedimer-current"], now=now)
    assert removed == [folders["cubedimer-old"]]
    # the current version's folder however old, another version's recent one and a folder not ours are kept
    assert all(folders[n].exists() for n in ("cubedimer-current", "cubedimer-recent", "someone-else"))
    assert not folders["cubedimer-old"].exists()
