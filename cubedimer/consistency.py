"""Cross-run consistency of a data set: one file in the wrong units must not corrupt the whole result.

Every run of a data set records the same dimer in the same trap, so a few numbers must agree across
runs within wide margins: the y amplitude, the dominant y frequency, the time span and the tracking
noise.  :func:`check_consistency` compares each run with the median of the *other* runs (so that one
bad file among four is as visible as one among twelve) and, when ``meta.json`` is given, with what the
experiment's constants allow.  Each finding names the file, the likely cause and the numbers, e.g.
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
* with ``meta``: a y amplitude beyond the quarter wavelength (no trap holds the dimer farther from its
  equilibrium), and a dominant y frequency outside a factor 2 of the small-particle Gor'kov trap
  frequency at the nominal pressure (:func:`nominal_trap_frequency`).

Runs are compared only when at least three are loaded; the meta checks apply to any number.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Mapping, Sequence

import numpy as np
from numpy.typing import NDArray

from .spectra import dominant_frequency

__all__ = ["ConsistencyConfig", "RunFeatures", "Inconsistency", "run_features", "check_consistency",
           "nominal_trap_frequency"]

GRAVITY = 9.81  # m/s^2 (PHYSICS.md section 1)


@dataclass(frozen=True)
class ConsistencyConfig:
    """Margins of :func:`check_consistency` (ratios, dimensionless)."""

    amplitude_ratio: float = 30.0
    frequency_ratio: float = 2.0
    duration_ratio: float = 20.0
    noise_ratio: float = 10.0
    min_signal_to_noise: float = 5.0
    meta_frequency_ratio: float = 2.0

    def __post_init__(self) -> None:
        for k, v in self.__dict__.items():
            if not v > 1:
                raise ValueError(f"{k} must exceed 1, got {v!r}")


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
        Frame-to-frame tracking noise of y [m] (robust scale of the residual of a short cubic smoothing,
        corrected for the filter).
    """

    name: str
    y_amplitude: float
    f_y: float
    duration: float
    noise_y: float


@dataclass(frozen=True)
class Inconsistency:
    """A run that does not fit: ``file`` and a one-line ``reason`` naming the likely cause."""

    file: str
    reason: str

    def __str__(self) -> str:
        return f"{self.file}: {self.reason}"


def _noise_level(x: NDArray) -> float:
    """Tracking noise [units of x]: the residual of a 7-frame cubic Savitzky-Golay smoothing, whose
    white-noise gain is sqrt(1 - c0) with c0 = 1/3 + ... the centre weight (a projection)."""
    from scipy.signal import savgol_coeffs, savgol_filter

    if x.size < 15:
        return float("nan")
    r = x - savgol_filter(x, 7, 3)
    c0 = float(savgol_coeffs(7, 3)[3])
    return 1.4826 * float(np.median(np.abs(r - np.median(r)))) / math.sqrt(1.0 - c0)


#: A peak at five or more cycles per run is the oscillation when it reaches this fraction of a slower peak.
SLOW_PEAK_FRACTION = 0.1


def run_features(name: str, t: NDArray, y: NDArray) -> RunFeatures:
    """:class:`RunFeatures` of one gap-filled run (t [s], y [m]).

    f_y is the largest spectral peak at five or more cycles per run, unless nothing there reaches
    :data:`SLOW_PEAK_FRACTION` of a slower peak: a slow drift of the levitation height (a drifting
    pressure) is not taken for the run's oscillation, and a run that only drifts keeps its slow f_y."""
    t, y = np.asarray(t, float), np.asarray(y, float)
    dt = float((t[-1] - t[0]) / (t.size - 1))
    duration = float(t[-1] - t[0])
    q = np.quantile(y, [0.01, 0.99])
    f_y = (dominant_frequency(y, dt, fmin=5.0 / duration, prefer_above=SLOW_PEAK_FRACTION)
           if np.ptp(y) > 0 else 0.0)
    return RunFeatures(name=name, y_amplitude=0.5 * float(q[1] - q[0]), f_y=f_y,
                       duration=duration, noise_y=_noise_level(y))



def nominal_trap_frequency(meta: Mapping[str, float]) -> float:
    """Small-particle Gor'kov estimate of the vertical trap frequency [Hz] at the nominal pressure.

    For a particle small against the wavelength, u(Z) = E [f1 sin^2 kZ - 3/2 f2 cos^2 kZ] per unit volume
    with E = p0^2 / (4 rho0 c0^2) (PHYSICS.md section 3); the levitation height solves
    E k (f1 + 3/2 f2) sin(-2 k Z_eq) = rho_p g and the stiffness per unit mass there is
    omega^2 = 2 E k^2 (f1 + 3/2 f2) cos(2 k Z_eq) / rho_p.  Independent of the particle's size and shape
    to leading order (the cube dimer's finite size lowers it by ~3 % at the defaults).  NaN when the
    field cannot levitate the particle.
    """
    from .meta import META_DEFAULTS

    m = {**META_DEFAULTS, **dict(meta)}
    rho0, c0, f = m["air_density_kg_m3"], m["sound_speed_m_s"], m["frequency_hz"]
    rho_p, k_p, p0 = m["particle_density_kg_m3"], m["bulk_modulus_pa"], m["pressure_amplitude_pa"]
    f1 = 1.0 - rho0 * c0**2 / k_p
    f2 = 2.0 * (rho_p - rho0) / (2.0 * rho_p + rho0)
    k = 2.0 * math.pi * f / c0
    e = p0**2 / (4.0 * rho0 * c0**2)
    strength = e * k * (f1 + 1.5 * f2)
    s = rho_p * GRAVITY / strength
    if not 0 <= s < 1:
        return float("nan")
    omega2 = 2.0 * e * k**2 * (f1 + 1.5 * f2) * math.sqrt(1.0 - s * s) / rho_p
    return math.sqrt(omega2) / (2.0 * math.pi)


