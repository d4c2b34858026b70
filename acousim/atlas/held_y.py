"""The held-y attractor map: where the hinge settles when y is held on an exact trap oscillation.

In a field drop the hinge's fate is decided while y rings down; holding y on one oscillation separates what the
hinge does at a given y amplitude from how a drop reaches it.  For a dimer of the full-wave family at a pressure
p0, y is held on the trap's exact periodic orbit through its lowest point ``y_eq - A`` (the y equation with the hinge
frozen at its static equilibrium theta* and no damping: :func:`held_y_acceleration`), and the hinge obeys its full
equation (the full-wave torque at the actual (y, theta), Lagrange's inertial term, the air's computed damping).
From a grid of hinge starts (theta0, thetadot0) each run is followed for ``settle_periods`` + ``analysed_periods``
periods of y, with the compiled fixed-step RK4 (:func:`cubedimer.rk4.rk4_batch`), and classified on the last
``analysed_periods`` by the one classifier (:func:`acousim.atlas.field_drops.settled_outcome`, which uses
:func:`cubedimer.attractors.classify_trajectory`); a hinge that reaches +-1 is ``folded``.

For every run that ends locked (at f_y or p:q) the Floquet multipliers of the hinge linearised about its orbit are
computed (:func:`floquet_multipliers`): the monodromy matrix of (theta, thetadot) over the orbit's period p T_y,
by central differences of the compiled flow.  With y held, the hinge is a periodically forced one-degree-of-freedom
system, so its multipliers decide the orbit's stability (|mu| < 1: stable) and their product is exp(-int gamma).

:func:`run_held_y_map` runs the cells (dimer x p0 x A) through :func:`cubedimer.executor.map_ordered`, writes each
finished cell at once and skips those already written (resumable), then writes ``held_y.csv``, ``held_y.json`` and
the figures (:mod:`acousim.atlas.held_y_figures`).  No random choice: the grid is deterministic.
"""
from __future__ import annotations

import logging
import math
import os
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numba as nb
import numpy as np
from numpy.typing import ArrayLike, NDArray

from cubedimer.atomic import atomic_write_text, write_json
from cubedimer.config_checks import check_given, check_in_range, named, raising
from cubedimer.attractors import LOCKED_AT_FY
from cubedimer.executor import ExecutorConfig
from cubedimer.rk4 import rk4, rk4_batch
from cubedimer.meta import DEFAULT_FREQUENCY_HZ

from .field_drops import (AtlasDimer, AtlasError, atlas_dynamics, cells_csv_text, check_dimers_buildable, open_study, run_resumable_cells,
                    settled_outcome)
from ..dynamics.equations import _P_MASS, _P_MG, _P_TWO_K, _P_ZEQ, _chebval, field_on_acceleration

__all__ = ["HeldYConfig", "held_y_acceleration", "held_y_arguments", "y_orbit_period", "held_y_orbits",
           "floquet_multipliers", "integrate_held", "HINGE_BOX",
           "held_y_cell", "cell_summary", "run_held_y_map", "MAP_COLUMNS", "TWO_FY_SHARE", "POPULATED", "CLOSED"]

logger = logging.getLogger(__name__)

#: The 2 f_y criterion: theta's 2 f_y line at least this share of its f_y line (the suite's choice: the paper reports
#: a visible 2 f_y line, with no threshold).
TWO_FY_SHARE = 0.05
#: A class counts as populated in a cell when it holds at least this share of the hinge starts.
POPULATED = 0.15
MAP_COLUMNS = ("dimer", "side_m", "gap_ratio", "pressure_pa", "amplitude_m", "f_y_hz", "f_theta_hz", "r",
               "period_s", "starts", "folded", "in_phase", "anti_phase", "quadrature", "ratio_locked", "independent",
               "at_rest", "two_phase_classes", "third_class", "classes", "max_share_2fy_locked", "reaches_2fy",
               "max_floquet", "unclosed", "seconds")
#: A locked run's orbit counts as closed (a periodic orbit, whose Floquet multipliers are meaningful) when its state
#: repeats after one orbit period to this (relative, ``closure``); larger: a slow modulation (a torus) or a drift.
CLOSED = 1e-3


