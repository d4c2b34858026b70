"""The free-y attractor map: periodic orbits of the whole system (y, the hinge and the cavity mode), y free.

The held-y map (:mod:`acousim.atlas.held_y`) holds y on a trap oscillation; its attractors are those of a hinge
driven by a prescribed y.  With y free and the air's damping, y lives only where the levitator, as a resonator
(:mod:`acousim.dynamics.resonator`), feeds it.  For a dimer of the full-wave family at p0, a cavity of quality factor
Q, cross-section A_cav and detuning x, a cell

1. runs the six-state system (y, ydot, theta, thetadot, Re a, Im a) from a grid of starts (y ``A`` below the
   equilibrium, the hinge at ``theta0`` at rest, the mode at its steady amplitude) for ``settle_time`` [s] with the
   drive on; a run that leaves the trap is ``escaped``, one whose hinge reaches +-1 ``folded``, one whose y
   amplitude falls below :data:`Y_REST` ``rest`` (the rest point: no orbit);
2. classifies the last half of each other run (:func:`cubedimer.attractors.classify_trajectory`), takes p (the
   lock's periods of y: 1, or p of a p:q lock) and y's period from its lowest points, and refines the periodic
   orbit of period p T_y through the run's last lowest point by shooting
   (:func:`acousim.dynamics.periodic_orbits.shoot_periodic_orbit`, ydot held: the section y's lowest point);
3. for each converged orbit: the Floquet multipliers (the monodromy matrix of all six states by central differences
   of the compiled flow), the trivial one and the largest other |mu| (stable below 1), its life (cycles of y over
   which a perturbation grows or decays by e, :func:`orbit_record`), the class of the orbit repeated 24 times by the
   suite's classifier, theta's f_y and 2 f_y lines (Fourier coefficients over the orbit) and the amplitudes; orbits
   reached from several starts count once (:func:`distinct_orbits`).

:func:`run_free_y_map` runs the cells (dimer x Q x detuning) through :func:`cubedimer.executor.map_ordered`, writes
each finished cell at once and skips those already written (resumable), then writes ``free_y.csv`` (one row per
cell, :func:`cell_summary`), ``free_y.json`` (every run and orbit) and the figure ``free_y_map.png``
(:mod:`acousim.atlas.free_y_figures`).  No random choice.
"""
from __future__ import annotations

import math
import os
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from cubedimer.atomic import atomic_write_text, write_json
from cubedimer.attractors import classify_trajectory
from cubedimer.config_checks import check_builds, check_given, check_in_range, named, raising
from cubedimer.executor import ExecutorConfig
from cubedimer.meta import DEFAULT_FREQUENCY_HZ, DEFAULT_PRESSURE_AMPLITUDE_PA

from .field_drops import AtlasDimer, AtlasError, atlas_dynamics, cells_csv_text, check_dimers_buildable, open_study, run_resumable_cells

__all__ = ["FreeYConfig", "settle_and_guess", "orbit_record", "same_orbit", "distinct_orbits", "free_y_cell",
           "cell_summary", "run_free_y_map", "MAP_COLUMNS", "Y_REST", "PHASE_CLASSES"]

#: A settled run whose y amplitude is below this [m] has come to rest (the rest point, not an orbit).
Y_REST = 1e-6
#: The phase classes counted per cell.
PHASE_CLASSES = ("locked-in-phase", "locked-anti-phase")
#: Repeats of a periodic orbit handed to the classifier (its section phase needs >= 3 crossings; 24 resolve
#: f_theta against f_y to 1/24 of f_y).
_CLASSIFY_REPEATS = 24
MAP_COLUMNS = ("dimer", "side_m", "gap_ratio", "pressure_pa", "quality_factor", "detuning", "cavity_area_m2", "f_y_hz",
               "f_theta_hz", "r", "band_low", "band_high", "growth_at_rest", "starts", "escaped", "folded", "rest",
               "not_converged", "orbits", "stable", "stable_in_phase", "stable_anti_phase", "stable_other",
               "unstable", "max_share_2fy_stable", "min_max_multiplier", "max_max_multiplier",
               "max_trivial_error", "seconds")


