"""The experiment's constants: one validated reader of a data set's ``meta.json`` (docs/formats.md).

Every key is optional; missing physical constants take the defaults of docs/conventions.md.  A key that
is present must be a real number (not a boolean, not a string), finite, and inside a physically
plausible range; otherwise :class:`~cubedimer.dataset.DatasetError` is raised with a one-line message
naming the file, the key and what to do.  Keys this suite does not know are passed through, with a
warning on the ``cubedimer.meta`` logger that names them and the known keys (a misspelt key would
otherwise be ignored without a word).
"""
from __future__ import annotations

import json
import math
import os
from pathlib import Path
from typing import Any

import logging

from .errors import DatasetError

__all__ = ["META_KEYS", "META_DEFAULTS", "META_RANGES", "META_RECORDING_KEYS", "META_TEXT_KEYS", "META_BLOCK_KEYS",
           "TRACKING_RANGES", "read_meta", "validate_meta", "check_meta_value", "check_tracking_block",
           "unknown_keys_message"]

logger = logging.getLogger(__name__)

#: Defaults (docs/conventions.md section 1) of the keys of docs/formats.md, SI units.
META_DEFAULTS: dict[str, float] = {
    "side_length_m": 500e-6,
    "particle_density_kg_m3": 2160.0,
    "bulk_modulus_pa": 24.9e9,
    "frequency_hz": 45_650.0,
    "sound_speed_m_s": 343.0,
    "air_density_kg_m3": 1.204,
    "pressure_amplitude_pa": 3000.0,
}

META_KEYS: tuple[str, ...] = tuple(META_DEFAULTS)

#: Keys that describe the recording rather than the physics (no default): ``frame_rate_hz`` turns a
#: ``frame`` column into times.
META_RECORDING_KEYS: tuple[str, ...] = ("frame_rate_hz",)

#: Free-text keys a data set may carry for people (any JSON value; not read).
META_TEXT_KEYS: tuple[str, ...] = ("source", "comment", "notes", "description")

#: Blocks a data set's meta.json may hold, written by the suite's own tools: ``tracking`` (the tracking's summary,
#: written by ``python -m tracking``; docs/formats.md).  Each must be a JSON object; its numbers are checked by
#: :func:`check_tracking_block`.
META_BLOCK_KEYS: tuple[str, ...] = ("tracking",)

#: The tracking block's numbers: each, when present, a finite number within its range.
TRACKING_RANGES: dict[str, tuple[float, float]] = {
    "noise_y_m": (0.0, 1e-2),
    "noise_theta": (0.0, 1.0),
    "fraction_measured": (0.0, 1.0),
    "pixel_size_m": (0.0, 1e-2),
    "side_length_m_measured": (0.0, 1e-2),
    "max_gap_frames": (0.0, 1e6),
}

#: Open ranges a value must lie in (a generous envelope around acoustic levitation in air or water).
META_RANGES: dict[str, tuple[float, float]] = {
    "side_length_m": (1e-7, 1e-2),
    "particle_density_kg_m3": (1.0, 1e5),
    "bulk_modulus_pa": (1e3, 1e13),
    "frequency_hz": (100.0, 1e8),
    "sound_speed_m_s": (10.0, 1e5),
    "air_density_kg_m3": (1e-3, 1e5),
    "pressure_amplitude_pa": (1e-3, 1e7),
    "frame_rate_hz": (1e-3, 1e9),
}


def check_meta_value(key: str, value: Any, source: str = "meta.json") -> float:
    """``value`` of the meta key ``key`` as a float, checked against :data:`META_RANGES`.

    Used for meta.json and for command-line options that set the same quantity.

    Raises
    ------
    DatasetError
        ``"<source>: <key> must be ..."`` on a wrong type (booleans and strings included), a
        non-finite or an implausible value.
    """
    lo, hi = META_RANGES[key]
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise DatasetError(f"{source}: {key} must be a number in SI units, got {value!r}")
    v = float(value)
    if not math.isfinite(v) or not lo < v < hi:
        raise DatasetError(f"{source}: {key} = {v!r} is outside the plausible range ({lo:g}, {hi:g}); "
                           f"check the value and its units (SI)")
    return v


def check_tracking_block(block: Any, source: str = "meta.json") -> dict:
    """meta.json's ``tracking`` block, checked: a JSON object whose numbers of :data:`TRACKING_RANGES` (the pooled
    tracking noise, the fraction of frames measured, the pixel size and the measured side) are finite and in range
    where present; other keys (per-run summaries, skipped recordings, the method) pass unread.

    Raises
    ------
    DatasetError
        ``"<source>: tracking.<key> ..."`` naming the key and what to do.
    """
    if not isinstance(block, dict):
        raise DatasetError(f"{source}: 'tracking' must be a JSON object (the block python -m tracking writes), got "
                           f"{type(block).__name__}; remove it or track the recordings again")
    for key, (lo, hi) in TRACKING_RANGES.items():
        if key not in block:
            continue
        v = block[key]
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or not lo <= v <= hi:
            raise DatasetError(f"{source}: tracking.{key} = {v!r} must be a number in [{lo:g}, {hi:g}] (SI units); "
                               f"correct it or track the recordings again")
    return dict(block)


