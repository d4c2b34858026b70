"""Synthetic trajectory data sets from a known polynomial model (for recovery tests and benchmarks).

Independent of ``acousim``: the generating model is any :class:`~fitting.model.PolynomialModel`,
by default :func:`paper_reduced_model` (docs/conventions.md section 6) with realistic scales.
:func:`write_generic_example` writes the worked example of a generic two-coordinate system (docs/fitting.md,
"Any two coordinates"; ``python -m fitting synth --system generic``).
"""
from __future__ import annotations

import os
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from cubedimer.atomic import atomic_write_text, write_json
from cubedimer.config_checks import check_bounds, check_non_negative, check_positive, check_whole
from cubedimer.dataset import write_run_csv
from cubedimer.meta import DEFAULT_TRACKING_NOISE

from .model import PolynomialModel

__all__ = ["SyntheticConfig", "paper_reduced_model", "generate_runs", "write_dataset", "generic_example_model",
           "GENERIC_EXAMPLE_SYSTEM", "write_generic_example"]


def paper_reduced_model() -> PolynomialModel:
    """The paper's reduced model with SI coefficients of the suite's own choice (the recovery-test truth; the
    paper gives no numeric values).

    yddot = a0 + a1 y + a2 y^2 + a3 ydot, thetaddot = b0 + b1 theta + b2 y + b3 theta y^2
    + b4 thetadot + b5 thetadot^2 y + b6 thetadot ydot y, with f_y = 22 Hz, f_theta = 9 Hz,
    gamma_y = 0.3 1/s, gamma_theta = 0.8 1/s.  The theta*y^2 term contributes ~2-4 % of
    |thetaddot| at y amplitudes of 100 um (see tests).
    """
    return PolynomialModel.from_equations({
        "yddot": {"1": 0.1, "y": -(2 * np.pi * 22.0) ** 2, "y^2": 9.5e6, "ydot": -0.3},
        "thetaddot": {"1": 60.0, "theta": -(2 * np.pi * 9.0) ** 2, "y": 1.5e6,
                      "y^2*theta": 2.0e10, "thetadot": -0.8,
                      "y*thetadot^2": 5.0e3, "y*ydot*thetadot": 8.0e6},
    })


@dataclass(frozen=True)
class SyntheticConfig:
    """Settings of a synthetic data set.

    Parameters
    ----------
    n_runs : int
    duration : float
        Run length [s].
    fps : float
        Frame rate [1/s].
    noise_y : float
        Gaussian tracking noise on y [m] (standard deviation).
    noise_theta : float
        Gaussian tracking noise on theta [-].
    y_amplitude : (float, float)
        Range of initial y amplitudes [m].
    theta_amplitude : (float, float)
        Range of initial theta amplitudes [-].
    missing_frames : int
        Frames per run blanked (NaN) at random interior positions, to exercise gap filling.
    seed : int
    """

    n_runs: int = 15
    duration: float = 3.0
    fps: float = 1500.0
    noise_y: float = DEFAULT_TRACKING_NOISE["noise_y_m"]
    noise_theta: float = DEFAULT_TRACKING_NOISE["noise_theta"]
    y_amplitude: tuple[float, float] = (60e-6, 150e-6)
    theta_amplitude: tuple[float, float] = (0.08, 0.4)
    missing_frames: int = 3
    seed: int = 0

    def __post_init__(self) -> None:
        check_whole(self, "n_runs")
        check_positive(self, "duration")
        check_positive(self, "fps")
        check_non_negative(self, "noise_y")
        check_non_negative(self, "noise_theta")
        check_bounds(self, "y_amplitude")
        check_bounds(self, "theta_amplitude")
        check_whole(self, "missing_frames", minimum=0)


def _initial_state(rng: np.random.Generator, cfg: SyntheticConfig, model: PolynomialModel) -> np.ndarray:
    from .model import TERMS
    wy = np.sqrt(max(-model.coef[0, TERMS.index("y")], 1.0))
    wt = np.sqrt(max(-model.coef[1, TERMS.index("theta")], 1.0))
    A = rng.uniform(*cfg.y_amplitude)
    B = rng.uniform(*cfg.theta_amplitude)
    p, q = rng.uniform(0, 2 * np.pi, 2)
    return np.array([A * np.cos(p), -A * wy * np.sin(p), B * np.cos(q), -B * wt * np.sin(q)])