@dataclass(frozen=True)
class FreeYConfig:
    """The map's grid and settings (SI units).

    Parameters
    ----------
    dimers : tuple of AtlasDimer
        Dimers of the full-wave family (their r = f_theta / f_y is the map's first axis).
    quality_factors : tuple of float
        Cavity Q values.
    detunings : tuple of float
        x [half-widths f / (2Q)], within the cavity's accepted range (:class:`acousim.dynamics.resonator.CavityMode`).
    pressure_pa : float
        p0 [Pa].
    area_m2 : float
        The cavity's cross-section A_cav [m^2].
    amplitudes_m, theta_starts : tuple of float
        The starts: every (depth of y below the equilibrium [m], hinge angle [-]) pair, the hinge at rest.
    settle_time : float
        The run before the shooting [s].
    samples_per_period : int
        Samples per period of y of the orbit's records.
    max_step : float
        Longest RK4 step [s] (also at most a tenth of the cavity's ring time).
    frequency_hz : float
        Drive frequency [Hz].
    """

    dimers: tuple[AtlasDimer, ...] = field(metadata=named("--dimers"))
    quality_factors: tuple[float, ...] = field(default=(200.0, 250.0, 300.0), metadata=named("--qualities"))
    detunings: tuple[float, ...] = field(default=(-7.0, -6.0, -5.5, -5.0, -4.5, -4.0), metadata=named("--detunings"))
    pressure_pa: float = field(default=DEFAULT_PRESSURE_AMPLITUDE_PA, metadata=named("--pressure"))
    area_m2: float = field(default=3e-5, metadata=named("--area"))
    amplitudes_m: tuple[float, ...] = field(default=(50e-6, 150e-6), metadata=named("--amplitudes"))
    theta_starts: tuple[float, ...] = field(default=(-0.3, 0.0, 0.3), metadata=named("--theta-starts"))
    settle_time: float = field(default=16.0, metadata=named("--settle-time"))
    samples_per_period: int = field(default=40, metadata=named("--samples-per-period"))
    max_step: float = field(default=1e-4, metadata=named("--max-step"))
    frequency_hz: float = field(default=DEFAULT_FREQUENCY_HZ, metadata=named("--frequency"))

    def __post_init__(self) -> None:
        from ..dynamics.resonator import CavityMode

        with raising(AtlasError):
            check_given(self, "dimers", "SIDE:GAP_RATIO pair")
            for q in self.quality_factors:
                for x in self.detunings:
                    check_builds(self, "--qualities/--detunings/--area",
                                 lambda q=q, x=x: CavityMode(q, x, self.area_m2))
            check_given(self, "quality_factors", "quality factor")
            check_given(self, "detunings", "detuning")
            check_in_range(self, "pressure_pa", 0.0, 1e5, low_open=True, unit="Pa")
            check_in_range(self, "amplitudes_m", 0.0, 1e-3, low_open=True, unit="m", each=True)
            check_in_range(self, "theta_starts", -0.99, 0.99, low_open=True, high_open=True, each=True)
            check_in_range(self, "settle_time", 1.0, 600.0, unit="s")
            check_in_range(self, "samples_per_period", 16, 1000, whole=True)
            check_in_range(self, "frequency_hz", 1e3, 1e6, unit="Hz")
            check_in_range(self, "max_step", 0.0, 1e-3, low_open=True, unit="s")

    def cells(self) -> list[tuple[int, int, int]]:
        """(dimer, Q, detuning) indices of every cell."""
        return [(d, q, x) for d in range(len(self.dimers)) for q in range(len(self.quality_factors))
                for x in range(len(self.detunings))]

    def starts(self) -> list[tuple[float, float]]:
        return [(a, th) for a in self.amplitudes_m for th in self.theta_starts]

    def to_dict(self) -> dict:
        out = asdict(self)
        out["dimers"] = [asdict(d) for d in self.dimers]
        for k in ("quality_factors", "detunings", "amplitudes_m", "theta_starts"):
            out[k] = list(getattr(self, k))
        return out


def _lowest_points(t: np.ndarray, ydot: np.ndarray) -> np.ndarray:
    """Times [s] of y's lowest points (ydot from - to +, linearly interpolated)."""
    k = np.flatnonzero((ydot[:-1] < 0) & (ydot[1:] >= 0))
    return t[k] + (t[k + 1] - t[k]) * ydot[k] / (ydot[k] - ydot[k + 1])


