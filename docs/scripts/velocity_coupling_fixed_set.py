"""A fixed set of twin data sets with one drawn effect beside the air's damping, diagnosed: the velocity coupling's
recall and c6 error, and the same for other effects (no regression).

Each case ``i`` of effect ``E`` draws, from ``SeedSequence([seed, sum of the letters of E, i])``, the effect's
parameters at the blind strengths (``validation.blind.candidates.draw_parameters``, the mirror asymmetry relative to
the hinge's hold), a pressure error within +-10 % and the twin's seed; the twin (10 runs of 3 s, its default physics
with the air's damping) writes the data set, whose truth is hidden, and the diagnosis runs without the cavity and
without the long-time errors.  ``none`` draws no effect.  Each case's result is kept in ``OUT/E_i/result_TAG.json``,
so a rerun resumes and two versions of the code can be compared on the same data sets (``--tag``).
``--complete-hinge-rate`` diagnoses with the integral form's hinge rate completed by the simulation's fast response
(validation.diagnosis.prepare.hinge_state, not the diagnosis's default).  The velocity coupling's trajectory test is on
(the diagnosis's default); ``--no-trajectory-test`` diagnoses with the held-out rounds alone.

    python docs/scripts/velocity_coupling_fixed_set.py --out /tmp/vc_set --effects velocity_coupling --cases 8
    python docs/scripts/velocity_coupling_fixed_set.py --out /tmp/vc_set \
        --effects none,mirror_asymmetry,linear_damping --cases 3

Prints one line per case and a summary per effect.  docs/diagnosis.md (Known limitations) quotes its output
(seed 4242 for the fixed set, 9090 for the fresh one).
"""
from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from validation.blind.candidates import (NOMINAL_PRESSURE_PA, candidate_truth, draw_parameters, generate_twin_case,
                                         hide_truth, hinge_strengths)
from validation.blind.config import BlindConfig


def draw(effect: str, index: int, seed: int) -> dict:
    rng = np.random.default_rng(np.random.SeedSequence([seed, sum(map(ord, effect)), index]))
    error = float(rng.uniform(-0.1, 0.1))
    drawn = {} if effect == "none" else {effect: draw_parameters(rng, effect)}
    return {"index": index, "effects": hinge_strengths(drawn, NOMINAL_PRESSURE_PA * (1 + error)),
            "pressure_error": error, "twin_seed": int(rng.integers(2**31))}


def generate_once(folder: Path, case: dict) -> bool:
    """The case's data set in ``folder / "data"`` and its hidden truth in ``folder / "truth.json"`` (10 runs of 3 s,
    the air's damping), written unless already there; False when the twin could not generate it."""
    if (folder / "truth.json").exists():
        return True
    folder.mkdir(parents=True, exist_ok=True)
    error, _ = generate_twin_case(case, BlindConfig(runs=10, duration=3.0, resonator=False), folder / "data",
                                  air_damping=True)
    if error:
        return False
    hide_truth(folder / "data", folder / "truth.json")
    return True


def run_case(folder: Path, case: dict, tag: str, trajectory_test: bool = True) -> dict | None:
    """The diagnosis of one case (generated once), or None when the twin could not generate it."""
    from validation.diagnosis import DiagnoseConfig, diagnose_dataset

    result = folder / f"result_{tag}.json"
    if result.exists():
        return json.loads(result.read_text())
    if not generate_once(folder, case):
        return None
    truth = json.loads((folder / "truth.json").read_text())
    diag = diagnose_dataset(folder / "data", DiagnoseConfig(long_time=False, trajectory_test=trajectory_test),
                            progress=False)
    out = {"identified": sorted(diag.identified), "true": candidate_truth(truth["effects"], truth.get("resonator")),
           "params": {e.name: dict(e.params) for e in diag.effects},
           "p_value": {e.name: e.p_value for e in diag.effects},
           "status": {e.name: e.status for e in diag.effects},
           "output_error": next((c["output_error"] for r in diag.identification_rounds
                                 for c in r["candidates"].values() if "output_error" in c), None)}
    result.write_text(json.dumps(out, indent=1))
    return out


def complete_hinge_rate() -> None:
    """Make the calibration step prepare its runs with the completed hinge rate (the default dimer's force model)."""
    import validation.diagnosis.calibrate.calibration_step as step
    from acousim import GorkovDimer
    from validation.diagnosis.prepare.hinge_state import with_fast_hinge_response
    from validation.diagnosis.prepare.problem import DiagnosisProblem

    force_model = DiagnosisProblem(GorkovDimer().interpolated(), []).surrogate()
    plain = step.prepare_diagnosis_runs
    step.prepare_diagnosis_runs = lambda dataset: with_fast_hinge_response(plain(dataset), force_model)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--effects", default="velocity_coupling")
    ap.add_argument("--cases", type=int, default=8)
    ap.add_argument("--seed", type=int, default=4242)
    ap.add_argument("--tag", default="current")
    ap.add_argument("--complete-hinge-rate", action="store_true")
    ap.add_argument("--no-trajectory-test", action="store_true",
                    help="diagnose without the velocity coupling's trajectory test (the held-out rounds alone)")
    args = ap.parse_args()
    if args.complete_hinge_rate:
        complete_hinge_rate()
    for effect in args.effects.split(","):
        exact, c6_errors, scored = 0, [], 0
        for i in range(args.cases):
            r = run_case(args.out / f"{effect}_{i}", draw(effect, i, args.seed), args.tag, not args.no_trajectory_test)
            if r is None:
                print(effect, i, "not generated", flush=True)
                continue
            scored += 1
            exact += r["identified"] == sorted(r["true"])
            line = f"{effect} {i}: named {r['identified']}, true {sorted(r['true'])}"
            if "velocity_coupling" in r["true"]:
                c6 = r["true"]["velocity_coupling"]["c6"]
                if "velocity_coupling" in r["identified"]:
                    c6_errors.append(abs(r["params"]["velocity_coupling"]["c6"] - c6) / abs(c6))
                line += f", p = {r['p_value'].get('velocity_coupling')}"
            print(line, flush=True)
        summary = f"{effect}: exact set {exact} of {scored}"
        if c6_errors:
            summary += f"; c6 error where named: median {np.median(c6_errors):.0%} ({len(c6_errors)} named)"
        print(summary, flush=True)


if __name__ == "__main__":
    main()
