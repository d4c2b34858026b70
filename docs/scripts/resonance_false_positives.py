"""Spurious terms of the default selection near parametric resonance (docs/fitting.md, "Near parametric resonance").

PYTHONPATH=. python docs/scripts/resonance_false_positives.py [--cases res43 ...] [--seeds 1101 ...]
                                                               [--no-natural-window]

Sparse truths of docs/conventions.md section 6's form with the hinge near twice the y frequency (f_y = 22 Hz,
f_theta = 43 or 44 Hz) and strong hinge damping (thetadot coefficient -3 or -6 1/s), so that y^2*theta pumps the
hinge close to its parametric resonance (``CASES``).  Data from ``fitting.synthetic`` (runs from random
states, white tracking noise), selection by ``fitting.discover_model`` with ``DiscoveryConfig()``.  Per data set it
prints the spurious terms (with their z in the fit, and their own oracle z and alias z: the oracle of the fitted
model at the exact initial states), the true terms lost (any oracle z) and the benchmark's criterion
(``benchmarks.bench_discovery.score``).  About 3 s of CPU per data set.  ``--no-natural-window`` gives the
selection with its windows from the dominant frequency alone (``DiscoveryConfig.natural_periods = None``).
"""
from __future__ import annotations

import argparse
import sys
import time

import numpy as np

from benchmarks.bench_discovery import Case, aliases, make_data, oracle, oracle_result, score


def _resonant(hinge_hz: float, damping: float, stiff: bool) -> dict:
    """Section 6's form with the hinge at ``hinge_hz`` and thetadot = ``damping`` [1/s]: with the hinge couplings of
    the benchmark's 35-Hz ``stiff`` truth (no constants), or of the paper's reduced model (constants on)."""
    w_y, w_t = 2 * np.pi * 22.0, 2 * np.pi * hinge_hz
    if stiff:
        return {"yddot": {"y": -w_y ** 2, "y^2": -9.5e6, "ydot": -0.4},
                "thetaddot": {"theta": -w_t ** 2, "y": 5.0e6, "y^2*theta": 2.0e11, "thetadot": damping,
                              "y*thetadot^2": -1.5e3, "y*ydot*thetadot": 5.0e6}}
    return {"yddot": {"1": 0.1, "y": -w_y ** 2, "y^2": 9.5e6, "ydot": -0.3},
            "thetaddot": {"1": 60.0, "theta": -w_t ** 2, "y": 1.5e6, "y^2*theta": 2.0e10, "thetadot": damping,
                          "y*thetadot^2": 5.0e3, "y*ydot*thetadot": 8.0e6}}


#: 12 runs of 3 s at 1500 fps, noise 1.5 um / 0.003 (the `paper` benchmark set's data size)
CASES = {
    # hinge at 43 Hz (1 Hz below 2 f_y), gamma_theta = 1.5 1/s, the stiff truth's couplings
    "res43": Case("res43", _resonant(43.0, -3.0, True), 12, 3.0, 1500.0, 1.5e-6, 0.003),
    # the same with gamma_theta = 3 1/s: the hinge's free oscillation dies within the run and theta moves at f_y
    "res43strong": Case("res43strong", _resonant(43.0, -6.0, True), 12, 3.0, 1500.0, 1.5e-6, 0.003),
    # the paper's reduced model (constants on) with the hinge at 2 f_y, gamma_theta = 1.5 1/s
    "paper44": Case("paper44", _resonant(44.0, -3.0, False), 12, 3.0, 1500.0, 1.5e-6, 0.003),
}


def measure(case: Case, seed: int, config=None) -> dict:
    """Selection on one data set: spurious terms (fit z, own oracle z and alias z), true terms lost, criterion."""
    from fitting.selection.discovery_config import DiscoveryConfig
    from fitting.selection.integral_discovery import discover_model
    from fitting.model import TERMS
    from fitting.uncertainty.oracle import NoiseLevels, OracleRun, oracle_standard_errors

    truth, runs, derivs, exact = make_data(case, seed)
    noise = (case.noise_y, case.noise_theta)
    orc = oracle_result(truth, runs, exact, noise)
    t0 = time.process_time()
    res = discover_model(runs, derivs, config or DiscoveryConfig())
    cpu = time.process_time() - t0
    sc = score(truth, res, oracle(truth, runs, exact, noise, orc), alias=aliases(orc))
    own = oracle_standard_errors(res.model, [OracleRun(e[0], len(e), r.dt) for r, e in zip(runs, exact)],
                                 NoiseLevels(*noise))
    spurious = []
    for name in sc["spurious"]:
        eq, t = name.split(":")
        o = own.terms[eq][t]
        q = 0 if eq == "yddot" else 1
        spurious.append((name, float(res.z[q, TERMS.index(t)]), o.z, o.alias, o.alias_z))
    lost = [f"{eq}:{t} (oracle z {z:.1f})" for eq, t, _c0, z, sel, *_r in sc["rows"] if not sel]
    return {"case": case.name, "seed": seed, "spurious": spurious, "lost": lost, "passed": sc["passed"],
            "bad": sc["bad"], "cpu": cpu}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", nargs="+", default=list(CASES), choices=list(CASES))
    ap.add_argument("--seeds", nargs="+", type=int, default=list(range(1101, 1111)))
    ap.add_argument("--no-natural-window", action="store_true",
                    help="windows from the dominant frequency alone (DiscoveryConfig(natural_periods=None))")
    args = ap.parse_args(argv)
    from fitting.selection.discovery_config import DiscoveryConfig

    config = DiscoveryConfig(natural_periods=None) if args.no_natural_window else DiscoveryConfig()
    print("| case | seed | spurious terms (fit z; own oracle z; alias, alias z) | true terms lost | criterion | "
          "CPU [s] |")
    print("|---|---|---|---|---|---|")
    totals = {}
    for name in args.cases:
        for seed in args.seeds:
            m = measure(CASES[name], seed, config)
            sp = "; ".join(f"{n} ({z:.1f}; {oz:.1f}; {a}, {az:.2f})" for n, z, oz, a, az in m["spurious"]) or "-"
            print(f"| {name} | {seed} | {sp} | {', '.join(m['lost']) or '-'} | "
                  f"{'yes' if m['passed'] else 'NO'} | {m['cpu']:.1f} |", flush=True)
            tot = totals.setdefault(name, [0, 0, 0, 0])
            tot[0] += 1
            tot[1] += len(m["spurious"])
            tot[2] += len(m["spurious"]) > 1
            tot[3] += len(m["lost"])
    for name, (n, sp, over, lost) in totals.items():
        print(f"{name}: {n} data sets, {sp} spurious terms, {over} sets with more than one, {lost} true terms lost")
    return 0


if __name__ == "__main__":
    sys.exit(main())