@dataclass(frozen=True)
class HeldYConfig:
    """The map's grid and settings (SI units).

    Parameters
    ----------
    dimers : tuple of AtlasDimer
        Dimers of the full-wave family.
    pressures_pa : tuple of float
        p0 values [Pa], each > 0.
    amplitudes_m : tuple of float
        Depths A of the held y orbit's lowest point below the equilibrium [m], each in (0, 1e-3].
    theta_starts, thetadot_starts : tuple of float
        The hinge starts: every (theta0 [-], thetadot0 [1/s]) pair, |theta0| < 0.99.
    frequency_hz : float
        Drive frequency [Hz].
    settle_periods, analysed_periods : int
        Periods of y before the classified part, and classified.
    samples_per_period : int
        Samples per period of y (the section and the spectra read them; >= 16).
    max_step : float
        Longest internal RK4 step [s].
    """

    dimers: tuple[AtlasDimer, ...] = field(metadata=named("--dimers"))
    pressures_pa: tuple[float, ...] = field(metadata=named("--pressures"))
    amplitudes_m: tuple[float, ...] = field(metadata=named("--amplitudes"))
    theta_starts: tuple[float, ...] = field(default=(-0.4, -0.2, 0.0, 0.2, 0.4), metadata=named("--theta-starts"))
    thetadot_starts: tuple[float, ...] = field(default=(-30.0, 0.0, 30.0), metadata=named("--thetadot-starts"))
    frequency_hz: float = field(default=DEFAULT_FREQUENCY_HZ, metadata=named("--frequency"))
    settle_periods: int = field(default=200, metadata=named("--settle-periods"))
    analysed_periods: int = field(default=104, metadata=named("--analysed-periods"))
    samples_per_period: int = field(default=40, metadata=named("--samples-per-period"))
    max_step: float = field(default=1e-4, metadata=named("--max-step"))

    def __post_init__(self) -> None:
        with raising(AtlasError):
            check_given(self, "dimers", "SIDE:GAP_RATIO pair")
            check_in_range(self, "pressures_pa", 0.0, 1e5, low_open=True, unit="Pa", each=True)
            check_in_range(self, "amplitudes_m", 0.0, 1e-3, low_open=True, unit="m", each=True)
            check_in_range(self, "theta_starts", -0.99, 0.99, low_open=True, high_open=True, each=True)
            check_in_range(self, "thetadot_starts", -1e3, 1e3, unit="1/s", each=True)
            check_in_range(self, "frequency_hz", 1e3, 1e6, unit="Hz")
            for name, low in (("settle_periods", 0), ("analysed_periods", 8), ("samples_per_period", 16)):
                check_in_range(self, name, low, 100_000, whole=True)
            check_in_range(self, "max_step", 0.0, 1e-3, low_open=True, unit="s")

    def cells(self) -> list[tuple[int, int, int]]:
        """(dimer, pressure, amplitude) indices of every cell."""
        return [(d, p, a) for d in range(len(self.dimers)) for p in range(len(self.pressures_pa))
                for a in range(len(self.amplitudes_m))]

    def starts(self) -> list[tuple[float, float]]:
        return [(th, thd) for th in self.theta_starts for thd in self.thetadot_starts]

    def to_dict(self) -> dict:
        out = asdict(self)
        out["dimers"] = [asdict(d) for d in self.dimers]
        for k in ("pressures_pa", "amplitudes_m", "theta_starts", "thetadot_starts"):
            out[k] = list(getattr(self, k))
        return out


# ---------------------------------------------------------------------- the held system
@nb.njit(cache=True)
def held_y_acceleration(t, y, ydot, theta, thetadot, args):
    """(yddot, thetaddot) with y held: y obeys the trap at the frozen hinge angle theta* without effects, the
    hinge its full equation.  ``args = (hinge args, (A_y, B_y, C_y) at theta*, theta*)`` (:func:`held_y_arguments`):
    the y force at theta* is ``A_y + B_y cos 2kZ + C_y sin 2kZ - M g``, the kernel's own series evaluated once."""
    args_hinge, y_series, theta_star = args
    par = args_hinge[6]
    z = par[_P_ZEQ] + y
    c, s = np.cos(par[_P_TWO_K] * z), np.sin(par[_P_TWO_K] * z)
    ay = (y_series[0] + y_series[1] * c + y_series[2] * s - par[_P_MG]) / par[_P_MASS]
    _, at = field_on_acceleration(t, y, ydot, theta, thetadot, args_hinge)
    return ay, at


@nb.njit(cache=True)
def integrate_held(args, x0, h, substeps, n_out, lower, upper, out):
    """:func:`cubedimer.rk4.rk4` of :func:`held_y_acceleration`: the hinge on the prescribed y orbit."""
    return rk4(held_y_acceleration, args, x0, h, substeps, n_out, lower, upper, out)


@nb.njit(cache=True)
def _integrate_held_batch(args, x0s, h, substeps, n_out, lower, upper, out, n_valid, status):
    rk4_batch(held_y_acceleration, args, x0s, h, substeps, n_out, lower, upper, out, n_valid, status)