def validate_meta(meta: Any, source: str = "meta.json") -> dict:
    """Check the known keys of ``meta`` (a parsed meta.json); return a copy with them as floats.

    Raises
    ------
    DatasetError
        ``"<source>: <key> must be ..."`` on a wrong type, a non-finite or an implausible value.
    """
    if not isinstance(meta, dict):
        raise DatasetError(f"{source}: meta.json must hold a JSON object, got {type(meta).__name__}")
    out = dict(meta)
    for key in META_RANGES:
        if key in meta:
            out[key] = check_meta_value(key, meta[key], source)
    if "tracking" in meta:
        out["tracking"] = check_tracking_block(meta["tracking"], source)
    if "system" in meta:
        from .system import read_system
        read_system(meta, source)  # the declared system (cubedimer.system), refused here in one line when bad
    unknown = [k for k in meta if k not in META_RANGES and k not in META_TEXT_KEYS and k not in META_BLOCK_KEYS
               and k != "system"]
    if unknown:
        logger.warning("%s: %s", source, unknown_keys_message(unknown))
    return out


def unknown_keys_message(unknown: list[str]) -> str:
    """The warning for meta.json keys this suite does not read: each with the known key it most likely misspells
    (``difflib``, e.g. ``side_lenght_m`` -> ``side_length_m``), and what is used instead."""
    import difflib

    known = [*META_RANGES, *META_TEXT_KEYS, *META_BLOCK_KEYS, "system"]
    parts = []
    for k in unknown:
        close = difflib.get_close_matches(str(k), known, n=1, cutoff=0.75)
        parts.append(f"{k!r} (did you mean {close[0]!r}?)" if close else repr(k))
    guessed = any("did you mean" in p for p in parts)
    return (f"unknown key(s) {', '.join(parts)} ignored" + ("; the default is used for a misspelt constant: correct "
            "the key" if guessed else "") + f"; the known keys are {', '.join(META_RANGES)} (docs/formats.md)")


def read_meta(data_dir: str | os.PathLike) -> dict:
    """The validated meta.json of the data set in ``data_dir`` ({} if there is none).

    Raises
    ------
    DatasetError
        Unreadable or invalid meta.json (the message names the file).
    """
    path = Path(data_dir) / "meta.json"
    if not path.exists():
        return {}
    try:
        meta = json.loads(path.read_text(encoding="utf-8-sig"))
    except (OSError, UnicodeDecodeError, ValueError) as exc:
        raise DatasetError(f"{path}: unreadable meta.json ({exc})") from None
    return validate_meta(meta, str(path))


#: The white tracking noise (standard deviations) that a simulated data set carries unless told otherwise: y [m]
#: and theta [-], sub-pixel tracking of a 500-um dimer by a high-speed camera (the synthetic data sets of the fit and
#: the twin-like data sets of the diagnosis read it here).
DEFAULT_TRACKING_NOISE: dict[str, float] = {"noise_y_m": 1e-6, "noise_theta": 0.005}

__all__ += ["DEFAULT_TRACKING_NOISE"]

#: The defaults that code outside meta.json reads (the drive's frequency [Hz], the cubes' density [kg/m^3] and the
#: pressure amplitude of the standing wave [Pa]; the cube side [m], the cubes' bulk modulus [Pa], the speed of sound
#: [m/s] and the air's density [kg/m^3]): the library reads every one of them here, never a number of its own.
DEFAULT_FREQUENCY_HZ: float = META_DEFAULTS["frequency_hz"]
DEFAULT_PARTICLE_DENSITY: float = META_DEFAULTS["particle_density_kg_m3"]
DEFAULT_PRESSURE_AMPLITUDE_PA: float = META_DEFAULTS["pressure_amplitude_pa"]
DEFAULT_SIDE_LENGTH_M: float = META_DEFAULTS["side_length_m"]
DEFAULT_BULK_MODULUS_PA: float = META_DEFAULTS["bulk_modulus_pa"]
DEFAULT_SOUND_SPEED_M_S: float = META_DEFAULTS["sound_speed_m_s"]
DEFAULT_AIR_DENSITY_KG_M3: float = META_DEFAULTS["air_density_kg_m3"]
__all__ += ["DEFAULT_FREQUENCY_HZ", "DEFAULT_PARTICLE_DENSITY", "DEFAULT_PRESSURE_AMPLITUDE_PA", "DEFAULT_SIDE_LENGTH_M",
            "DEFAULT_BULK_MODULUS_PA", "DEFAULT_SOUND_SPEED_M_S", "DEFAULT_AIR_DENSITY_KG_M3"]
