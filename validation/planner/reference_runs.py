"""The planner's reference runs: a twin configuration's noise-free runs and the per-run information of the columns
the diagnosis fits on them.

A run design (:class:`RunDesign`: duration, frame rate, drop amplitudes, number of reference runs) turns a twin
configuration (:class:`acousim.twin.TwinConfig`: the dimer, the pressure, the true effects and the cavity) into
reference runs simulated by the twin itself (:func:`acousim.twin.simulate_field_drop_runs`; their exact states, not
the camera's noisy ones).  On each run, per equation (0: yddot, 1: thetaddot), the columns are

* the model's own terms in the y equation, as the diagnosis calibrates them beside the effects: the pressure scale
  (the acoustic acceleration ``(Q_y + M g) / M`` of the force model at the state;
  :func:`validation.diagnosis.prepare.candidate_effects.parameter_slots`: column 0 of the y equation) and the
  origin of y (linearised: ``d(Q_y / M)/dy``, per metre of offset; the diagnosis searches the height);
* every named candidate's columns: :func:`validation.diagnosis.prepare.candidate_effects.effect_regressors` for the
  registered effects, :class:`validation.diagnosis.prepare.cavity_lag.CavityColumns` for the cavity's lag (the
  twin's own force model, completed to second order about the twin's own mode when it has one),

and their integral form (:func:`fitting.uncertainty.oracle.integral_design`: windows of 0.75 periods of the
coordinate's dominant frequency, the fit's and the oracle's) gives the run's unit-noise information matrix
``X_r^T X_r``.  Matrices of runs add: :mod:`validation.planner.candidate_plan` pools random draws of them.
"""
from __future__ import annotations

import logging
import math
from dataclasses import dataclass, replace
from typing import Sequence

import numpy as np
from numpy.typing import NDArray

from acousim.medium import GRAVITY, Medium
from cubedimer.config_checks import check_positive, check_that, check_whole
from cubedimer.executor import ExecutorConfig
from fitting.uncertainty.oracle import integral_design
from validation.diagnosis.prepare.candidate_effects import (CANDIDATE_EFFECTS, MODEL_CANDIDATES, effect_regressors,
                                                            parameter_slots)
from validation.diagnosis.prepare.cavity_lag import CavityColumns, gains_from_mode

__all__ = ["RunDesign", "ReferenceRuns", "drop_time", "twin_from_truth", "reference_runs", "parameter_labels",
           "true_parameters", "has_contribution", "OWN_TERMS", "EQUATIONS"]

logger = logging.getLogger(__name__)

#: The equations' names, in the diagnosis's order (0: y, 1: theta).
EQUATIONS = ("yddot", "thetaddot")
#: The model's own terms the diagnosis calibrates beside the effects, per equation: the pressure scale and the origin
#: height of y (linearised: the y acceleration's derivative in y, per metre of offset) in the y equation.
OWN_TERMS: tuple[tuple[str, ...], tuple[str, ...]] = (("pressure_scale", "origin"), ())
#: The height step of the origin's column (a central difference of the force model's generalised force) [m].
_ORIGIN_STEP = 1e-7


def drop_time(amplitude: float, omega_y: float) -> float:
    """The field-off time [s] after which the dimer oscillates with the amplitude ``amplitude`` [m] about its rest
    height in a trap of angular frequency ``omega_y`` [rad/s]: it falls ``h = g t^2 / 2`` and returns with the speed
    ``g t``, so that ``A^2 = h^2 + (g t / omega_y)^2`` (the linear trap; solved for t)."""
    a = float(amplitude)
    # A^2 = g^2 t^4 / 4 + g^2 t^2 / w^2: a quadratic in t^2
    u = (-1.0 / omega_y**2 + math.sqrt(1.0 / omega_y**4 + a * a / GRAVITY**2)) * 2.0
    return math.sqrt(u)