def settle_and_guess(cavity, x0: np.ndarray, settle_time: float, max_step: float) -> dict:
    """Run from ``x0`` (six states) and return the shooting guess (module docstring, step 2).

    Returns
    -------
    dict
        ``outcome`` (``escaped``, ``folded``, ``rest`` or the classifier's class of the last half), ``lock_ratio``,
        ``amp_y_m``, ``amp_theta`` and, for a run to shoot, ``x_guess`` (the state at the run's last sample before
        a lowest point of y, with ydot = 0), ``p`` and ``period_guess`` [s] (p periods of y).
    """
    from ..dynamics.resonator import integrate_coupled

    dt = 1e-3
    run = integrate_coupled(cavity, x0[:4], complex(x0[4], x0[5]), settle_time, dt, max_step=max_step)
    if not run.ok:
        return {"outcome": "folded" if run.status == 2 else "escaped", "t_end_s": float(run.t[-1])}
    half = run.t.size // 2
    c = classify_trajectory(run.t, run.state, start_fraction=0.5)
    amp_y = float(0.5 * np.ptp(run.state[-int(1.0 / dt):, 0]))
    res = {"outcome": c.label, "lock_ratio": c.lock_ratio, "amp_y_m": amp_y, "amp_theta": float(c.amp_theta)}
    if amp_y < Y_REST:
        return {**res, "outcome": "rest"}
    lows = _lowest_points(run.t[half:], run.state[half:, 1])
    if lows.size < 3:
        return {**res, "outcome": "rest"}
    t_y = float(np.mean(np.diff(lows[-min(lows.size, 20):])))
    p = int(c.lock_ratio.split(":")[0]) if c.label == "locked-p:q" else 1
    k = int(np.searchsorted(run.t, lows[-1])) - 1  # the sample just before the last lowest point
    x_guess = np.concatenate([run.state[k], [run.mode[k].real, run.mode[k].imag]])
    x_guess[1] = 0.0  # the section exactly at y's lowest point: every orbit's record starts at the same phase
    return {**res, "x_guess": x_guess, "p": p, "period_guess": p * t_y}


def orbit_record(cavity, orbit, p: int, samples_per_period: int, max_step: float) -> dict:
    """What the map records of a converged orbit (:class:`acousim.dynamics.periodic_orbits.PeriodicOrbit` of p
    periods of y): ``period_s``, ``p``, ``x0``, the amplitudes (half the range over the orbit) ``amp_y_m`` and
    ``amp_theta``, ``theta_mean``, the class and ``lock_ratio`` of the orbit repeated (the suite's classifier),
    ``f_theta_over_f_y`` (theta's dominant line over y's), ``share_2fy`` (theta's 2 f_y Fourier coefficient over its
    f_y one), ``multipliers`` (|mu| of the non-trivial ones, largest first), ``max_multiplier``, ``stable``,
    ``trivial_error`` (|mu_trivial - 1|), ``flow_invariance``, ``residual`` and ``e_fold_cycles`` (cycles of y over
    which a perturbation along the largest non-trivial multiplier grows or decays by e: p / |ln |mu_max||)."""
    from ..dynamics.resonator import integrate_coupled

    n = p * samples_per_period
    dt = orbit.period / n
    rec = integrate_coupled(cavity, orbit.x0[:4], complex(orbit.x0[4], orbit.x0[5]), orbit.period - dt, dt,
                            max_step=max_step)
    one = rec.state[:n]
    tiled = np.tile(one, (_CLASSIFY_REPEATS, 1))
    t = np.arange(tiled.shape[0]) * dt
    c = classify_trajectory(t, tiled, start_fraction=0.0)
    coef = np.fft.rfft(one[:, 2]) / n
    share = float(abs(coef[2 * p]) / abs(coef[p])) if abs(coef[p]) > 0 else float("nan")
    mus = np.abs(orbit.multipliers)
    return {"period_s": float(orbit.period), "p": int(p), "x0": [float(v) for v in orbit.x0],
            "amp_y_m": float(0.5 * np.ptp(one[:, 0])), "amp_theta": float(0.5 * np.ptp(one[:, 2])),
            "theta_mean": float(np.mean(one[:, 2])), "class": c.label, "lock_ratio": c.lock_ratio,
            "f_theta_over_f_y": float(c.f_theta / c.f_y) if c.f_y > 0 else float("nan"), "share_2fy": share,
            "multipliers": [float(v) for v in mus], "max_multiplier": orbit.max_multiplier, "stable": orbit.stable,
            "trivial_error": float(abs(orbit.trivial_multiplier - 1.0)),
            "flow_invariance": float(orbit.flow_invariance), "residual": float(orbit.residual),
            "e_fold_cycles": float(p * orbit.e_fold_periods)}


