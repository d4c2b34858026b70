"""One builder per cache entry: an advisory lock that makes concurrent processes wait for the first one's result.

Some cache entries are expensive to make: the OpenCL verdict runs a trial assembly (half a minute, minutes under
load), a full-wave table built on demand takes several minutes of boundary-element solves.  When the parallel
workers of one command (or two commands) miss the same entry at once, each would otherwise make it on its own and
compete for the same cores.  :func:`cache_entry_lock` holds an exclusive lock on ``<entry>.lock`` beside the entry:
the first process makes the entry, the others wait, then find it made and load it.

The lock is the operating system's (``fcntl.flock``): it is released when the holder closes it, exits or is
killed, so a crashed builder never leaves a stale lock behind.  Where no lock can be taken (a system without
``fcntl``, a cache folder that cannot be written) the block runs unlocked: a lock only saves work, and an entry is
always written atomically, so that at worst it is made twice.
"""
from __future__ import annotations

import logging
import os
from contextlib import contextmanager
from pathlib import Path
from typing import Iterator

try:
    import fcntl
except ImportError:  # not POSIX
    fcntl = None  # type: ignore[assignment]

__all__ = ["cache_entry_lock"]

log = logging.getLogger(__name__)


@contextmanager
def cache_entry_lock(entry: str | os.PathLike, what: str = "this cache entry") -> Iterator[bool]:
    """Hold the exclusive lock of the cache entry ``entry`` for the duration of the block.

    Parameters
    ----------
    entry : path-like
        The cache file the block makes; the lock is the file ``<entry>.lock`` beside it.
    what : str
        What the entry is, for the log line a waiting process writes.

    Yields
    ------
    bool
        True when the lock is held, False when the block runs unlocked (no ``fcntl``, or the lock file cannot be
        created).  Callers re-check the cache inside the block: another process may have made the entry meanwhile.
    """
    path = Path(str(entry) + ".lock")
    if fcntl is None:
        yield False
        return
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o666)
    except OSError as exc:
        log.debug("cannot lock %s (%s); going on unlocked", path, exc)
        yield False
        return
    locked = True
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        log.info("waiting for another process that is making %s (%s)", what, path.with_suffix(""))
        try:
            fcntl.flock(fd, fcntl.LOCK_EX)
        except OSError as exc:
            locked = False
            log.debug("cannot lock %s (%s); going on unlocked", path, exc)
    except OSError as exc:  # a file system without locks
        locked = False
        log.debug("cannot lock %s (%s); going on unlocked", path, exc)
    try:
        yield locked
    finally:
        os.close(fd)  # closing releases the lock
