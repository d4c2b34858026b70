"""numba's on-disk cache of the suite's compiled kernels, keyed by the suite's sources.

numba validates a cached kernel only against the source file that defines it.  The suite's compiled entry
points inline functions from other files (the RK4 kernel binds the equations of motion, which bind every effect's
accelerations), so after an update of one of those files a kernel cached before it would still be loaded, and
would integrate the old equations.  The suite therefore caches into a folder named by a fingerprint of all its
sources: any change of any source file gives a fresh folder, and a kernel is never reused across versions.
Each process that starts on a folder marks it as used; the folders of other versions that no process has used
for :data:`STALE_AFTER_DAYS` days are removed then, so that a working copy that changes often does not fill the
disk with kernels of versions that are gone.

The folder is ``$NUMBA_CACHE_DIR/cubedimer-<fingerprint>`` when ``NUMBA_CACHE_DIR`` is set, else
``numba/cubedimer-<fingerprint>`` under the suite's user cache (:func:`suite_cache_root`:
``$XDG_CACHE_HOME/cubedimer``, ``~/.cache/cubedimer`` by default, the system's temporary folder when that cannot
be written).  ``make clean`` removes the default folder; the test suite uses a folder of its own.

A cache is never fatal.  An entry that cannot be loaded - an index or a kernel that does not unpickle (it names a
module this process cannot import, such as a kernel compiled in a process that had registered an effect of its
own), a truncated or corrupt file, an entry numba cannot rebuild - is passed over: the kernel is compiled again
and the entry rewritten, with one warning per process.  An entry that cannot be saved (a cache folder that is not
writable) only costs the compilation next time.  :func:`make_cache_failures_harmless` installs this on numba's
cache classes.

:func:`configure_compile_cache` runs when :mod:`cubedimer` is imported, which every package of the suite does
before it defines a compiled function.
"""
from __future__ import annotations

import hashlib
import logging
import os
import shutil
import tempfile
import time
from pathlib import Path

__all__ = ["SUITE_PACKAGES", "STALE_AFTER_DAYS", "suite_cache_root", "source_fingerprint", "compile_cache_dir",
           "prune_stale_caches", "make_cache_failures_harmless", "configure_compile_cache", "kernel_array"]

log = logging.getLogger(__name__)

#: The packages whose sources make the fingerprint (every package that defines or binds a compiled function).
SUITE_PACKAGES = ("cubedimer", "acousim", "fitting", "tracking", "validation")

#: Days after which the cache folder of another source version, unused since, is removed.
STALE_AFTER_DAYS = 7.0

_SUITE_ROOT = Path(__file__).resolve().parents[1]


def suite_cache_root() -> Path:
    """The suite's user cache folder: ``$XDG_CACHE_HOME/cubedimer`` (``~/.cache/cubedimer`` by default), or
    ``<system temporary folder>/cubedimer-<user>`` when that cannot be created or written.

    Every cache of the suite lives below it (compiled kernels, full-wave tables built on demand, the OpenCL
    verdict), so that ``XDG_CACHE_HOME`` moves them all; the test suite points it at a folder of its own."""
    base = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "cubedimer"
    try:
        base.mkdir(parents=True, exist_ok=True)
        if not os.access(base, os.W_OK):
            raise PermissionError(str(base))
    except OSError:
        base = Path(tempfile.gettempdir()) / f"cubedimer-{_user_name()}"
    return base


def _user_name() -> str:
    try:
        return str(os.getuid())
    except AttributeError:  # not POSIX
        return os.environ.get("USERNAME", "user")


def source_fingerprint(root: Path = _SUITE_ROOT, packages: tuple[str, ...] = SUITE_PACKAGES) -> str:
    """A 16-hex-digit digest of the path and content of every ``.py`` file of ``packages`` under ``root``."""
    digest = hashlib.sha1()
    for package in packages:
        for path in sorted((Path(root) / package).rglob("*.py")):
            digest.update(path.relative_to(root).as_posix().encode())
            digest.update(b"\0")
            digest.update(path.read_bytes())
    return digest.hexdigest()[:16]


def compile_cache_dir(fingerprint: str | None = None) -> Path:
    """The cache folder of this version of the sources (module docstring)."""
    name = f"cubedimer-{fingerprint or source_fingerprint()}"
    if os.environ.get("NUMBA_CACHE_DIR"):
        return Path(os.environ["NUMBA_CACHE_DIR"]) / name
    return suite_cache_root() / "numba" / name


