"""numba's cache folder follows the suite's sources (cubedimer.compile_cache)."""
import os
import pickle
import subprocess
import sys
import time
from pathlib import Path

import pytest

from cubedimer.compile_cache import STALE_AFTER_DAYS, compile_cache_dir, prune_stale_caches, source_fingerprint

REPO = Path(__file__).resolve().parents[2]


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


# ------------------------------------------------------------------------------- a cache is never fatal
def _simulate_outside_the_repository(workdir: Path, cache: Path, out: str) -> subprocess.CompletedProcess:
    """``python -m acousim simulate`` (one short run, which compiles the twin's kernels) run as a user would, from
    ``workdir``, with the compiled-kernel cache in ``cache``."""
    env = dict(os.environ, NUMBA_CACHE_DIR=str(cache))
    env["PYTHONPATH"] = os.pathsep.join([str(REPO), env.get("PYTHONPATH", "")])  # also without an install
    return subprocess.run([sys.executable, "-m", "acousim", "simulate", "--runs", "1", "--duration", "0.3", "--seed",
                           "1", "--out", out, "--no-progress"], cwd=workdir, env=env, capture_output=True, text=True,
                          timeout=600)


def _poison(cache: Path) -> int:
    """Make every index of ``cache`` name a module that cannot be imported (as an index written by a process that
    had registered an effect of its own does), and every kernel file garbage; returns the number of indexes."""
    import numba

    indexes = list(cache.rglob("*.nbi"))
    for index in indexes:
        index.write_bytes(pickle.dumps(numba.__version__) + b"cno_such_module_of_a_test_run\nEffect\n.")
    for kernel in cache.rglob("*.nbc"):
        kernel.write_bytes(b"\x80\x05not a kernel")
    return len(indexes)


@pytest.mark.slow
def test_a_poisoned_kernel_cache_is_recompiled_not_fatal(tmp_path):
    """Every cache entry unloadable (indexes naming a missing module, corrupt kernels): the command still works,
    from a folder outside the repository, gives the same numbers, warns once, and rewrites the indexes."""
    cache, work = tmp_path / "cache", tmp_path / "work"
    work.mkdir()
    first = _simulate_outside_the_repository(work, cache, "clean")
    assert first.returncode == 0, first.stderr[-2000:]
    assert _poison(cache) >= 5  # the twin's kernels were cached, and are now all unloadable
    again = _simulate_outside_the_repository(work, cache, "poisoned")
    assert again.returncode == 0, again.stderr[-2000:]
    assert "Traceback" not in again.stderr and again.stderr.count("compiled-kernel cache: an entry could not") == 1
    assert (work / "poisoned" / "run01.csv").read_bytes() == (work / "clean" / "run01.csv").read_bytes()
    assert not any(b"no_such_module" in index.read_bytes() for index in cache.rglob("*.nbi"))  # rewritten


def test_an_unwritable_cache_folder_falls_back_with_one_warning(monkeypatch, tmp_path, caplog):
    from cubedimer import compile_cache

    monkeypatch.setattr(compile_cache, "_writable_folder", lambda folder: "fallback-numba" in str(folder))
    monkeypatch.setattr(compile_cache.tempfile, "gettempdir", lambda: str(tmp_path / "fallback-numba"))
    with caplog.at_level("WARNING", logger=compile_cache.__name__):
        folder = compile_cache.configure_compile_cache()
    try:
        assert str(folder).startswith(str(tmp_path / "fallback-numba")) and len(caplog.records) == 1
        assert "cannot be written; using" in caplog.text
    finally:
        monkeypatch.undo()
        compile_cache.configure_compile_cache()  # back to the test run's own folder
