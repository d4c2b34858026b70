"""Cross-run consistency of a data set: one file in the wrong units must not corrupt the whole result.

Every run of a data set records the same dimer in the same trap, so a few numbers must agree across
runs within wide margins: the y amplitude, the dominant y frequency, the time span and the tracking
noise.  :func:`check_consistency` compares each run with the median of the *other* runs (so that one
bad file among four is as visible as one among twelve) and, with or without ``meta.json`` (its defaults
stand in for missing keys), with what the physics of levitation allows any levitated dimer
(docs/conventions.md).  Each finding names the file, the likely cause and the numbers, e.g.
``y looks like micrometres: amplitude 180 against 2.1e-04 m in the other runs``.

Rules (margins chosen so that legitimate run-to-run variation after a field drop stays far inside):

* a constant y, or a y whose amplitude is within 5 tracking-noise levels (pure noise: no oscillation);
* y amplitude beyond 30 times (or below 1/30 of) the others' median: micrometres (ratio ~1e6),
  millimetres (~1e3), otherwise "does not fit";
* dominant y frequency outside a factor 2 of the others': milliseconds when the ratio is ~1e-3 (and the
  time span ~1e3 times longer), otherwise another experiment;
* time span beyond 20 times the others': units of t;
* tracking noise beyond 10 times the others' median (and above 0.5 % of the amplitude): a bad track or
  another camera setting;
* the physics bounds, checked on every run whatever the others say (meta.json's constants or their
  defaults): a y amplitude beyond a quarter wavelength (no trap holds the dimer farther from its
  equilibrium: y in micrometres or millimetres), a median y beyond an eighth of a wavelength (the trap
  keeps the dimer within |Z_eq| < lambda/8 of its levitation height: y written as an absolute height),
  and a dominant y frequency outside the 5-200 Hz of any vertical acoustic trap (t in milliseconds or
  microseconds when the frequency times 1e3 or 1e6 falls inside);
* with a trap-frequency estimator (``trap_frequency``, passed in by a caller that has the physics, e.g.
  the Gor'kov estimate :func:`acousim.analytic.nominal_trap_frequency`) and a meta.json: a dominant y
  frequency outside a factor 2 of the estimate at the nominal pressure.

Runs are compared only when at least three are loaded; the physics bounds apply to any number.  Each
finding carries a ``code`` (e.g. ``t_milliseconds``) so that a data set whose every file fails the same
check is refused with that check's message.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable, Mapping, Sequence

import numpy as np
from numpy.typing import NDArray

from .config_checks import check_above, check_bounds
from .meta import META_DEFAULTS
from .noise import white_noise_std
from .spectra import dominant_frequency

__all__ = ["ConsistencyConfig", "RunFeatures", "Inconsistency", "run_features", "check_consistency",
           "TRAP_FREQUENCY_RANGE_HZ"]

#: Vertical trap frequencies [Hz] of any acoustically levitated dimer (mm-sized and smaller particles at
#: 20-100 kHz and 0.5-20 kPa sit at 10-100 Hz; the band leaves a factor 2 either side).
TRAP_FREQUENCY_RANGE_HZ = (5.0, 200.0)
#: The median y beyond which y is taken for an absolute height, as a fraction of the wavelength: the dimer
#: levitates less than lambda/8 below the pressure node, so no trap moves it farther from its levitation height.
MAX_OFFSET_WAVELENGTHS = 0.125


@dataclass(frozen=True)
class ConsistencyConfig:
    """Margins of :func:`check_consistency` (ratios, dimensionless)."""

    amplitude_ratio: float = 30.0
    frequency_ratio: float = 2.0
    duration_ratio: float = 20.0
    noise_ratio: float = 10.0
    min_signal_to_noise: float = 5.0
    meta_frequency_ratio: float = 2.0
    #: vertical trap frequencies [Hz] any levitated dimer has (:data:`TRAP_FREQUENCY_RANGE_HZ`)
    trap_frequency_range_hz: tuple[float, float] = TRAP_FREQUENCY_RANGE_HZ

    def __post_init__(self) -> None:
        for name in self.__dataclass_fields__:
            if name == "trap_frequency_range_hz":
                check_bounds(self, name, strict=True)
            else:
                check_above(self, name, 1.0)


@dataclass(frozen=True)
class RunFeatures:
    """The numbers of one run that the consistency rules compare (SI units).

    Attributes
    ----------
    name : str
    y_amplitude : float
        Half the 1-99 % quantile range of y [m].
    f_y : float
        Dominant frequency of y [Hz] (0 for a constant y).
    duration : float
        Time span [s].
    noise_y : float
        Frame-to-frame tracking noise of y [m] (:func:`cubedimer.noise.white_noise_std`: the robust scale of its
        fourth differences).
    y_median : float
        Median of y [m] (near 0: y is measured from the levitation height).
    """

    name: str
    y_amplitude: float
    f_y: float
    duration: float
    noise_y: float
    y_median: float = 0.0


@dataclass(frozen=True)
class Inconsistency:
    """A run that does not fit: ``file``, a one-line ``reason`` naming the likely cause and what to do, and a
    ``code`` naming the check (``y_micrometres``, ``t_milliseconds``, ``y_absolute_height``, ...)."""

    file: str
    reason: str
    code: str = "other"

    def __str__(self) -> str:
        return f"{self.file}: {self.reason}"


def _noise_level(x: NDArray) -> float:
    """Tracking noise [units of x] (:func:`cubedimer.noise.white_noise_std`); NaN for fewer than 15 frames."""
    return float("nan") if x.size < 15 else white_noise_std([x])


#: A peak at five or more cycles per run is the oscillation when it reaches this fraction of a slower peak.
SLOW_PEAK_FRACTION = 0.1

#: The fewest cycles per run of the y oscillation: a slower peak is a drift of the levitation height.
Y_MIN_CYCLES = 5.0


def oscillation_frequency(x: NDArray, dt: float, duration: float, min_cycles: float = Y_MIN_CYCLES) -> float:
    """The oscillation frequency [Hz] of a coordinate sampled every ``dt`` [s] over ``duration`` [s]: the largest
    spectral peak at ``min_cycles`` or more cycles per run (:func:`cubedimer.spectra.dominant_frequency`), unless
    nothing there reaches :data:`SLOW_PEAK_FRACTION` of a slower peak (then the slower one)."""
    return dominant_frequency(x, dt, fmin=min_cycles / duration, prefer_above=SLOW_PEAK_FRACTION)


def run_features(name: str, t: NDArray, y: NDArray) -> RunFeatures:
    """:class:`RunFeatures` of one gap-filled run (t [s], y [m]).

    f_y is the largest spectral peak at five or more cycles per run, unless nothing there reaches
    :data:`SLOW_PEAK_FRACTION` of a slower peak: a slow drift of the levitation height (a drifting
    pressure) is not taken for the run's oscillation, and a run that only drifts keeps its slow f_y."""
    t, y = np.asarray(t, float), np.asarray(y, float)
    dt = float((t[-1] - t[0]) / (t.size - 1))
    duration = float(t[-1] - t[0])
    q = np.quantile(y, [0.01, 0.99])
    f_y = oscillation_frequency(y, dt, duration) if np.ptp(y) > 0 else 0.0
    return RunFeatures(name=name, y_amplitude=0.5 * float(q[1] - q[0]), f_y=f_y,
                       duration=duration, noise_y=_noise_level(y), y_median=float(np.median(y)))



