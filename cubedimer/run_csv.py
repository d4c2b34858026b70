"""Writing one run's CSV in the data-set format (docs/formats.md), the loader's counterpart (:mod:`cubedimer.dataset`).

Every writer of runs (the twin, the tracking, the synthetic data sets and the blind study) goes through
:func:`write_run_csv`, so that the files the suite writes are the files its loader reads.
"""
from __future__ import annotations

import os
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

__all__ = ["format_run_csv", "write_run_csv"]

def _csv_number(v: float, spec: str, missing: str) -> str:
    return missing if not np.isfinite(v) else format(v, spec)


def format_run_csv(t: NDArray, y: NDArray, theta: NDArray, comments: tuple[str, ...] | list[str] = (),
                   t_decimals: int = 9, y_digits: int = 10, theta_decimals: int = 10, missing: str = "nan") -> str:
    """The text of one run's CSV (docs/formats.md): ``# comment`` lines, header ``t,y,theta``, one row per frame.

    Parameters
    ----------
    t, y, theta : ndarray (n,)
        Times [s], heights [m], bends [-]; non-finite y or theta (missing frames) are written as ``missing``.
    comments : sequence of str
        Comment lines, written after ``# ``.
    t_decimals, theta_decimals : int
        Decimals of t and theta (fixed point).
    y_digits : int
        Decimals of y's mantissa (scientific notation).
    missing : str
        Text of a missing value (``"nan"`` or ``""``; the loader reads both).
    """
    ts, ys, ths = f".{int(t_decimals)}f", f".{int(y_digits)}e", f".{int(theta_decimals)}f"
    lines = [f"# {c}" for c in comments] + ["t,y,theta"]
    lines += [f"{format(a, ts)},{_csv_number(b, ys, missing)},{_csv_number(c, ths, missing)}"
              for a, b, c in zip(np.asarray(t, float), np.asarray(y, float), np.asarray(theta, float))]
    return "\n".join(lines) + "\n"


def write_run_csv(path: str | os.PathLike, t: NDArray, y: NDArray, theta: NDArray,
                  comments: tuple[str, ...] | list[str] = (), **number_format) -> Path:
    """Write one run's CSV atomically (:func:`format_run_csv`; ``number_format`` are its format
    keywords); returns the path."""
    from .atomic import atomic_write_text

    atomic_write_text(path, format_run_csv(t, y, theta, comments, **number_format))
    return Path(path)
