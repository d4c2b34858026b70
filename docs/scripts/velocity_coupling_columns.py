"""How well the integral form's velocity-coupling columns are measured, and how much the theta equation can say about
c5 and c6.

Makes one twin data set with the air's damping and a velocity coupling (10 runs of 3 s, the blind study's camera), and
the same runs without tracking noise.  Prints, for the columns ``P K[thetadot^2 y]`` (c5) and ``P K[thetadot ydot y]``
(c6) of the theta equation's integral form:

* their relative rms difference from the columns at the exact states, and the slope of their regression on them
  (1: no attenuation), at the diagnosis's column states with the hinge rate smoothed only (``smoothed``) and completed
  by the simulation's fast response (``completed``, validation.diagnosis.prepare.hinge_state);
* the standard errors of c5 and c6 that the integral form would reach at the exact states (the tracking noise of
  theta over the columns, with linear damping, a constant torque and mirror asymmetry's y column beside them).

    python docs/scripts/velocity_coupling_columns.py --seed 5 --c5 1860 --c6 9.0e5

docs/diagnosis.md (Known limitations) quotes its output.
"""
from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

import numpy as np
from scipy.interpolate import make_interp_spline

from acousim.dynamics.effects import EffectSet
from acousim.twin import TwinConfig, simulate_dataset
from acousim.twin.config import Camera
from acousim import GorkovDimer
from cubedimer.dataset import load_dataset
from fitting.derivatives.integral_form import integral_columns, integral_window, window_starts
from validation.diagnosis.prepare.hinge_state import prepared_problem
from validation.diagnosis.prepare.runs import prepare_diagnosis_runs


def exact_states(run) -> np.ndarray:
    """[y, ydot, theta, thetadot] of a noise-free run (order-7 spline through every frame)."""
    sp = [make_interp_spline(run.t, x, k=7) for x in (run.y, run.theta)]
    return np.column_stack([sp[0](run.t), sp[0].derivative()(run.t), sp[1](run.t), sp[1].derivative()(run.t)])


def coupling_columns(s: np.ndarray) -> np.ndarray:
    return np.column_stack([s[:, 3] ** 2 * s[:, 0], s[:, 3] * s[:, 1] * s[:, 0]])


def compare(runs, exact) -> tuple[np.ndarray, np.ndarray]:
    """Relative rms difference and regression slope of the two columns against those at the exact states."""
    num, den, cross = np.zeros(2), np.zeros(2), np.zeros(2)
    for r in runs:
        pi = r.integral
        k0 = int(round(pi.t0 / pi.dt))
        ex = exact[r.name][k0:k0 + pi.positions.shape[0]]
        a, b = pi.columns(1, coupling_columns(pi.state)), pi.columns(1, coupling_columns(ex))
        num += np.sum((a - b) ** 2, 0)
        den += np.sum(b ** 2, 0)
        cross += np.sum(a * b, 0)
    return np.sqrt(num / den), cross / den


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seed", type=int, default=5)
    ap.add_argument("--c5", type=float, default=1860.0)
    ap.add_argument("--c6", type=float, default=9.0e5)
    args = ap.parse_args()
    effects = EffectSet.from_dict({"velocity_coupling": {"c5": args.c5, "c6": args.c6}})
    with tempfile.TemporaryDirectory() as tmp:
        noisy, clean = Path(tmp) / "noisy", Path(tmp) / "clean"
        for path, camera in ((noisy, Camera()), (clean, Camera(noise_y=0.0, noise_theta=0.0))):
            simulate_dataset(TwinConfig(runs=10, duration=3.0, seed=args.seed, effects=effects, camera=camera), path,
                             progress=False, force=True)
        dataset = load_dataset(noisy, report=lambda m: None)
        exact = {r.name: exact_states(r) for r in load_dataset(clean, report=lambda m: None).runs}
        smoothed = prepare_diagnosis_runs(dataset)
        completed = prepared_problem(GorkovDimer().interpolated(), dataset, 1500).recorded_runs
    for label, runs in (("smoothed", smoothed), ("completed", completed)):
        err, slope = compare(runs, exact)
        print(f"{label:9s} c5 column: {err[0]:.3f} rms off, slope {slope[0]:.3f};  "
              f"c6 column: {err[1]:.3f} rms off, slope {slope[1]:.3f}")
    design = []
    for name, s in exact.items():
        y = s[:, 0] - s[:, 0].mean()
        f_theta = np.abs(np.fft.rfft(s[:, 2] - s[:, 2].mean()))[1:].argmax() + 1
        w = integral_window(5e-4, f_theta / (len(y) * 5e-4))
        cols = np.column_stack([s[:, 3] ** 2 * y, s[:, 3] * s[:, 1] * y, s[:, 3], np.ones_like(y), y])
        design.append(integral_columns(cols, 5e-4, window_starts(len(y), w), w))
    x = np.concatenate(design)
    se = 0.005 * np.sqrt(np.diag(np.linalg.inv(x.T @ x)))
    print(f"integral form at the exact states: SE(c5) = {se[0]:.3g} 1/m, SE(c6) = {se[1]:.3g} 1/m^2")


if __name__ == "__main__":
    main()
