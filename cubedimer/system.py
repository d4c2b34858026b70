"""The dynamical system a data set records: a levitated dimer (the default) or a generic two-coordinate system.

A data set's ``meta.json`` may declare a generic system (docs/formats.md, "Generic two-coordinate systems")::

    "system": {"kind": "generic",
               "coordinates": [{"name": "phi1", "unit": "rad", "velocity": "omega1"},
                               {"name": "phi2", "unit": "rad"}],
               "frequency_range_hz": [0.2, 20]}

The CSV files then hold ``t`` and one column per declared coordinate (named as declared, with an optional unit
label that is converted to the declared SI unit), and optionally a measured velocity per coordinate.  The first
coordinate takes the place of y and the second that of theta in every computation (the library, the windows,
the minimum number of periods); names in the outputs are the declared ones (:meth:`SystemSpec.term`).  The
levitation checks (5-200 Hz, y within a quarter wavelength, |theta| < 1, the refused labels) apply only to a
levitated dimer, which is what a data set without a ``system`` is.
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .errors import DatasetError
from .terms import EQUATION_NAMES, STATE_NAMES, parse_term, term_name

__all__ = ["Coordinate", "SystemSpec", "LEVITATED_DIMER", "SYSTEM_KINDS", "read_system", "require_levitated_dimer",
           "coordinate_unit_factor", "check_velocity"]

#: The kinds of system a meta.json may declare.
SYSTEM_KINDS = ("levitated_dimer", "generic")

#: Declared SI units of a generic coordinate and the labels a CSV header may carry for each (factor to SI).
COORDINATE_UNITS: dict[str, dict[str, float]] = {
    "m": {"m": 1.0, "cm": 1e-2, "mm": 1e-3, "um": 1e-6, "\u00b5m": 1e-6, "nm": 1e-9},
    "rad": {"rad": 1.0, "mrad": 1e-3, "deg": math.pi / 180, "degree": math.pi / 180, "degrees": math.pi / 180,
            "\u00b0": math.pi / 180},
    "-": {"-": 1.0, "1": 1.0, "": 1.0},
}

_NAME = re.compile(r"^[A-Za-z][A-Za-z0-9_]*$")


@dataclass(frozen=True)
class Coordinate:
    """One coordinate: its ``name`` (the CSV column and the term names), SI ``unit`` and optional measured
    ``velocity`` column."""

    name: str
    unit: str
    velocity: str | None = None


@dataclass(frozen=True)
class SystemSpec:
    """What a data set records (module docstring)."""

    kind: str
    coordinates: tuple[Coordinate, Coordinate]
    frequency_range_hz: tuple[float, float]

    @property
    def generic(self) -> bool:
        return self.kind == "generic"

    @property
    def names(self) -> tuple[str, str]:
        return (self.coordinates[0].name, self.coordinates[1].name)

    @property
    def state_names(self) -> tuple[str, str, str, str]:
        """The state's names in the order [first, its rate, second, its rate] (``y, ydot, theta, thetadot``)."""
        a, b = self.names
        return (a, f"{a}dot", b, f"{b}dot")

    @property
    def equation_names(self) -> tuple[str, str]:
        a, b = self.names
        return (f"{a}ddot", f"{b}ddot")

    def describe(self, values: tuple[float, float]) -> str:
        """``values`` of the two coordinates as a log line writes them, named and in their declared SI units:
        ``"y 0.000415 m, theta 0.308"`` for the levitated dimer, ``"phi1 0.415 rad, phi2 0.308 rad"``."""
        return ", ".join(f"{c.name} {v:.3g}" + ("" if c.unit == "-" else f" {c.unit}")
                         for c, v in zip(self.coordinates, values))

    def term(self, name: str) -> str:
        """A library term name (``y^2*theta``) in the declared coordinates (``phi1^2*phi2``)."""
        return term_name(parse_term(name), self.state_names)

    def rename(self, obj: Any) -> Any:
        """``obj`` (JSON-like) with every dict key and string that is a state, equation or library term name, or
        an ``equation:term`` pair, written in the declared coordinates (identity for the levitated dimer)."""
        if not self.generic:
            return obj
        if isinstance(obj, dict):
            return {self._name(k) if isinstance(k, str) else k: self.rename(v) for k, v in obj.items()}
        if isinstance(obj, (list, tuple)):
            return [self.rename(v) for v in obj]
        return self._name(obj) if isinstance(obj, str) else obj

    def _name(self, s: str) -> str:
        if s in EQUATION_NAMES:
            return self.equation_names[EQUATION_NAMES.index(s)]
        eq, sep, rest = s.partition(":")
        if sep and eq in EQUATION_NAMES:
            return f"{self._name(eq)}:{self._name(rest)}"
        if s in STATE_NAMES or (s and set(s) <= set("ydothea*^0123456789") and s[0] in "yt"):
            try:
                return self.term(s)
            except ValueError:
                return s
        return s

    def internal(self, pair: str) -> str:
        """``equation:term`` in the declared names (``phi2ddot:phi1^2*phi2``) in the library's names (identity for
        the levitated dimer); ValueError on an unknown equation or factor."""
        if not self.generic:
            return pair
        eq, sep, term = pair.rpartition(":")
        if not sep:
            return term_name(parse_term(term, self.state_names))
        if eq not in self.equation_names:
            raise ValueError(f"unknown equation {eq!r} in {pair!r}; the declared system's are "
                             f"{', '.join(self.equation_names)}")
        return f"{EQUATION_NAMES[self.equation_names.index(eq)]}:{term_name(parse_term(term, self.state_names))}"

    def internal_equations(self, equations: dict) -> dict:
        """Equations written in the declared names (``{"phi1ddot": {"phi1^2*phi2": c}}``) in the library's names."""
        out = {}
        for eq, terms in equations.items():
            if eq not in self.equation_names:
                raise ValueError(f"unknown equation {eq!r}; the declared system's are {self.equation_names}")
            out[EQUATION_NAMES[self.equation_names.index(eq)]] = {
                term_name(parse_term(t, self.state_names)): v for t, v in terms.items()}
        return out

    def to_json(self) -> dict:
        return {"kind": self.kind, "coordinates": [
            {"name": c.name, "unit": c.unit, **({"velocity": c.velocity} if c.velocity else {})}
            for c in self.coordinates], "frequency_range_hz": list(self.frequency_range_hz)}