def _near_power_of_ten(ratio: float, power: int, tol: float = 1.0) -> bool:
    return ratio > 0 and abs(math.log10(ratio) - power) < tol


Problem = tuple[str, str]  # (code, one-line reason)

#: Where the conventions of a data set are described (quoted in messages).
CONVENTIONS_DOC = "docs/conventions.md"


def _run_problem(f: RunFeatures, others: Sequence[RunFeatures], c: ConsistencyConfig) -> Problem | None:
    """The first rule ``f`` breaks against the others' medians, or None."""
    med = lambda key: float(np.median([getattr(o, key) for o in others]))  # noqa: E731
    amp, freq, dur, noise = med("y_amplitude"), med("f_y"), med("duration"), med("noise_y")
    r_amp = f.y_amplitude / amp if amp > 0 else math.inf
    if r_amp > c.amplitude_ratio or r_amp < 1.0 / c.amplitude_ratio:
        for power, unit in ((6, "micrometres"), (3, "millimetres"), (-6, "megametres"), (-3, "kilometres")):
            if _near_power_of_ten(r_amp, power):
                return (f"y_{unit}", f"y looks like {unit}: amplitude {f.y_amplitude:.3g} against {amp:.2g} m in "
                                     f"the other runs; write y in metres")
        return ("y_amplitude", f"y amplitude {f.y_amplitude:.3g} m does not fit the other runs ({amp:.2g} m, "
                               f"ratio {r_amp:.3g}): another experiment or other units?")
    r_f = f.f_y / freq if freq > 0 else math.inf
    r_d = f.duration / dur if dur > 0 else math.inf
    if _near_power_of_ten(r_f, -3, 0.5) or _near_power_of_ten(r_d, 3, 0.5):
        return ("t_milliseconds", f"t looks like milliseconds: time span {f.duration:.4g} against {dur:.3g} s and "
                                  f"dominant y frequency {f.f_y:.3g} against {freq:.3g} Hz in the other runs; write t "
                                  f"in seconds")
    if r_f > c.frequency_ratio or r_f < 1.0 / c.frequency_ratio:
        return ("f_y", f"dominant y frequency {f.f_y:.3g} Hz against {freq:.3g} Hz in the other runs: another "
                       f"experiment (other pressure or particle), or t in other units")
    if r_d > c.duration_ratio or r_d < 1.0 / c.duration_ratio:
        return ("duration", f"time span {f.duration:.4g} s against {dur:.3g} s in the other runs: units of t?")
    # the noise rule needs noise that matters (above 0.5 % of the amplitude): noise-free synthetic runs differ
    # only by round-off and the smoothing's own residual
    if noise > 0 and f.noise_y > c.noise_ratio * noise and f.noise_y > 5e-3 * amp:
        return ("noise", f"tracking noise {f.noise_y:.3g} m is {f.noise_y / noise:.0f} times the other runs' "
                         f"({noise:.2g} m): a bad track or another camera setting")
    return None


