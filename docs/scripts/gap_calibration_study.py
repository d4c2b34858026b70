"""The hinge-gap calibration of `validation diagnose --model fullwave` on full-wave twin data (docs/fullwave.md).

Each case is a twin-like data set (validation.blind.write_twin_like_dataset) made on the full-wave model of a
dimer between the family's nodes, with linear damping and, in every other case, a pressure drifting within
runs; the diagnosis then calibrates the gap without knowing it.  Prints one markdown row per case.
The data have no air damping (the twin-like generator integrates the given effects only): the drawn
linear damping is the only damping, so the numbers in docs/fullwave.md are measured without the air's drag.

    python docs/scripts/gap_calibration_study.py --seeds 31 32 33 --out /tmp/gapstudy
"""
from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path

import numpy as np

from acousim.models import ExperimentConditions, dynamic_model
from acousim.fullwave.family import shipped_family
from validation.blind import TwinLikeConfig, write_twin_like_dataset
from validation.diagnosis import DiagnoseConfig, diagnose_dataset
from acousim.models import ModelSpec


EFFECTS = {"linear_damping": {"gamma_y": 0.5, "gamma_theta": 2.0}}  # the only damping (no air_damping) by default


def gorkov_identified(seed: int, drift: float, out: Path, effects: dict = EFFECTS, runs: int = 8,
                      duration: float = 3.0) -> list:
    """What the diagnosis names on the Gor'kov twin of the same case (same seed, effects and drift)."""
    write_twin_like_dataset(out, TwinLikeConfig(runs=runs, duration=duration, seed=seed, pressure_error=0.05, drift=drift,
                                                effects=effects))
    d = diagnose_dataset(out, DiagnoseConfig(long_time=False), progress=False, spec=ModelSpec("gorkov"))
    return d.identified


