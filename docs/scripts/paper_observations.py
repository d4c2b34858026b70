"""The source paper's observations judged on the paper preset (docs/twin.md): python docs/scripts/paper_observations.py

Fresh seeds of the `paper` preset: each seed set draws its runs' drops exactly as `python -m acousim simulate
--preset paper --seed S` does; every run is followed for DURATION s after the field is back on (longer than the
twin's default, so that "long-lived" can mean more than 100 cycles of y after the transient) and judged by
acousim.atlas.field_drops.settled_outcome: the classifier of cubedimer.attractors plus the 2 f_y share.  A run that folds
(faces touch) or escapes is counted as such instead of stopping the set.  Also prints what the physics gives for
the quantities the paper's reduced model needs (f_theta / f_y, the hinge damping, the theta*y^2 coefficient).
Takes about a minute on one core.
"""
import sys

import numpy as np

from acousim.atlas.field_drops import drop_and_settle, observations
from acousim.twin import PAPER, TwinConfig, twin_dynamics
from acousim.twin.simulation import run_seeds

SEEDS = (101, 102, 103, 104, 105)
RUNS = 20
DURATION = 8.0

rows = []
for seed in SEEDS:
    config = TwinConfig.from_preset(PAPER, runs=RUNS, seed=seed, duration=DURATION)
    dyn, _ = twin_dynamics(config)
    _, streams = run_seeds(seed, RUNS)
    cells = []
    for stream in streams:
        drop = config.protocol.draw(np.random.default_rng(stream))  # the twin's own first draws of each run
        cells.append(drop_and_settle(dyn, drop["t_off_s"], drop["theta_drop"], DURATION, 1000.0,
                                     thetadot_drop=drop["thetadot_drop"]))
    o = observations(cells)
    rows.append(o)
    labels = {}
    for c in cells:
        key = c["outcome"] + (f"/{c['amplitude_class']}" if "amplitude_class" in c else "")
        labels[key] = labels.get(key, 0) + 1
    free = [c for c in cells if c["outcome"] == "independent"]
    ratio = [c["f_theta_hz"] / c["f_y_hz"] for c in free]
    free_text = (f"; independent: theta amplitude {min(c['amp_theta'] for c in free):.2f}-"
                 f"{max(c['amp_theta'] for c in free):.2f} at f_theta / f_y {min(ratio):.3f}-{max(ratio):.3f}, "
                 f"2 f_y share {min(c['share_2fy'] for c in free):.2f}-{max(c['share_2fy'] for c in free):.2f}"
                 if free else "")
    print(f"seed {seed}: {labels}; locked at f_y {o['locked_at_fy']}/{RUNS}, p:q locks {o['lock_ratios']}, "
          f"2 f_y >= 5 % {o['with_2fy']} (of the locks at f_y {o['with_2fy_at_fy']}), "
          f"in phase {o['in_phase']}, anti-phase {o['anti_phase']}, long-lived attractors {o['attractors']}"
          f"{free_text}", flush=True)

for key in ("locked_at_fy_fraction", "with_2fy_fraction"):
    v = np.array([r[key] for r in rows])
    print(f"{key}: {v.mean():.3f} +- {v.std(ddof=1):.3f} over {len(rows)} seed sets of {RUNS}")
for key in ("folded", "escaped", "in_phase", "anti_phase", "n_attractors"):
    v = np.array([r[key] for r in rows], float)
    print(f"{key}: mean {v.mean():.2f}, range {v.min():g}-{v.max():g}")
print("both phase classes >= 15 %:", [r["both_phase_classes"] for r in rows])

fm = dyn.force_model
f_y, f_t = fm.linear_frequencies()
tc = fm.taylor_coefficients()["thetaddot"]
air = dyn.effects["air_damping"]
print(f"physics at the preset: f_y {f_y:.2f} Hz, f_theta {f_t:.2f} Hz (ratio {f_t / f_y:.3f}); air damping gamma_y "
      f"{air.gamma_y:.3f} 1/s, gamma_theta(0) {air.gamma_theta:.3f} 1/s; thetaddot theta {tc['theta']:.3g} 1/s^2, "
      f"y^2*theta {tc['y^2*theta']:+.3g} 1/(m^2 s^2), y {tc.get('y', float('nan')):+.3g} 1/(m s^2); no velocity "
      "coupling (y*thetadot^2, y*ydot*thetadot) in the inviscid model", file=sys.stdout)
