"""Loading trajectory data sets (FORMATS.md) with the bad-input rules, and short-gap filling.

A data set is a directory of CSV files (header with at least ``t``, ``y``, ``theta``; ``#``
comment lines; extra columns ignored) and an optional ``meta.json``.  Every rule violation
raises :class:`DatasetError` whose message is one line naming the file and the problem.
"""
from __future__ import annotations

import logging
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np
from numpy.typing import NDArray
from scipy.interpolate import PchipInterpolator

from .consistency import ConsistencyConfig, check_consistency, run_features
from .glitches import GlitchConfig, find_glitches
from .spectra import dominant_frequency

__all__ = ["DatasetError", "Run", "Dataset", "SkippedFile", "LoadConfig", "load_run", "load_dataset", "fill_gaps"]

logger = logging.getLogger(__name__)


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
    glitches : GlitchConfig or None
        Isolated tracking glitches are found (:mod:`cubedimer.glitches`) and masked like missing
        frames; None keeps every frame.
    consistency : ConsistencyConfig or None
        Runs that do not fit the rest of the set or meta.json (:mod:`cubedimer.consistency`) are
        reported and skipped; None loads every readable run.
    """

    max_gap: int = 10
    max_missing_fraction: float = 0.05
    uniform_tol: float = 0.01
    min_periods: float = 5.0
    glitches: GlitchConfig | None = field(default_factory=GlitchConfig)
    consistency: ConsistencyConfig | None = field(default_factory=ConsistencyConfig)


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
        Frames that were missing or masked as glitches, and filled.
    glitch_frames : tuple of int
        Indices of the frames masked as tracking glitches (in y or theta).
    """

    name: str
    t: NDArray[np.float64]
    y: NDArray[np.float64]
    theta: NDArray[np.float64]
    n_filled: int = 0
    glitch_frames: tuple[int, ...] = ()

    @property
    def n_glitches(self) -> int:
        """Number of frames masked as tracking glitches."""
        return len(self.glitch_frames)

    @property
    def dt(self) -> float:
        """Mean frame interval [s]."""
        return float((self.t[-1] - self.t[0]) / (self.t.size - 1))

    @property
    def duration(self) -> float:
        return float(self.t[-1] - self.t[0])


@dataclass(frozen=True, eq=False)
class Dataset:
    """Good runs of a data set, its meta data and the files that were skipped, with their reasons."""

    path: str
    runs: tuple[Run, ...]
    meta: dict = field(default_factory=dict)
    skipped: tuple["SkippedFile", ...] = ()

    @property
    def n_glitches(self) -> int:
        """Frames masked as tracking glitches over all runs."""
        return sum(r.n_glitches for r in self.runs)

    def skipped_files(self) -> list[dict[str, str]]:
        """``[{"file": name, "reason": one line}, ...]`` (the ``skipped_files`` of FORMATS.md)."""
        return [{"file": s.file, "reason": s.reason} for s in self.skipped]


@dataclass(frozen=True)
class SkippedFile:
    """A file left out of a data set: its name and the one-line reason."""

    file: str
    reason: str

    def __str__(self) -> str:
        return f"{self.file}: {self.reason}"


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


#: Longest piece of a file's content echoed into an error message [characters].
ECHO_LIMIT = 80

#: Height of the largest peak at or above the ``min_periods`` frequency, relative to the overall largest
#: peak, above which that peak is taken for the oscillation rather than a slow drift below it.
DRIFT_PROMINENCE = 0.3


def _cut(text: str, limit: int = ECHO_LIMIT) -> str:
    """``text`` cut to at most ``limit`` characters, an ellipsis marking the cut."""
    return text if len(text) <= limit else text[: limit - 1] + "\u2026"


def _echo(text: str) -> str:
    """File content quoted in an error message: cut (see :func:`_cut`) and repr-quoted."""
    return repr(_cut(text))