def run_case(side: float, gap_ratio: float, seed: int, drift: float, out: Path, effects: dict = EFFECTS,
             runs: int = 8, duration: float = 3.0) -> dict:
    fm = dynamic_model("fullwave", ExperimentConditions(side_length_m=side, gap_m=gap_ratio * side))
    truth = write_twin_like_dataset(out, TwinLikeConfig(runs=runs, duration=duration, seed=seed, pressure_error=0.05,
                                                        drift=drift, effects=effects, force_model=fm))
    t0 = time.perf_counter()
    d = diagnose_dataset(out, DiagnoseConfig(long_time=False), progress=False, spec=ModelSpec("fullwave"))
    cal = d.calibration
    discovered = [t["term"] for eq in d.remaining_gap["discovered_terms"].values() for t in eq]
    return {"side_um": side * 1e6, "ks": fm.wavenumber * side, "gap_true_um": gap_ratio * side * 1e6,
            "gap_um": cal["gap_m"] * 1e6, "gap_std_um": (cal["gap_std_m"] or float("nan")) * 1e6,
            "gap_model_error_um": (cal.get("gap_model_error_m") or float("nan")) * 1e6,
            "calibrated": cal["gap_calibrated"], "seed": seed, "drift": drift,
            "drift_detected": bool(cal.get("drift", {}).get("detected", False)), "identified": d.identified,
            "discovered": discovered,
            "damping": next((e.params for e in d.effects if e.name == "linear_damping"), None),
            "pressure_error": cal["pressure_amplitude_pa"] / truth["pressure_amplitude_pa"] - 1,
            "wall_s": time.perf_counter() - t0,
            "gorkov_identified": gorkov_identified(seed, drift, out.with_name(out.name + "_gorkov"), effects,
                                                   runs, duration)}


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--seeds", type=int, nargs="+", default=[31, 32, 33])
    p.add_argument("--gamma-y", type=float, default=EFFECTS["linear_damping"]["gamma_y"],
                   help="the linear damping's y rate [1/s] (default %(default)s)")
    p.add_argument("--gamma-theta", type=float, default=EFFECTS["linear_damping"]["gamma_theta"],
                   help="the linear damping's hinge rate [1/s] (default %(default)s)")
    p.add_argument("--runs", type=int, default=8, help="runs per data set (default %(default)s)")
    p.add_argument("--duration", type=float, default=3.0, help="seconds per run (default %(default)s)")
    p.add_argument("--out", default=None, help="keep the data sets here (default: a temporary folder)")
    p.add_argument("--json", default=None, help="also write the rows as JSON")
    args = p.parse_args()
    effects = {"linear_damping": {"gamma_y": args.gamma_y, "gamma_theta": args.gamma_theta}}
    fam = shipped_family()
    (k0, k1), (g0, g1) = fam.ranges()
    # dimers between the nodes: sides at 45.65 kHz inside the ks range, gaps between the gap nodes
    sides = [s for s in (450e-6, 600e-6) if k0 <= ExperimentConditions(side_length_m=s).ks <= k1]
    gaps = sorted({float(np.sqrt(a * b)) for a, b in zip(fam.gap_nodes[:-1], fam.gap_nodes[1:])}) or [g0]
    root = Path(args.out) if args.out else Path(tempfile.mkdtemp())
    rows = []
    print("| side [um] | ks | true g [um] | calibrated g [um] | std [um] | (g - true) / std | model error [um] | "
          "calibrated | seed | drift | drift found | "
          "identified | gamma_y, gamma_theta [1/s] | same case on Gor'kov: identified | discovered | p0 error | wall [s] |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    i = 0
    for seed in args.seeds:
        for side in sides:
            for g in gaps:
                drift = 0.04 if i % 2 else 0.0
                i += 1
                r = run_case(side, g, seed, drift, root / f"case{i:03d}", effects, args.runs, args.duration)
                rows.append(r)
                damping = "-" if r["damping"] is None else ", ".join(f"{v:.3g}" for v in r["damping"].values())
                print(f"| {r['side_um']:.0f} | {r['ks']:.3f} | {r['gap_true_um']:.2f} | {r['gap_um']:.3f} | "
                      f"{r['gap_std_um']:.2g} | {(r['gap_um'] - r['gap_true_um']) / r['gap_std_um']:+.1f} | "
                      f"{r['gap_model_error_um']:.2g} | {r['calibrated']} | {seed} | {drift:g} | {r['drift_detected']} | "
                      f"{', '.join(r['identified']) or '-'} | {damping} | {', '.join(r['gorkov_identified']) or '-'} | "
                      f"{', '.join(r['discovered']) or '-'} | "
                      f"{100 * r['pressure_error']:+.2f} % | {r['wall_s']:.0f} |", flush=True)
    err = np.array([r["gap_um"] / r["gap_true_um"] - 1 for r in rows])
    print(f"\ngap error: median {100 * np.median(np.abs(err)):.1f} %, max {100 * np.max(np.abs(err)):.1f} %, "
          f"within 20 %: {int(np.sum(np.abs(err) <= 0.2))}/{len(rows)}; calibrated: "
          f"{sum(r['calibrated'] for r in rows)}/{len(rows)}")
    z = np.array([(r["gap_um"] - r["gap_true_um"]) / r["gap_std_um"] for r in rows])
    drifting = np.array([r["drift"] > 0 for r in rows])
    print(f"(g - true) / std: within 2 in {int(np.sum(np.abs(z) <= 2))}/{len(rows)}; largest |.| "
          f"{np.max(np.abs(z[~drifting]), initial=0):.1f} without a drift, {np.max(np.abs(z[drifting]), initial=0):.1f} "
          f"with one; estimate below the truth in {int(np.sum(z < 0))}/{len(rows)}")
    exact = sum(r["identified"] == list(effects) and not r["discovered"] for r in rows)
    exact_gorkov = sum(r["gorkov_identified"] == list(effects) for r in rows)
    print(f"effects named exactly (the damping, nothing else named or discovered): {exact}/{len(rows)} on the full "
          f"wave, {exact_gorkov}/{len(rows)} on the Gor'kov twins of the same cases")
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=1))


if __name__ == "__main__":
    main()
