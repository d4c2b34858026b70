"""The digital twin: field-drop protocol, camera and synthetic data sets (FORMATS.md).

A synthetic experiment follows the protocol of the source paper:

1. the dimer levitates at its equilibrium height (y = 0, ydot = 0) with its hinge at a random
   angle ``theta_drop`` and rate ``thetadot_drop`` (:class:`DropProtocol`);
2. the field is switched off for a random ``t_off``: free fall (``yddot = -g``) with a free hinge
   (:class:`~acousim.dynamics.DimerDynamics` with ``field_on=False``), so the dimer starts its
   oscillation ~ g t_off^2 / 2 below the equilibrium, moving down at g t_off;
3. the field is switched on again and the camera (:class:`Camera`) records the free oscillation
   for ``duration`` seconds at ``fps`` frames per second, starting at t = 0 when the field is back
   on, with Gaussian tracking noise on y and theta and a few missing frames (written as ``nan``).

:func:`simulate_dataset` writes ``runNN.csv`` (columns ``t, y, theta``), ``meta.json`` (the
*nominal* settings, FORMATS.md keys), ``truth.json`` (the true pressure, the effects with their
parameters, the seed and every other setting, including each run's drawn initial conditions) and
``truth_states.npz`` (the exact integrated states at every frame, for tests and diagnostics), into
a temporary folder renamed into place at the end, so a failure leaves nothing behind.

Randomness: one :class:`numpy.random.SeedSequence` from the seed is split into a stream for the
pressure error and one child per run (``spawn``), so every run's draws depend on the seed and the
run's index only, not on the number of workers.

:data:`PAPER_LIKE` is the effect set and protocol documented in ``docs/twin.md`` that reproduces
what it can of the source paper's dynamics.
"""
from __future__ import annotations

import json
import os
import shutil
import tempfile
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Sequence

import numpy as np
from numpy.typing import NDArray

from .dynamics import DEFAULT_MAX_STEP, DimerDynamics
from .effects import (EffectSet, LinearDamping, MirrorAsymmetry, PairScattering, QuadraticDrag,
                      VelocityCoupling)
from .surrogate import ForceSurrogate, cached_surrogate

__all__ = [
    "DropProtocol",
    "Camera",
    "TwinConfig",
    "TwinPreset",
    "SimulatedRun",
    "TwinError",
    "PAPER_LIKE",
    "PRESETS",
    "simulate_run",
    "simulate_runs",
    "simulate_dataset",
    "true_pressure",
    "run_seeds",
]


class TwinError(ValueError):
    """A twin setting or run that cannot be simulated; ``str(err)`` is one line."""


def _range(name: str, r: Sequence[float], low: float | None = None, high: float | None = None,
           strict_low: bool = False) -> tuple[float, float]:
    try:
        a, b = (float(v) for v in r)
    except (TypeError, ValueError):
        raise TwinError(f"{name} must be a (min, max) pair of numbers, got {r!r}") from None
    if not (np.isfinite(a) and np.isfinite(b)) or a > b:
        raise TwinError(f"{name} must be finite with min <= max, got ({a:g}, {b:g})")
    if low is not None and (a < low or (strict_low and a <= low)):
        raise TwinError(f"{name} must be {'>' if strict_low else '>='} {low:g}, got ({a:g}, {b:g})")
    if high is not None and b > high:
        raise TwinError(f"{name} must be <= {high:g}, got ({a:g}, {b:g})")
    return a, b


@dataclass(frozen=True)
class DropProtocol:
    """The field-drop protocol; every quantity is drawn uniformly from its (min, max) range per run.

    Parameters
    ----------
    t_off : (float, float)
        Time the field is off [s].  The dimer falls g t_off^2 / 2 and starts at g t_off downwards;
        at the defaults a drop longer than ~6 ms throws it out of the trap.
    theta_drop : (float, float)
        Hinge angle when the field drops [-].
    thetadot_drop : (float, float)
        Hinge rate when the field drops [1/s].
    """

    t_off: tuple[float, float] = (2.0e-3, 4.0e-3)
    theta_drop: tuple[float, float] = (-0.3, 0.3)
    thetadot_drop: tuple[float, float] = (-3.0, 3.0)

    def __post_init__(self) -> None:
        object.__setattr__(self, "t_off", _range("t_off", self.t_off, low=0.0))
        object.__setattr__(self, "theta_drop", _range("theta_drop", self.theta_drop, low=-0.99, high=0.99))
        object.__setattr__(self, "thetadot_drop", _range("thetadot_drop", self.thetadot_drop))

    def draw(self, rng: np.random.Generator) -> dict[str, float]:
        """One run's drop: ``{"t_off_s", "theta_drop", "thetadot_drop"}``."""
        return {
            "t_off_s": float(rng.uniform(*self.t_off)),
            "theta_drop": float(rng.uniform(*self.theta_drop)),
            "thetadot_drop": float(rng.uniform(*self.thetadot_drop)),
        }


