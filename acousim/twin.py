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

from cubedimer.atomic import json_text

from .dynamics import DEFAULT_MAX_STEP, DimerDynamics
from .effects import EffectSet, LinearDamping, MirrorAsymmetry, PairScattering
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
    "twin_dynamics",
    "LockState",
    "lock_state",
    "write_twin_figures",
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
    """Simulate every run of ``config`` through :func:`cubedimer.executor.map_ordered`.

    Returns
    -------
    (runs, dynamics, true pressure [Pa])
    """
    from cubedimer.executor import ExecutorConfig, map_ordered

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
        (tmp / "meta.json").write_text(json_text(meta_dict(config, dynamics)), encoding="utf-8")
        (tmp / "truth.json").write_text(json_text(truth), encoding="utf-8")
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


# ---------------------------------------------------------------------- analysis and figures
@dataclass(frozen=True)
class LockState:
    """How the hinge moves relative to y in the second half of a run (from exact states).

    Attributes
    ----------
    label : str
        ``"in-phase"`` / ``"anti-phase"`` / ``"quadrature"`` (theta locked to y: the hinge's phase at the
        Poincare section y = 0, ydot < 0 is constant), ``"unlocked"`` (it drifts), ``"at-rest"``
        (theta amplitude below 0.02).
    phase_deg : float
        Phase of theta's y-frequency motion relative to y [deg] (0: in phase), circular mean over
        the section crossings.
    coherence : float
        |mean of exp(i phase)| over the crossings (1: perfectly locked).
    theta_amplitude : float
        Half the peak-to-peak theta.
    """

    label: str
    phase_deg: float
    coherence: float
    theta_amplitude: float


def lock_state(t: NDArray, state: NDArray, coherence_min: float = 0.95, rest: float = 0.02,
               start_fraction: float = 0.5) -> LockState:
    """Classify a run (from ``start_fraction`` of it on; default its second half) by the hinge phase
    at the Poincare section (y = 0, ydot < 0); ``state`` (n, 4) exact, t (n,) [s].

    With y ~ A cos(w t), the section is w t = pi/2; for theta ~ B cos(w t + p) there
    theta = -B sin p and thetadot = -B w cos p, so p = atan2(-theta, -thetadot / w).
    """
    from cubedimer.poincare import poincare_section

    t, state = np.asarray(t, float), np.asarray(state, float)
    h = int(len(t) * start_fraction)
    amp = 0.5 * float(np.ptp(state[h:, 2]))
    sec = poincare_section(t[h:], state[h:])
    if amp < rest or len(sec) < 3:
        return LockState("at-rest", float("nan"), float("nan"), amp)
    w = 2 * np.pi * (len(sec) - 1) / (sec.times[-1] - sec.times[0])
    z = np.mean(np.exp(1j * np.arctan2(-sec.theta, -sec.thetadot / w)))
    ph, coh = float(np.degrees(np.angle(z))), float(abs(z))
    if coh < coherence_min:
        label = "unlocked"
    elif abs(ph) < 60:
        label = "in-phase"
    elif abs(ph) > 120:
        label = "anti-phase"
    else:
        label = "quadrature"
    return LockState(label, ph, coh, amp)


_COLORS = {"in-phase": "tab:blue", "anti-phase": "tab:red", "quadrature": "tab:purple", "unlocked": "tab:gray",
           "at-rest": "tab:green"}


