"""The paper's observations judged on full drops of a dimer in the held-y window (docs/twin.md, "Full drops in the
window"): python docs/scripts/window_observations.py SIDE G/S P0 T_OFF_MIN T_OFF_MAX Q SEEDS DURATION
e.g. 500e-6 0.02 3000 1e-3 3e-3 250 921,922,923,924,925 12

Each seed set draws 20 drops as `python -m acousim simulate` does (t_off uniform in [T_OFF_MIN, T_OFF_MAX], the hinge
at rest, theta_drop uniform in +-0.4 and thetadot_drop in +-30 1/s), with the field's ring (transducer Q) and
the air's computed damping; every run is followed for DURATION s after the drive is back and judged on its second
half by acousim.atlas.field_drops.settled_outcome (folded and escaped runs are counted as such).  Besides the classifier's
classes it prints the runs whose hinge moves at f_y (within 5 %) whatever their phase coherence, split by the
settled phase (|phase| < 60 or > 120 degrees).
"""
import sys

import numpy as np

from acousim.atlas.field_drops import drop_and_settle, observations
from acousim.dynamics.switching import ring_time
from acousim.models import ExperimentConditions, ModelSpec
from acousim.twin import DropProtocol, TwinConfig, twin_dynamics
from acousim.twin.simulation import run_seeds

side, gap_ratio, p0, t_lo, t_hi, q = (float(v) for v in sys.argv[1:7])
seeds = [int(v) for v in sys.argv[7].split(",")]
duration = float(sys.argv[8])
RUNS = 20
protocol = DropProtocol(t_off=(t_lo, t_hi), theta_drop=(-0.4, 0.4), thetadot_drop=(-30.0, 30.0))
rows = []
for seed in seeds:
    config = TwinConfig(runs=RUNS, seed=seed, duration=duration, model_spec=ModelSpec("fullwave", {"gap_m": gap_ratio * side}),
                        experiment=ExperimentConditions(side_length_m=side, pressure_amplitude_pa=p0),
                        protocol=protocol, transducer_q=q)
    dyn, _ = twin_dynamics(config)
    tau = ring_time(q, config.frequency)
    cells = []
    for stream in run_seeds(seed, RUNS)[1]:
        drop = protocol.draw(np.random.default_rng(stream))  # the twin's own first draws of each run
        cells.append(drop_and_settle(dyn, drop["t_off_s"], drop["theta_drop"], duration, 1000.0,
                                     thetadot_drop=drop["thetadot_drop"], ring_time_s=tau))
    o = observations(cells)
    rows.append(o)
    at_fy = [c for c in cells if c.get("f_y_hz", 0) > 0 and abs(c["f_theta_hz"] / c["f_y_hz"] - 1) < 0.05
             and c["amp_theta"] >= 0.02 and np.isfinite(c["section_phase_deg"])]
    near0 = [c for c in at_fy if abs(c["section_phase_deg"]) < 60]
    near180 = [c for c in at_fy if abs(c["section_phase_deg"]) > 120]
    amps = lambda cs: (f"{min(c['amp_theta'] for c in cs):.2f}-{max(c['amp_theta'] for c in cs):.2f}" if cs else "-")
    labels = {}
    for c in cells:
        key = c["outcome"] + (f" {c['lock_ratio']}" if c["outcome"] == "locked-p:q" else "") \
            + (f"/{c['amplitude_class']}" if "amplitude_class" in c else "")
        labels[key] = labels.get(key, 0) + 1
    shares = [c["share_2fy"] for c in at_fy]
    print(f"seed {seed}: {labels}; locked at f_y {o['locked_at_fy']} (in phase {o['in_phase']}, anti-phase "
          f"{o['anti_phase']}), p:q {o['lock_ratios']}, 2 f_y >= 5 % {o['with_2fy']}; long-lived {o['attractors']}; "
          f"at f_y whatever the coherence: near 0 deg {len(near0)} (amplitude {amps(near0)}), near 180 deg "
          f"{len(near180)} (amplitude {amps(near180)}); largest 2 f_y share {max(shares, default=float('nan')):.4f}",
          flush=True)
for key in ("locked_at_fy", "in_phase", "anti_phase", "folded", "escaped", "with_2fy", "n_attractors"):
    v = np.array([r[key] for r in rows], float)
    print(f"{key}: mean {v.mean():.1f}, range {v.min():g}-{v.max():g} of {RUNS}")
print("both phase classes >= 15 %:", [r["both_phase_classes"] for r in rows])