@dataclass(frozen=True)
class Camera:
    """The tracking camera.

    Parameters
    ----------
    fps : float
        Frame rate [1/s].
    noise_y : float
        Standard deviation of the Gaussian tracking noise on y [m].
    noise_theta : float
        Standard deviation of the Gaussian tracking noise on theta [-].
    missing_frames : int
        Frames per run lost by the tracker (both y and theta written as ``nan``), at random
        interior positions, never two adjacent.
    """

    fps: float = 2000.0
    noise_y: float = 1.0e-6
    noise_theta: float = 0.005
    missing_frames: int = 3

    def __post_init__(self) -> None:
        for name in ("fps", "noise_y", "noise_theta"):
            v = getattr(self, name)
            if not isinstance(v, (int, float)) or not np.isfinite(v) or v < 0 or (name == "fps" and v <= 0):
                raise TwinError(f"camera {name} must be {'positive' if name == 'fps' else '>= 0'} and finite, got {v!r}")
        if int(self.missing_frames) != self.missing_frames or self.missing_frames < 0:
            raise TwinError(f"missing_frames must be a non-negative integer, got {self.missing_frames!r}")

    def record(self, state: NDArray[np.float64], rng: np.random.Generator) -> tuple[NDArray, NDArray, NDArray]:
        """Observed (y [m], theta [-]) of exact states (n, 4), and the indices of the missing frames.

        Observed theta is clipped to +-0.999 (a tracker never reports an angle past face contact).
        """
        n = state.shape[0]
        y = state[:, 0] + self.noise_y * rng.standard_normal(n)
        th = np.clip(state[:, 2] + self.noise_theta * rng.standard_normal(n), -0.999, 0.999)
        k = int(self.missing_frames)
        if k:
            interior = n - 2
            if interior < 2 * k:
                raise TwinError(f"a run of {n} frames cannot have {k} missing frames")
            # k non-adjacent positions in 1..n-2: choose from n-2-(k-1) slots and spread them
            slots = np.sort(rng.choice(interior - (k - 1), size=k, replace=False))
            idx = 1 + slots + np.arange(k)
        else:
            idx = np.zeros(0, int)
        y[idx] = np.nan
        th[idx] = np.nan
        return y, th, idx


@dataclass(frozen=True)
class TwinPreset:
    """A named set of effects, pressure and protocol (e.g. :data:`PAPER_LIKE`)."""

    name: str
    effects: EffectSet
    pressure_amplitude_pa: float = 3000.0
    protocol: DropProtocol = field(default_factory=DropProtocol)
    description: str = ""