#: The default: a levitated cube dimer (docs/conventions.md), y [m] and theta [-], vertical trap at 5-200 Hz.
LEVITATED_DIMER = SystemSpec("levitated_dimer", (Coordinate("y", "m"), Coordinate("theta", "-")), (5.0, 200.0))


def read_system(meta: dict, source: str = "meta.json") -> SystemSpec:
    """The system ``meta["system"]`` declares (:data:`LEVITATED_DIMER` without one).

    Raises
    ------
    DatasetError
        One line naming ``source``, the key and the fix: a missing or inconsistent coordinate list, a unit that
        cannot be read, an implausible frequency range.
    """
    spec = meta.get("system") if isinstance(meta, dict) else None
    if spec is None:
        return LEVITATED_DIMER
    example = ('{"kind": "generic", "coordinates": [{"name": "x1", "unit": "m"}, {"name": "x2", "unit": "rad"}], '
               '"frequency_range_hz": [0.5, 50]}')
    if not isinstance(spec, dict):
        raise DatasetError(f"{source}: system must be an object such as {example}")
    kind = spec.get("kind", "generic")
    if kind not in SYSTEM_KINDS:
        raise DatasetError(f"{source}: system.kind {kind!r} is not one of {', '.join(SYSTEM_KINDS)}")
    if kind == "levitated_dimer":
        if set(spec) - {"kind"}:
            raise DatasetError(f"{source}: a levitated_dimer system takes no other keys (its coordinates are y [m] "
                               f"and theta [-]); remove {', '.join(sorted(set(spec) - {'kind'}))}")
        return LEVITATED_DIMER
    unknown = set(spec) - {"kind", "coordinates", "frequency_range_hz"}
    if unknown:
        raise DatasetError(f"{source}: unknown system key(s) {', '.join(sorted(unknown))}; a generic system is {example}")
    coords = spec.get("coordinates")
    if not isinstance(coords, list) or len(coords) != 2:
        raise DatasetError(f"{source}: system.coordinates must list exactly two coordinates, e.g. {example}")
    out = tuple(_coordinate(c, k, source) for k, c in enumerate(coords))
    names = [c.name for c in out] + [c.velocity for c in out if c.velocity]
    state = [n for c in out for n in (c.name, f"{c.name}dot", f"{c.name}ddot")]
    if len(set(names)) != len(names) or len(set(state)) != len(state) or "t" in names or "frame" in names:
        raise DatasetError(f"{source}: system.coordinates: names {', '.join(names)} must be distinct, not t or frame, "
                           f"and no name may be another's with 'dot' appended; rename them")
    rng = spec.get("frequency_range_hz")
    if not (isinstance(rng, list) and len(rng) == 2 and all(isinstance(v, (int, float)) and not isinstance(v, bool)
                                                         for v in rng) and 0 < rng[0] < rng[1] < math.inf):
        raise DatasetError(f"{source}: system.frequency_range_hz must be [low, high] in Hz with 0 < low < high "
                           f"(the dominant frequencies the runs may have), got {rng!r}")
    return SystemSpec("generic", (out[0], out[1]), (float(rng[0]), float(rng[1])))


