"""Atomic file output: write to a temporary file in the target directory, then ``os.replace``.

Readers never see a partial file, and an interrupted or failing writer leaves the old file (or
none) in place.  The temporary file is created private (``tempfile.mkstemp`` gives mode 0600);
before it is moved into place it gets the mode an ordinary ``open(path, "w")`` would give
(0666 minus the process umask), so that results written to a shared folder stay readable to
colleagues (:func:`default_dir_mode` gives the same for a directory built in a temporary place).

There is one JSON writer, :func:`write_json`: indent 2, keys in insertion order, NaN and
infinities written as ``null`` (strict JSON that every reader accepts).
"""
from __future__ import annotations

import json
import math
import os
import tempfile
from pathlib import Path
from contextlib import contextmanager
from typing import Any, Callable, Iterator

__all__ = ["atomic_write_text", "write_json", "json_safe", "json_text", "atomic_save", "save_figure", "default_file_mode",
           "default_dir_mode", "atomic_directory"]


def _umask() -> int:
    """The process umask, read without changing it where the system allows (Linux ``/proc``), since
    setting it briefly would race with other threads creating files."""
    try:
        with open("/proc/self/status", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except (OSError, ValueError, IndexError):
        pass
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def default_file_mode() -> int:
    """The permission bits ``open(path, "w")`` gives a new file: 0o666 minus the process umask."""
    return 0o666 & ~_umask()


def default_dir_mode() -> int:
    """The permission bits ``os.mkdir(path)`` gives a new directory: 0o777 minus the process umask.

    A directory made with ``tempfile.mkdtemp`` (mode 0700) and moved into place as a result should
    be given this mode first, like a file written by :func:`atomic_save`.
    """
    return 0o777 & ~_umask()


def atomic_save(path: str | os.PathLike, writer: Callable[[str], Any]) -> None:
    """Call ``writer(tmp_path)`` then move the temporary file onto ``path``.

    The parent directory is created if needed.  On any exception the temporary file is removed and
    the exception propagates; ``path`` is untouched.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.stem}.", suffix=path.suffix or ".tmp")
    os.close(fd)
    try:
        writer(tmp)
        os.chmod(tmp, default_file_mode())
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


@contextmanager
def atomic_directory(path: str | os.PathLike) -> Iterator[Path]:
    """Build a directory in a temporary folder beside ``path`` and move it into place when the block ends.

    Yields the temporary folder.  On success it gets an ordinary folder's mode and replaces ``path`` (an
    existing ``path`` is moved aside first and removed after the swap); on any exception it is removed and
    ``path`` is untouched.  The caller decides beforehand whether an existing ``path`` may be replaced.
    """
    import shutil

    out = Path(path)
    parent = out.absolute().parent
    parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}.", dir=parent))
    try:
        yield tmp
        os.chmod(tmp, default_dir_mode())  # mkdtemp's folder is private; give it an ordinary folder's mode
        if out.exists():
            trash = Path(tempfile.mkdtemp(prefix=f".{out.name}.old.", dir=parent))
            os.replace(out, trash / out.name)
            os.replace(tmp, out)
            shutil.rmtree(trash, ignore_errors=True)
        else:
            os.replace(tmp, out)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise


def atomic_write_text(path: str | os.PathLike, text: str) -> None:
    """Write ``text`` (UTF-8) to ``path`` so that readers never see a partial file."""
    atomic_save(path, lambda tmp: Path(tmp).write_text(text, encoding="utf-8"))


def json_safe(obj: Any) -> Any:
    """``obj`` with NaN and infinities replaced by None, recursively; numpy scalars and arrays become
    Python numbers and lists, tuples become lists."""
    if isinstance(obj, bool) or obj is None or isinstance(obj, (str, int)):
        return obj
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {str(k) if not isinstance(k, str) else k: json_safe(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [json_safe(v) for v in obj]
    tolist = getattr(obj, "tolist", None)  # numpy scalars and arrays
    if callable(tolist):
        return json_safe(tolist())
    return obj


def json_text(data: Any) -> str:
    """``data`` as the text of a strict JSON file: indent 2, non-finite numbers as null, final newline."""
    return json.dumps(json_safe(data), indent=2, allow_nan=False) + "\n"


def write_json(path: str | os.PathLike, data: Any) -> None:
    """Write ``data`` as strict JSON (see :func:`json_text`) atomically."""
    atomic_write_text(path, json_text(data))


def save_figure(fig, path: str | os.PathLike, dpi: int = 130) -> Path:
    """Save a matplotlib figure atomically (format from the suffix), close it, return the path."""
    import matplotlib.pyplot as plt

    atomic_save(path, lambda tmp: fig.savefig(tmp, dpi=dpi))
    plt.close(fig)
    return Path(path)
