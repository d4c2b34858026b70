"""How well the runs' whole trajectories determine the velocity coupling's c6: on a fixed set of twin data sets with
the air's damping and a drawn coupling, the output-error test's c6 against the truth, in units of its own standard
error, its relative standard error, and its correlations with c5 and the damping rates.

Each case ``i`` draws its coupling at the blind strengths as ``velocity_coupling_fixed_set.py`` does (the same
``draw``: ``SeedSequence([seed, letters of "velocity_coupling", i])``), the twin (10 runs of 3 s, the air's damping)
writes the data set, the calibration step of the diagnosis prepares it, and the trajectory test
(``validation.diagnosis.identify.output_error.velocity_coupling_output_error``) is made beside linear damping, as
the diagnosis makes it where the held-out rounds named the air's damping alone.  Cases are kept in ``OUT/vc_i``
(the data set and a record per case, ``record.json``), so a rerun resumes.

    python docs/scripts/velocity_coupling_information.py --out /tmp/vc_info --seed 16100 --cases 16

Prints one line per case (truth, error, relative standard error, error in standard errors, correlations, CPU-seconds
and runs simulated by the test) and the medians; docs/diagnosis.md ("c6's information limit") quotes its output.  An
unbiased estimate with standard error s has a median absolute error of 0.67 s: the median relative standard error
says what c6 accuracy the data can give.
"""
from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from velocity_coupling_fixed_set import draw, generate_once  # noqa: E402

import validation.diagnosis.identify.output_error as output_error  # noqa: E402

#: the pairs whose Gauss-Newton correlation each case reports
PAIRS = [("c5", "c6"), ("c6", "gamma_theta"), ("c6", "gamma_y"), ("c6", "pressure_pa")]


def _counted(counter: dict):
    """output_error's simulation, counting the runs it simulates."""
    plain = output_error._simulate_states

    def simulate(surrogate, pressure, effects, starts, dt, frames):
        counter["runs"] += len(starts)
        return plain(surrogate, pressure, effects, starts, dt, frames)

    return simulate


def run_case(folder: Path, case: dict) -> dict | None:
    """The record of one case (generated and tested once), or None when the twin could not generate it."""
    from validation.diagnosis import DiagnoseConfig
    from validation.diagnosis.calibrate.calibration_step import calibration_step
    from validation.diagnosis.calibrate.gap_model import fit_gap_model
    from validation.diagnosis.steps import load_for_diagnosis, start_diagnosis

    record = folder / "record.json"
    if record.exists():
        return json.loads(record.read_text())
    if not generate_once(folder, case):
        return None
    truth = json.loads((folder / "truth.json").read_text())["effects"]["velocity_coupling"]
    start = start_diagnosis(load_for_diagnosis(folder / "data", progress=False))
    cal = calibration_step(start.prepared, start.conditions, start.model, start.spec,
                           DiagnoseConfig(long_time=False), lambda *a: None)
    counter = {"runs": 0}
    output_error._simulate_states = _counted(counter)
    cpu = time.process_time()
    test = output_error.velocity_coupling_output_error(cal.problem, fit_gap_model(cal.problem, ["linear_damping"]),
                                                       cal.conditions)
    cpu = time.process_time() - cpu
    d = test.to_dict()
    out = {"truth": truth, "params": d["params"], "std_errors": d["std_errors"], "significant": d["significant"],
           "statistic": d["statistic"], "damping_law": d["damping_law"], "cpu_s": cpu, "runs_simulated": counter["runs"],
           "correlations": {f"{a}|{b}": test.coupled.correlation(a, b) for a, b in PAIRS}}
    record.write_text(json.dumps(out, indent=1))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--cases", type=int, default=16)
    ap.add_argument("--seed", type=int, default=16100)
    args = ap.parse_args()
    rows = []
    for i in range(args.cases):
        r = run_case(args.out / f"vc_{i}", draw("velocity_coupling", i, args.seed))
        if r is None:
            print(i, "not generated", flush=True)
            continue
        c6, est, se = r["truth"]["c6"], r["params"]["c6"], r["std_errors"]["c6"]
        rows.append((abs(est / c6 - 1), se / abs(c6), (est - c6) / se, r["significant"]))
        corr = r["correlations"]
        print(f"{i}: c5 {r['truth']['c5']:.0f}, c6 {c6:.3g}; c6 error {est / c6 - 1:+.0%}, relative SE {se / abs(c6):.2f}, "
              f"z {(est - c6) / se:+.2f}; c5 error {r['params']['c5'] / r['truth']['c5'] - 1:+.1%}; named "
              f"{r['significant']}; corr(c6, c5) {corr['c5|c6']:+.2f}, corr(c6, gamma_theta) "
              f"{corr['c6|gamma_theta']:+.2f}; {r['cpu_s']:.1f} CPU-s, {r['runs_simulated']} runs simulated", flush=True)
    if rows:
        a = np.array(rows, float)
        named = a[a[:, 3] > 0]
        print(f"{len(a)} cases, {len(named)} named: c6 median |error| {np.median(named[:, 0]):.0%} where named, "
              f"median relative SE {np.median(a[:, 1]):.2f} (an unbiased estimate: median |error| 0.67 of it), "
              f"z rms {np.sqrt(np.mean(a[:, 2] ** 2)):.2f}, mean {np.mean(a[:, 2]):+.2f}")


if __name__ == "__main__":
    main()