def load_run(path: str | os.PathLike, config: LoadConfig = LoadConfig()) -> Run:
    """Read one CSV run, check it against FORMATS.md, fill short gaps.

    The file is read as UTF-8 with or without a byte-order mark (spreadsheet programs write one).
    Line numbers in messages are those of the file (comments and blank lines counted), and file
    content quoted in a message is cut to :data:`ECHO_LIMIT` characters.

    Raises
    ------
    DatasetError
        One-line message ``"<file>: <problem>"``.
    """
    path = Path(path)
    name = path.name
    try:
        text = path.read_text(encoding="utf-8-sig")
    except (OSError, UnicodeDecodeError) as exc:
        raise DatasetError(f"{path}: unreadable file ({exc.__class__.__name__}: {_cut(str(exc))})") from None
    lines = [(k, ln) for k, ln in enumerate(text.splitlines(), 1) if ln.strip() and not ln.lstrip().startswith("#")]
    if not lines:
        raise DatasetError(f"{path}: empty file (no header row)")
    header_line, header_text = lines[0]
    header = [h.strip().lower() for h in header_text.split(",")]
    for col in ("t", "y", "theta"):
        if col not in header:
            raise DatasetError(f"{path}: missing column {col!r} (header on line {header_line}: "
                               f"{_echo(','.join(header))})")
    idx = [header.index(c) for c in ("t", "y", "theta")]
    rows, line_no = [], []
    for k, ln in lines[1:]:
        parts = ln.split(",")
        if len(parts) < len(header):
            raise DatasetError(f"{path}: line {k} has {len(parts)} fields, header has {len(header)}")
        vals = []
        for i in idx:
            s = parts[i].strip()
            try:
                vals.append(float(s) if s else np.nan)
            except ValueError:
                raise DatasetError(f"{path}: non-numeric value {_echo(s)} in column {header[i]!r} on line {k}") from None
        rows.append(vals)
        line_no.append(k)
    if len(rows) < 16:
        raise DatasetError(f"{path}: only {len(rows)} data rows; too short to hold {config.min_periods:g} oscillation periods")
    a = np.asarray(rows, dtype=float)
    t, y, th = a[:, 0], a[:, 1], a[:, 2]
    if not np.all(np.isfinite(t)):
        k = int(np.flatnonzero(~np.isfinite(t))[0])
        raise DatasetError(f"{path}: missing or non-finite time value on line {line_no[k]}")
    dt = np.diff(t)
    if np.any(dt <= 0):
        k = int(np.flatnonzero(dt <= 0)[0])
        raise DatasetError(f"{path}: time is not strictly increasing at t={t[k]:.6g} s (line {line_no[k + 1]})")
    med = float(np.median(dt))
    dev = float(np.max(np.abs(dt - med)) / med)
    if dev > config.uniform_tol:
        k = int(np.argmax(np.abs(dt - med)))
        raise DatasetError(f"{path}: time is not uniformly sampled (step deviates {dev:.1%} from the median "
                           f"{med:.4g} s on line {line_no[k + 1]}; allowed {config.uniform_tol:.0%})")
    fin = np.isfinite(th)
    if fin.any() and np.any(np.abs(th[fin]) >= 1.0):
        k = int(np.flatnonzero(fin & (np.abs(np.where(fin, th, 0.0)) >= 1.0))[0])
        raise DatasetError(f"{path}: theta outside (-1, 1) (max |theta| = {np.max(np.abs(th[fin])):.4g}; "
                           f"first on line {line_no[k]})")
    nmiss = int((~np.isfinite(y) | ~np.isfinite(th)).sum())
    if nmiss > config.max_missing_fraction * t.size:
        raise DatasetError(f"{path}: {nmiss} of {t.size} frames missing (more than {config.max_missing_fraction:.0%})")
    y_raw, th_raw = y, th
    y, ny = fill_gaps(t, y, config.max_gap, "y", str(path))
    th, nt = fill_gaps(t, th, config.max_gap, "theta", str(path))
    duration = t[-1] - t[0]
    f = dominant_frequency(y, duration / (t.size - 1), config.min_periods / duration if duration > 0 else 0.0,
                           prefer_above=DRIFT_PROMINENCE, refine=False)
    if f <= 0 or duration * f < config.min_periods:
        raise DatasetError(f"{path}: too short to hold {config.min_periods:g} oscillation periods "
                           f"({duration:.3g} s at a dominant y frequency of {f:.3g} Hz)")
    glitch_frames: tuple[int, ...] = ()
    if config.glitches is not None:
        frames_per_period = t.size / (duration * f)
        gy = find_glitches(y_raw, frames_per_period, config.glitches)
        gt = find_glitches(th_raw, frames_per_period, config.glitches)
        if gy.any() or gt.any():
            glitch_frames = tuple(int(i) for i in np.flatnonzero(gy | gt))
            y, ny = fill_gaps(t, np.where(gy, np.nan, y_raw), config.max_gap, "y", str(path))
            th, nt = fill_gaps(t, np.where(gt, np.nan, th_raw), config.max_gap, "theta", str(path))
            logger.info("%s: %d tracking glitch frame(s) masked", name, len(glitch_frames))
    return Run(name=name, t=t, y=y, theta=th, n_filled=max(ny, nt), glitch_frames=glitch_frames)


def _log_skip(message: str) -> None:
    logger.warning("skipping %s", message)


def load_dataset(path: str | os.PathLike, strict: bool = False, config: LoadConfig = LoadConfig(),
                 report: Callable[[str], None] | None = None) -> Dataset:
    """Load every CSV file (``*.csv``, any case of the suffix) in ``path``, sorted by name.

    Parameters
    ----------
    path : path-like
        Data set directory.
    strict : bool
        If True the first bad file raises; otherwise it is reported (``report(message)``,
        default: a warning on the ``cubedimer.dataset`` logger) and skipped.
    config : LoadConfig
    report : callable, optional

    Raises
    ------
    DatasetError
        If ``path`` does not exist or is not a directory, holds no CSV, no file is good, or
        (strict) any file is bad.
    """
    p = Path(path)
    if not p.exists():
        raise DatasetError(f"{p}: does not exist")
    if not p.is_dir():
        raise DatasetError(f"{p}: not a directory (a data set is a directory of CSV files)")
    files = sorted(f for f in p.iterdir() if f.suffix.lower() == ".csv" and f.is_file())
    if not files:
        raise DatasetError(f"{p}: no CSV files in the data set")
    from .meta import read_meta

    meta = read_meta(p)
    report = report or _log_skip
    runs, skipped = [], []

    def skip(file: str, reason: str) -> None:
        if strict:
            raise DatasetError(f"{p / file}: {reason}")
        skipped.append(SkippedFile(file, reason))
        report(f"{p / file}: {reason}")

    for f in files:
        try:
            runs.append(load_run(f, config))
        except DatasetError as exc:
            if strict:
                raise
            prefix = f"{f}: "
            msg = str(exc)
            skipped.append(SkippedFile(f.name, msg[len(prefix):] if msg.startswith(prefix) else msg))
            report(msg)
    if config.consistency is not None and runs:
        features = [run_features(r.name, r.t, r.y) for r in runs]
        # meta.json's constants are checked only when the data set has one (defaults prove nothing)
        bad = {x.file: x.reason for x in check_consistency(features, meta if meta else None, config.consistency)}
        for r in runs:
            if r.name in bad:
                skip(r.name, bad[r.name])
        runs = [r for r in runs if r.name not in bad]
    if not runs:
        raise DatasetError(f"{p}: no usable runs ({len(skipped)} bad files)")
    skipped.sort(key=lambda s: s.file)
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