@dataclass(frozen=True)
class RunDesign:
    """The runs a plan is for.

    Parameters
    ----------
    duration : float
        Run length [s].
    fps : float
        Frame rate [1/s].
    n_reference : int
        Reference runs simulated (the pool the draws of n runs come from); split evenly over the drop amplitudes.
    amplitudes : tuple of float, optional
        The y amplitudes the drops start [m] (each run's field-off time is :func:`drop_time` in the twin's linear
        trap); the runs cycle through them.  None: the twin configuration's own drop protocol (its range of
        field-off times).
    theta_drop : (float, float), optional
        Range of the hinge angle at the drop [-]; None: the twin configuration's.
    seed : int
        Seed of the twin's runs (drop values); amplitudes take the seeds ``seed``, ``seed + 1``, ...
    periods : float
        Integral-form window in periods of the coordinate's dominant frequency.
    """

    duration: float = 3.0
    fps: float = 2000.0
    n_reference: int = 24
    amplitudes: tuple[float, ...] | None = None
    theta_drop: tuple[float, float] | None = None
    seed: int = 0
    periods: float = 0.75

    def __post_init__(self) -> None:
        check_positive(self, "duration")
        check_positive(self, "fps")
        check_whole(self, "n_reference", minimum=2)
        check_positive(self, "periods")
        if self.amplitudes is not None:
            object.__setattr__(self, "amplitudes", tuple(float(h) for h in self.amplitudes))
            check_that(self, len(self.amplitudes) > 0 and all(0 < h < 1e-3 for h in self.amplitudes),
                       f"drop amplitudes must lie in (0, 1 mm), got {self.amplitudes!r}")
            check_that(self, self.n_reference >= len(self.amplitudes),
                       "n_reference must be at least the number of drop amplitudes")


@dataclass(frozen=True, eq=False)
class ReferenceRuns:
    """The reference runs and their per-run information (module docstring).

    Attributes
    ----------
    labels : per equation, the column labels (``"pressure_scale"``, ``"effect.parameter"``)
    information : per equation, array (R, P, P): each run's unit-noise ``X_r^T X_r``
    heights : array (R,): each run's stated drop amplitude [m] (nan: the twin's own protocol)
    amplitudes : array (R,): each run's largest |y| [m]
    window_s : per equation, the median integral window [s]
    truth : ``{label: true coefficient}`` (:func:`true_parameters`)
    trajectory : the trajectory test's oracle (labels, information, truth), or None
    """

    labels: tuple[tuple[str, ...], tuple[str, ...]]
    information: tuple[NDArray[np.float64], NDArray[np.float64]]
    heights: NDArray[np.float64]
    amplitudes: NDArray[np.float64]
    window_s: tuple[float, float]
    truth: dict[str, float]
    #: the velocity coupling's trajectory test on the same runs (:func:`validation.planner.trajectory_oracle.trajectory_information`:
    #: labels, per-run information in the parameters' units, truth), None where not measured
    trajectory: tuple[tuple[str, ...], NDArray[np.float64], dict[str, float]] | None = None

    def __len__(self) -> int:
        return int(self.heights.size)


def twin_from_truth(truth: dict):
    """The twin configuration a twin data set's truth.json records (the Gor'kov default model): its true pressure
    (as the nominal one, no error), side, seed, duration and runs, effects (the air's computed drag among them when
    the twin added it), drop protocol, camera and cavity mode.  With the same run design (the runs, duration, fps
    and seed of truth.json, no drop amplitudes) :func:`reference_runs` simulates exactly the data set's runs.

    Raises
    ------
    ValueError
        A truth.json of another force model, or one that lacks a key the twin needs (named).
    """
    from acousim.dynamics.effects import EffectSet
    from acousim.models import ExperimentConditions
    from acousim.gorkov.forces import GORKOV
    from acousim.twin import Camera, DropProtocol, TwinConfig

    if truth.get("force_model") not in (None, GORKOV):
        raise ValueError(f"truth.json of the {truth['force_model']} model: the planner reads the Gor'kov twin's only")
    try:
        experiment = ExperimentConditions.from_meta({"side_length_m": truth.get("side_length_m")},
                                                    pressure_amplitude_pa=float(truth["pressure_amplitude_pa"]))
        resonator = truth.get("resonator") or {}
        cavity = ({"transducer_q": float((truth.get("field_switching") or {}).get("transducer_q", 0.0))}
                  if not resonator else
                  {"transducer_q": float(resonator["quality_factor"]),
                   "cavity_detuning": float(resonator["detuning_half_widths"]),
                   "cavity_area": float(resonator["cavity_area_m2"])})
        protocol = DropProtocol(**{k: tuple(v) for k, v in truth.get("protocol", {}).items()})
        return TwinConfig(runs=int(truth.get("runs", 10)), duration=float(truth.get("duration_s", 3.0)),
                          seed=int(truth["seed"]), experiment=experiment,
                          effects=EffectSet.from_dict(truth.get("effects") or {}), protocol=protocol,
                          camera=Camera(fps=float((truth.get("camera") or {}).get("fps", Camera.fps))),
                          air_damping=bool(truth.get("air_damping", True)), **cavity)
    except KeyError as exc:
        raise ValueError(f"truth.json lacks the key {exc.args[0]!r} the twin needs") from None


