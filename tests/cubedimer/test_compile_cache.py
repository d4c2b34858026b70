"""numba's cache folder follows the suite's sources (cubedimer.compile_cache)."""
import os
import pickle
import re
import shutil
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
SIMULATE_ARGS = ("simulate", "--runs", "1", "--duration", "0.3", "--seed", "1", "--no-progress")


def _simulate_outside_the_repository(workdir: Path, cache: Path, out: str,
                                     log_cache: bool = False) -> subprocess.CompletedProcess:
    """``python -m acousim simulate`` (one short run, which compiles the twin's kernels) run as a user would, from
    ``workdir``, with the compiled-kernel cache in ``cache``; ``log_cache``: numba prints every index it loads or
    saves (``NUMBA_DEBUG_CACHE``)."""
    env = dict(os.environ, NUMBA_CACHE_DIR=str(cache), NUMBA_DEBUG_CACHE="1" if log_cache else "0")
    env["PYTHONPATH"] = os.pathsep.join([str(REPO), env.get("PYTHONPATH", "")])  # also without an install
    return subprocess.run([sys.executable, "-m", "acousim", *SIMULATE_ARGS, "--out", out], cwd=workdir, env=env,
                          capture_output=True, text=True, timeout=600)


def _copy_of_the_warm_cache(cache: Path, tmp_path: Path) -> None:
    """Fill ``cache`` with a copy of this test run's own kernel folder after making sure it holds the twin's kernels
    (the same command run in this process: a worker of the test run compiles them for its other tests anyway), so
    that the clean run loads its kernels instead of compiling them.  Files another process is replacing meanwhile
    are skipped: a missing entry is only compiled."""
    from numba.core import config

    from acousim.cli import main

    assert main([*SIMULATE_ARGS, "--out", str(tmp_path / "warm-up")]) == 0
    own = Path(config.CACHE_DIR)
    for source in own.rglob("*.nb[ic]"):
        target = cache / own.name / source.relative_to(own)
        target.parent.mkdir(parents=True, exist_ok=True)
        try:
            shutil.copyfile(source, target)
        except FileNotFoundError:
            pass


def _indexes(log: str, *actions: str) -> set[Path]:
    """The index files that numba's cache log ``log`` (``NUMBA_DEBUG_CACHE``) says were ``actions`` ("loaded from",
    "saved to")."""
    pattern = r"\[cache\] index (?:%s) '([^']+)'" % "|".join(map(re.escape, actions))
    return {Path(p) for p in re.findall(pattern, log)}


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
    _copy_of_the_warm_cache(cache, tmp_path)
    first = _simulate_outside_the_repository(work, cache, "clean", log_cache=True)
    assert first.returncode == 0, first.stderr[-2000:]
    entry_points = _indexes(first.stdout + first.stderr, "loaded from", "saved to")
    assert entry_points, "numba printed no cache index: is NUMBA_DEBUG_CACHE still honoured?"
    poisoned = {index for index in cache.rglob("*.nbi")}
    assert _poison(cache) == len(poisoned)
    again = _simulate_outside_the_repository(work, cache, "poisoned", log_cache=True)
    assert again.returncode == 0, again.stderr[-2000:]
    assert "Traceback" not in again.stderr and again.stderr.count("compiled-kernel cache: an entry could not") == 1
    assert (work / "poisoned" / "run01.csv").read_bytes() == (work / "clean" / "run01.csv").read_bytes()
    # the cache copied from the test run's own holds kernels of other commands too, which this one never reads: the
    # indexes it needs are the ones it rewrote, among them every entry point it loaded from the clean cache, and the
    # twin's kernels (the entry points and the functions they bind) were cached and are now all unloadable
    rewritten = _indexes(again.stdout + again.stderr, "saved to")
    assert entry_points <= rewritten and len(rewritten & poisoned) >= 5
    assert not any(b"no_such_module" in index.read_bytes() for index in rewritten)  # rewritten


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
