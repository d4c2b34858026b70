"""Loading trajectory data sets (docs/formats.md) with the bad-input rules, and short-gap filling.

A data set is a directory of CSV files (header with at least ``t``, ``y``, ``theta``; ``#``
comment lines; extra columns ignored) and an optional ``meta.json``.  Every rule violation
raises :class:`DatasetError` whose message is one line naming the file and the problem.
"""
from __future__ import annotations

import logging
import os
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Callable

import numpy as np
from numpy.typing import NDArray

from .errors import DatasetError
from .meta import read_meta
from .drop_phases import field_on_start
from .gaps import fill_gaps, fill_lost_frames, gap_segments
from .noise import recorded_run_noise
from .consistency import SLOW_PEAK_FRACTION, check_consistency, run_features
from .glitches import find_glitches
from .load_config import DEFAULT_MAX_GAP, LoadConfig
from .lab_csv import cut_text, echo, missing_columns_message, parse_header, read_rows, separator, unit_factor
from .spectra import dominant_frequency
from .run_csv import format_run_csv, write_run_csv
from .system import LEVITATED_DIMER, SystemSpec, check_velocity, coordinate_unit_factor, read_system

__all__ = ["DatasetError", "Run", "Dataset", "SkippedFile", "LoadConfig", "load_run", "load_run_parts", "load_dataset",
           "fill_gaps", "gap_segments", "DEFAULT_MAX_GAP", "format_run_csv", "write_run_csv"]