@dataclass(frozen=True)
class TwinConfig:
    """Every setting of a synthetic data set.

    Parameters
    ----------
    runs : int
        Number of runs (one CSV each).
    duration : float
        Recorded time per run [s] (from the moment the field is back on).
    seed : int
        Master seed: every random choice derives from it.
    side : float
        Cube side [m].
    pressure_amplitude_pa : float
        Nominal pressure amplitude p0 [Pa] (written to meta.json).
    pressure_error : float
        The true p0 is drawn uniformly in nominal x [1 - e, 1 + e] (0: true = nominal); FORMATS.md
        allows real data to be off by up to 10 %.
    effects : EffectSet
    protocol : DropProtocol
    camera : Camera
    mesh_size : float, optional
        Mesh edge [m] of the Gor'kov model behind the surrogate (default: the model's default).
    max_step : float
        Longest internal RK4 step [s].
    preset : str, optional
        Name of the preset these settings came from (bookkeeping only).
    """

    runs: int = 10
    duration: float = 4.0
    seed: int = 0
    side: float = 500e-6
    pressure_amplitude_pa: float = 3000.0
    pressure_error: float = 0.0
    effects: EffectSet = field(default_factory=EffectSet)
    protocol: DropProtocol = field(default_factory=DropProtocol)
    camera: Camera = field(default_factory=Camera)
    mesh_size: float | None = None
    max_step: float = DEFAULT_MAX_STEP
    preset: str | None = None

    def __post_init__(self) -> None:
        if int(self.runs) != self.runs or self.runs < 1:
            raise TwinError(f"runs must be a positive integer, got {self.runs!r}")
        if not np.isfinite(self.duration) or self.duration <= 0:
            raise TwinError(f"duration must be positive, got {self.duration!r} s")
        if int(self.seed) != self.seed or self.seed < 0:
            raise TwinError(f"seed must be a non-negative integer, got {self.seed!r}")
        if not np.isfinite(self.side) or not 50e-6 <= self.side <= 2e-3:
            raise TwinError(f"side must lie in [50 um, 2 mm], got {self.side!r} m")
        if not np.isfinite(self.pressure_amplitude_pa) or self.pressure_amplitude_pa <= 0:
            raise TwinError(f"pressure amplitude must be positive, got {self.pressure_amplitude_pa!r} Pa")
        if not np.isfinite(self.pressure_error) or not 0 <= self.pressure_error < 0.5:
            raise TwinError(f"pressure error must lie in [0, 0.5), got {self.pressure_error!r}")
        if self.mesh_size is not None and (not np.isfinite(self.mesh_size) or self.mesh_size <= 0):
            raise TwinError(f"mesh size must be positive, got {self.mesh_size!r} m")
        if not np.isfinite(self.max_step) or self.max_step <= 0:
            raise TwinError(f"max_step must be positive, got {self.max_step!r} s")
        n = int(round(self.duration * self.camera.fps))
        if n < 16:
            raise TwinError(f"{self.duration:g} s at {self.camera.fps:g} fps gives only {n} frames")

    @classmethod
    def from_preset(cls, preset: TwinPreset, **overrides) -> "TwinConfig":
        """Settings of a preset (effects, pressure, protocol), with any field overridden."""
        base = dict(effects=preset.effects, pressure_amplitude_pa=preset.pressure_amplitude_pa,
                    protocol=preset.protocol, preset=preset.name)
        base.update(overrides)
        return cls(**base)

    @property
    def n_frames(self) -> int:
        """Frames per run."""
        return int(round(self.duration * self.camera.fps))

    def to_dict(self) -> dict:
        """JSON-ready settings (SI units)."""
        return {
            "runs": int(self.runs),
            "duration_s": float(self.duration),
            "seed": int(self.seed),
            "side_length_m": float(self.side),
            "nominal_pressure_amplitude_pa": float(self.pressure_amplitude_pa),
            "pressure_error": float(self.pressure_error),
            "effects": self.effects.to_dict(),
            "protocol": {k: list(v) for k, v in asdict(self.protocol).items()},
            "camera": {"fps": float(self.camera.fps), "noise_y_m": float(self.camera.noise_y),
                       "noise_theta": float(self.camera.noise_theta),
                       "missing_frames": int(self.camera.missing_frames)},
            "mesh_size_m": self.mesh_size,
            "max_step_s": float(self.max_step),
            "preset": self.preset,
        }


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
    """

    t: NDArray[np.float64]
    y: NDArray[np.float64]
    theta: NDArray[np.float64]
    state: NDArray[np.float64]
    drop: dict
    missing: NDArray[np.int64]

    @property
    def state_at_field_on(self) -> NDArray[np.float64]:
        return self.state[0]


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
                 seed: np.random.SeedSequence | int, max_step: float = DEFAULT_MAX_STEP) -> SimulatedRun:
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

    Raises
    ------
    TwinError
        If the dimer leaves the trap or the hinge closes (theta = +-1) during the run.
    """
    rng = np.random.default_rng(seed)
    drop = protocol.draw(rng)
    x_drop = np.array([0.0, 0.0, drop["theta_drop"], drop["thetadot_drop"]])
    if drop["t_off_s"] > 0:
        fall = dynamics.integrate(x_drop, drop["t_off_s"], drop["t_off_s"], max_step=max_step, field_on=False)
        if not fall.ok:
            raise TwinError(f"during the drop (t_off = {drop['t_off_s'] * 1e3:.2f} ms): {fall.message}")
        x_on = fall.state[-1]
    else:
        x_on = x_drop
    n = int(round(duration * camera.fps))
    traj = dynamics.integrate(x_on, (n - 1) / camera.fps, 1.0 / camera.fps, max_step=max_step, field_on=True)
    if not traj.ok:
        raise TwinError(
            f"{traj.message} at t = {traj.t[-1]:.3f} s (t_off = {drop['t_off_s'] * 1e3:.2f} ms, "
            f"theta_drop = {drop['theta_drop']:.3f}, thetadot_drop = {drop['thetadot_drop']:.3g} 1/s); "
            "use shorter drops or a smaller hinge range"
        )
    y, th, idx = camera.record(traj.state, rng)
    return SimulatedRun(t=traj.t, y=y, theta=th, state=traj.state, drop=drop, missing=idx)