def write_twin_figures(data_dir: str | os.PathLike, fig_dir: str | os.PathLike, prefix: str = "twin_") -> list[Path]:
    """Figures of a twin data set's exact states (``truth_states.npz``) into ``fig_dir``.

    ``{prefix}timeseries.png`` (time series and amplitude spectra of representative runs),
    ``{prefix}phase_portraits.png`` ((theta, thetadot, y) portraits), ``{prefix}poincare.png`` (the
    section y = 0, ydot < 0 and its map theta_k -> theta_k+1) and ``{prefix}phase_hist.png`` (the
    y-theta phase difference per run and per 0.5 s window).  Returns the paths written.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from cubedimer.atomic import save_figure

    from cubedimer.poincare import poincare_section
    from cubedimer.spectra import amplitude_spectrum

    data_dir, fig_dir = Path(data_dir), Path(fig_dir)
    npz = np.load(data_dir / "truth_states.npz")
    truth = json.loads((data_dir / "truth.json").read_text())
    t = npz["t"]
    names = sorted(k for k in npz.files if k != "t")
    states = [npz[k] for k in names]
    dt = float(t[1] - t[0])
    locks = [lock_state(t, x) for x in states]
    fig_dir.mkdir(parents=True, exist_ok=True)
    title = f"acousim twin: {EffectSet.from_dict(truth['effects']).describe()}"
    reps = []
    for lab in ("in-phase", "anti-phase", "unlocked", "quadrature", "at-rest"):
        idx = [i for i, l in enumerate(locks) if l.label == lab]
        if idx:
            reps.append(idx[0])
    reps = reps[:3]
    out = []

    # 1. time series and spectra
    fig, axes = plt.subplots(len(reps), 2, figsize=(12, 3.0 * len(reps)), squeeze=False)
    for row, i in enumerate(reps):
        x, lab = states[i], locks[i]
        ax = axes[row, 0]
        ax.plot(t, x[:, 0] * 1e6, color="k", lw=0.6, label="y [um]")
        ax.set_ylabel("y [um]")
        ax2 = ax.twinx()
        ax2.plot(t, x[:, 2], color=_COLORS[lab.label], lw=0.6, label="theta")
        ax2.set_ylabel("theta")
        ax.set_title(f"{names[i]}: {lab.label} (phase {lab.phase_deg:.0f} deg)", fontsize=9)
        ax.set_xlabel("t [s] (field back on at 0)")
        ins = ax.inset_axes([0.62, 0.6, 0.36, 0.38])
        sel = t > t[-1] - 0.15
        ins.plot(t[sel], x[sel, 0] / np.max(np.abs(x[sel, 0])), "k", lw=0.8)
        ins.plot(t[sel], (x[sel, 2] - x[sel, 2].mean()) / np.max(np.abs(x[sel, 2] - x[sel, 2].mean())),
                 color=_COLORS[lab.label], lw=0.8)
        ins.set_xticks([]), ins.set_yticks([])
        ax = axes[row, 1]
        h = len(t) // 2
        f, ay = amplitude_spectrum(x[h:, 0], dt)
        _, at = amplitude_spectrum(x[h:, 2], dt)
        ax.semilogy(f, ay / ay.max(), "k", lw=0.7, label="y")
        ax.semilogy(f, at / at.max(), color=_COLORS[lab.label], lw=0.7, label="theta")
        fy = f[np.argmax(ay)]
        for m in (1, 2, 3):
            ax.axvline(m * fy, color="0.7", lw=0.5, ls="--")
        ax.set_xlim(0, 80)
        ax.set_ylim(1e-5, 2)
        ax.set_xlabel("f [Hz] (second half of the run; dashed: 1, 2, 3 x f_y)")
        ax.set_ylabel("amplitude / max")
        ax.legend(fontsize=8, loc="upper right")
    fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    out.append(fig_dir / f"{prefix}timeseries.png")
    save_figure(fig, out[-1], dpi=110)

    # 2. phase portraits
    fig = plt.figure(figsize=(12, 5))
    ax3 = fig.add_subplot(1, 2, 1, projection="3d")
    ax = fig.add_subplot(1, 2, 2)
    last = t > t[-1] - 1.0
    for i, (x, lab) in enumerate(zip(states, locks)):
        c = _COLORS[lab.label]
        if i in reps:
            ax3.plot(x[last, 2], x[last, 3], x[last, 0] * 1e6, color=c, lw=0.5)
        ax.plot(x[last, 2], x[last, 3], color=c, lw=0.3, alpha=0.6)
    ax3.set_xlabel("theta"), ax3.set_ylabel("thetadot [1/s]"), ax3.set_zlabel("y [um]")
    ax3.set_title("(theta, thetadot, y), last second, representative runs", fontsize=9)
    ax.set_xlabel("theta"), ax.set_ylabel("thetadot [1/s]")
    ax.set_title("(theta, thetadot), last second, all runs (colour: class)", fontsize=9)
    for lab, c in _COLORS.items():
        ax.plot([], [], color=c, label=f"{lab} ({sum(l.label == lab for l in locks)})")
    ax.legend(fontsize=8)
    fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    out.append(fig_dir / f"{prefix}phase_portraits.png")
    save_figure(fig, out[-1], dpi=110)

    # 3. Poincare section and map
    fig, axes = plt.subplots(1, 2, figsize=(12, 5))
    for x, lab in zip(states, locks):
        sec = poincare_section(t, x)
        c = _COLORS[lab.label]
        late = sec.times > t[-1] / 2
        axes[0].plot(sec.theta[~late], sec.thetadot[~late], ".", color=c, ms=1.5, alpha=0.3)
        axes[0].plot(sec.theta[late], sec.thetadot[late], ".", color=c, ms=3)
        axes[1].plot(sec.theta[:-1], sec.theta[1:], ".", color=c, ms=2, alpha=0.6)
    lim = max(1e-3, max(np.max(np.abs(x[:, 2])) for x in states))
    axes[1].plot([-lim, lim], [-lim, lim], "k:", lw=0.6)
    axes[0].set_xlabel("theta at y = 0, ydot < 0"), axes[0].set_ylabel("thetadot [1/s]")
    axes[0].set_title("Poincare section (faint: first half, bold: second half)", fontsize=9)
    axes[1].set_xlabel("theta_k"), axes[1].set_ylabel("theta_k+1")
    axes[1].set_title("Poincare map of theta", fontsize=9)
    for lab, c in _COLORS.items():
        axes[0].plot([], [], ".", color=c, label=lab)
    axes[0].legend(fontsize=8)
    fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    out.append(fig_dir / f"{prefix}poincare.png")
    save_figure(fig, out[-1], dpi=110)

    # 4. phase-difference distribution
    fig, axes = plt.subplots(1, 2, figsize=(12, 4))
    bins = np.linspace(-180, 180, 37)
    per_run = [l.phase_deg for l in locks if np.isfinite(l.phase_deg)]
    axes[0].hist(per_run, bins=bins, color="0.4")
    axes[0].set_xlabel("phase of theta relative to y at f_y [deg] (second half of each run)")
    axes[0].set_ylabel("runs")
    win = int(round(0.5 / dt))
    rows = []
    for x in states:
        for k0 in range(0, len(t) - win + 1, win):
            ls = lock_state(t[k0:k0 + win], x[k0:k0 + win], 0.0, start_fraction=0.0)
            if np.isfinite(ls.phase_deg):
                rows.append((k0 * dt, ls.phase_deg))
    rows = np.array(rows) if rows else np.zeros((0, 2))
    if len(rows):
        sc = axes[1].scatter(rows[:, 1], rows[:, 0], c=rows[:, 0], s=6, cmap="viridis")
        fig.colorbar(sc, ax=axes[1], label="window start [s]")
    axes[1].set_xlabel("phase per 0.5 s window [deg]"), axes[1].set_ylabel("window start [s]")
    axes[1].set_xlim(-180, 180)
    fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    out.append(fig_dir / f"{prefix}phase_hist.png")
    save_figure(fig, out[-1], dpi=110)
    return out


# ---------------------------------------------------------------------- presets
#: The "paper-like" twin of docs/twin.md.  pair_scattering tunes the hinge to just below the y
#: frequency (f_theta = 21.0 Hz vs f_y = 21.3-21.8 Hz), mirror_asymmetry's beta1 y term drives the
#: hinge at f_y, y is weakly damped (amplitude decay time 20 s) and the hinge transient dies in
#: ~1-2 s.  Over 200 drops: ~45 % lock anti-phase with a small hinge amplitude (~0.15), ~40 % lock
#: in-phase with a large one (~0.65), ~15 % have not settled after 4 s; never a failed run.
PAPER_LIKE = TwinPreset(
    name="paper-like",
    effects=EffectSet((
        LinearDamping(gamma_y=0.1, gamma_theta=1.5),
        PairScattering(kappa=19500.0),
        MirrorAsymmetry(beta0=0.0, beta1=1.0e6),
    )),
    pressure_amplitude_pa=3000.0,
    protocol=DropProtocol(t_off=(2.0e-3, 4.0e-3), theta_drop=(-0.3, 0.3), thetadot_drop=(-3.0, 3.0)),
    description="hinge tuned just below the y frequency by pair scattering and driven at f_y by a "
    "mirror asymmetry; weak damping: bistable in-phase (large) and anti-phase (small) locking, see docs/twin.md",
)

#: Presets by name (the ``--preset`` values of ``python -m acousim simulate``).
PRESETS: dict[str, TwinPreset] = {PAPER_LIKE.name: PAPER_LIKE}