def held_y_arguments(dynamics) -> tuple[tuple, NDArray[np.float64]]:
    """(kernel ``args`` of :func:`held_y_acceleration`, the static equilibrium [y, 0, theta*, 0]) of a
    :class:`~acousim.dynamics.integrator.DimerDynamics`."""
    eq = dynamics.equilibrium()
    a_y, b_y, c_y = dynamics._args_on[:3]
    y_series = np.array([_chebval(c, float(eq[2])) for c in (a_y, b_y, c_y)])
    return (dynamics._args_on, y_series, float(eq[2])), eq


#: The state box of the held-y integrations: theta within +-1 (the faces touch at +-1), the rest unbounded.
HINGE_BOX = (np.array([-np.inf, -np.inf, -np.nextafter(1.0, 0.0), -np.inf]),
        np.array([np.inf, np.inf, np.nextafter(1.0, 0.0), np.inf]))


def y_orbit_period(args: tuple, y_start: float, f_guess: float, max_step: float = 2e-5) -> float:
    """The period [s] of the held y orbit from (y_start, ydot = 0): the time between its lowest points, read from
    the sign changes of ydot (from - to +) sampled every ``max_step``, linearly interpolated (error ~1e-12 s)."""
    n = int(math.ceil(2.6 / f_guess / max_step)) + 1
    out = np.empty((n, 4))
    x0 = np.array([y_start, 0.0, args[2], 0.0])
    m, _ = integrate_held(args, x0, max_step, 1, n, *HINGE_BOX, out)
    yd = out[:m, 1]
    k = np.nonzero((yd[:-1] < 0) & (yd[1:] >= 0))[0]
    if k.size < 2:
        raise ValueError("the held y orbit did not return to its lowest point within 2.6 guessed periods")
    times = (k + yd[k] / (yd[k] - yd[k + 1])) * max_step
    return float(times[1] - times[0])


def floquet_multipliers(integrate, args, x_orbit: ArrayLike, period: float, steps: int,
                        eps: float = 1e-6) -> NDArray[np.complex128]:
    """The Floquet multipliers of the hinge (theta, thetadot) about a periodic orbit.

    The monodromy matrix M[i, j] = d(theta, thetadot)_i(T) / d(theta, thetadot)_j(0) by central differences of the
    flow over one period (``steps`` RK4 steps of ``integrate``, a compiled entry point with the signature of
    :func:`cubedimer.rk4.rk4`'s drivers), y and ydot unperturbed (:func:`acousim.dynamics.periodic_orbits.monodromy_matrix`'s
    block); its eigenvalues are the multipliers.  With
    relative steps ``eps`` the error is O(eps^2) of M's curvature plus the integrator's.

    Parameters
    ----------
    integrate : numba dispatcher
        ``integrate(args, x0, h, substeps, n_out, lower, upper, out) -> (n_valid, status)``.
    args : tuple
        Its model arguments.
    x_orbit : array_like (4,)
        A state on the orbit, at the phase where the period starts.
    period : float
        The orbit's period (the forcing's period times p for a p:q lock) [s].
    steps : int
        RK4 steps over the period.
    """
    from ..dynamics.periodic_orbits import monodromy_matrix

    x = np.asarray(x_orbit, float)

    def flow(x0, t):
        out = np.empty((2, 4))
        n, _ = integrate(args, x0, t / steps, steps, 2, *HINGE_BOX, out)
        return out[1] if n == 2 else np.full(4, np.nan)

    m = monodromy_matrix(flow, x, period, np.array([1.0, 1.0, 1.0, max(1.0, abs(x[3]))]), eps, components=(2, 3))
    return np.linalg.eigvals(m) if np.all(np.isfinite(m)) else np.full(2, np.nan + 0j)


