"""The worked example of docs/fitting.md, "Any two coordinates": a simulated generic two-coordinate data set.

PYTHONPATH=. python docs/scripts/generic_system_example.py DATA_DIR [--seed 3]
(the same as ``python -m fitting synth DATA_DIR --system generic --seed 3`` from an installed package)
python -m fitting fit DATA_DIR --out OUT_DIR

Two coupled nonlinear oscillators (angles phi1, phi2 [rad] at 1.2 and 2 Hz; the truth of
tests/fitting/test_generic_system.py), 5 runs of 16 s at 200 frames/s from random states
(:func:`fitting.synthetic.write_generic_example`), white noise of 0.002 rad on each angle, written in degrees with a
measured phi1 rate in deg/s (noise 0.02 rad/s), and a meta.json that declares the system.
"""
from __future__ import annotations

import argparse
from pathlib import Path

from fitting.synthetic import write_generic_example


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("data_dir")
    p.add_argument("--seed", type=int, default=3)
    a = p.parse_args()
    out = Path(a.data_dir)
    out.mkdir(parents=True, exist_ok=False)
    cfg = write_generic_example(out, seed=a.seed)
    print(f"wrote {cfg.n_runs} runs, meta.json and truth.json to {out}")


if __name__ == "__main__":
    main()