def same_orbit(a: dict, b: dict, rel: float = 1e-4) -> bool:
    """Two :func:`orbit_record` s of one orbit: period, y amplitude, theta amplitude and mean equal to ``rel`` of
    their size (y amplitudes below 1 um and hinge values below 1e-3 / 1e-2 count as those sizes)."""
    return (abs(a["period_s"] - b["period_s"]) <= rel * b["period_s"]
            and abs(a["amp_y_m"] - b["amp_y_m"]) <= rel * max(b["amp_y_m"], 1e-6)
            and abs(a["amp_theta"] - b["amp_theta"]) <= rel * max(b["amp_theta"], 1e-3)
            and abs(a["theta_mean"] - b["theta_mean"]) <= rel * max(abs(b["theta_mean"]), 1e-2))


def distinct_orbits(orbits: list[dict], rel: float = 1e-4) -> list[dict]:
    """The orbits that differ (:func:`same_orbit`), each with ``starts``: how many of the given orbits it stands
    for."""
    out: list[dict] = []
    for o in orbits:
        match = next((d for d in out if same_orbit(o, d, rel)), None)
        if match is None:
            out.append({**o, "starts": 1})
        else:
            match["starts"] += 1
    return out


def orbit_scale(omega_y: float) -> np.ndarray:
    """The sizes of the six states in the shooting (100 um, 0.1 of the hinge, |a| = 1; rates times w_y)."""
    return np.array([1e-4, omega_y * 1e-4, 0.1, omega_y * 0.1, 1.0, 1.0])


def free_y_cell(dimer: AtlasDimer, quality_factor: float, detuning: float, config: FreeYConfig) -> dict:
    """Every start of one cell settled and shot, and the distinct periodic orbits (module docstring).

    Returns
    -------
    dict
        The cell's settings; ``f_y_hz``, ``f_theta_hz``, ``r`` (linear, about the equilibrium); ``band`` (the linear
        theory's unstable band of x, :mod:`acousim.dynamics.cavity_stability`) and ``growth_at_rest`` [1/s];
        ``runs`` (one per start: the settled outcome, and ``converged`` / ``orbit`` index where shot); ``orbits``
        (:func:`orbit_record` plus ``starts``); ``seconds``.
    """
    from ..dynamics.cavity_stability import LinearCavityCoupling
    from ..dynamics.periodic_orbits import shoot_periodic_orbit
    from ..dynamics.resonator import CavityMode, CoupledCavity, coupled_flow
    from ..medium import Medium

    t0 = time.perf_counter()
    dyn = atlas_dynamics(dimer.side, dimer.gap_ratio, config.pressure_pa, config.frequency_hz)
    cav = CoupledCavity(dyn, CavityMode(quality_factor, detuning, config.area_m2),
                        Medium(frequency_hz=config.frequency_hz))
    f_y, f_theta = dyn.force_model.linear_frequencies()
    gamma_y = float(dyn.effects["air_damping"].gamma_y)
    lin = LinearCavityCoupling.from_cavity(cav, gamma_y=gamma_y)
    band = lin.unstable_detunings() or (float("nan"), float("nan"))
    eq = dyn.equilibrium()
    a_s = cav.mode.steady_amplitude()
    scale = orbit_scale(2 * math.pi * f_y)
    h = cav.max_step(config.max_step)
    runs, found = [], []
    for amp, th0 in config.starts():
        x0 = np.array([eq[0] - amp, 0.0, th0, 0.0, a_s.real, a_s.imag])
        g = settle_and_guess(cav, x0, config.settle_time, config.max_step)
        run = {"amplitude_m": amp, "theta0": th0, **{k: v for k, v in g.items() if k != "x_guess"}}
        if "x_guess" in g:
            steps = int(math.ceil(g["period_guess"] / h))
            orbit = shoot_periodic_orbit(coupled_flow(cav, steps), g["x_guess"], g["period_guess"], pinned=1,
                                         scale=scale)
            run["converged"] = orbit.converged
            if orbit.converged and orbit.multipliers.size:
                run["orbit"] = len(found)
                found.append(orbit_record(cav, orbit, g["p"], config.samples_per_period, config.max_step))
        runs.append(run)
    orbits = distinct_orbits(found)
    for run in runs:  # the index of the distinct orbit each shot run reached
        if "orbit" in run:
            o = found[run["orbit"]]
            run["orbit"] = next(i for i, d in enumerate(orbits) if same_orbit(o, d))
    return {"dimer": dimer.label, "side_m": dimer.side, "gap_ratio": dimer.gap_ratio, "pressure_pa": config.pressure_pa,
            "quality_factor": quality_factor, "detuning": detuning, "cavity_area_m2": config.area_m2,
            "f_y_hz": f_y, "f_theta_hz": f_theta, "r": f_theta / f_y, "band": list(band),
            "growth_at_rest": lin.growth_rate(), "runs": runs, "orbits": orbits,
            "seconds": time.perf_counter() - t0}