def parameter_labels(names: Sequence[str]) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """Per equation, the labels of the columns of the model's own terms and of the candidates ``names``: the
    parameters that act in that equation (``"velocity_coupling.c6"``)."""
    out: list[list[str]] = [list(OWN_TERMS[0]), list(OWN_TERMS[1])]
    for name in names:
        if name not in CANDIDATE_EFFECTS:
            raise ValueError(f"unknown candidate {name!r}; candidates are {', '.join(CANDIDATE_EFFECTS)}")
        for q in (0, 1):
            out[q] += [f"{name}.{p}" for p in CANDIDATE_EFFECTS[name] if q in _acting(name, p)]
    return tuple(out[0]), tuple(out[1])


def _acting(name: str, parameter: str) -> tuple[int, ...]:
    """The equations a candidate's parameter acts in
    (:func:`~validation.diagnosis.prepare.candidate_effects.parameter_slots`)."""
    return tuple(q for q in (0, 1) if any(p == parameter for _, p, _ in parameter_slots([name], q)))


def true_parameters(twin, dynamics) -> dict[str, float]:
    """The true coefficient of every candidate column the twin's physics holds: the effects' parameters, the
    cavity's gains (:func:`~validation.diagnosis.prepare.cavity_lag.gains_from_mode` at the twin's mode), the
    pressure scale 1, the origin's offset 0, and the air's computed drag as linear damping's rates at theta = 0 (its rates, which the
    diagnosis's linear damping stands for)."""
    truth = {"pressure_scale": 1.0, "origin": 0.0}
    for effect in dynamics.effects:
        if effect.name == "air_damping":
            for p in ("gamma_y", "gamma_theta"):
                key = f"linear_damping.{p}"
                truth[key] = truth.get(key, 0.0) + float(getattr(effect, p))
        elif effect.name in CANDIDATE_EFFECTS:
            for p, v in effect.params().items():
                key = f"{effect.name}.{p}"
                truth[key] = truth.get(key, 0.0) + float(v)
    mode = twin.cavity_mode
    if mode is not None:
        gains = gains_from_mode(mode, twin.frequency)
        truth["cavity_lag.static_gain"] = gains.static_gain
        truth["cavity_lag.lag_gain"] = gains.lag_gain
    return truth


def has_contribution(truth: dict[str, float], name: str) -> bool:
    """Whether the truth (:func:`true_parameters`) holds candidate ``name`` with a parameter that is not zero."""
    return any(v for k, v in truth.items() if k.split(".")[0] == name)


def _columns(state: NDArray, fm, cavity: CavityColumns | None, mode, names: Sequence[str]) -> list[NDArray]:
    """Per equation, the columns (n, P) at the exact states, in the order of :func:`parameter_labels`."""
    y, th = state[:, 0], state[:, 2]
    q_y, _ = fm.generalized_forces(th, y)
    up, _ = fm.generalized_forces(th, y + _ORIGIN_STEP)
    down, _ = fm.generalized_forces(th, y - _ORIGIN_STEP)
    cols: list[list[NDArray]] = [[(np.asarray(q_y, float) + fm.mass * fm.gravity) / fm.mass,
                                  (np.asarray(up, float) - np.asarray(down, float)) / (2 * _ORIGIN_STEP * fm.mass)], []]
    for name in names:
        if name in MODEL_CANDIDATES:
            block = cavity.columns(state, 0.0, reference=mode)
        else:
            block = effect_regressors(name, state, fm.z_eq + y, fm.wavenumber, fm.z_eq)
        for j, p in enumerate(CANDIDATE_EFFECTS[name]):
            for q in _acting(name, p):
                cols[q].append(block[:, q, j])
    return [np.stack(c, axis=1) for c in cols]


