"""The worked example of docs/fitting.md, "Any two coordinates": a simulated generic two-coordinate data set.

PYTHONPATH=. python docs/scripts/generic_system_example.py DATA_DIR [--seed 3]
python -m fitting fit DATA_DIR --out OUT_DIR

Two coupled nonlinear oscillators (angles phi1, phi2 [rad] at 1.2 and 2 Hz; the truth of
tests/fitting/test_generic_system.py), 5 runs of 16 s at 200 frames/s from random states (``fitting.synthetic``),
white noise of 0.002 rad on each angle, written in degrees with a measured phi1 rate in deg/s (noise 0.02 rad/s),
and a meta.json that declares the system.
"""
from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from fitting.model import PolynomialModel
from fitting.synthetic import SyntheticConfig, generate_runs

W1, W2 = 2 * np.pi * 1.2, 2 * np.pi * 2.0
TRUTH = PolynomialModel.from_equations({
    "yddot": {"y": -W1**2, "ydot": -0.15, "y^3": 15.0, "theta": 12.0},
    "thetaddot": {"theta": -W2**2, "thetadot": -0.3, "y^2*theta": 20.0, "y": 25.0}})
SYSTEM = {"kind": "generic", "coordinates": [{"name": "phi1", "unit": "rad", "velocity": "omega1"},
                                             {"name": "phi2", "unit": "rad"}], "frequency_range_hz": [0.5, 5]}


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("data_dir")
    p.add_argument("--seed", type=int, default=3)
    a = p.parse_args()
    cfg = SyntheticConfig(n_runs=5, duration=16.0, fps=200.0, noise_y=0.002, noise_theta=0.002,
                          y_amplitude=(0.3, 0.6), theta_amplitude=(0.1, 0.3), missing_frames=0, seed=a.seed)
    out = Path(a.data_dir)
    out.mkdir(parents=True, exist_ok=False)
    deg = 180 / np.pi
    rng = np.random.default_rng(a.seed + 1000)
    for i, r in enumerate(generate_runs(TRUTH, cfg), 1):
        om = r["state"][:, 1] + 0.02 * rng.standard_normal(r["t"].size)
        rows = ["t,phi1 [deg],phi2 [deg],omega1 [deg/s]"] + [
            f"{t:.5f},{x * deg:.6f},{z * deg:.6f},{w * deg:.6f}" for t, x, z, w in zip(r["t"], r["y"], r["theta"], om)]
        (out / f"run{i:02d}.csv").write_text("\n".join(rows) + "\n")
    (out / "meta.json").write_text(json.dumps({"system": SYSTEM}, indent=1) + "\n")
    (out / "truth.json").write_text(json.dumps({"equations": {
        "phi1ddot": {"phi1": -W1**2, "phi1dot": -0.15, "phi1^3": 15.0, "phi2": 12.0},
        "phi2ddot": {"phi2": -W2**2, "phi2dot": -0.3, "phi1^2*phi2": 20.0, "phi1": 25.0}}}, indent=1) + "\n")
    print(f"wrote {cfg.n_runs} runs, meta.json and truth.json to {out}")


if __name__ == "__main__":
    main()