def _coordinate(c: Any, k: int, source: str) -> Coordinate:
    where = f"{source}: system.coordinates[{k}]"
    if not isinstance(c, dict) or set(c) - {"name", "unit", "velocity"}:
        raise DatasetError(f"{where} must be an object with name, unit and optionally velocity (a column name), "
                           f"got {c!r}")
    name, unit, velocity = c.get("name"), c.get("unit"), c.get("velocity")
    for key, v in (("name", name), ("velocity", velocity)):
        if (v is not None or key == "name") and not (isinstance(v, str) and _NAME.match(v)):
            raise DatasetError(f"{where}.{key} must be a column name (a letter, then letters, digits or _), got {v!r}")
    if unit not in COORDINATE_UNITS:
        raise DatasetError(f"{where}.unit {unit!r} cannot be read: give the SI unit, one of "
                           f"{', '.join(COORDINATE_UNITS)} (CSV headers may then carry labels such as mm or deg)")
    return Coordinate(name, unit, velocity)


def require_levitated_dimer(meta: dict, command: str, source: str = "meta.json") -> None:
    """Raise :class:`DatasetError` (one line) when ``meta`` declares a generic system: ``command`` is for levitated
    dimers only."""
    if read_system(meta, source).generic:
        raise DatasetError(f"{source}: declares a generic two-coordinate system; {command} is for levitated dimers "
                           f"only (python -m fitting fit fits any two coordinates)")


def coordinate_unit_factor(path: Any, column: str, declared: str, label: str | None, velocity: bool = False) -> float:
    """The factor taking a column with the header label ``label`` to the declared SI unit (per second for a
    velocity column, whose label is ``<unit>/s``).

    Raises
    ------
    DatasetError
        A label that is not a unit of the declared kind, naming the file, the column and the labels read.
    """
    if label is None:
        return 1.0
    base = label
    if velocity:
        if not label.endswith("/s"):
            raise DatasetError(f"{path}: column '{column} [{label}]' is a velocity: label it '{column} "
                               f"[{declared if declared != '-' else '1'}/s]' or another length or angle per second")
        base = label[:-2]
    table = COORDINATE_UNITS[declared]
    if base not in table:
        known = ", ".join(u + ("/s" if velocity else "") for u in table if u)
        raise DatasetError(f"{path}: column '{column} [{label}]': unit label not read for a coordinate declared in "
                           f"{declared}; use one of {known} or convert the column (docs/formats.md)")
    return table[base]


def check_velocity(path: Any, column: str, t: NDArray, x: NDArray, v: NDArray, periods: float) -> None:
    """Refuse a measured velocity ``v`` whose integral disagrees with the positions ``x`` beyond the noise.

    Over windows of one dominant period (``periods`` of them in the run), ``x[end] - x[start]`` is compared with
    the trapezoid integral of ``v``; the noise of that difference is sqrt(2 sx^2 + n dt^2 sv^2) with sx and sv the
    white noise of x and v (:func:`cubedimer.noise.white_noise_std`).  The RMS difference may be at most 5 times
    that plus 5 % of the RMS of x about its mean (the trapezoid rule's error and slow drifts); a velocity in other
    units, of another coordinate or of the wrong sign misses by the size of the motion itself.
    """
    from .noise import white_noise_std

    n = max(4, int(t.size / max(periods, 1.0)))
    dt = float((t[-1] - t[0]) / (t.size - 1))
    starts = np.arange(0, t.size - n, n)
    if starts.size == 0:
        return
    cum = np.concatenate([[0.0], np.cumsum(0.5 * (v[1:] + v[:-1]) * dt)])
    diff = (x[starts + n] - x[starts]) - (cum[starts + n] - cum[starts])
    sx, sv = white_noise_std([x]), white_noise_std([v])
    allowed = 5.0 * math.sqrt(2 * sx**2 + n * (dt * sv) ** 2) + 0.05 * float(np.std(x))
    rms = float(np.sqrt(np.mean(diff**2)))
    if rms > allowed:
        raise DatasetError(f"{path}: column '{column}': its integral over one period disagrees with the positions by "
                           f"{rms:.3g} RMS (allowed {allowed:.3g} from the noise); check its units, sign and "
                           f"coordinate, or leave it out of meta.json's system to differentiate the positions")
