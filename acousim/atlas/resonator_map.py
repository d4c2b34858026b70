"""The resonator map: y's growth rate, its threshold and where y's self-sustained motion ends, over (Q, detuning, area).

For each dimer (the Gor'kov default or a full-wave family dimer, with the air's computed damping), cavity quality
factor Q and cross-section A_cav, and for each detuning x (half-widths), a cell records

* the linear theory of :mod:`acousim.dynamics.cavity_stability`: the exact growth rate (the quartic's root), the
  first-order formula and the first-order unstable band of x (the threshold);
* the growth rate measured on the full simulation (:func:`acousim.dynamics.resonator.integrate_coupled`) from
  y = ``small_amplitude`` above rest: the slope of the log of y's successive maxima (parabolic peaks) after the mode's
  transient (``settle_time``), over ``growth_time`` or until y reaches ten times its start;
* the fate of a larger start (y = ``start_amplitude``) after ``duration``: ``decayed`` (below a tenth of the start),
  ``limit cycle`` (the amplitude of the last ``window`` seconds within 2 % of the window before, where the linear
  growth rate would have changed it by more than 10 %: a saturation, :func:`fate`), ``near threshold`` (within 2 %,
  but so would the linear rate), ``growing`` or ``decaying`` (neither yet), ``escaped`` (left the trap) or
  ``folded``, with y's and theta's amplitudes at the end.

The hinge starts at the force model's static equilibrium (theta = 0 for the Gor'kov dimer, which keeps it there by
symmetry).  :func:`run_resonator_map` runs the cells (dimer x Q x A_cav, every detuning in one task) through
:func:`cubedimer.executor.map_ordered`, writes each finished cell at once and skips those already written
(resumable), then writes ``resonator_map.csv``, ``resonator_map.json`` and the figure ``resonator_map.png``.
No random choice.
"""
from __future__ import annotations

import math
import os
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from cubedimer.atomic import atomic_write_text, save_figure, write_json
from cubedimer.config_checks import check_builds, check_that, named, raising
from cubedimer.executor import ExecutorConfig
from cubedimer.meta import DEFAULT_FREQUENCY_HZ

from .field_drops import AtlasError, atlas_dynamics, cells_csv_text, open_study, run_resumable_cells

__all__ = ["ResonatorMapConfig", "map_dynamics", "growth_from_peaks", "fate", "detuning_row", "run_resonator_map",
           "MAP_COLUMNS", "DEFAULT_DIMERS"]

#: Default dimers: the Gor'kov default (500 um at 3 kPa) and two full-wave family dimers (side:gap ratio:pressure).
DEFAULT_DIMERS = ("gorkov:500e-6:3000", "fullwave:500e-6:0.02:3000", "fullwave:700e-6:0.05:6000")
MAP_COLUMNS = ("dimer", "quality_factor", "cavity_area_m2", "detuning", "f_y_hz", "gamma_y", "kappa",
               "growth_exact", "growth_first_order", "growth_simulated", "static_stiffness_ratio", "band_low",
               "band_high", "outcome", "y_amplitude_m", "theta_amplitude", "seconds")