def cell_summary(cell: dict) -> dict:
    """One row of ``free_y.csv`` (:data:`MAP_COLUMNS`): the starts' outcomes, the distinct orbits, the stable ones
    per class (in phase, anti-phase, other), the unstable ones, the largest 2 f_y share of a stable orbit, the range
    of the largest non-trivial |mu| and the largest |mu_trivial - 1|."""
    runs, orbits = cell["runs"], cell["orbits"]
    count = lambda o: sum(r["outcome"] == o for r in runs)  # noqa: E731
    stable = [o for o in orbits if o["stable"]]
    mx = [o["max_multiplier"] for o in orbits]
    nan = float("nan")
    return {**{k: cell[k] for k in ("dimer", "side_m", "gap_ratio", "pressure_pa", "quality_factor", "detuning",
                                     "cavity_area_m2", "f_y_hz", "f_theta_hz", "r", "growth_at_rest", "seconds")},
            "band_low": cell["band"][0], "band_high": cell["band"][1], "starts": len(runs),
            "escaped": count("escaped"), "folded": count("folded"), "rest": count("rest"),
            "not_converged": sum(1 for r in runs if r.get("converged") is False), "orbits": len(orbits),
            "stable": len(stable),
            "stable_in_phase": sum(o["class"] == PHASE_CLASSES[0] for o in stable),
            "stable_anti_phase": sum(o["class"] == PHASE_CLASSES[1] for o in stable),
            "stable_other": sum(o["class"] not in PHASE_CLASSES for o in stable),
            "unstable": len(orbits) - len(stable),
            "max_share_2fy_stable": max((o["share_2fy"] for o in stable), default=nan),
            "min_max_multiplier": min(mx, default=nan), "max_max_multiplier": max(mx, default=nan),
            "max_trivial_error": max((o["trivial_error"] for o in orbits), default=nan)}


# ---------------------------------------------------------------------- the map
def _cell_task(item: tuple) -> dict:
    config, (d, q, x) = item
    return {**free_y_cell(config.dimers[d], config.quality_factors[q], config.detunings[x], config),
            "index": [d, q, x]}


def _cell_path(out: Path, config: FreeYConfig, d: int, q: int, x: int) -> Path:
    return out / "cells" / f"{config.dimers[d].label}_q{q:02d}_x{x:02d}.json"


def run_free_y_map(config: FreeYConfig, out: str | os.PathLike, executor: ExecutorConfig | None = None,
                   progress: bool = True, figures: bool = True, force: bool = False) -> dict:
    """Run (or resume) the free-y map into ``out``; returns the ``free_y.json`` content.

    ``out/free_y_settings.json`` pins the settings (another map in the folder is refused, :class:`AtlasError`, or
    with ``force`` discarded first); finished cells are ``out/cells/*.json`` (written as each finishes, atomically)
    and are skipped on a rerun.  Then ``free_y.csv`` (:func:`cell_summary` per cell), ``free_y.json`` (settings,
    summaries, every cell) and, with ``figures``, ``free_y_map.png``.
    """
    out = Path(out)
    settings = config.to_dict()
    open_study(out, settings, "free_y_settings.json", "a free-y map", force,
               lambda: check_dimers_buildable(config.dimers, (config.pressure_pa,), config.frequency_hz))
    cells = run_resumable_cells(out, config.cells(), lambda c: _cell_path(out, config, *c), _cell_task,
                                lambda c: (config, c), executor, progress, "free-y map")
    rows = [cell_summary(c) for c in cells]
    atomic_write_text(out / "free_y.csv", cells_csv_text(MAP_COLUMNS, rows))
    result = {"settings": settings, "summary": rows, "cells": cells,
              "units": "SI; detuning in half-widths f/(2Q); multipliers per orbit period (p periods of y)"}
    write_json(out / "free_y.json", result)
    if figures:
        from .free_y_figures import write_free_y_figure

        write_free_y_figure(config, rows, out / "free_y_map.png")
    return result