def _run_task(item: tuple) -> SimulatedRun:
    dynamics, protocol, camera, duration, seed, max_step = item
    return simulate_run(dynamics, protocol, camera, duration, seed, max_step)


def twin_dynamics(config: TwinConfig) -> tuple[DimerDynamics, float]:
    """The true dynamics of a configuration and its true pressure amplitude [Pa]."""
    p_true = true_pressure(config.pressure_amplitude_pa, config.pressure_error, config.seed)
    try:
        sur: ForceSurrogate = cached_surrogate(float(config.side), float(config.pressure_amplitude_pa),
                                               config.mesh_size)
        if p_true != config.pressure_amplitude_pa:
            sur = sur.with_pressure(p_true)
    except ValueError as exc:  # the field cannot levitate the dimer
        raise TwinError(str(exc)) from None
    return DimerDynamics(sur, config.effects), p_true


def simulate_runs(config: TwinConfig, executor=None, progress: bool = True) -> tuple[list[SimulatedRun], DimerDynamics, float]:
    """Simulate every run of ``config`` through :func:`fitting.executor.map_ordered`.

    Returns
    -------
    (runs, dynamics, true pressure [Pa])
    """
    from fitting.executor import ExecutorConfig, map_ordered

    dynamics, p_true = twin_dynamics(config)
    _, seeds = run_seeds(config.seed, config.runs)
    items = [(dynamics, config.protocol, config.camera, config.duration, s, config.max_step) for s in seeds]
    executor = executor or ExecutorConfig()
    try:
        runs = map_ordered(_run_task, items, executor, desc="simulate", progress=progress)
    except TwinError as exc:
        raise TwinError(f"a run could not be simulated: {exc}") from None
    return runs, dynamics, p_true


def _fmt(v: float, spec: str) -> str:
    return "nan" if not np.isfinite(v) else format(v, spec)


def run_csv_text(run: SimulatedRun, index: int, total: int) -> str:
    """The CSV of one run (FORMATS.md): comments, header ``t,y,theta``, one row per frame."""
    lines = [
        f"# acousim digital twin, run {index} of {total}: free oscillation after the field is back on at t = 0",
        "# units: t [s], y [m] (centre-of-mass height above the levitation height), theta [-]",
        "t,y,theta",
    ]
    lines += [f"{t:.9f},{_fmt(y, '.10e')},{_fmt(th, '.10f')}" for t, y, th in zip(run.t, run.y, run.theta)]
    return "\n".join(lines) + "\n"


def meta_dict(config: TwinConfig, dynamics: DimerDynamics) -> dict:
    """meta.json: the FORMATS.md keys with the *nominal* pressure amplitude."""
    st = dynamics.surrogate.settings
    return {
        "side_length_m": float(config.side),
        "particle_density_kg_m3": float(st["particle_density_kg_m3"]),
        "bulk_modulus_pa": float(st["bulk_modulus_pa"]),
        "frequency_hz": float(st["frequency_hz"]),
        "sound_speed_m_s": float(st["sound_speed_m_s"]),
        "air_density_kg_m3": float(st["air_density_kg_m3"]),
        "pressure_amplitude_pa": float(config.pressure_amplitude_pa),
        "source": "acousim digital twin (synthetic)",
    }


