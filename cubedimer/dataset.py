"""Loading trajectory data sets (FORMATS.md) with the bad-input rules, and short-gap filling.

A data set is a directory of CSV files (header with at least ``t``, ``y``, ``theta``; ``#``
comment lines; extra columns ignored) and an optional ``meta.json``.  Every rule violation
raises :class:`DatasetError` whose message is one line naming the file and the problem.
"""
from __future__ import annotations

import json
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.typing import NDArray
from scipy.interpolate import PchipInterpolator

__all__ = ["DatasetError", "Run", "Dataset", "LoadConfig", "load_run", "load_dataset", "fill_gaps"]


class DatasetError(ValueError):
    """A bad input file; ``str(err)`` is a one-line message naming the file and the problem."""


@dataclass(frozen=True)
class LoadConfig:
    """Rules for loading.

    Parameters
    ----------
    max_gap : int
        Longest run of consecutive missing frames that is filled (PCHIP through the neighbours);
        longer gaps are an error.
    max_missing_fraction : float
        Largest allowed fraction of missing frames per run.
    uniform_tol : float
        Allowed relative deviation of any time step from the median step (FORMATS.md: 1 %).
    min_periods : float
        Minimum number of oscillation periods (of the dominant y frequency) a run must hold.
    """

    max_gap: int = 10
    max_missing_fraction: float = 0.05
    uniform_tol: float = 0.01
    min_periods: float = 5.0


@dataclass(frozen=True, eq=False)
class Run:
    """One recorded run, gaps filled.

    Attributes
    ----------
    name : str
        File name (e.g. ``run01.csv``).
    t : ndarray
        Times [s], uniform.
    y : ndarray
        Vertical displacement [m].
    theta : ndarray
        Normalised bending angle [-].
    n_filled : int
        Frames that were missing and filled.
    """

    name: str
    t: NDArray[np.float64]
    y: NDArray[np.float64]
    theta: NDArray[np.float64]
    n_filled: int = 0

    @property
    def dt(self) -> float:
        """Mean frame interval [s]."""
        return float((self.t[-1] - self.t[0]) / (self.t.size - 1))

    @property
    def duration(self) -> float:
        return float(self.t[-1] - self.t[0])


@dataclass(frozen=True, eq=False)
class Dataset:
    """Good runs of a data set, its meta data and the one-line errors of skipped files."""

    path: str
    runs: tuple[Run, ...]
    meta: dict = field(default_factory=dict)
    skipped: tuple[str, ...] = ()


def fill_gaps(t: NDArray, x: NDArray, max_gap: int, what: str, name: str) -> tuple[NDArray, int]:
    """Fill runs of at most ``max_gap`` non-finite samples by PCHIP interpolation.

    Raises DatasetError on a longer gap or on missing first/last frames beyond ``max_gap``.
    """
    bad = ~np.isfinite(x)
    if not bad.any():
        return x, 0
    # lengths of consecutive missing runs
    d = np.diff(np.r_[0, bad.astype(np.int8), 0])
    starts, ends = np.flatnonzero(d == 1), np.flatnonzero(d == -1)
    longest = int((ends - starts).max())
    if longest > max_gap:
        raise DatasetError(f"{name}: {longest} consecutive missing values of {what} at t={t[starts[np.argmax(ends - starts)]]:.4g} s "
                           f"(at most {max_gap} are filled)")
    good = ~bad
    if good.sum() < 4:
        raise DatasetError(f"{name}: almost no valid values of {what}")
    out = x.copy()
    out[bad] = PchipInterpolator(t[good], x[good], extrapolate=True)(t[bad])
    return out, int(bad.sum())


def _dominant_frequency(t: NDArray, x: NDArray, fmin: float = 0.0) -> float:
    """Frequency [Hz] of the largest spectral peak; if that lies below ``fmin`` (e.g. a slow drift of
    the levitation height from a drifting pressure), the largest peak at or above ``fmin`` instead,
    provided it is prominent (at least 30 % of the largest), so that noise is never taken for it."""
    x = x - x.mean()
    n = x.size
    spec = np.abs(np.fft.rfft(x * np.hanning(n)))
    f = np.fft.rfftfreq(n, (t[-1] - t[0]) / (n - 1))
    spec[0] = 0.0
    j = int(np.argmax(spec))
    if fmin > 0 and f[j] < fmin:
        above = f >= fmin
        if above.any():
            k = int(np.argmax(np.where(above, spec, 0.0)))
            if spec[k] >= 0.3 * spec[j]:
                return float(f[k])
    return float(f[j])


