"""The default ``fit`` end to end on sparse truths: criterion pass rate and wall time.

``python -m benchmarks.bench_fitting_default [--cases paper signs ...] [--seeds 601 602 603] [--no-speed]``
writes each data set as CSV (:func:`fitting.synthetic.write_dataset`), runs
:func:`fitting.fit.fit_dataset` with the default :class:`fitting.fit.FitConfig` (method
"discovery": discovery, long-time polish, attractor check) and scores the final model with the criterion of
:func:`benchmarks.bench_discovery.score` (true terms with oracle z >= 5 found, at most one spurious term,
coefficients within max(10 %, 3 oracle standard errors)), then the wall time on 12 and 30 runs
of 3 s of the paper's reduced model.  ``main()`` returns a markdown report.
"""
from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

import numpy as np

from .bench_discovery import CASES, aliases, oracle, oracle_result, score


class _Final:
    """The final model of a fit in the shape :func:`score` expects (mask, coef)."""

    def __init__(self, model):
        self.coef, self.mask = model.coef, model.support


def fit_case(case, seed: int, workdir: Path, config=None) -> tuple[dict, float, object, dict | None]:
    """(score of the final model, wall time [s], FitResult, score of the discovery before the polish or None) of
    the fit (default: ``FitConfig()``) on one data set."""
    from cubedimer.dataset import Run
    from fitting.model import PolynomialModel
    from fitting.config import FitConfig
    from fitting.fit import fit_dataset
    from fitting.synthetic import SyntheticConfig, write_dataset

    truth = PolynomialModel.from_equations(case.equations)
    cfg = SyntheticConfig(n_runs=case.n_runs, duration=case.duration, fps=case.fps, noise_y=case.noise_y,
                          noise_theta=case.noise_theta, seed=seed)
    data = workdir / f"{case.name}-{seed}"
    raw = write_dataset(data, truth, cfg)
    runs = [Run(name=f"run{i + 1:02d}.csv", t=r["t"], y=r["y"], theta=r["theta"]) for i, r in enumerate(raw)]
    orc = oracle_result(truth, runs, [r["state"] for r in raw], (case.noise_y, case.noise_theta))
    se = oracle(truth, runs, [r["state"] for r in raw], (case.noise_y, case.noise_theta), orc)
    t0 = time.perf_counter()
    res = fit_dataset(data, config or FitConfig(), progress=False)
    wall = time.perf_counter() - t0
    al = aliases(orc)
    before = score(truth, res.extras.discovery, se, alias=al) if res.method == "discovery" else None
    return score(truth, _Final(res.model), se, alias=al), wall, res, before


def speed(n_runs: int, workdir: Path, seed: int = 0) -> tuple[float, float]:
    """Wall and CPU time [s] of the default fit (no plots) on ``n_runs`` runs of 3 s (paper's reduced model,
    1500 fps); the fit runs in one process, so on an idle machine the wall time is about the CPU time."""
    from fitting.config import FitConfig
    from fitting.fit import fit_dataset
    from fitting.synthetic import SyntheticConfig, paper_reduced_model, write_dataset

    data = workdir / f"speed{n_runs}"
    write_dataset(data, paper_reduced_model(), SyntheticConfig(n_runs=n_runs, duration=3.0, seed=seed))
    t0, c0 = time.perf_counter(), time.process_time()
    fit_dataset(data, FitConfig(), progress=False)
    return time.perf_counter() - t0, time.process_time() - c0


def main(argv: list[str] | None = None) -> str:
    p = argparse.ArgumentParser(prog="python -m benchmarks.bench_fitting_default")
    p.add_argument("--cases", nargs="+", default=list(CASES), choices=list(CASES))
    p.add_argument("--seeds", nargs="+", type=int, default=[601])
    p.add_argument("--no-speed", action="store_true", help="skip the wall time on 12 and 30 runs of 3 s")
    a = p.parse_args([] if argv is None else argv)
    lines = ["| case | runs | seed | criterion | missed (z >= 5) | spurious | outside tolerance | model written | "
             "criterion before the polish | wall [s] |", "|---|---|---|---|---|---|---|---|---|---|"]
    passed = total = 0
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        for name in a.cases:
            case = CASES[name]
            for seed in a.seeds:
                sc, wall, res, before = fit_case(case, seed, work)
                total += 1
                passed += sc["passed"]
                used = "fallback: " + res.fallback["used"] if res.fallback else "discovery + polish"
                lines.append(f"| {name} | {case.n_runs} | {seed} | {'yes' if sc['passed'] else 'NO'} | "
                             f"{', '.join(sc['missed']) or '-'} | {', '.join(sc['spurious']) or '-'} | "
                             f"{', '.join(sc['bad']) or '-'} | {used} | "
                             f"{'-' if before is None else ('yes' if before['passed'] else 'NO')} | {wall:.1f} |")
                print(lines[-1], flush=True)
        lines.append(f"\n**{passed} of {total} data sets meet the criterion.**")
        if not a.no_speed:
            load = os.getloadavg()[0]
            for n in (12, 30):
                wall, cpu = speed(n, work)
                lines.append(f"\nDefault fit (no plots), {n} runs of 3 s at 1500 fps: {wall:.1f} s wall, {cpu:.1f} s CPU "
                             f"(load average {load:.1f} on {os.cpu_count()} cores)")
                print(lines[-1], flush=True)
    return "\n".join(lines)


if __name__ == "__main__":
    import sys

    print(main(sys.argv[1:]))