def held_y_orbits(dynamics, amplitude_m: float, starts, periods: int, samples_per_period: int = 40,
                  max_step: float = 1e-4) -> tuple:
    """Integrate the held system from every hinge start (one compiled call).

    Parameters
    ----------
    dynamics : acousim.dynamics.integrator.DimerDynamics
    amplitude_m : float
        Depth of the held y orbit's lowest point below the equilibrium [m].
    starts : sequence of (theta0, thetadot0)
        Hinge starts at y's lowest point.
    periods, samples_per_period : int
        Periods of y integrated and samples per period.
    max_step : float
        Longest internal RK4 step [s].

    Returns
    -------
    (t, states (B, n, 4), n_valid (B,), status (B,), period [s], kernel args, RK4 substeps per sample)
        Rows of ``states`` from ``n_valid`` on are NaN; a non-zero status is a fold (theta = +-1).
    """
    f_y, _ = dynamics.force_model.linear_frequencies()
    args, eq = held_y_arguments(dynamics)
    y_start = float(eq[0]) - amplitude_m
    period = y_orbit_period(args, y_start, f_y)
    dt_out = period / samples_per_period
    substeps = max(1, int(math.ceil(dt_out / max_step - 1e-9)))
    n_out = periods * samples_per_period + 1
    x0s = np.array([[y_start, 0.0, th, thd] for th, thd in starts])
    b = len(x0s)
    out = np.full((b, n_out, 4), np.nan)
    n_valid, status = np.zeros(b, np.int64), np.zeros(b, np.int64)
    lower, upper = (np.tile(v, (b, 1)) for v in HINGE_BOX)
    _integrate_held_batch(args, x0s, np.full(b, dt_out / substeps), substeps, np.full(b, n_out), lower, upper, out,
                          n_valid, status)
    return np.arange(n_out) * dt_out, out, n_valid, status, period, args, substeps


# ---------------------------------------------------------------------- one cell
def held_y_cell(dimer: AtlasDimer, pressure_pa: float, amplitude_m: float, config: HeldYConfig) -> dict:
    """Every hinge start of one cell, classified, with the Floquet multipliers of the locked orbits.

    Returns
    -------
    dict
        The cell's settings, ``f_y_hz``, ``f_theta_hz`` and ``r`` (the linear frequencies about the equilibrium and
        their ratio), ``period_s`` (of the held y orbit), ``runs`` (one dict per start: ``theta0``, ``thetadot0``,
        ``outcome``, ``lock_ratio``, ``amp_theta``, ``amplitude_class``, ``section_phase_deg``, ``share_2fy``,
        ``long_lived``, ``floquet`` (|mu| of the two multipliers, locked runs only) and ``closure`` (how far the
        state is from repeating after one orbit period, relative)), and ``seconds`` (wall time).
    """
    import time

    t0 = time.perf_counter()
    dyn = atlas_dynamics(dimer.side, dimer.gap_ratio, pressure_pa, config.frequency_hz)
    f_y, f_theta = dyn.force_model.linear_frequencies()
    starts = config.starts()
    n_per = int(config.samples_per_period)
    periods = int(config.settle_periods) + int(config.analysed_periods)
    t, out, n_valid, status, period, args, substeps = held_y_orbits(dyn, amplitude_m, starts, periods, n_per,
                                                                    config.max_step)
    n_out = t.size
    keep = 2 * int(config.analysed_periods) * n_per  # settled_outcome classifies the second half of what it gets
    runs = []
    for k, (th0, thd0) in enumerate(starts):
        run = {"theta0": th0, "thetadot0": thd0}
        if status[k] != 0:
            runs.append({**run, "outcome": "folded", "t_end_s": float(t[n_valid[k] - 1])})
            continue
        x = out[k, n_out - keep:]
        res = settled_outcome(t[n_out - keep:], x)
        res = {key: res[key] for key in ("outcome", "lock_ratio", "amp_theta", "amplitude_class",
                                         "section_phase_deg", "share_2fy", "long_lived", "f_theta_hz")}
        if res["outcome"] in LOCKED_AT_FY or res["outcome"] == "locked-p:q":
            p = int(res["lock_ratio"].split(":")[0]) if res["lock_ratio"] else 1
            x_end, x_back = out[k, n_out - 1], out[k, n_out - 1 - p * n_per]
            mu = floquet_multipliers(integrate_held, args, x_end, p * period, p * n_per * substeps)
            res["floquet"] = [float(v) for v in np.sort(np.abs(mu))[::-1]]
            res["closure"] = float(np.max(np.abs(x_end[2:] - x_back[2:]) / np.array([1.0, 2 * np.pi * f_y])))
        runs.append({**run, **res})
    return {"dimer": dimer.label, "side_m": dimer.side, "gap_ratio": dimer.gap_ratio, "pressure_pa": pressure_pa,
            "amplitude_m": amplitude_m, "f_y_hz": f_y, "f_theta_hz": f_theta, "r": f_theta / f_y,
            "period_s": period, "runs": runs, "seconds": time.perf_counter() - t0}