@dataclass(frozen=True)
class ResonatorMapConfig:
    """Settings of the resonator map (module docstring); lengths in m, times in s."""

    dimers: tuple[str, ...] = field(default=DEFAULT_DIMERS, metadata=named("--dimers"))
    quality_factors: tuple[float, ...] = field(default=(100.0, 250.0, 500.0), metadata=named("--qualities"))
    areas_m2: tuple[float, ...] = field(default=(3.0e-5, 1.0e-4, math.pi * 0.010**2), metadata=named("--areas"))
    detunings: tuple[float, ...] = field(default=tuple(np.round(np.linspace(-4.0, 1.0, 11), 6)),
                                         metadata=named("--detunings"))
    small_amplitude: float = 1.0e-6
    settle_time: float = 0.05
    growth_time: float = 3.0
    start_amplitude: float = field(default=30.0e-6, metadata=named("--start-amplitude"))
    duration: float = field(default=40.0, metadata=named("--duration"))
    window: float = 5.0
    frequency_hz: float = DEFAULT_FREQUENCY_HZ

    def __post_init__(self) -> None:
        from ..dynamics.resonator import CavityMode

        with raising(AtlasError):
            for d in self.dimers:
                _parse_dimer(d)
            for q in self.quality_factors:
                for a in self.areas_m2:
                    for x in self.detunings:
                        check_builds(self, "--qualities/--areas/--detunings", lambda q=q, a=a, x=x: CavityMode(q, x, a))
            check_that(self, 0 < self.small_amplitude < self.start_amplitude <= 1e-3,
                       "the amplitudes must satisfy 0 < small < start <= 1 mm")
            check_that(self, 0 < self.settle_time < self.growth_time and 0 < 2 * self.window < self.duration,
                       "the times must satisfy 0 < settle < growth and 0 < 2 window < duration")

    def cells(self) -> list[tuple[int, int, int]]:
        return [(d, q, a) for d in range(len(self.dimers)) for q in range(len(self.quality_factors))
                for a in range(len(self.areas_m2))]

    def to_dict(self) -> dict:
        return {k: list(v) if isinstance(v, tuple) else v for k, v in asdict(self).items()}


def _parse_dimer(spec: str) -> tuple:
    from ..fullwave.statics import MODEL_NAME as FULLWAVE
    from ..gorkov.forces import GORKOV

    parts = spec.split(":")
    try:
        if parts[0] == GORKOV and len(parts) == 3:
            return (GORKOV, float(parts[1]), float(parts[2]))
        if parts[0] == FULLWAVE and len(parts) == 4:
            return (FULLWAVE, float(parts[1]), float(parts[2]), float(parts[3]))
    except ValueError:
        pass
    raise AtlasError(f"--dimers {spec!r}: expected {GORKOV}:SIDE:PRESSURE or {FULLWAVE}:SIDE:GAP_RATIO:PRESSURE")


def map_dynamics(spec: str, frequency_hz: float):
    """(DimerDynamics with the air's computed damping, x_rest = [y*, 0, theta*, 0]) of a dimer spec."""
    from ..fullwave.statics import MODEL_NAME as FULLWAVE

    kind, *par = _parse_dimer(spec)
    if kind == FULLWAVE:
        dyn = atlas_dynamics(par[0], par[1], par[2], frequency_hz)
        theta, y = dyn.force_model.equilibrium()
        return dyn, np.array([y, 0.0, theta, 0.0])
    from ..models import ExperimentConditions
    from ..twin import TwinConfig
    from ..twin.simulation import twin_dynamics

    experiment = ExperimentConditions(side_length_m=par[0], pressure_amplitude_pa=par[1], frequency_hz=frequency_hz)
    dyn, _ = twin_dynamics(TwinConfig(experiment=experiment))
    return dyn, np.zeros(4)


def growth_from_peaks(t: np.ndarray, y: np.ndarray, t_from: float) -> float:
    """The slope [1/s] of log(y's maxima) against their times from ``t_from`` on (maxima refined by a parabola
    through the three samples about each), NaN with fewer than four maxima."""
    i = np.flatnonzero((y[1:-1] > y[:-2]) & (y[1:-1] >= y[2:])) + 1
    a, b, c = y[i - 1], y[i], y[i + 1]
    off = 0.5 * (a - c) / (a - 2 * b + c)
    peak, tp = b - 0.25 * (a - c) * off, t[i] + off * (t[1] - t[0])
    keep = (tp >= t_from) & (peak > 0)
    if keep.sum() < 4:
        return float("nan")
    return float(np.polyfit(tp[keep], np.log(peak[keep]), 1)[0])


def _envelope(y: np.ndarray, n: int) -> np.ndarray:
    """Max |y - mean| in consecutive blocks of n samples."""
    m = y.size // n
    blocks = y[: m * n].reshape(m, n)
    return np.max(np.abs(blocks - blocks.mean(axis=1, keepdims=True)), axis=1)


