"""Output-error fit of a velocity coupling on one data set of docs/scripts/velocity_coupling_fixed_set.py, with the
standard errors of the whole trajectories (the Cramer-Rao bound at the fit).

Every run is simulated from its own initial state (fitted) with the twin's force model at the true pressure (from the
case's hidden truth.json), the damping law given by ``--damping`` (``linear``: linear damping, the candidate that
stands for the air; ``air``: the air's damping law of the truth with its two rates free) and c5, c6; Gauss-Newton on
every frame of y and theta weighted by the tracking noise (1 um, 0.005), from c5 = c6 = 0, the rates 0.6 and 1.2 1/s,
and initial states from the smoothed data.  Prints each iteration's chi^2 per frame and estimates with their standard
errors, then the truth.

    python docs/scripts/velocity_coupling_output_error.py DIR/velocity_coupling_0 --damping air

docs/diagnosis.md (Known limitations) quotes its output.
"""
from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from acousim import DimerDynamics, EffectSet, cached_surrogate
from cubedimer.dataset import load_dataset
from fitting.derivatives.savitzky_golay import differentiate

NOISE = np.array([1e-6, 0.005])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("case", type=Path)
    ap.add_argument("--damping", choices=("linear", "air"), default="linear")
    ap.add_argument("--iterations", type=int, default=3)
    args = ap.parse_args()
    truth = json.loads((args.case / "truth.json").read_text())
    runs = load_dataset(args.case / "data", report=lambda m: None).runs
    sur = cached_surrogate().with_pressure(truth["pressure_amplitude_pa"])
    dt, n, w = float(runs[0].dt), min(len(r.t) for r in runs), 31
    data = np.stack([np.column_stack([r.y[:n], r.theta[:n]]) for r in runs])[:, w:] / NOISE
    x0 = np.array([[d[w] for d in (*differentiate(r.y, dt, w, 5)[:2], *differentiate(r.theta, dt, 101, 3)[:2])]
                   for r in runs])

    def effects(p):
        if args.damping == "air":
            air = dict(truth["effects"]["air_damping"], gamma_y=p[2], gamma_theta=p[3])
            return {"velocity_coupling": {"c5": p[0], "c6": p[1]}, "air_damping": air}
        return {"velocity_coupling": {"c5": p[0], "c6": p[1]}, "linear_damping": {"gamma_y": p[2], "gamma_theta": p[3]}}

    def simulated(p, starts):
        out, _, _ = DimerDynamics(sur, EffectSet.from_dict(effects(p))).integrate_batch(starts, dt * (n - w - 1), dt)
        out = out[..., [0, 2]]
        out[..., 0] += p[4] if len(starts) == len(runs) else 0.0
        return out / NOISE

    p, starts, R = np.array([0.0, 0.0, 0.6, 1.2, 0.0]), x0.copy(), len(runs)
    hp, hs = np.array([50.0, 5e4, 0.005, 0.005, 1e-7]), np.array([2e-7, 2e-5, 2e-4, 2e-3])
    for it in range(args.iterations):
        r0 = np.nan_to_num(data - simulated(p, starts))
        shared = []
        for k in range(5):
            dp = np.eye(5)[k] * hp[k]
            shared.append(((simulated(p + dp, starts) - simulated(p - dp, starts)) / (2 * hp[k])).reshape(R, -1))
        shared = np.stack(shared, -1)
        moved = np.concatenate([starts + np.eye(4)[k] * hs[k] for k in range(4)]
                               + [starts - np.eye(4)[k] * hs[k] for k in range(4)])
        o = simulated(p, moved)
        own = (o[:4 * R] - o[4 * R:]).reshape(4, R, -1) / (2 * hs[:, None, None])
        size = 5 + 4 * R
        jtj, jtr = np.zeros((size, size)), np.zeros(size)
        for i in range(R):
            a = np.zeros((own.shape[2], size))
            a[:, :5], a[:, 5 + 4 * i:9 + 4 * i] = shared[i], own[:, i].T
            keep = np.isfinite(data[i].reshape(-1)) & (np.abs(r0[i].reshape(-1)) < 50)
            jtj += a[keep].T @ a[keep]
            jtr += a[keep].T @ r0[i].reshape(-1)[keep]
        step = np.linalg.solve(jtj, jtr)
        p, starts = p + step[:5], starts + step[5:].reshape(R, 4)
        se = np.sqrt(np.diag(np.linalg.inv(jtj)))
        print(f"{it}: chi2/frame {np.mean(r0 ** 2):.4f}  c5 = {p[0]:.1f} +- {se[0]:.1f}  "
              f"c6 = {p[1]:.4g} +- {se[1]:.3g}  gamma_y = {p[2]:.4f}  gamma_theta = {p[3]:.4f}", flush=True)
    air = truth["effects"].get("air_damping", {})
    print("truth:", truth["effects"].get("velocity_coupling"), {k: air.get(k) for k in ("gamma_y", "gamma_theta")})


if __name__ == "__main__":
    main()