def cell_summary(cell: dict) -> dict:
    """One row of ``held_y.csv`` (:data:`MAP_COLUMNS`): the counts per class over the cell's hinge starts,
    ``two_phase_classes`` (in phase and anti-phase each >= :data:`POPULATED` of the starts), ``third_class``
    (a long-lived state beyond those two: a p:q lock, quadrature, or a second amplitude class of a phase class),
    ``classes`` (the distinct long-lived (class, amplitude class) pairs), ``max_share_2fy_locked`` and
    ``reaches_2fy`` (>= :data:`TWO_FY_SHARE` in a run locked at f_y), ``max_floquet`` (the largest |mu| over
    the locked runs whose orbit closes to :data:`CLOSED`: < 1 for stable orbits) and ``unclosed`` (locked runs
    whose orbit does not close: a slowly modulated lock, for which multipliers are not defined)."""
    runs = cell["runs"]
    n = len(runs)
    count = lambda o: sum(r["outcome"] == o for r in runs)
    inp, anti = count("locked-in-phase"), count("locked-anti-phase")
    long_lived = [r for r in runs if r.get("long_lived")]
    name = lambda r: r["outcome"] + (f" {r['lock_ratio']}" if r["outcome"] == "locked-p:q" else "")
    classes = sorted({(name(r), r["amplitude_class"]) for r in long_lived})
    phase = [c for c in classes if c[0] in ("locked-in-phase", "locked-anti-phase")]
    others = [c for c in classes if c[0] not in ("locked-in-phase", "locked-anti-phase", "theta-at-rest",
                                                   "independent")]
    two = bool(n and inp >= POPULATED * n and anti >= POPULATED * n)
    third = bool(others) or len(phase) > len({c[0] for c in phase})
    shares = [r["share_2fy"] for r in runs if r["outcome"] in LOCKED_AT_FY and np.isfinite(r.get("share_2fy", np.nan))]
    flo = [r["floquet"][0] for r in runs if r.get("floquet") and r["closure"] < CLOSED]
    unclosed = sum(1 for r in runs if r.get("floquet") and not r["closure"] < CLOSED)
    return {**{k: cell[k] for k in ("dimer", "side_m", "gap_ratio", "pressure_pa", "amplitude_m", "f_y_hz",
                                     "f_theta_hz", "r", "period_s", "seconds")},
            "starts": n, "folded": count("folded"), "in_phase": inp, "anti_phase": anti,
            "quadrature": count("locked-quadrature"), "ratio_locked": count("locked-p:q"),
            "independent": count("independent"), "at_rest": count("theta-at-rest"),
            "two_phase_classes": two, "third_class": third, "classes": "; ".join(f"{a}/{b}" for a, b in classes),
            "max_share_2fy_locked": max(shares) if shares else float("nan"),
            "reaches_2fy": bool(shares and max(shares) >= TWO_FY_SHARE),
            "max_floquet": max(flo) if flo else float("nan"), "unclosed": unclosed}


# ---------------------------------------------------------------------- the map
def _cell_task(item: tuple) -> dict:
    config, (d, p, a) = item
    return {**held_y_cell(config.dimers[d], config.pressures_pa[p], config.amplitudes_m[a], config), "index": [d, p, a]}


def _cell_path(out: Path, config: HeldYConfig, d: int, p: int, a: int) -> Path:
    return out / "cells" / f"{config.dimers[d].label}_p{p:02d}_a{a:02d}.json"


def run_held_y_map(config: HeldYConfig, out: str | os.PathLike, executor: ExecutorConfig | None = None,
                   progress: bool = True, figures: bool = True, force: bool = False) -> dict:
    """Run (or resume) the held-y map into ``out``; returns the ``held_y.json`` content.

    ``out/held_y_settings.json`` pins the settings (another map in the folder is refused, :class:`AtlasError`, or
    with ``force`` discarded first);
    finished cells are ``out/cells/*.json`` (written as each finishes, atomically) and are skipped on a rerun.
    Then ``held_y.csv`` (:func:`cell_summary` per cell), ``held_y.json`` (settings, the summaries, every cell)
    and, with ``figures``, :func:`acousim.atlas.held_y_figures.write_held_y_figures`.
    """
    out = Path(out)
    settings = config.to_dict()
    open_study(out, settings, "held_y_settings.json", "a held-y map", force,
               lambda: check_dimers_buildable(config.dimers, config.pressures_pa, config.frequency_hz))
    cells = run_resumable_cells(out, config.cells(), lambda c: _cell_path(out, config, *c), _cell_task,
                                lambda c: (config, c), executor, progress, "held-y map")
    rows = [cell_summary(c) for c in cells]
    atomic_write_text(out / "held_y.csv", cells_csv_text(MAP_COLUMNS, rows))
    result = {"settings": settings, "summary": rows, "cells": cells, "units": "SI"}
    write_json(out / "held_y.json", result)
    if figures:
        from .held_y_figures import write_held_y_figures

        write_held_y_figures(config, rows, out)
    return result