def _signal_problem(f: RunFeatures, c: ConsistencyConfig) -> Problem | None:
    """A run without an oscillation to fit: constant or pure noise."""
    if not f.y_amplitude > 0:
        return ("y_constant", "y is constant: no motion was tracked")
    if f.noise_y > 0 and f.y_amplitude < c.min_signal_to_noise * f.noise_y:
        return ("pure_noise", f"looks like pure noise: y amplitude {f.y_amplitude:.3g} m is only "
                              f"{f.y_amplitude / f.noise_y:.1f} times its frame-to-frame noise")
    return None


def _y_units(amplitude: float, quarter: float) -> list[tuple[str, str, float]]:
    """The units y may be in, judged by which put the amplitude [given units] between 0.5 um (the smallest
    oscillation a camera tracks) and a quarter wavelength: (unit, label, factor to metres)."""
    return [(unit, label, k) for unit, label, k in (("micrometres", "um", 1e-6), ("millimetres", "mm", 1e-3))
            if 5e-7 <= amplitude * k <= quarter]


def _physics_problem(f: RunFeatures, meta: Mapping[str, float], c: ConsistencyConfig,
                     trap_frequency: Callable[[Mapping[str, float]], float] | None,
                     others_amplitude: float | None) -> Problem | None:
    """Rules any levitated dimer obeys (module docstring), with meta.json's constants or their defaults."""
    m = {**META_DEFAULTS, **dict(meta)}
    wavelength = m["sound_speed_m_s"] / m["frequency_hz"]
    quarter = wavelength / 4.0
    context = f" against {others_amplitude:.2g} m in the other runs" if others_amplitude else ""
    if f.y_amplitude > quarter:
        units = _y_units(f.y_amplitude, quarter)
        if len(units) == 1:
            unit, label, k = units[0]
            todo = f"write y in metres (multiply by {k:g}) or label the column 'y [{label}]' ({CONVENTIONS_DOC})"
            if context:
                return (f"y_{unit}", f"y looks like {unit}: amplitude {f.y_amplitude:.3g}{context}, beyond a quarter "
                                     f"wavelength ({quarter:.3g} m) where no trap holds a dimer; {todo}")
            return (f"y_{unit}", f"y amplitude {f.y_amplitude:.3g} exceeds a quarter wavelength ({quarter:.3g} m) "
                                 f"where no trap holds a dimer: y looks like {unit}; {todo}")
        return ("y_units", f"y amplitude {f.y_amplitude:.3g}{context} exceeds a quarter wavelength ({quarter:.3g} m) "
                           f"where no trap holds a dimer: write y in metres, or label the column with its unit, "
                           f"e.g. 'y [um]' ({CONVENTIONS_DOC})")
    offset = abs(f.y_median)
    if offset > MAX_OFFSET_WAVELENGTHS * wavelength:
        return ("y_absolute_height", f"y looks like an absolute height: its median {f.y_median:.3g} m lies beyond "
                                     f"lambda/8 ({MAX_OFFSET_WAVELENGTHS * wavelength:.3g} m) from 0, farther than any "
                                     f"trap moves a dimer; write y as the displacement from the levitation height "
                                     f"(subtract the height at rest) ({CONVENTIONS_DOC})")
    lo, hi = c.trap_frequency_range_hz
    if f.f_y > 0 and not lo <= f.f_y <= hi:
        for factor, unit, label in ((1e3, "milliseconds", "ms"), (1e6, "microseconds", "us")):
            if lo <= f.f_y * factor <= hi:
                return (f"t_{unit}", f"t looks like {unit}: dominant y frequency {f.f_y:.3g} Hz over a time span of "
                                     f"{f.duration:.4g}, while a levitated dimer oscillates at {lo:g}-{hi:g} Hz; write "
                                     f"t in seconds (divide by {factor:g}) or label the column 't [{label}]' "
                                     f"({CONVENTIONS_DOC})")
        return ("f_y_range", f"dominant y frequency {f.f_y:.3g} Hz is outside the {lo:g}-{hi:g} Hz of any vertical "
                             f"acoustic trap: check the units of t and that y is the vertical displacement "
                             f"({CONVENTIONS_DOC})")
    if trap_frequency is not None and f.f_y > 0:
        f_trap = float(trap_frequency(m))
        if math.isfinite(f_trap) and f_trap > 0:
            r = f.f_y / f_trap
            if r > c.meta_frequency_ratio or r < 1.0 / c.meta_frequency_ratio:
                return ("f_y_meta", f"dominant y frequency {f.f_y:.3g} Hz is far from the trap frequency "
                                    f"{f_trap:.3g} Hz that meta.json's constants give at the nominal pressure: units "
                                    f"of t, or another experiment?")
    return None