def _near_power_of_ten(ratio: float, power: int, tol: float = 1.0) -> bool:
    return ratio > 0 and abs(math.log10(ratio) - power) < tol


def _run_problem(f: RunFeatures, others: Sequence[RunFeatures], c: ConsistencyConfig) -> str | None:
    """The first rule ``f`` breaks against the others' medians, or None."""
    med = lambda key: float(np.median([getattr(o, key) for o in others]))  # noqa: E731
    amp, freq, dur, noise = med("y_amplitude"), med("f_y"), med("duration"), med("noise_y")
    r_amp = f.y_amplitude / amp if amp > 0 else math.inf
    if r_amp > c.amplitude_ratio or r_amp < 1.0 / c.amplitude_ratio:
        for power, unit in ((6, "micrometres"), (3, "millimetres"), (-6, "megametres"), (-3, "kilometres")):
            if _near_power_of_ten(r_amp, power):
                return f"y looks like {unit}: amplitude {f.y_amplitude:.3g} against {amp:.2g} m in the other runs"
        return (f"y amplitude {f.y_amplitude:.3g} m does not fit the other runs ({amp:.2g} m, "
                f"ratio {r_amp:.3g}): another experiment or other units?")
    r_f = f.f_y / freq if freq > 0 else math.inf
    r_d = f.duration / dur if dur > 0 else math.inf
    if _near_power_of_ten(r_f, -3, 0.5) or _near_power_of_ten(r_d, 3, 0.5):
        return (f"t looks like milliseconds: time span {f.duration:.4g} against {dur:.3g} s and dominant y "
                f"frequency {f.f_y:.3g} against {freq:.3g} Hz in the other runs")
    if r_f > c.frequency_ratio or r_f < 1.0 / c.frequency_ratio:
        return (f"dominant y frequency {f.f_y:.3g} Hz against {freq:.3g} Hz in the other runs: another "
                f"experiment (other pressure or particle), or t in other units")
    if r_d > c.duration_ratio or r_d < 1.0 / c.duration_ratio:
        return f"time span {f.duration:.4g} s against {dur:.3g} s in the other runs: units of t?"
    # the noise rule needs noise that matters (above 0.5 % of the amplitude): noise-free synthetic runs differ
    # only by round-off and the smoothing's own residual
    if noise > 0 and f.noise_y > c.noise_ratio * noise and f.noise_y > 5e-3 * amp:
        return (f"tracking noise {f.noise_y:.3g} m is {f.noise_y / noise:.0f} times the other runs' "
                f"({noise:.2g} m): a bad track or another camera setting")
    return None


def _own_problem(f: RunFeatures, meta: Mapping[str, float] | None, c: ConsistencyConfig) -> str | None:
    """Rules a run breaks on its own or against ``meta``, or None."""
    if not f.y_amplitude > 0:
        return "y is constant: no motion was tracked"
    if f.noise_y > 0 and f.y_amplitude < c.min_signal_to_noise * f.noise_y:
        return (f"looks like pure noise: y amplitude {f.y_amplitude:.3g} m is only "
                f"{f.y_amplitude / f.noise_y:.1f} times its frame-to-frame noise")
    if meta is None:
        return None
    from .meta import META_DEFAULTS

    m = {**META_DEFAULTS, **dict(meta)}
    quarter = m["sound_speed_m_s"] / m["frequency_hz"] / 4.0
    if f.y_amplitude > quarter:
        unit = " (micrometres?)" if _near_power_of_ten(f.y_amplitude / 1e-4, 6) else ""
        return (f"y amplitude {f.y_amplitude:.3g} m exceeds a quarter wavelength ({quarter:.3g} m), beyond any "
                f"trap{unit}: check the units of y")
    f_trap = nominal_trap_frequency(m)
    if math.isfinite(f_trap) and f.f_y > 0:
        r = f.f_y / f_trap
        if r > c.meta_frequency_ratio or r < 1.0 / c.meta_frequency_ratio:
            return (f"dominant y frequency {f.f_y:.3g} Hz is far from the trap frequency {f_trap:.3g} Hz that "
                    f"meta.json's constants give at the nominal pressure: units of t, or another experiment?")
    return None


def check_consistency(features: Sequence[RunFeatures], meta: Mapping[str, float] | None = None,
                      config: ConsistencyConfig = ConsistencyConfig()) -> list[Inconsistency]:
    """The runs of a data set that do not fit (module docstring), each with its likely cause.

    Parameters
    ----------
    features : sequence of RunFeatures
        One per loaded run (:func:`run_features`).
    meta : mapping, optional
        The data set's validated meta.json (PHYSICS.md defaults for missing keys); None skips the meta checks.
    config : ConsistencyConfig

    Returns
    -------
    list of Inconsistency, in the order of ``features``.
    """
    found: list[Inconsistency] = []
    ok: list[RunFeatures] = []
    for f in features:
        problem = _own_problem(f, meta, config)
        if problem:
            found.append(Inconsistency(f.name, problem))
        else:
            ok.append(f)
    if len(ok) >= 3:
        for f in ok:
            others = [o for o in ok if o is not f]
            problem = _run_problem(f, others, config)
            if problem:
                found.append(Inconsistency(f.name, problem))
    order = {f.name: i for i, f in enumerate(features)}
    return sorted(found, key=lambda x: order[x.file])