def generate_runs(model: PolynomialModel, cfg: SyntheticConfig = SyntheticConfig()) -> list[dict]:
    """Integrate ``model`` from random initial states and add tracking noise.

    Returns
    -------
    list of dict with keys ``t`` [s], ``y`` [m], ``theta`` [-] (noisy, NaN in missing frames),
    ``state`` (n, 4) exact SI states, ``x0`` (4,).
    """
    rng = np.random.default_rng(cfg.seed)
    n = int(round(cfg.duration * cfg.fps))
    t = np.arange(n) / cfg.fps
    runs = []
    for _ in range(cfg.n_runs):
        x0 = _initial_state(rng, cfg, model)
        states, nv = model.simulate(x0, t, substeps=max(8, model.default_substeps(1 / cfg.fps, 0.01)))
        if nv < n:
            raise RuntimeError("the generating model blew up; choose other coefficients or amplitudes")
        y = states[:, 0] + cfg.noise_y * rng.standard_normal(n)
        th = states[:, 2] + cfg.noise_theta * rng.standard_normal(n)
        if cfg.missing_frames:
            idx = rng.choice(np.arange(10, n - 10), size=cfg.missing_frames, replace=False)
            y[idx] = np.nan
            th[idx] = np.nan
        runs.append({"t": t, "y": y, "theta": th, "state": states, "x0": x0})
    return runs


def write_dataset(out_dir: str | os.PathLike, model: PolynomialModel,
                  cfg: SyntheticConfig = SyntheticConfig()) -> list[dict]:
    """Write ``runNN.csv`` files (t, y, theta) and ``truth.json`` to ``out_dir`` (atomically per file)."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    runs = generate_runs(model, cfg)
    for i, r in enumerate(runs, 1):
        write_run_csv(out / f"run{i:02d}.csv", r["t"], r["y"], r["theta"],
                      ["synthetic run from fitting.synthetic (SI units)"],
                      t_decimals=7, y_digits=6, theta_decimals=6, missing="")
    truth = {**model.to_json(), "config": asdict(cfg),
             "initial_states": [r["x0"].tolist() for r in runs], "seed": cfg.seed}
    write_json(out / "truth.json", truth)
    return runs


#: The generic system of :func:`write_generic_example`: two angles [rad], a measured rate of the first.
GENERIC_EXAMPLE_SYSTEM = {"kind": "generic", "coordinates": [{"name": "phi1", "unit": "rad", "velocity": "omega1"},
                                                             {"name": "phi2", "unit": "rad"}],
                          "frequency_range_hz": [0.5, 5]}


def generic_example_model() -> PolynomialModel:
    """Two coupled nonlinear oscillators at 1.2 and 2 Hz in the library's slots (y = phi1, theta = phi2 [rad]).

    phi1'' = -(2 pi 1.2)^2 phi1 - 0.15 phi1' + 12 phi2 + 15 phi1^3,
    phi2'' = 25 phi1 - (2 pi 2)^2 phi2 - 0.3 phi2' + 20 phi1^2 phi2 [1/s^2 and 1/s].
    """
    w1, w2 = 2 * np.pi * 1.2, 2 * np.pi * 2.0
    return PolynomialModel.from_equations({
        "yddot": {"y": -w1**2, "ydot": -0.15, "y^3": 15.0, "theta": 12.0},
        "thetaddot": {"theta": -w2**2, "thetadot": -0.3, "y^2*theta": 20.0, "y": 25.0}})


def write_generic_example(out_dir: str | os.PathLike, seed: int = 3) -> SyntheticConfig:
    """Write the generic-system example: 5 runs of 16 s at 200 frames/s of :func:`generic_example_model` from random
    states, white noise 0.002 rad on each angle, written in degrees with a measured phi1 rate in deg/s (noise
    0.02 rad/s), ``meta.json`` declaring :data:`GENERIC_EXAMPLE_SYSTEM`, and ``truth.json`` in the declared names.

    Parameters
    ----------
    out_dir : path-like
        Directory to write into (created; each file is written atomically).
    seed : int
        Seed of the initial states and of the noise.

    Returns
    -------
    SyntheticConfig
        The settings the runs were drawn with.
    """
    cfg = SyntheticConfig(n_runs=5, duration=16.0, fps=200.0, noise_y=0.002, noise_theta=0.002,
                          y_amplitude=(0.3, 0.6), theta_amplitude=(0.1, 0.3), missing_frames=0, seed=seed)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    deg = 180 / np.pi
    rng = np.random.default_rng(seed + 1000)
    for i, r in enumerate(generate_runs(generic_example_model(), cfg), 1):
        om = r["state"][:, 1] + 0.02 * rng.standard_normal(r["t"].size)
        rows = ["t,phi1 [deg],phi2 [deg],omega1 [deg/s]"] + [
            f"{t:.5f},{x * deg:.6f},{z * deg:.6f},{w * deg:.6f}" for t, x, z, w in zip(r["t"], r["y"], r["theta"], om)]
        atomic_write_text(out / f"run{i:02d}.csv", "\n".join(rows) + "\n")
    write_json(out / "meta.json", {"system": GENERIC_EXAMPLE_SYSTEM})
    names = {"yddot": "phi1ddot", "thetaddot": "phi2ddot", "y": "phi1", "ydot": "phi1dot", "theta": "phi2",
             "thetadot": "phi2dot", "y^3": "phi1^3", "y^2*theta": "phi1^2*phi2"}
    truth = {names[eq]: {names[t]: c for t, c in terms.items()} for eq, terms in generic_example_model().equations().items()}
    write_json(out / "truth.json", {"equations": truth})
    return cfg