def _simulated(twin, design: RunDesign, omega_y: float) -> list[tuple[float, NDArray]]:
    """(stated drop amplitude or nan, exact states) of the design's reference runs of ``twin`` (linear trap
    frequency ``omega_y`` [rad/s])."""
    from acousim.twin import simulate_field_drop_runs

    camera = replace(twin.camera, fps=float(design.fps), missing_frames=0)
    protocol = twin.protocol if design.theta_drop is None else replace(twin.protocol, theta_drop=design.theta_drop)
    heights = design.amplitudes or (float("nan"),)
    counts = [len(range(i, design.n_reference, len(heights))) for i in range(len(heights))]
    out = []
    for i, (h, k) in enumerate(zip(heights, counts)):
        t_off = float("nan") if math.isnan(h) else drop_time(h, omega_y)
        drops = protocol if math.isnan(h) else replace(protocol, t_off=(t_off, t_off))
        cfg = replace(twin, runs=k, duration=float(design.duration), camera=camera, protocol=drops,
                      seed=int(design.seed) + i)
        runs, _, _ = simulate_field_drop_runs(cfg, ExecutorConfig(workers=1), progress=False)
        out += [(h, r.state) for r in runs]
    return out


def reference_runs(twin, design: RunDesign, names: Sequence[str], noise=None) -> ReferenceRuns:
    """Simulate the design's reference runs of the twin configuration and measure each one's information for the
    columns of the model's own terms and the candidates ``names`` (module docstring).

    Parameters
    ----------
    twin : acousim.twin.TwinConfig
        The truth: dimer, pressure, effects (the air's drag with ``air_damping``), cavity.
    design : RunDesign
    names : candidate effects whose columns are measured (keys of
        :data:`validation.diagnosis.prepare.candidate_effects.CANDIDATE_EFFECTS`)
    noise : fitting.uncertainty.oracle.NoiseLevels, optional
        With ``velocity_coupling`` among ``names``: the noise of the trajectory test's oracle on the same runs
        (:mod:`validation.planner.trajectory_oracle`; not measured without it)

    Returns
    -------
    ReferenceRuns
        Runs too short for one integral window (a fold or an escape early in the run) are left out.
    """
    from acousim.twin import twin_dynamics

    labels = parameter_labels(names)
    dynamics, _ = twin_dynamics(twin)
    fm = dynamics.force_model
    mode = twin.cavity_mode
    cavity = (CavityColumns(fm, twin.cavity_area, Medium(frequency_hz=twin.frequency)) if "cavity_lag" in names
              else None)
    dt = 1.0 / float(design.fps)
    info: list[list[NDArray]] = [[], []]
    windows: list[list[float]] = [[], []]
    kept_h, amps, kept = [], [], []
    omega_y = 2.0 * math.pi * float(fm.linear_frequencies()[0])
    for h, state in _simulated(twin, design, omega_y):
        cols = _columns(state, fm, cavity, mode, names)
        designs = [integral_design(cols[q], state[:, 2 * q], dt, design.periods) for q in (0, 1)]
        if any(d is None for d in designs):
            continue
        for q, (X, w) in enumerate(designs):
            info[q].append(X.T @ X)
            windows[q].append(w * dt)
        kept_h.append(h)
        kept.append(state)
        amps.append(float(np.max(np.abs(state[:, 0]))))
    if not kept_h:
        raise ValueError("no reference run is long enough for one integral window: use longer runs")
    logger.info("planner: %d reference runs of %.2f s at %g fps", len(kept_h), design.duration, design.fps)
    trajectory = None
    if noise is not None and "velocity_coupling" in names:
        from .trajectory_oracle import trajectory_information

        trajectory = trajectory_information(twin, dynamics, kept, dt, noise)
    return ReferenceRuns(labels, (np.array(info[0]), np.array(info[1])), np.array(kept_h), np.array(amps),
                         (float(np.median(windows[0])), float(np.median(windows[1]))),
                         true_parameters(twin, dynamics), trajectory)
