"""The field-drop simulation: one run (drop, free oscillation, camera) and every run of a configuration.

A synthetic experiment follows the protocol of the source paper:

1. the dimer levitates at its equilibrium height (y = 0, ydot = 0) with its hinge at a random
   angle ``theta_drop`` and rate ``thetadot_drop`` (:class:`~acousim.twin.config.DropProtocol`);
2. the field is switched off for a random ``t_off``: free fall (``yddot = -g``) with a free hinge
   (:class:`~acousim.dynamics.integrator.DimerDynamics` with ``field_on=False``), so the dimer starts its
   oscillation ~ g t_off^2 / 2 below the equilibrium, moving down at g t_off;
3. the field is switched on again and the camera (:class:`~acousim.twin.config.Camera`) records
   the free oscillation for ``duration`` seconds at ``fps`` frames per second, starting at t = 0
   when the field is back on, with Gaussian tracking noise on y and theta and a few missing frames.

With a transducer quality factor (``TwinConfig.transducer_q``) the field does not switch instantly: it rings down
while the drive is off and rings up when it is back, with tau = Q / (pi f), and the acoustic forces follow
p(t)^2 / p0^2 (:mod:`acousim.dynamics.switching`).  With a resonator (``TwinConfig.cavity_detuning``) the mode's
complex amplitude is a state of the run (:mod:`acousim.dynamics.resonator`): it starts at its steady value with the
dimer at rest, rings down while the drive is off, and is detuned by the dimer's position all along
(:func:`twin_cavity`).  A run whose hinge folds (theta reaches +-1: the faces touch) is an
outcome, not an error: it is recorded up to the fold and its ``event`` says so.  With a resonator a run that leaves
the trap is an outcome too (its motion is fed, and may grow until it escapes), recorded up to the escape; without
one, an escape stops the data set (the drops are too deep).

Randomness: one :class:`numpy.random.SeedSequence` from the seed is split into a stream for the
pressure error and one child per run (``spawn``), so every run's draws depend on the seed and the
run's index only, not on the number of workers.
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray

from cubedimer.executor import ExecutorConfig, map_ordered

from ..dynamics.integrator import DEFAULT_MAX_STEP, STATUS_MESSAGES, DimerDynamics
from ..dynamics.effects import EffectSet, air_damping_for
from ..dynamics.resonator import CoupledCavity, coupled_field_drop
from ..dynamics.switching import field_drop, ring_time
from ..medium import Medium
from .config import Camera, DropProtocol, TwinConfig, TwinError

__all__ = ["SimulatedRun", "run_seeds", "true_pressure", "simulate_run", "twin_dynamics", "twin_cavity",
           "simulate_field_drop_runs"]


@dataclass(frozen=True, eq=False)
class SimulatedRun:
    """One synthetic run.

    Attributes
    ----------
    t : ndarray (n,)
        Frame times [s], 0 when the field is back on.
    y, theta : ndarray (n,)
        Observed (noisy, ``nan`` in missing frames) y [m] and theta [-].
    state : ndarray (n, 4)
        Exact [y, ydot, theta, thetadot] at the frames.
    drop : dict
        The drawn protocol values (``t_off_s``, ``theta_drop``, ``thetadot_drop``).
    missing : ndarray of int
        Indices of the missing frames.
    event : dict, optional
        ``{"event": "folded", "t_s": time of the fold from the moment the field is back on (negative: during
        the drop)}`` for a run whose hinge folded; the frames stop before it (none for a fold during the drop).
        With a resonator, ``{"event": "escaped", "t_s": ...}`` likewise for a run that left the trap (the
        resonator's self-sustained motion can grow until it does).
        None for a run recorded over the whole duration.
    field_on_state : ndarray (4,), optional
        The state when the drive comes back (``state[0]``, or the state at the fold during the drop).
    mode : ndarray of complex (n,), optional
        With a resonator: the cavity mode's amplitude A / p0 at the frames.
    pressure_at_field_on : float, optional
        With a resonator: |A| / p0 when the drive comes back.
    """

    t: NDArray[np.float64]
    y: NDArray[np.float64]
    theta: NDArray[np.float64]
    state: NDArray[np.float64]
    drop: dict
    missing: NDArray[np.int64]
    event: dict | None = None
    field_on_state: NDArray[np.float64] | None = None
    mode: NDArray[np.complex128] | None = None
    pressure_at_field_on: float | None = None

    @property
    def state_at_field_on(self) -> NDArray[np.float64]:
        return self.state[0] if self.field_on_state is None else self.field_on_state

    @property
    def folded(self) -> bool:
        return self.event is not None and self.event.get("event") == "folded"

    @property
    def escaped(self) -> bool:
        return self.event is not None and self.event.get("event") == "escaped"


def run_seeds(seed: int, runs: int) -> tuple[np.random.SeedSequence, list[np.random.SeedSequence]]:
    """(pressure stream, one stream per run) derived from the master seed."""
    p, r = np.random.SeedSequence(int(seed)).spawn(2)
    return p, r.spawn(int(runs))


def true_pressure(nominal: float, error: float, seed: int) -> float:
    """The true p0 [Pa]: uniform in nominal x [1 - error, 1 + error], from the seed's pressure stream."""
    if error == 0:
        return float(nominal)
    rng = np.random.default_rng(run_seeds(seed, 0)[0])
    return float(nominal * (1.0 + error * rng.uniform(-1.0, 1.0)))


def simulate_run(dynamics: DimerDynamics, protocol: DropProtocol, camera: Camera, duration: float,
                 seed: np.random.SeedSequence | int, max_step: float = DEFAULT_MAX_STEP,
                 ring_time_s: float = 0.0, cavity: CoupledCavity | None = None) -> SimulatedRun:
    """Simulate one field-drop run and record it with the camera.

    Parameters
    ----------
    dynamics : DimerDynamics
        The (true) dimer and effects.
    protocol : DropProtocol
    camera : Camera
    duration : float
        Recorded time [s].
    seed : SeedSequence or int
        The run's random stream (drop values first, then camera noise and missing frames).
    max_step : float
        Longest internal RK4 step [s].
    ring_time_s : float
        The transducer's ring time tau [s] (:mod:`acousim.dynamics.switching`; 0: the field switches instantly).
    cavity : CoupledCavity, optional
        The levitator as a resonator (:func:`twin_cavity`); ``ring_time_s`` must then be 0 (the cavity has its own).

    Returns
    -------
    SimulatedRun
        A run whose hinge folds is recorded up to the fold (``event``); with a ``cavity``, a run that leaves the
        trap likewise up to its escape.

    Raises
    ------
    TwinError
        If the dimer leaves the trap without a resonator, or the state stops being finite.
    """
    rng = np.random.default_rng(seed)
    drop = protocol.draw(rng)
    x_drop = np.array([0.0, 0.0, drop["theta_drop"], drop["thetadot_drop"]])
    n = int(round(duration * camera.fps))
    if cavity is None:
        motion = field_drop(dynamics, x_drop, drop["t_off_s"], (n - 1) / camera.fps, 1.0 / camera.fps,
                            tau=ring_time_s, max_step=max_step)
    else:
        if ring_time_s:
            raise ValueError("a coupled cavity has its own ring time: give ring_time_s = 0")
        motion = coupled_field_drop(cavity, x_drop, drop["t_off_s"], (n - 1) / camera.fps, 1.0 / camera.fps,
                                    max_step=max_step)
    escaped = cavity is not None and motion.status in (1, 4)  # a resonator's self-sustained motion may end so
    if motion.status not in (0, 2) and not escaped:
        where = (f"during the drop (t_off = {drop['t_off_s'] * 1e3:.2f} ms)" if motion.trajectory is None else
                 f"at t = {motion.t_stop:.3f} s (t_off = {drop['t_off_s'] * 1e3:.2f} ms, theta_drop = "
                 f"{drop['theta_drop']:.3f}, thetadot_drop = {drop['thetadot_drop']:.3g} 1/s)")
        raise TwinError(f"{STATUS_MESSAGES[motion.status]} {where}; use shorter drops or a smaller hinge range")
    event = None if motion.ok else {"event": "escaped" if escaped else "folded", "t_s": float(motion.t_stop)}
    extra = {} if cavity is None else {"mode": motion.mode, "pressure_at_field_on": motion.pressure_at_field_on}
    if motion.trajectory is None:
        empty = np.zeros(0)
        return SimulatedRun(t=empty, y=empty, theta=empty, state=np.zeros((0, 4)), drop=drop,
                            missing=np.zeros(0, np.int64), event=event, field_on_state=motion.state_at_field_on,
                            **extra)
    traj = motion.trajectory
    if event is not None:  # a short run keeps its missing frames apart: at most one in two interior frames
        camera = replace(camera, missing_frames=min(int(camera.missing_frames), max(0, (len(traj.t) - 2) // 2)))
    y, th, idx = camera.record(traj.state, rng)
    return SimulatedRun(t=traj.t, y=y, theta=th, state=traj.state, drop=drop, missing=idx, event=event, **extra)


def _run_task(item: tuple) -> SimulatedRun:
    dynamics, protocol, camera, duration, seed, max_step, tau, cavity = item
    return simulate_run(dynamics, protocol, camera, duration, seed, max_step, tau, cavity)


def twin_cavity(config: TwinConfig, dynamics: DimerDynamics) -> CoupledCavity | None:
    """The resonator of a configuration coupled to its dynamics, None without one.

    Raises
    ------
    TwinError
        The cavity's quasi-static response removes y's stiffness (the detuning and coupling are so large that the
        dimer is not trapped; :meth:`acousim.dynamics.cavity_stability.LinearCavityCoupling.static_stiffness`).
    """
    from ..dynamics.cavity_stability import LinearCavityCoupling

    mode = config.cavity_mode
    if mode is None:
        return None
    cavity = CoupledCavity(dynamics, mode, Medium(frequency_hz=config.frequency))
    ratio = LinearCavityCoupling.from_cavity(cavity).static_stiffness()
    if not ratio > 0:
        raise TwinError(f"--detuning {mode.detuning:g}: the cavity's response removes the trap's vertical stiffness "
                        f"(dimer not trapped); use a smaller |detuning|, a larger --cavity-area or a lower "
                        f"--transducer-q")
    return cavity


def twin_dynamics(config: TwinConfig) -> tuple[DimerDynamics, float]:
    """The true dynamics of a configuration and its true pressure amplitude [Pa].

    With ``config.air_damping`` (the default) the air's computed drag (:func:`acousim.dynamics.effects.air_damping_for`, at the true
    pressure's frequencies) is added to the effects, unless they already hold an ``air_damping``; the
    dynamics' ``effects`` are then what truth.json records.
    """
    p_true = true_pressure(config.pressure_amplitude_pa, config.pressure_error, config.seed)
    effects = config.effects
    try:
        sur = config.model_spec.dynamic(config.conditions)
        if p_true != config.pressure_amplitude_pa:
            sur = sur.with_pressure(p_true)
        if config.air_damping and "air_damping" not in effects:
            effects = effects.merged(EffectSet((air_damping_for(sur, config.conditions),)))
    except ValueError as exc:  # the field cannot levitate the dimer, a dimer outside the full-wave family
        raise TwinError(str(exc)) from None
    return DimerDynamics(sur, effects), p_true


def simulate_field_drop_runs(config: TwinConfig, executor=None, progress: bool = True) -> tuple[list[SimulatedRun], DimerDynamics, float]:
    """Simulate every run of ``config`` through :func:`cubedimer.executor.map_ordered`.

    Returns
    -------
    (runs, dynamics, true pressure [Pa])
    """
    dynamics, p_true = twin_dynamics(config)
    _, seeds = run_seeds(config.seed, config.runs)
    cavity = twin_cavity(config, dynamics)
    tau = ring_time(config.transducer_q, config.frequency) if cavity is None else 0.0
    items = [(dynamics, config.protocol, config.camera, config.duration, s, config.max_step, tau, cavity)
             for s in seeds]
    executor = executor or ExecutorConfig()
    try:
        runs = map_ordered(_run_task, items, executor, desc="simulate", progress=progress)
    except TwinError as exc:
        raise TwinError(f"a run could not be simulated: {exc}") from None
    return runs, dynamics, p_true
