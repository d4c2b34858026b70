"""The attractor atlas: where field drops of a full-wave dimer settle, over the drop and the hinge's start.

A grid of field drops per dimer (drop duration ``t_off`` x hinge angle when the field drops, the dimer at rest
at its levitation height, the hinge at rest) on the full-wave model of a dimer of the table family, with the
air's computed damping (:mod:`acousim.dynamics.air_damping`) and no other effect.  Each cell's run is classified once its
transient has decayed by the one classifier of the suite (:func:`cubedimer.attractors.classify_trajectory`),
and :func:`settled_outcome` adds what the source paper reports:

* the outcome: ``escaped`` (out of the trap), ``folded`` (the faces touch), or the classifier's class
  (``locked-in-phase``, ``locked-anti-phase``, ``locked-quadrature``, ``independent``, ``theta-at-rest``);
* the amplitude class of the hinge (:data:`AMPLITUDE_CLASSES`);
* the share of theta's 2 f_y line in its f_y line;
* whether the settled state is long-lived: the same class in the third and the last quarter of the run, over at
  least :data:`LONG_LIVED_CYCLES` cycles of y.

:func:`run_atlas` runs the cells through :func:`cubedimer.executor.map_ordered`, writes each finished cell at
once (atomically) and skips the cells already written, so that an interrupted atlas resumes; then it writes the
table (``atlas.csv``, ``atlas.json``) and the figures (:mod:`acousim.atlas.field_drop_figures`).  No random choice: the
grid is deterministic.
"""
from __future__ import annotations

import json
import logging
import math
import os
import shutil
from dataclasses import asdict, dataclass, field
from functools import lru_cache
from pathlib import Path
from typing import Callable

import numpy as np

from cubedimer.atomic import atomic_write_text, json_text, write_json
from cubedimer.attractors import ATTRACTOR_CLASSES, LOCKED_AT_FY, classify_trajectory
from cubedimer.config_checks import check_given, check_in_range, named, raising
from cubedimer.executor import ExecutorConfig, map_ordered
from cubedimer.spectra import line_amplitude
from cubedimer.meta import DEFAULT_FREQUENCY_HZ

__all__ = ["AtlasError", "AtlasDimer", "AtlasConfig", "OUTCOMES", "AMPLITUDE_CLASSES", "LONG_LIVED_CYCLES",
           "atlas_dynamics", "drop_and_settle", "settled_outcome", "observations", "run_atlas", "CSV_COLUMNS"]

logger = logging.getLogger(__name__)

#: Every outcome of a cell: the two failures, then the classifier's classes.
OUTCOMES = ("escaped", "folded") + ATTRACTOR_CLASSES
#: Hinge amplitude classes (half the 1-99 % range of theta): (name, upper bound).
AMPLITUDE_CLASSES = (("small", 0.05), ("medium", 0.3), ("large", math.inf))
#: Cycles of y a settled class must persist over to count as long-lived.
LONG_LIVED_CYCLES = 100
CSV_COLUMNS = ("dimer", "side_m", "gap_ratio", "t_off_s", "theta_drop", "outcome", "t_end_s", "f_y_hz", "f_theta_hz",
               "amp_y_m", "amp_theta", "amplitude_class", "section_phase_deg", "coherence", "lock_ratio", "share_2fy",
               "long_lived", "cycles")


class AtlasError(ValueError):
    """A bad atlas setting; ``str(err)`` is one line naming the option and its valid range."""


@dataclass(frozen=True)
class AtlasDimer:
    """A dimer of the atlas: cube side [m] and hinge gap over side [-] (inside the full-wave family)."""

    side: float = field(metadata=named("--dimers: the side"))
    gap_ratio: float = field(metadata=named("--dimers: the gap ratio"))

    def __post_init__(self) -> None:
        with raising(AtlasError):
            check_in_range(self, "side", 50e-6, 2e-3, unit="m")
            check_in_range(self, "gap_ratio", 0.0, 0.5, low_open=True)

    @property
    def label(self) -> str:
        return f"s{self.side * 1e6:.0f}um_g{self.gap_ratio:g}"