logger = logging.getLogger(__name__)

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
    velocities : ndarray (n, 2) or None
        Measured rates of the two coordinates [SI per s] (a generic system's declared velocity columns; NaN for a
        coordinate without one), or None.  In a generic system y and theta hold its first and second coordinate.
    source : str, optional
        For a part of a run split at a long gap (:func:`load_run_parts`): the file it came from.
    frames : (int, int), optional
        For such a part: its frames ``[start, stop)`` in the file.
    noise : (float, float) or None
        The run's own white tracking noise of y [m] and theta [-] as meta.json's ``tracking.runs[]`` records it
        (``noise_y_m``, ``noise_theta``; a part of a split run has its file's), or None when the set records none.
        The fit weights each run by it (:mod:`fitting.selection.support_search`).
    """

    name: str
    t: NDArray[np.float64]
    y: NDArray[np.float64]
    theta: NDArray[np.float64]
    n_filled: int = 0
    glitch_frames: tuple[int, ...] = ()
    velocities: NDArray[np.float64] | None = None
    source: str | None = None
    frames: tuple[int, int] | None = None
    noise: tuple[float, float] | None = None

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
    system: SystemSpec = LEVITATED_DIMER

    @property
    def n_glitches(self) -> int:
        """Frames masked as tracking glitches over all runs."""
        return sum(r.n_glitches for r in self.runs)

    def skipped_files(self) -> list[dict[str, str]]:
        """``[{"file": name, "reason": one line}, ...]`` (the ``skipped_files`` of docs/formats.md)."""
        return [{"file": s.file, "reason": s.reason} for s in self.skipped]


@dataclass(frozen=True)
class SkippedFile:
    """A file left out of a data set: its name and the one-line reason."""

    file: str
    reason: str

    def __str__(self) -> str:
        return f"{self.file}: {self.reason}"


def _data_lines(path: Path) -> list[tuple[int, str]]:
    """The file's header and data lines with their line numbers (comments and blank lines left out, counted)."""
    try:
        text = path.read_text(encoding="utf-8-sig")
    except (OSError, UnicodeDecodeError) as exc:
        raise DatasetError(f"{path}: unreadable file ({exc.__class__.__name__}: {cut_text(str(exc))})") from None
    lines = [(k, ln) for k, ln in enumerate(text.splitlines(), 1) if ln.strip() and not ln.lstrip().startswith("#")]
    if not lines:
        raise DatasetError(f"{path}: empty file (no header row)")
    return lines


def _columns(path: Path, header_line: int, header_text: str, header: list[str], units: list[str | None],
             frame_rate_hz: float | None, system: SystemSpec) -> tuple[str | None, list[int], list[float]]:
    """The time column's name (``t`` or ``frame``), the indices of the columns read (time, the system's
    coordinates, its velocities) and their factors to SI units."""
    time_col = "t" if "t" in header else ("frame" if "frame" in header and frame_rate_hz else None)
    velocity_cols = [c.velocity for c in system.coordinates if c.velocity]
    missing = [c for c in ("t", *system.names, *velocity_cols)
               if c not in header and not (c == "t" and time_col == "frame")]
    if missing and not system.generic:
        raise DatasetError(missing_columns_message(path, header_line, header_text, missing, header, frame_rate_hz))
    if missing:
        raise DatasetError(f"{path}: missing column{'s' if len(missing) > 1 else ''} "
                           f"{', '.join(repr(c) for c in missing)} (header on line {header_line}: "
                           f"{echo(header_text)}); meta.json's system declares the columns "
                           f"{', '.join(['t', *system.names, *velocity_cols])}: rename the columns or the declaration")
    used = [time_col, *system.names, *velocity_cols]
    idx = [header.index(c) for c in used]
    factors = [unit_factor(path, c, units[i]) for c, i in zip(used[:1], idx)]
    if system.generic:
        factors += [coordinate_unit_factor(path, c.name, c.unit, units[header.index(c.name)])
                    for c in system.coordinates]
        factors += [coordinate_unit_factor(path, c.velocity, c.unit, units[header.index(c.velocity)], velocity=True)
                    for c in system.coordinates if c.velocity]
    else:
        factors += [unit_factor(path, c, units[i]) for c, i in zip(used[1:], idx[1:])]
    return time_col, idx, factors


def _frame_times(path: Path, t: NDArray, time_col: str | None, frame_rate_hz: float | None,
                 line_no: list[int | None]) -> NDArray:
    """The frames' times [s]: finite, whole frame numbers divided by the frame rate for a ``frame`` column,
    strictly increasing."""
    if not np.all(np.isfinite(t)):
        k = int(np.flatnonzero(~np.isfinite(t))[0])
        raise DatasetError(f"{path}: missing or non-finite {time_col} value on line {line_no[k]}")
    if time_col == "frame":
        if np.any(np.abs(t - np.rint(t)) > 1e-6):
            k = int(np.flatnonzero(np.abs(t - np.rint(t)) > 1e-6)[0])
            raise DatasetError(f"{path}: frame numbers must be whole numbers ({echo(str(t[k]))} on line {line_no[k]})")
        t = np.rint(t) / float(frame_rate_hz)
    dt = np.diff(t)
    if np.any(dt <= 0):
        k = int(np.flatnonzero(dt <= 0)[0])
        raise DatasetError(f"{path}: time is not strictly increasing at t={t[k]:.6g} s (line {line_no[k + 1]})")
    return t


def _check_uniform(path: Path, t: NDArray, line_no: list[int | None], tol: float) -> None:
    """A uniform frame interval within the relative tolerance ``tol`` of the median (after lost frames are filled)."""
    dt = np.diff(t)
    med = float(np.median(dt))
    dev = float(np.max(np.abs(dt - med)) / med)
    if dev > tol:
        k = int(np.argmax(np.abs(dt - med)))
        raise DatasetError(f"{path}: time is not uniformly sampled (step deviates {dev:.1%} from the median "
                           f"{med:.4g} s on line {line_no[k + 1]}; allowed {tol:.0%}); write every "
                           f"frame at its time, with empty y and theta where it was lost, or leave its row out "
                           f"(docs/formats.md)")


def _check_theta_range(path: Path, th: NDArray, line_no: list[int | None]) -> None:
    """The dimer's bend theta = (alpha - beta)/pi inside (-1, 1), with the conversion from degrees as the hint."""
    fin = np.isfinite(th)
    if fin.any() and np.any(np.abs(th[fin]) >= 1.0):
        k = int(np.flatnonzero(fin & (np.abs(np.where(fin, th, 0.0)) >= 1.0))[0])
        worst = float(np.max(np.abs(th[fin])))
        hint = ("; if it holds alpha - beta in degrees divide by 180 (docs/conventions.md)" if worst <= 180 else "")
        raise DatasetError(f"{path}: theta outside (-1, 1) (max |theta| = {worst:.4g}; first on line {line_no[k]}); "
                           f"theta is the dimensionless (alpha - beta)/pi{hint}")


def _oscillation_frequency(path: Path, t: NDArray, y: NDArray, config: LoadConfig, system: SystemSpec) -> float:
    """The dominant frequency [Hz] of the first coordinate (gaps filled): enough periods in the run, and inside
    a generic system's declared range."""
    duration = t[-1] - t[0]
    f = dominant_frequency(y, duration / (t.size - 1), config.min_periods / duration if duration > 0 else 0.0,
                           prefer_above=SLOW_PEAK_FRACTION, refine=False)
    if f <= 0 or duration * f < config.min_periods:
        raise DatasetError(f"{path}: too short to hold {config.min_periods:g} oscillation periods "
                           f"({duration:.3g} s at a dominant {system.names[0]} frequency of {f:.3g} Hz)")
    lo, hi = system.frequency_range_hz
    if system.generic and not lo <= f <= hi:
        raise DatasetError(f"{path}: dominant {system.names[0]} frequency {f:.3g} Hz is outside meta.json's "
                           f"system.frequency_range_hz [{lo:g}, {hi:g}]: check the units of t or widen the range")
    return f


def _mask_glitches(path: Path, t: NDArray, y_raw: NDArray, th_raw: NDArray, periods: float, config: LoadConfig
                   ) -> tuple[tuple[int, ...], NDArray, NDArray, int] | None:
    """Isolated tracking glitches (:mod:`cubedimer.glitches`) masked and filled like missing frames: the glitch
    frames, y, theta and the most frames filled in one coordinate; None without a glitch."""
    frames_per_period = t.size / periods
    gy = find_glitches(y_raw, frames_per_period, config.glitches)
    gt = find_glitches(th_raw, frames_per_period, config.glitches)
    if not (gy.any() or gt.any()):
        return None
    glitch_frames = tuple(int(i) for i in np.flatnonzero(gy | gt))
    y, ny = fill_gaps(t, np.where(gy, np.nan, y_raw), config.fill_limit, "y", str(path))
    th, nt = fill_gaps(t, np.where(gt, np.nan, th_raw), config.fill_limit, "theta", str(path))
    logger.info("%s: %d tracking glitch frame(s) masked", path.name, len(glitch_frames))
    return glitch_frames, y, th, max(ny, nt)


def load_run(path: str | os.PathLike, config: LoadConfig = LoadConfig(), frame_rate_hz: float | None = None,
             system: SystemSpec = LEVITATED_DIMER) -> Run:
    """Read one CSV run, check it against the data-set format (docs/formats.md), fill short gaps.

    What labs write is read: the file as UTF-8 with or without a byte-order mark, CRLF line endings, ``,``
    ``;`` or tab separators (taken from the header row), a decimal comma when the separator is ``;`` or a
    tab, unit labels after column names (``t [ms]``, ``y (um)``: converted to SI; labels that leave the
    quantity open, such as ``theta [deg]`` or ``y [px]``, are refused with the conversion to use), a
    ``frame`` column of integer frame numbers in place of ``t`` when ``frame_rate_hz`` is given (meta.json),
    and omitted rows of lost frames (a time step that is an integer multiple of the frame interval: the
    frames in between are missing and filled as such).

    A generic ``system`` (:mod:`cubedimer.system`) reads its declared coordinate columns (and velocity columns)
    into ``y`` and ``theta`` (and ``velocities``), converting their unit labels to the declared SI units; the
    levitation checks (|theta| < 1, the refused labels) are skipped and the dominant frequency of the first
    coordinate must lie in the declared range.

    Line numbers in messages are those of the file (comments and blank lines counted), and file
    content quoted in a message is cut to :data:`cubedimer.lab_csv.ECHO_LIMIT` characters.

    Raises
    ------
    DatasetError
        One-line message ``"<file>: <problem>"``.
    """
    path = Path(path)
    t, y, th, vel = _read_columns(path, config, frame_rate_hz, system)
    return _prepared_run(path, path.name, t, y, th, vel, config, system)


def load_run_parts(path: str | os.PathLike, config: LoadConfig = LoadConfig(), frame_rate_hz: float | None = None,
                   system: SystemSpec = LEVITATED_DIMER) -> tuple[list[Run], list[SkippedFile]]:
    """:func:`load_run`, with a run split at every gap longer than ``config.fill_limit`` frames (a lost stretch of a
    tracking) into parts named ``RUN_part1.csv``, ``RUN_part2.csv``, ... (each ``Run.source`` the file, ``Run.frames``
    its frames in it): every part is checked like a run, and a part too short to hold the oscillation periods (or
    otherwise bad) is skipped with its reason, the others kept.

    Raises
    ------
    DatasetError
        A file that cannot be read as a run, or of which no part is usable (one line naming the file).
    """
    path = Path(path)
    t, y, th, vel = _read_columns(path, config, frame_rate_hz, system)
    bad = ~np.isfinite(y) | ~np.isfinite(th)
    parts = gap_segments(bad, config.fill_limit)
    if len(parts) <= 1 and not (len(parts) == 1 and parts[0] != (0, t.size)):
        return [_prepared_run(path, path.name, t, y, th, vel, config, system)], []
    runs, skipped = [], []
    for j, (a, b) in enumerate(parts, 1):
        name = f"{path.stem}_part{j}{path.suffix}"
        try:
            run = _prepared_run(path.parent / name, name, t[a:b], y[a:b], th[a:b], [v[a:b] for v in vel], config,
                                system)
            runs.append(replace(run, source=path.name, frames=(int(a), int(b))))
        except DatasetError as exc:
            skipped.append(SkippedFile(name, str(exc).split(": ", 1)[-1] + f" (frames {a}-{b - 1} of {path.name})"))
    gaps = len(parts) - 1
    if not runs:
        raise DatasetError(f"{path}: split at {gaps} gap(s) longer than {config.fill_limit} frames, and no part is "
                           f"usable: {skipped[0].file}: {skipped[0].reason}")
    logger.warning("%s: split at %d gap(s) longer than %d missing frames into %s%s", path.name, gaps,
                   config.fill_limit, ", ".join(f"{r.name} (frames {r.frames[0]}-{r.frames[1] - 1})" for r in runs),
                   f"; {len(skipped)} part(s) too short or bad, skipped" if skipped else "")
    return runs, skipped


def _read_columns(path: Path, config: LoadConfig, frame_rate_hz: float | None, system: SystemSpec
                  ) -> tuple[NDArray, NDArray, NDArray, list[NDArray]]:
    """The file's t, coordinates and velocity columns (SI), lost frames inserted, uniform, a field drop cut."""
    lines = _data_lines(path)
    header_line, header_text = lines[0]
    sep = separator(header_text)
    header, units = parse_header(path, header_line, header_text, sep)
    time_col, idx, factors = _columns(path, header_line, header_text, header, units, frame_rate_hz, system)
    rows, line_no = read_rows(path, lines[1:], header, idx, sep, sep != ",")
    if len(rows) < 16:
        raise DatasetError(f"{path}: only {len(rows)} data rows; too short to hold {config.min_periods:g} oscillation periods")
    a = np.asarray(rows, dtype=float) * np.asarray(factors)
    t, y, th, vel = a[:, 0], a[:, 1], a[:, 2], list(a[:, 3:].T)
    t = _frame_times(path, t, time_col, frame_rate_hz, line_no)
    t, (y, th, *vel), line_no, n_lost = fill_lost_frames(t, [y, th, *vel], line_no, config.uniform_tol)
    if n_lost:
        logger.info("%s: %d omitted frame(s) taken as missing", path.name, n_lost)
    _check_uniform(path, t, line_no, config.uniform_tol)
    if not system.generic:
        _check_theta_range(path, th, line_no)
        first = field_on_start(path, t, y)
        t, y, th, vel, line_no = t[first:], y[first:], th[first:], [v[first:] for v in vel], line_no[first:]
    return t, y, th, vel


def _prepared_run(path: Path, name: str, t: NDArray, y: NDArray, th: NDArray, vel: list[NDArray], config: LoadConfig,
                  system: SystemSpec) -> Run:
    """A run from its columns: the missing frames checked and filled, enough periods, velocities, glitches."""
    nmiss = int((~np.isfinite(y) | ~np.isfinite(th)).sum())
    if nmiss > config.max_missing_fraction * t.size:
        raise DatasetError(f"{path}: {nmiss} of {t.size} frames missing (more than {config.max_missing_fraction:.0%})")
    y_raw, th_raw = y, th
    y, ny = fill_gaps(t, y, config.fill_limit, "y", str(path))
    th, nt = fill_gaps(t, th, config.fill_limit, "theta", str(path))
    periods = (t[-1] - t[0]) * _oscillation_frequency(path, t, y, config, system)
    velocities = _velocities(path, t, (y, th), vel, system, config.fill_limit, periods) if vel else None
    glitches = _mask_glitches(path, t, y_raw, th_raw, periods, config) if config.glitches is not None else None
    glitch_frames: tuple[int, ...] = ()
    n_filled = max(ny, nt)
    if glitches is not None:
        glitch_frames, y, th, n_filled = glitches
    return Run(name=name, t=t, y=y, theta=th, n_filled=n_filled, glitch_frames=glitch_frames,
               velocities=velocities)


def _velocities(path: Path, t: NDArray, x: tuple[NDArray, NDArray], vel: list[NDArray], system: SystemSpec,
                max_gap: int, periods: float) -> NDArray:
    """The declared velocity columns as (n, 2) (NaN for a coordinate without one), gaps filled, each checked
    against its positions (:func:`cubedimer.system.check_velocity`)."""
    out = np.full((t.size, 2), np.nan)
    columns = iter(vel)
    for k, c in enumerate(system.coordinates):
        if c.velocity:
            v, _ = fill_gaps(t, next(columns), max_gap, c.velocity, str(path))
            check_velocity(path, c.velocity, t, x[k], v, periods)
            out[:, k] = v
    return out


def _with_recorded_max_gap(config: LoadConfig, meta: dict) -> LoadConfig:
    """The fill limit a tracked data set records (meta.json ``tracking.max_gap_frames``, ``tracking track --max-gap``)
    where the caller left ``max_gap`` None (a limit the caller chose, ``--max-gap``, stays)."""
    block = meta.get("tracking")
    if isinstance(block, dict) and "max_gap_frames" in block and config.max_gap is None:
        return replace(config, max_gap=int(block["max_gap_frames"]))
    return config


def _with_run_noise(runs: list[Run], meta: dict) -> list[Run]:
    """Each run with its recorded noise (:func:`cubedimer.noise.recorded_run_noise`, by its file: ``Run.source`` for
    a part)."""
    recorded = recorded_run_noise(meta)
    if not recorded:
        return runs
    return [replace(r, noise=recorded.get(r.source or r.name)) for r in runs]


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
    meta = read_meta(p)
    config = _with_recorded_max_gap(config, meta)
    system = read_system(meta, str(p / "meta.json"))
    if system.kind not in config.systems:
        raise DatasetError(f"{p / 'meta.json'}: declares a {system.kind.replace('_', ' ')} system "
                           f"({', '.join(system.names)}); this command reads {' or '.join(config.systems)} data sets "
                           f"only (python -m fitting fit fits any two coordinates)")
    report = report or _log_skip
    runs, skipped = [], []
    # the skipped files are reported once the set is known to hold good runs: a set refused as a whole is
    # one line (its error), not one line per file before it
    pending: list[str] = []

    def skip(file: str, reason: str) -> None:
        if strict:
            raise DatasetError(f"{p / file}: {reason}")
        skipped.append(SkippedFile(file, reason))
        pending.append(f"{p / file}: {reason}")

    codes: dict[str, str] = {}
    for f in files:
        try:
            parts, short = load_run_parts(f, config, frame_rate_hz=meta.get("frame_rate_hz"), system=system)
            runs.extend(parts)
            skipped.extend(short)
            pending.extend(f"{p / x.file}: {x.reason}" for x in short)
        except DatasetError as exc:
            if strict:
                raise
            prefix = f"{f}: "
            msg = str(exc)
            skipped.append(SkippedFile(f.name, msg[len(prefix):] if msg.startswith(prefix) else msg))
            pending.append(msg)
    if config.consistency is not None and runs:
        features = [run_features(r.name, r.t, r.y) for r in runs]
        # the physics bounds hold with or without meta.json (defaults stand in); the estimate of the trap
        # frequency at the nominal pressure only when the data set states its constants
        found = check_consistency(features, meta, config.consistency,
                                  trap_frequency=config.trap_frequency if meta else None,
                                  levitated=not system.generic)
        bad = {x.file: x.reason for x in found}
        codes = {x.file: x.code for x in found}
        for r in runs:
            if r.name in bad:
                skip(r.name, bad[r.name])
        runs = [r for r in runs if r.name not in bad]
    if not runs:
        skipped.sort(key=lambda s: s.file)
        first = skipped[0]
        same = len(skipped) > 1 and (all(s.reason == first.reason for s in skipped) or (
            first.file in codes and all(codes.get(s.file) == codes[first.file] for s in skipped)))
        whole = ((f"every file fails the same check, e.g. {first.file}: {first.reason}") if same else
                 f"{len(skipped)} bad file{'s' if len(skipped) > 1 else ''}, e.g. {first.file}: {first.reason}")
        raise DatasetError(f"{p}: no usable runs: {whole}")
    for message in pending:
        report(message)
    skipped.sort(key=lambda s: s.file)
    runs = _with_run_noise(runs, meta)
    return Dataset(path=str(p), runs=tuple(runs), meta=meta, skipped=tuple(skipped), system=system)
