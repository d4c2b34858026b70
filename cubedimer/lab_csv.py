"""The CSV dialect of a run file as labs write it (docs/formats.md): the separator, the header's column names and
unit labels (converted to SI, or refused with the conversion to use), the data rows with a decimal comma, and the
quoting of file content in one-line error messages.  Used by :func:`cubedimer.dataset.load_run`.
"""
from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from .errors import DatasetError

__all__ = ["ECHO_LIMIT", "REQUIRED_COLUMNS", "UNIT_FACTORS", "REFUSED_UNITS", "COLUMN_HINTS", "cut_text", "echo",
           "separator", "parse_header", "unit_factor", "missing_columns_message", "read_rows"]


#: Longest piece of a file's content echoed into an error message [characters].
ECHO_LIMIT = 80

def cut_text(text: str, limit: int = ECHO_LIMIT) -> str:
    """``text`` cut to at most ``limit`` characters, an ellipsis marking the cut."""
    return text if len(text) <= limit else text[: limit - 1] + "\u2026"


def echo(text: str) -> str:
    """File content quoted in an error message: cut (see :func:`cut_text`) and repr-quoted."""
    return repr(cut_text(text))


#: Column names a run must have (any order; ``frame`` may stand in for ``t``, see :func:`cubedimer.dataset.load_run`).
REQUIRED_COLUMNS = ("t", "y", "theta")

#: Unit labels read after a column name (``t [ms]``, ``y (um)``) and their factors to SI units.
UNIT_FACTORS: dict[str, dict[str, float]] = {
    "t": {"s": 1.0, "sec": 1.0, "ms": 1e-3, "us": 1e-6, "\u00b5s": 1e-6, "\u03bcs": 1e-6},
    "y": {"m": 1.0, "cm": 1e-2, "mm": 1e-3, "um": 1e-6, "\u00b5m": 1e-6, "\u03bcm": 1e-6, "micron": 1e-6,
          "microns": 1e-6, "nm": 1e-9},
    "theta": {"-": 1.0, "1": 1.0, "": 1.0, "dimensionless": 1.0},
    "frame": {"-": 1.0, "1": 1.0, "": 1.0, "frame": 1.0, "frames": 1.0, "#": 1.0},
}

#: Labels refused for a column, with the conversion to use (the label alone does not say what was measured).
REFUSED_UNITS: dict[str, tuple[tuple[str, ...], str]] = {
    "theta": (("deg", "degree", "degrees", "\u00b0", "rad", "radian", "radians"),
              "theta is the dimensionless (alpha - beta)/pi: if the column holds alpha - beta in degrees divide "
              "it by 180 (in radians: by pi), if it holds each cube's turn phi in degrees divide it by 45, and "
              "label it 'theta [-]'"),
    "y": (("px", "pixel", "pixels"),
          "multiply y by the pixel size in metres (object plane) and label it 'y [m]'"),
    "t": (("frame", "frames", "fps"),
          "name the column 'frame' and give frame_rate_hz in meta.json, or divide by the frame rate"),
}

#: Column names labs use for the required quantities, with the name to use (a hint in the message only).
COLUMN_HINTS = {"time": "t", "times": "t", "time_s": "t", "angle": "theta", "bend": "theta", "bending": "theta",
                "alpha": "theta", "phi": "theta", "z": "y", "height": "y", "position": "y", "frames": "frame",
                "frame_number": "frame"}

_HEADER_CELL = re.compile(r"^\s*([^\[\(]*?)\s*(?:[\[\(]\s*(.*?)\s*[\]\)])?\s*$")


def separator(header: str) -> str:
    """The field separator of a file, from its header: tab, ``;`` or ``,`` (docs/formats.md)."""
    if "\t" in header:
        return "\t"
    if ";" in header:
        return ";"
    return ","


def parse_header(path: Path, header_line: int, header_text: str, sep: str) -> tuple[list[str], list[str | None]]:
    """Column names (lower case, quotes stripped) and unit labels (None without a label) of a header row."""
    names, units = [], []
    for cell in header_text.split(sep):
        cell = cell.strip().strip('"').strip("'").strip()
        m = _HEADER_CELL.match(cell)
        name, unit = (m.group(1), m.group(2)) if m else (cell, None)
        names.append(name.strip().lower())
        units.append(None if unit is None else unit.strip().lower())
    return names, units


def unit_factor(path: Path, column: str, unit: str | None) -> float:
    """The factor that takes a column with the unit label ``unit`` to SI (1 without a label).

    Raises DatasetError for a label refused with its conversion or one this loader does not know."""
    if unit is None:
        return 1.0
    refused, what_to_do = REFUSED_UNITS.get(column, ((), ""))
    if unit in refused:
        raise DatasetError(f"{path}: column '{column} [{unit}]': {what_to_do} (docs/conventions.md)")
    table = UNIT_FACTORS[column]
    if unit not in table:
        known = ", ".join(k for k in table if k and not k.isdigit() and k not in ("-", "#"))
        raise DatasetError(f"{path}: unknown unit label '{column} [{unit}]'; labels read for {column}: "
                           f"{known or '-'} (docs/formats.md)")
    return table[unit]


def missing_columns_message(path: Path, header_line: int, header_text: str, missing: list[str],
                             names: list[str], frame_rate_hz: float | None) -> str:
    """The one-line message of a dimer run without its required columns, with the renames labs need."""
    hints = [f"'{n}' -> '{COLUMN_HINTS[n]}'" for n in names if n in COLUMN_HINTS and COLUMN_HINTS[n] in missing]
    frame_note = ("; 'frame' (integer frame numbers) replaces t when meta.json gives frame_rate_hz"
                  if "t" in missing else "")
    if "t" in missing and "frame" in names and frame_rate_hz is None:
        return (f"{path}: column 'frame' needs frame_rate_hz in meta.json (frames per second) to give the times; "
                f"or write a column t in seconds (docs/formats.md)")
    return (f"{path}: missing column{'s' if len(missing) > 1 else ''} {', '.join(repr(c) for c in missing)} "
            f"(header on line {header_line}: {echo(header_text)}); accepted names: t [s], y [m], theta [-], with "
            f"an optional unit label such as 't [ms]'{frame_note}"
            + (f"; rename {', '.join(hints)} if they hold those quantities" if hints else "")
            + " (docs/formats.md)")


def read_rows(path: Path, lines: list[tuple[int, str]], header: list[str], idx: list[int], sep: str,
               decimal_comma: bool) -> tuple[list[list[float]], list[int | None]]:
    """The values of the columns ``idx`` of every data line (NaN where empty) and the lines' numbers."""
    rows, line_no = [], []
    for k, ln in lines:
        parts = ln.split(sep)
        if len(parts) < len(header):
            raise DatasetError(f"{path}: line {k} has {len(parts)} fields, header has {len(header)}"
                               + ("; with a decimal comma the separator must be ';' or a tab" if sep == "," and
                                  len(parts) > len(header) else ""))
        vals = []
        for i in idx:
            s = parts[i].strip().strip('"')
            if decimal_comma:
                s = s.replace(",", ".")
            try:
                vals.append(float(s) if s else np.nan)
            except ValueError:
                raise DatasetError(f"{path}: non-numeric value {echo(s)} in column {header[i]!r} on line {k}") from None
        rows.append(vals)
        line_no.append(k)
    return rows, line_no