@dataclass(frozen=True)
class AtlasConfig:
    """The atlas's grid and settings (SI units).

    Parameters
    ----------
    dimers : tuple of AtlasDimer
    t_off : tuple of float
        Drop durations [s], each in [0, 0.03].
    theta_drop : tuple of float
        Hinge angles when the field drops [-], each in (-0.99, 0.99).
    pressure_amplitude_pa : float
        p0 [Pa].
    frequency_hz : float
        Drive frequency [Hz].
    duration : float
        Recorded time after the field is back on [s] (>= 1).
    sample_rate : float
        Samples per second of the classified motion [1/s] (>= 8 f_y is needed for the 2 f_y line; >= 200).
    transducer_q : float
        The transducer's quality factor (the field's ring time Q / (pi f), :mod:`acousim.dynamics.switching`; 0: instant).
    """

    dimers: tuple[AtlasDimer, ...] = field(metadata=named("--dimers"))
    t_off: tuple[float, ...] = field(metadata=named("--t-off"))
    theta_drop: tuple[float, ...] = field(metadata=named("--theta-drop"))
    pressure_amplitude_pa: float = field(default=6000.0, metadata=named("--pressure"))
    frequency_hz: float = field(default=DEFAULT_FREQUENCY_HZ, metadata=named("--frequency"))
    duration: float = field(default=8.0, metadata=named("--duration"))
    sample_rate: float = field(default=1000.0, metadata=named("--sample-rate"))
    transducer_q: float = field(default=0.0, metadata=named("--transducer-q"))

    def __post_init__(self) -> None:
        with raising(AtlasError):
            check_in_range(self, "transducer_q", 0.0, 1e5)  # 0: instant switching
            check_given(self, "dimers", "SIDE:GAP_RATIO pair")
            check_in_range(self, "t_off", 0.0, 0.03, unit="s", each=True)
            check_in_range(self, "theta_drop", -0.99, 0.99, low_open=True, high_open=True, each=True)
            check_in_range(self, "pressure_amplitude_pa", 0.0, 1e5, low_open=True, unit="Pa")
            check_in_range(self, "frequency_hz", 1e3, 1e6, unit="Hz")
            check_in_range(self, "duration", 1.0, 120.0, unit="s")
            check_in_range(self, "sample_rate", 200.0, 20_000.0, unit="1/s")

    def cells(self) -> list[tuple[int, int, int]]:
        """(dimer, t_off, theta_drop) indices of every cell, dimer by dimer."""
        return [(d, i, j) for d in range(len(self.dimers)) for i in range(len(self.t_off))
                for j in range(len(self.theta_drop))]

    def to_dict(self) -> dict:
        out = asdict(self)
        out["dimers"] = [asdict(d) for d in self.dimers]
        out["t_off"] = list(self.t_off)
        out["theta_drop"] = list(self.theta_drop)
        if self.transducer_q == 0:  # an instant switch pins the folder as before the ring time existed
            del out["transducer_q"]
        return out


@lru_cache(maxsize=8)
def atlas_dynamics(side: float, gap_ratio: float, pressure_amplitude_pa: float, frequency_hz: float):
    """The full-wave dynamics of a dimer with the air's computed damping (cached per process).

    Raises
    ------
    ValueError
        A dimer outside the table family, or a field that does not hold it (one line).
    """
    from ..dynamics.integrator import DimerDynamics
    from ..dynamics.effects import EffectSet, air_damping_for
    from ..fullwave.statics import MODEL_NAME
    from ..models import ExperimentConditions, dynamic_model

    conditions = ExperimentConditions(side_length_m=side, gap_m=gap_ratio * side, frequency_hz=frequency_hz,
                                      pressure_amplitude_pa=pressure_amplitude_pa)
    model = dynamic_model(MODEL_NAME, conditions)
    return DimerDynamics(model, EffectSet((air_damping_for(model, conditions),)))


def _amplitude_class(amp_theta: float) -> str:
    return next(name for name, upper in AMPLITUDE_CLASSES if amp_theta < upper)


