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
``$XDG_CACHE_HOME/cubedimer/numba/cubedimer-<fingerprint>`` (``~/.cache`` by default; the system's temporary
folder when that cannot be written).  ``make clean`` removes the default folder.

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

__all__ = ["SUITE_PACKAGES", "STALE_AFTER_DAYS", "source_fingerprint", "compile_cache_dir", "prune_stale_caches",
           "configure_compile_cache", "kernel_array"]

log = logging.getLogger(__name__)

#: The packages whose sources make the fingerprint (every package that defines or binds a compiled function).
SUITE_PACKAGES = ("cubedimer", "acousim", "fitting", "tracking", "validation")

#: Days after which the cache folder of another source version, unused since, is removed.
STALE_AFTER_DAYS = 7.0

_SUITE_ROOT = Path(__file__).resolve().parents[1]


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
    base = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "cubedimer" / "numba"
    try:
        base.mkdir(parents=True, exist_ok=True)
        if not os.access(base, os.W_OK):
            raise PermissionError(str(base))
    except OSError:
        base = Path(tempfile.gettempdir()) / "cubedimer-numba"
    return base / name


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


def configure_compile_cache() -> Path:
    """Point numba's cache at :func:`compile_cache_dir`, mark that folder as used, and remove the folders of other
    source versions unused for :data:`STALE_AFTER_DAYS` days; returns the folder."""
    from numba.core import config

    folder = compile_cache_dir()
    config.CACHE_DIR = str(folder)
    try:
        folder.mkdir(parents=True, exist_ok=True)
        os.utime(folder)
    except OSError:  # numba reports an unwritable cache itself, at the first compilation
        pass
    else:
        for gone in prune_stale_caches(folder):
            log.debug("removed the stale numba cache %s", gone)
    log.debug("numba cache: %s", folder)
    return folder


def kernel_array(a, dtype=float):
    """``a`` as a C-contiguous, writeable array of ``dtype`` (a copy only where needed), for the arguments of a
    compiled entry point.  numba compiles one specialisation per array type, and read-only arrays (broadcasts,
    frozen inputs) are another type: passing every argument through here compiles each entry point once."""
    import numpy as np

    return np.require(a, dtype=dtype, requirements=("C", "W"))