def prune_stale_caches(current: Path, max_age_days: float = STALE_AFTER_DAYS, now: float | None = None) -> list[Path]:
    """Remove the folders ``cubedimer-*`` beside ``current`` (other source versions) whose modification time is
    more than ``max_age_days`` old; returns the folders removed.  Best effort: a folder that cannot be read or
    removed is left alone."""
    cutoff = (time.time() if now is None else float(now)) - 86400.0 * float(max_age_days)
    removed: list[Path] = []
    try:
        siblings = [d for d in Path(current).parent.glob("cubedimer-*") if d.is_dir() and d != Path(current)]
    except OSError:
        return removed
    for folder in siblings:
        try:
            stale = folder.stat().st_mtime < cutoff
        except OSError:
            continue
        if stale:
            shutil.rmtree(folder, ignore_errors=True)
            if not folder.exists():
                removed.append(folder)
    return removed


_WARNED = False


def _passed_over(what: str, where: str, exc: BaseException) -> None:
    """The one warning per process about a cache entry that could not be used (module docstring)."""
    global _WARNED
    if not _WARNED:
        _WARNED = True
        log.warning("compiled-kernel cache: an entry could not be %s (%s: %s; %s); compiling again "
                    "(further such entries are passed over silently)", what, type(exc).__name__, exc, where)
    else:
        log.debug("compiled-kernel cache: an entry could not be %s (%s: %s; %s)", what, type(exc).__name__, exc, where)


def make_cache_failures_harmless() -> None:
    """Make numba's on-disk cache skip every entry it cannot load or save instead of raising (module docstring).

    numba reads a kernel's index with :func:`pickle.loads` and lets any error through: an index that names a
    module this process cannot import ends the command with ``ModuleNotFoundError``.  Here a failed read counts
    as an empty index (the kernel is compiled, and the next save rewrites the index without the entry), a
    failed rebuild as a miss, and a failed save is logged.  Idempotent."""
    from numba.core import caching

    if getattr(caching.IndexDataCacheFile, "_cubedimer_harmless", False):
        return
    load_index, load, load_overload, save_overload = (caching.IndexDataCacheFile._load_index,
                                                      caching.IndexDataCacheFile.load, caching.Cache.load_overload,
                                                      caching.Cache.save_overload)

    def _load_index(self):
        try:
            return load_index(self)
        except Exception as exc:  # unpicklable, truncated, another format: an empty index, rewritten at the next save
            _passed_over("read", self._index_path, exc)
            return {}

    def _load(self, key):
        try:
            return load(self, key)
        except Exception as exc:  # a corrupt or unpicklable kernel file
            _passed_over("read", self._cache_path, exc)
            return None

    def _load_overload(self, sig, target_context):
        try:
            return load_overload(self, sig, target_context)
        except Exception as exc:  # an entry numba cannot rebuild in this process
            _passed_over("loaded", self._name, exc)
            return None

    def _save_overload(self, sig, data):
        try:
            return save_overload(self, sig, data)
        except Exception as exc:  # an unwritable folder, a full disk
            _passed_over("saved", self._name, exc)
            return None

    caching.IndexDataCacheFile._load_index = _load_index
    caching.IndexDataCacheFile.load = _load
    caching.Cache.load_overload = _load_overload
    caching.Cache.save_overload = _save_overload
    caching.IndexDataCacheFile._cubedimer_harmless = True


def configure_compile_cache() -> Path:
    """Point numba's cache at :func:`compile_cache_dir`, make unusable entries harmless
    (:func:`make_cache_failures_harmless`), mark the folder as used, and remove the folders of other source
    versions unused for :data:`STALE_AFTER_DAYS` days; returns the folder."""
    from numba.core import config

    make_cache_failures_harmless()
    folder = compile_cache_dir()
    if not _writable_folder(folder):
        fallback = Path(tempfile.gettempdir()) / f"cubedimer-{_user_name()}" / "numba" / folder.name
        log.warning("compiled-kernel cache %s cannot be written; using %s (set NUMBA_CACHE_DIR to a writable "
                    "folder to keep kernels between runs)", folder, fallback)
        folder = fallback
        if not _writable_folder(folder):  # numba then finds a folder of its own, or compiles every time
            log.warning("compiled-kernel cache %s cannot be written either", folder)
            return folder
    config.CACHE_DIR = str(folder)
    for gone in prune_stale_caches(folder):
        log.debug("removed the stale numba cache %s", gone)
    log.debug("numba cache: %s", folder)
    return folder


def _writable_folder(folder: Path) -> bool:
    """Create ``folder`` if needed, mark it as used now, and tell whether a file can be written in it."""
    try:
        folder.mkdir(parents=True, exist_ok=True)
        os.utime(folder)
        tempfile.TemporaryFile(dir=folder).close()
    except OSError:
        return False
    return True


def kernel_array(a, dtype=float):
    """``a`` as a C-contiguous, writeable array of ``dtype`` (a copy only where needed), for the arguments of a
    compiled entry point.  numba compiles one specialisation per array type, and read-only arrays (broadcasts,
    frozen inputs) are another type: passing every argument through here compiles each entry point once."""
    import numpy as np

    return np.require(a, dtype=dtype, requirements=("C", "W"))