def load_run(path: str | os.PathLike, config: LoadConfig = LoadConfig()) -> Run:
    """Read one CSV run, check it against FORMATS.md, fill short gaps.

    Raises
    ------
    DatasetError
        One-line message ``"<file>: <problem>"``.
    """
    path = Path(path)
    name = path.name
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise DatasetError(f"{path}: unreadable file ({exc.__class__.__name__}: {exc})") from None
    lines = [ln for ln in text.splitlines() if ln.strip() and not ln.lstrip().startswith("#")]
    if not lines:
        raise DatasetError(f"{path}: empty file (no header row)")
    header = [h.strip().lower() for h in lines[0].split(",")]
    for col in ("t", "y", "theta"):
        if col not in header:
            raise DatasetError(f"{path}: missing column {col!r} (header: {','.join(header)})")
    idx = [header.index(c) for c in ("t", "y", "theta")]
    rows = []
    for k, ln in enumerate(lines[1:], 2):
        parts = ln.split(",")
        if len(parts) < len(header):
            raise DatasetError(f"{path}: data line {k} has {len(parts)} fields, header has {len(header)}")
        vals = []
        for i in idx:
            s = parts[i].strip()
            try:
                vals.append(float(s) if s else np.nan)
            except ValueError:
                raise DatasetError(f"{path}: non-numeric value {s!r} in column {header[i]!r} on data line {k}") from None
        rows.append(vals)
    if len(rows) < 16:
        raise DatasetError(f"{path}: only {len(rows)} data rows; too short to hold {config.min_periods:g} oscillation periods")
    a = np.asarray(rows, dtype=float)
    t, y, th = a[:, 0], a[:, 1], a[:, 2]
    if not np.all(np.isfinite(t)):
        raise DatasetError(f"{path}: missing or non-finite time values")
    dt = np.diff(t)
    if np.any(dt <= 0):
        k = int(np.flatnonzero(dt <= 0)[0])
        raise DatasetError(f"{path}: time is not strictly increasing at t={t[k]:.6g} s (row {k + 2})")
    med = float(np.median(dt))
    dev = float(np.max(np.abs(dt - med)) / med)
    if dev > config.uniform_tol:
        raise DatasetError(f"{path}: time is not uniformly sampled (step deviates {dev:.1%} from the median "
                           f"{med:.4g} s; allowed {config.uniform_tol:.0%})")
    fin = th[np.isfinite(th)]
    if fin.size and np.any(np.abs(fin) >= 1.0):
        raise DatasetError(f"{path}: theta outside (-1, 1) (max |theta| = {np.max(np.abs(fin)):.4g})")
    nmiss = int((~np.isfinite(y) | ~np.isfinite(th)).sum())
    if nmiss > config.max_missing_fraction * t.size:
        raise DatasetError(f"{path}: {nmiss} of {t.size} frames missing (more than {config.max_missing_fraction:.0%})")
    y, ny = fill_gaps(t, y, config.max_gap, "y", str(path))
    th, nt = fill_gaps(t, th, config.max_gap, "theta", str(path))
    duration = t[-1] - t[0]
    f = _dominant_frequency(t, y, config.min_periods / duration if duration > 0 else 0.0)
    if f <= 0 or duration * f < config.min_periods:
        raise DatasetError(f"{path}: too short to hold {config.min_periods:g} oscillation periods "
                           f"({duration:.3g} s at a dominant y frequency of {f:.3g} Hz)")
    return Run(name=name, t=t, y=y, theta=th, n_filled=max(ny, nt))


def load_dataset(path: str | os.PathLike, strict: bool = False, config: LoadConfig = LoadConfig(),
                 report=None) -> Dataset:
    """Load every ``*.csv`` in ``path`` (sorted by name).

    Parameters
    ----------
    path : path-like
        Data set directory.
    strict : bool
        If True the first bad file raises; otherwise it is reported (``report(message)``,
        default: print to stderr) and skipped.
    config : LoadConfig
    report : callable, optional

    Raises
    ------
    DatasetError
        If ``path`` is not a directory, holds no CSV, no file is good, or (strict) any file is bad.
    """
    import sys

    p = Path(path)
    if not p.is_dir():
        raise DatasetError(f"{p}: not a directory")
    files = sorted(p.glob("*.csv"))
    if not files:
        raise DatasetError(f"{p}: no CSV files in the data set")
    from .meta import read_meta

    meta = read_meta(p)
    report = report or (lambda msg: print(f"warning: skipping {msg}", file=sys.stderr))
    runs, skipped = [], []
    for f in files:
        try:
            runs.append(load_run(f, config))
        except DatasetError as exc:
            if strict:
                raise
            skipped.append(str(exc))
            report(str(exc))
    if not runs:
        raise DatasetError(f"{p}: no usable runs ({len(skipped)} bad files)")
    return Dataset(path=str(p), runs=tuple(runs), meta=meta, skipped=tuple(skipped))


# ---------------------------------------------------------------------- writing
__all__ += ["format_run_csv", "write_run_csv"]


def _csv_number(v: float, spec: str, missing: str) -> str:
    return missing if not np.isfinite(v) else format(v, spec)


def format_run_csv(t: NDArray, y: NDArray, theta: NDArray, comments: tuple[str, ...] | list[str] = (),
                   t_decimals: int = 9, y_digits: int = 10, theta_decimals: int = 10, missing: str = "nan") -> str:
    """The text of one run's CSV (FORMATS.md): ``# comment`` lines, header ``t,y,theta``, one row per frame.

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