def fate(outcome: str, growth_exact: float, window: float) -> str:
    """The outcome of a map row: a ``limit cycle`` (amplitude within 2 % over ``window`` [s]) whose linear growth rate
    would change the amplitude by less than 10 % over the window is ``near threshold`` (no saturation shown)."""
    if outcome == "limit cycle" and abs(growth_exact) * window < 0.1:
        return "near threshold"
    return outcome


def detuning_row(dyn, x_rest, quality_factor: float, area: float, detuning: float, config: ResonatorMapConfig) -> dict:
    """One detuning of a cell (module docstring)."""
    import time

    from ..dynamics.cavity_stability import LinearCavityCoupling
    from ..dynamics.integrator import STATUS_MESSAGES
    from ..dynamics.resonator import CavityMode, CoupledCavity, integrate_coupled
    from ..medium import Medium

    t0 = time.perf_counter()
    cav = CoupledCavity(dyn, CavityMode(quality_factor, detuning, area), Medium(frequency_hz=config.frequency_hz))
    gamma_y = float(dyn.effects["air_damping"].gamma_y) if "air_damping" in dyn.effects else 0.0
    lin = LinearCavityCoupling.from_cavity(cav, gamma_y=gamma_y)
    band = lin.unstable_detunings() or (float("nan"), float("nan"))
    a0 = cav.mode.steady_amplitude()
    dt = 2e-4
    small = integrate_coupled(cav, x_rest + [config.small_amplitude, 0, 0, 0], a0, config.growth_time, dt)
    y = small.state[:, 0] - x_rest[0]
    big = np.flatnonzero(np.abs(y) > 10 * config.small_amplitude)
    stop = big[0] if big.size else y.size
    growth = growth_from_peaks(small.t[:stop], y[:stop], config.settle_time)
    run = integrate_coupled(cav, x_rest + [config.start_amplitude, 0, 0, 0], a0, config.duration, 1e-3)
    n_win = int(round(config.window / 1e-3))
    if run.status == 2:
        outcome = "folded"
    elif run.status != 0:
        outcome = "escaped" if run.status in (1, 4) else STATUS_MESSAGES[run.status]
    else:
        env = _envelope(run.state[:, 0], n_win)
        last, before = env[-1], env[-2]
        if last < 0.1 * config.start_amplitude:
            outcome = "decayed"
        elif abs(last - before) <= 0.02 * last:
            outcome = "limit cycle"
        else:
            outcome = "growing" if last > before else "decaying"
    tail = run.state[-n_win:] if run.state.shape[0] >= n_win else run.state
    return {"quality_factor": quality_factor, "cavity_area_m2": area, "detuning": detuning,
            "f_y_hz": lin.omega_y / (2 * math.pi), "gamma_y": gamma_y, "kappa": lin.kappa,
            "growth_exact": lin.growth_rate(), "growth_first_order": lin.first_order_growth_rate(),
            "growth_simulated": growth, "static_stiffness_ratio": lin.static_stiffness() / lin.omega_y**2,
            "band_low": band[0], "band_high": band[1], "outcome": fate(outcome, lin.growth_rate(), config.window),
            "y_amplitude_m": float(0.5 * np.ptp(tail[:, 0])), "theta_amplitude": float(0.5 * np.ptp(tail[:, 2])),
            "seconds": time.perf_counter() - t0}


def _cell_task(item: tuple) -> dict:
    config, (d, q, a) = item
    spec = config.dimers[d]
    dyn, x_rest = map_dynamics(spec, config.frequency_hz)
    rows = [dict(dimer=spec, **detuning_row(dyn, x_rest, config.quality_factors[q], config.areas_m2[a], x, config))
            for x in config.detunings]
    return {"dimer": spec, "rows": rows}


def _check_map_dimers(config: ResonatorMapConfig) -> None:
    """Refuse a map one of whose dimers cannot be built (:class:`AtlasError`), before anything is written."""
    for spec in config.dimers:
        try:
            map_dynamics(spec, config.frequency_hz)
        except ValueError as exc:
            raise AtlasError(f"--dimers {spec}: {exc}") from None