def check_consistency(features: Sequence[RunFeatures], meta: Mapping[str, float] | None = None,
                      config: ConsistencyConfig = ConsistencyConfig(),
                      trap_frequency: Callable[[Mapping[str, float]], float] | None = None,
                      levitated: bool = True) -> list[Inconsistency]:
    """The runs of a data set that do not fit (module docstring), each with its likely cause.

    Parameters
    ----------
    features : sequence of RunFeatures
        One per loaded run (:func:`run_features`).
    meta : mapping, optional
        The data set's validated meta.json; the physics bounds use its constants, or the defaults for missing
        keys (None: all defaults).  The bounds apply with or without it.
    config : ConsistencyConfig
    trap_frequency : callable, optional
        ``trap_frequency(meta_with_defaults) -> Hz``: a physics estimate of the vertical trap frequency at the
        nominal pressure (NaN when it has none).  Used only with a ``meta``: the run's dominant y frequency must
        lie within ``config.meta_frequency_ratio`` of it.  This package carries no acoustic model; the caller
        that has one passes it in.
    levitated : bool
        False for a generic two-coordinate system (:mod:`cubedimer.system`): only a constant run and pure noise are
        refused; the levitation bounds and the comparisons in metres and seconds do not apply.

    Returns
    -------
    list of Inconsistency, in the order of ``features``.
    """
    found: list[Inconsistency] = []
    signal_ok = []
    for f in features:
        problem = _signal_problem(f, config)
        if problem:
            found.append(Inconsistency(f.name, problem[1], problem[0]))
        else:
            signal_ok.append(f)
    if not levitated:
        return found
    physical = [f for f in signal_ok if _physics_problem(f, meta or {}, config, None, None) is None]
    reference = float(np.median([f.y_amplitude for f in physical])) if len(physical) >= 2 else None
    ok: list[RunFeatures] = []
    for f in signal_ok:
        problem = _physics_problem(f, meta or {}, config, trap_frequency if meta else None,
                                   reference if f not in physical else None)
        if problem:
            found.append(Inconsistency(f.name, problem[1], problem[0]))
        else:
            ok.append(f)
    if len(ok) >= 3:
        for f in ok:
            others = [o for o in ok if o is not f]
            problem = _run_problem(f, others, config)
            if problem:
                found.append(Inconsistency(f.name, problem[1], problem[0]))
    order = {f.name: i for i, f in enumerate(features)}
    return sorted(found, key=lambda x: order[x.file])