def settled_outcome(t: np.ndarray, state: np.ndarray) -> dict:
    """What a run that stayed trapped and hinged settles on (the classifier plus the paper's observables).

    Parameters
    ----------
    t : ndarray (n,)
        Uniform times [s] from the moment the field is back on.
    state : ndarray (n, 4)
        [y, ydot, theta, thetadot].

    Returns
    -------
    dict
        ``outcome`` (the class of the second half), ``f_y_hz``, ``f_theta_hz``, ``amp_y_m``, ``amp_theta``,
        ``amplitude_class``, ``section_phase_deg``, ``coherence``, ``lock_ratio`` (``"p:q"`` of a lock, ``""``
        otherwise), ``share_2fy`` (theta's line at 2 f_y over its
        line at f_y, second half), ``long_lived`` (the third and the last quarter have the same class and span
        at least :data:`LONG_LIVED_CYCLES` cycles of y together) and ``cycles`` (cycles of y in the second half).
    """
    c = classify_trajectory(t, state, start_fraction=0.5)
    n = len(t)
    third = classify_trajectory(t[: 3 * n // 4], state[: 3 * n // 4], start_fraction=2 / 3)
    last = classify_trajectory(t, state, start_fraction=0.75)
    dt = float(t[1] - t[0])
    half = state[n // 2:, 2]
    at_fy = line_amplitude(half, dt, c.f_y) if c.f_y > 0 else 0.0
    at_2fy = line_amplitude(half, dt, 2 * c.f_y) if c.f_y > 0 else 0.0
    cycles = c.f_y * (t[-1] - t[n // 2])
    return {"outcome": c.label, "f_y_hz": c.f_y, "f_theta_hz": c.f_theta, "amp_y_m": c.amp_y, "amp_theta": c.amp_theta,
            "amplitude_class": _amplitude_class(c.amp_theta),
            "section_phase_deg": float(np.degrees(c.section_phase)) if np.isfinite(c.section_phase) else float("nan"),
            "coherence": c.coherence, "lock_ratio": c.lock_ratio, "share_2fy": at_2fy / at_fy if at_fy > 0 else float("nan"),
            "long_lived": bool(third.label == last.label == c.label and cycles >= LONG_LIVED_CYCLES),
            "cycles": float(cycles)}


def drop_and_settle(dynamics, t_off: float, theta_drop: float, duration: float, sample_rate: float,
                    thetadot_drop: float = 0.0, ring_time_s: float = 0.0, cavity=None) -> dict:
    """One field drop from rest at the levitation height and what it settles on.

    The drive is off for ``t_off`` [s] (free fall, free hinge, the air's damping acting; with a ring time
    ``ring_time_s`` [s] the field rings down and back up, :mod:`acousim.dynamics.switching`), then on for ``duration`` [s],
    sampled at ``sample_rate`` [1/s].  Returns the :func:`settled_outcome` dict, or
    ``{"outcome": "escaped" | "folded", "t_end_s": time after the field came back}`` for a run that left the trap
    or whose faces touched (``t_end_s`` is NaN for a completed run, ``-t_off`` for one lost during the drop).
    With a coupled cavity (:class:`acousim.dynamics.resonator.CoupledCavity`, built on ``dynamics``) the drop is
    :func:`acousim.dynamics.resonator.coupled_field_drop` (``ring_time_s`` must then be 0).
    """
    from ..dynamics.resonator import coupled_field_drop
    from ..dynamics.switching import field_drop

    x_drop = [0.0, 0.0, float(theta_drop), float(thetadot_drop)]
    if cavity is not None:
        if ring_time_s:
            raise ValueError("a coupled cavity has its own ring time: give ring_time_s = 0")
        motion = coupled_field_drop(cavity, x_drop, t_off, duration, 1.0 / sample_rate)
    else:
        motion = field_drop(dynamics, x_drop, t_off, duration, 1.0 / sample_rate, tau=ring_time_s)
    if not motion.ok:
        return {"outcome": "folded" if motion.status == 2 else "escaped", "t_end_s": float(motion.t_stop)}
    traj = motion.trajectory
    return {**settled_outcome(traj.t, traj.state), "t_end_s": float("nan")}


def _cell_task(item: tuple) -> dict:
    config, (d, i, j) = item
    dimer = config.dimers[d]
    dyn = atlas_dynamics(dimer.side, dimer.gap_ratio, config.pressure_amplitude_pa, config.frequency_hz)
    res = drop_and_settle(dyn, config.t_off[i], config.theta_drop[j], config.duration, config.sample_rate,
                          ring_time_s=config.transducer_q / (math.pi * config.frequency_hz))
    return {"dimer": dimer.label, "side_m": dimer.side, "gap_ratio": dimer.gap_ratio, "t_off_s": config.t_off[i],
            "theta_drop": config.theta_drop[j], "index": [d, i, j], **res}


def observations(cells: list[dict]) -> dict:
    """The source paper's observations over a set of runs (:func:`drop_and_settle` results).

    Returns the counts and fractions, over all runs: ``trapped`` (neither escaped nor folded), ``locked_at_fy``
    (theta's strongest line at f_y: a class of :data:`cubedimer.attractors.LOCKED_AT_FY`), ``locked_ratio`` (a
    ``locked-p:q`` lock) with ``lock_ratios`` (runs per ratio), ``with_2fy`` (of every lock, at f_y or p:q, a 2 f_y
    line >= 5 % of the f_y one) and ``with_2fy_at_fy`` (of the locks at f_y only), ``in_phase`` and ``anti_phase``
    (locked classes), ``both_phase_classes`` (each >= 15 % of all runs), ``long_lived`` and ``attractors`` (the
    distinct (class, amplitude class) pairs among long-lived runs; a p:q lock's class names its ratio).
    """
    n = len(cells)
    get = lambda key: [c for c in cells if c["outcome"] == key]
    locked = [c for c in cells if c["outcome"] in LOCKED_AT_FY]
    ratio_locked = get("locked-p:q")
    big_2fy = lambda c: c.get("share_2fy") is not None and c["share_2fy"] >= 0.05  # NaN >= 0.05 is False
    with_2fy = [c for c in locked + ratio_locked if big_2fy(c)]
    long_lived = [c for c in cells if c.get("long_lived")]
    name = lambda c: c["outcome"] + (f" {c['lock_ratio']}" if c["outcome"] == "locked-p:q" else "")
    attractors = sorted({(name(c), c["amplitude_class"]) for c in long_lived})
    ratios = {}
    for c in ratio_locked:
        ratios[c.get("lock_ratio", "")] = ratios.get(c.get("lock_ratio", ""), 0) + 1
    frac = lambda k: k / n if n else float("nan")
    inp, anti = len(get("locked-in-phase")), len(get("locked-anti-phase"))
    return {"runs": n, "escaped": len(get("escaped")), "folded": len(get("folded")),
            "trapped": n - len(get("escaped")) - len(get("folded")),
            "locked_at_fy": len(locked), "locked_at_fy_fraction": frac(len(locked)),
            "locked_ratio": len(ratio_locked), "lock_ratios": dict(sorted(ratios.items())),
            "with_2fy": len(with_2fy), "with_2fy_fraction": frac(len(with_2fy)),
            "with_2fy_at_fy": sum(map(big_2fy, locked)),
            "in_phase": inp, "anti_phase": anti,
            "both_phase_classes": bool(n and inp >= 0.15 * n and anti >= 0.15 * n),
            "long_lived": len(long_lived), "attractors": [list(a) for a in attractors],
            "n_attractors": len(attractors)}


def _cell_path(out: Path, config: AtlasConfig, d: int, i: int, j: int) -> Path:
    return out / "cells" / f"{config.dimers[d].label}_t{i:03d}_th{j:03d}.json"


def cells_csv_text(columns: tuple[str, ...], rows: list[dict]) -> str:
    """The CSV of a cell study: a header of ``columns`` and one line per row (booleans lower case, non-finite
    floats and missing values empty, floats to 6 significant digits)."""
    def fmt(v):
        if isinstance(v, bool):
            return str(v).lower()
        if isinstance(v, float):
            return "" if not math.isfinite(v) else f"{v:.6g}"
        return "" if v is None else str(v)

    lines = [",".join(columns)] + [",".join(fmt(r.get(k)) for k in columns) for r in rows]
    return "\n".join(lines) + "\n"


def check_pinned_settings(pinned: Path, settings: dict, what: str, force: bool = False) -> None:
    """Refuse a study folder whose ``pinned`` settings file holds other settings (:class:`AtlasError`, naming
    ``what``: "an atlas", "a held-y map"); with ``force``, discard the study in the folder instead (its pinned
    settings and its finished cells)."""
    if force and pinned.exists():
        shutil.rmtree(pinned.parent / "cells", ignore_errors=True)
        pinned.unlink()
    if pinned.exists() and json.loads(pinned.read_text()) != json.loads(json_text(settings)):
        raise AtlasError(f"--out {pinned.parent} holds {what} with other settings; choose another --out (or --force)")


def check_dimers_buildable(dimers, pressures_pa, frequency_hz: float) -> None:
    """Refuse (:class:`AtlasError`, one line naming the dimer and pressure) a study one of whose dimers cannot be
    built at one of its pressures, before anything is written."""
    for dimer in dimers:
        for p in pressures_pa:
            try:
                atlas_dynamics(dimer.side, dimer.gap_ratio, p, frequency_hz)
            except ValueError as exc:
                raise AtlasError(f"--dimers {dimer.side:g}:{dimer.gap_ratio:g} at {p:g} Pa: {exc}") from None


def open_study(out: Path, settings: dict, pinned_name: str, what: str, force: bool,
               check_buildable: Callable[[], None]) -> None:
    """Open the folder ``out`` of a resumable study (an atlas, a map) with ``settings``: refuse another study's
    folder, or with ``force`` discard it (:func:`check_pinned_settings`, ``what`` names the study), run
    ``check_buildable`` (it raises :class:`AtlasError`) before anything is written, then create the folder and pin
    the settings in ``out/pinned_name``."""
    pinned = out / pinned_name
    check_pinned_settings(pinned, settings, what, force)
    check_buildable()
    out.mkdir(parents=True, exist_ok=True)
    write_json(pinned, settings)


def run_resumable_cells(out: Path, cells: list, cell_path, task, item, executor: ExecutorConfig | None,
                        progress: bool, desc: str) -> list[dict]:
    """Run the cells of a study whose result file ``cell_path(cell)`` does not exist yet, each ``task(item(cell))``
    through the executor, writing each result atomically as it finishes (so that a rerun resumes); returns
    every cell's result, in the order of ``cells``."""
    (out / "cells").mkdir(parents=True, exist_ok=True)
    todo = [c for c in cells if not cell_path(c).exists()]
    logger.info("%s: %d of %d cells to run", desc, len(todo), len(cells))

    def save(k: int, result: dict) -> None:
        write_json(cell_path(todo[k]), result)

    map_ordered(task, [item(c) for c in todo], executor or ExecutorConfig(), desc=desc, progress=progress,
                on_result=save)
    return [json.loads(cell_path(c).read_text()) for c in cells]


def run_atlas(config: AtlasConfig, out: str | os.PathLike, executor: ExecutorConfig | None = None,
              progress: bool = True, figures: bool = True, force: bool = False) -> dict:
    """Run (or resume) the atlas into ``out``; returns the ``atlas.json`` content.

    ``out/atlas_settings.json`` pins the settings: a folder holding an atlas with other settings is refused
    (:class:`AtlasError`), or with ``force`` that atlas is discarded first.  Finished cells are ``out/cells/*.json`` (written as each finishes, atomically) and
    are skipped on a rerun.  Then ``atlas.csv`` (:data:`CSV_COLUMNS`), ``atlas.json`` (settings, per-dimer
    outcome counts and :func:`observations`, every cell) and, with ``figures``, one basin map per dimer and the
    phase histogram (:func:`acousim.atlas.field_drop_figures.write_atlas_figures`).
    """
    out = Path(out)
    settings = config.to_dict()
    open_study(out, settings, "atlas_settings.json", "an atlas", force,
               lambda: check_dimers_buildable(config.dimers, (config.pressure_amplitude_pa,), config.frequency_hz))
    rows = run_resumable_cells(out, config.cells(), lambda c: _cell_path(out, config, *c), _cell_task,
                               lambda c: (config, c), executor, progress, "atlas")
    atomic_write_text(out / "atlas.csv", cells_csv_text(CSV_COLUMNS, rows))
    summary = {}
    for dimer in config.dimers:
        mine = [r for r in rows if r["dimer"] == dimer.label]
        summary[dimer.label] = {"counts": {o: sum(r["outcome"] == o for r in mine) for o in OUTCOMES},
                                "observations": observations(mine)}
    result = {"settings": settings, "dimers": summary, "cells": rows, "units": "SI"}
    write_json(out / "atlas.json", result)
    if figures:
        from .field_drop_figures import write_atlas_figures

        write_atlas_figures(config, rows, out, OUTCOMES)
    return result