def truth_dict(config: TwinConfig, dynamics: DimerDynamics, p_true: float, runs: list[SimulatedRun],
               files: list[str]) -> dict:
    """truth.json: true pressure, effects, seed, every setting and each run's initial conditions."""
    sur = dynamics.surrogate
    f_y, f_theta = sur.linear_frequencies()
    out = {
        "pressure_amplitude_pa": float(p_true),
        "effects": config.effects.to_dict(),
        "seed": int(config.seed),
        **config.to_dict(),
        "equilibrium_height_m": float(sur.z_eq),
        "escape_height_m": float(sur.escape_height()),
        "gorkov_linear_frequencies_hz": {"y": f_y, "theta": f_theta},
        "model": {k: v for k, v in sur.settings.items() if k not in ("pressure_amplitude_pa", "equilibrium_height_m")},
        "surrogate": {"build_accuracy": sur.build_accuracy, "box": asdict(sur.box)},
        "state": ["y", "ydot", "theta", "thetadot"],
        "runs_detail": [
            {"file": f, **r.drop, "state_at_field_on": [float(v) for v in r.state[0]],
             "missing_frames": [int(i) for i in r.missing]}
            for f, r in zip(files, runs)
        ],
        "units": "SI",
    }
    return out


def _json(data: dict) -> str:
    return json.dumps(data, indent=2, sort_keys=False, allow_nan=True) + "\n"


def check_output_dir(out_dir: str | os.PathLike, force: bool = False) -> Path:
    """Refuse an existing non-empty directory (or a file) unless ``force``; returns the path."""
    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise TwinError(f"{out} exists and is not a directory")
    if out.is_dir() and any(out.iterdir()) and not force:
        raise TwinError(f"{out} is not empty (use --force to replace it)")
    return out


def simulate_dataset(config: TwinConfig, out_dir: str | os.PathLike, executor=None, force: bool = False,
                     progress: bool = True) -> dict:
    """Simulate and write a data set (see the module docstring); returns the truth dictionary.

    Raises
    ------
    TwinError
        Bad settings, a non-empty ``out_dir`` without ``force``, or a run that leaves the trap;
        nothing is written then.
    """
    out = check_output_dir(out_dir, force)
    runs, dynamics, p_true = simulate_runs(config, executor, progress)
    width = max(2, len(str(config.runs)))
    files = [f"run{i:0{width}d}.csv" for i in range(1, config.runs + 1)]
    truth = truth_dict(config, dynamics, p_true, runs, files)
    parent = out.resolve().parent
    parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}.", dir=parent))
    try:
        for i, (f, r) in enumerate(zip(files, runs), 1):
            (tmp / f).write_text(run_csv_text(r, i, config.runs), encoding="utf-8")
        (tmp / "meta.json").write_text(_json(meta_dict(config, dynamics)), encoding="utf-8")
        (tmp / "truth.json").write_text(_json(truth), encoding="utf-8")
        with open(tmp / "truth_states.npz", "wb") as fh:
            np.savez(fh, t=runs[0].t, **{Path(f).stem: r.state for f, r in zip(files, runs)})
        os.chmod(tmp, 0o755)
        if out.exists():
            trash = Path(tempfile.mkdtemp(prefix=f".{out.name}.old.", dir=parent))
            os.replace(out, trash / out.name)
            os.replace(tmp, out)
            shutil.rmtree(trash, ignore_errors=True)
        else:
            os.replace(tmp, out)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return truth


# ---------------------------------------------------------------------- presets
#: The "paper-like" twin (docs/twin.md): see there for how the strengths were chosen.
PAPER_LIKE = TwinPreset(
    name="paper-like",
    effects=EffectSet((
        PairScattering(kappa=12000.0),
        LinearDamping(gamma_y=0.2, gamma_theta=0.2),
    )),
    pressure_amplitude_pa=3000.0,
    protocol=DropProtocol(),
    description="placeholder",
)

#: Presets by name (the ``--preset`` values of ``python -m acousim simulate``).
PRESETS: dict[str, TwinPreset] = {PAPER_LIKE.name: PAPER_LIKE}
