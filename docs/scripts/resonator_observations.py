"""The paper's observations judged on full drops with the levitator as a resonator (docs/twin.md, "The levitator as
a resonator"): python docs/scripts/resonator_observations.py SIDE G/S P0 T_OFF_MIN T_OFF_MAX Q DETUNING AREA SEEDS
DURATION, e.g. 500e-6 0.02 3000 1e-3 3e-3 250 -4 3e-5 941,942,943 12

As docs/scripts/window_observations.py (20 drops per seed set drawn as `python -m acousim simulate` does, the hinge
at rest, theta_drop uniform in +-0.4 and thetadot_drop in +-30 1/s, the air's computed damping, judged on the second
half of DURATION s by acousim.atlas.field_drops.settled_outcome), with the cavity mode as a state: quality factor Q,
detuning in half-widths f / (2Q) (< 0: drive above the resonance) and cavity area [m^2].  Also prints, per class, y's
amplitude over the last second of the trapped runs and its ratio to the amplitude half the run earlier (1: not
decaying over the judged half), and theta's.
"""
import sys

import numpy as np

from acousim.atlas.field_drops import observations, settled_outcome
from acousim.dynamics.resonator import coupled_field_drop
from acousim.models import ExperimentConditions, ModelSpec
from acousim.twin import DropProtocol, TwinConfig, twin_dynamics
from acousim.twin.simulation import run_seeds, twin_cavity

side, gap_ratio, p0, t_lo, t_hi, q, detuning, area = (float(v) for v in sys.argv[1:9])
seeds = [int(v) for v in sys.argv[9].split(",")]
duration = float(sys.argv[10])
RUNS = 20
protocol = DropProtocol(t_off=(t_lo, t_hi), theta_drop=(-0.4, 0.4), thetadot_drop=(-30.0, 30.0))
rows = []
for seed in seeds:
    config = TwinConfig(runs=RUNS, seed=seed, duration=duration, model_spec=ModelSpec("fullwave", {"gap_m": gap_ratio * side}),
                        experiment=ExperimentConditions(side_length_m=side, pressure_amplitude_pa=p0),
                        protocol=protocol, transducer_q=q, cavity_detuning=detuning, cavity_area=area)
    dyn, _ = twin_dynamics(config)
    cavity = twin_cavity(config, dyn)
    cells, ratios, amps, by_class = [], [], [], {}
    for stream in run_seeds(seed, RUNS)[1]:
        drop = protocol.draw(np.random.default_rng(stream))  # the twin's own first draws of each run
        m = coupled_field_drop(cavity, [0.0, 0.0, drop["theta_drop"], drop["thetadot_drop"]], drop["t_off_s"],
                               duration, 1e-3)
        if not m.ok:
            cells.append({"outcome": "folded" if m.status == 2 else "escaped", "t_end_s": float(m.t_stop)})
            continue
        x = m.trajectory.state
        cells.append({**settled_outcome(m.trajectory.t, x), "t_end_s": float("nan")})
        mid = x.shape[0] // 2
        last, half = np.ptp(x[-1000:, 0]) / 2, np.ptp(x[mid - 1000:mid, 0]) / 2
        th_last, th_half = np.ptp(x[-1000:, 2]) / 2, np.ptp(x[mid - 1000:mid, 2]) / 2
        amps.append(last)
        ratios.append(last / half)
        by_class.setdefault(cells[-1]["outcome"], []).append((last / half, th_last / max(th_half, 1e-12)))
    o = observations(cells)
    rows.append(o)
    labels = {}
    for c in cells:
        key = c["outcome"] + (f" {c['lock_ratio']}" if c["outcome"] == "locked-p:q" else "") \
            + (f"/{c['amplitude_class']}" if "amplitude_class" in c else "")
        labels[key] = labels.get(key, 0) + 1
    span = lambda v: f"{min(v):.3g}-{max(v):.3g}" if v else "-"  # noqa: E731
    print(f"seed {seed}: {labels}; locked at f_y {o['locked_at_fy']} (in phase {o['in_phase']}, anti-phase "
          f"{o['anti_phase']}), 2 f_y >= 5 % {o['with_2fy']}; long-lived {o['attractors']}; y amplitude at the end "
          f"{span([a * 1e6 for a in amps])} um, over the judged half x {span(ratios)}", flush=True)
    for name, v in sorted(by_class.items()):
        print(f"    {name}: y amplitude over the judged half x {span([r[0] for r in v])}, theta's x "
              f"{span([r[1] for r in v])}", flush=True)
for key in ("locked_at_fy", "in_phase", "anti_phase", "folded", "escaped", "with_2fy", "n_attractors"):
    v = np.array([r[key] for r in rows], float)
    print(f"{key}: mean {v.mean():.1f}, range {v.min():g}-{v.max():g} of {RUNS}")
print("both phase classes >= 15 %:", [r["both_phase_classes"] for r in rows])