def run_resonator_map(config: ResonatorMapConfig, out: str | os.PathLike, executor: ExecutorConfig | None = None,
                      progress: bool = True, figures: bool = True, force: bool = False) -> dict:
    """Run (or resume) the resonator map into ``out``; returns the ``resonator_map.json`` content.

    ``out/resonator_map_settings.json`` pins the settings (another map in the folder is refused, :class:`AtlasError`,
    or with ``force`` discarded first); finished cells are ``out/cells/*.json``, skipped on a rerun.
    """
    out = Path(out)
    settings = config.to_dict()
    open_study(out, settings, "resonator_map_settings.json", "a resonator map", force,
               lambda: _check_map_dimers(config))
    cells = run_resumable_cells(out, config.cells(), lambda c: out / "cells" / f"d{c[0]}_q{c[1]}_a{c[2]}.json",
                                _cell_task, lambda c: (config, c), executor, progress, "resonator map")
    rows = [dict(r, outcome=fate(r["outcome"], r["growth_exact"], config.window)) for c in cells for r in c["rows"]]
    atomic_write_text(out / "resonator_map.csv", cells_csv_text(MAP_COLUMNS, rows))
    result = {"settings": settings, "rows": rows, "units": "SI; detuning in half-widths f/(2Q), growth rates in 1/s"}
    write_json(out / "resonator_map.json", result)
    if figures:
        write_resonator_map_figure(config, rows, out / "resonator_map.png")
    return result


_OUTCOME_MARKERS = {"decayed": ("o", "tab:blue"), "decaying": ("o", "tab:cyan"), "limit cycle": ("*", "tab:red"),
                    "near threshold": ("D", "tab:green"),
                    "growing": ("^", "tab:orange"), "escaped": ("x", "black"), "folded": ("s", "tab:purple")}


def write_resonator_map_figure(config: ResonatorMapConfig, rows: list[dict], path: Path) -> Path:
    """One panel per (dimer, Q): the growth rate against the detuning (lines: exact linear theory, one per area;
    markers: the simulated growth, shaped by the larger start's outcome)."""
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D

    nd, nq = len(config.dimers), len(config.quality_factors)
    fig, axes = plt.subplots(nd, nq, figsize=(3.6 * nq + 1.5, 2.9 * nd), squeeze=False, sharex=True)
    colours = plt.cm.viridis(np.linspace(0, 0.85, len(config.areas_m2)))
    for i, spec in enumerate(config.dimers):
        for j, q in enumerate(config.quality_factors):
            ax = axes[i, j]
            for a, col in zip(config.areas_m2, colours):
                mine = sorted((r for r in rows if r["dimer"] == spec and r["quality_factor"] == q
                               and r["cavity_area_m2"] == a), key=lambda r: r["detuning"])
                if not mine:
                    continue
                x = [r["detuning"] for r in mine]
                ax.plot(x, [r["growth_exact"] for r in mine], color=col, lw=1.2)
                for r in mine:
                    m, c = _OUTCOME_MARKERS.get(r["outcome"], ("d", "grey"))
                    if r["growth_simulated"] is not None and math.isfinite(r["growth_simulated"]):  # NaN is null in JSON
                        ax.plot(r["detuning"], r["growth_simulated"], m, color=c, ms=5, mec=col)
            ax.axhline(0.0, color="grey", lw=0.6)
            ax.set_title(f"{spec}, Q = {q:g}", fontsize=8)
            ax.set_yscale("symlog", linthresh=1.0)
            if i == nd - 1:
                ax.set_xlabel("detuning x = (f_c - f_d) / (f / 2Q)")
            if j == 0:
                ax.set_ylabel("growth rate of y [1/s]")
    handles = [Line2D([], [], color=c, label=f"A_cav = {a * 1e6:.0f} mm^2 (exact linear)")
               for a, c in zip(config.areas_m2, colours)]
    handles += [Line2D([], [], ls="", marker=m, color=c, label=f"simulated; start {config.start_amplitude * 1e6:.0f} um: {o}")
                for o, (m, c) in _OUTCOME_MARKERS.items()]
    fig.legend(handles=handles, loc="center right", fontsize=7, frameon=False)
    fig.tight_layout(rect=(0, 0, 0.78, 1))
    return save_figure(fig, path)
