"""Executor throughput: a blind study on a dask cluster of one worker process against two.

The cluster is a ``LocalCluster`` of daemonic worker processes on the loopback (what
``dask scheduler`` plus ``dask worker --nworkers N`` gives), driven through the same seam as
``python -m validation blind --scheduler ADDRESS``.  Each worker is warmed first (imports, the
Gor'kov surrogate, compiled kernels) with one throw-away case, so that the table shows the
steady-state rate of a long study.  The cases are short (``RUNS`` runs of ``DURATION`` s instead of
the blind check's 10 x 3 s) so that the benchmark takes minutes; per-case work scales with runs x
duration, the per-task overhead does not.
"""
from __future__ import annotations

import os
import pickle
import resource
import tempfile
import time
from pathlib import Path

CASES = int(os.environ.get("CUBEDIMER_BENCH_CASES", 40))
RUNS = 3
DURATION = 1.0
NOOP_TASKS = 200


def _cpu_seconds() -> float:
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def _warm(out_dir: str) -> float:
    """One throw-away case on this worker; returns its wall time [s]."""
    from validation.blind import BlindConfig, draw_case, run_case

    t0 = time.perf_counter()
    out = Path(out_dir) / f"warm-{os.getpid()}"
    out.mkdir(parents=True, exist_ok=True)
    run_case(draw_case(12345, 0), BlindConfig(cases=1, runs=RUNS, duration=DURATION), out)
    return time.perf_counter() - t0


def _noop(x: int) -> int:
    return x


def _study(n_workers: int, tmp: Path) -> dict:
    from dask.distributed import Client

    from cubedimer.executor import ExecutorConfig, loopback_cluster, map_ordered
    from validation.blind import BlindConfig, run_blind

    config = BlindConfig(cases=CASES, runs=RUNS, duration=DURATION)
    with loopback_cluster(n_workers) as address, Client(address) as client:
        executor = ExecutorConfig(scheduler=address)
        warm = client.run(_warm, str(tmp / f"warm{n_workers}"))
        cpu0 = sum(client.run(_cpu_seconds).values())
        t0 = time.perf_counter()
        summary = run_blind(config, tmp / f"study{n_workers}", executor, progress=False)
        wall = time.perf_counter() - t0
        cpu = sum(client.run(_cpu_seconds).values()) - cpu0
        t0 = time.perf_counter()
        map_ordered(_noop, range(NOOP_TASKS), executor, progress=False)
        noop = (time.perf_counter() - t0) / NOOP_TASKS
    return {"workers": n_workers, "wall": wall, "cpu": cpu, "warm": max(warm.values()), "noop": noop,
            "failed": summary["failed"], "summary": (tmp / f"study{n_workers}" / "summary.json").read_bytes()}


def main() -> str:
    try:
        import cloudpickle
        import dask.distributed  # noqa: F401
    except ImportError:
        return "## executor\n\nSkipped: dask.distributed is not installed (pip install 'cubedimer[dask]')."

    from cubedimer.executor import _Task
    from validation.blind import BlindConfig, draw_case
    from validation.blind.study import _case_task

    load_before = os.getloadavg()[0]
    with tempfile.TemporaryDirectory() as d:
        tmp = Path(d)
        rows = [_study(n, tmp) for n in (1, 2)]
        case = draw_case(0, 0)
        item = (case, BlindConfig(cases=CASES, runs=RUNS, duration=DURATION), str(tmp / "cases" / "case000"))
        shipped = len(cloudpickle.dumps(_Task(_case_task))) + len(cloudpickle.dumps(item))
        result = (tmp / "study1" / "cases" / "case000" / "result.json").read_bytes()
        returned = len(pickle.dumps(__import__("json").loads(result)))
    load_after = os.getloadavg()[0]
    one, two = rows
    lines = [
        f"## executor: a {CASES}-case blind study on a dask cluster of 1 worker process against 2",
        "",
        f"Cases of {RUNS} runs x {DURATION:g} s (the blind check's default is 10 x 3 s; a case's work scales with "
        "runs x duration, the per-task overhead does not). Workers warmed with one throw-away case each. "
        f"Command: `python -m benchmarks --only executor`. Machine load average before / after: "
        f"{load_before:.1f} / {load_after:.1f} (other jobs share the cores: wall times are upper bounds).",
        "",
        "| worker processes | wall [s] | cases / min | worker CPU [s] | CPU / wall | first (warm-up) case [s] | "
        "scheduler round trip per no-op task [ms] |",
        "|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(f"| {r['workers']} | {r['wall']:.1f} | {CASES / r['wall'] * 60:.1f} | {r['cpu']:.1f} | "
                     f"{r['cpu'] / r['wall']:.2f} | {r['warm']:.1f} | {r['noop'] * 1e3:.2f} |")
    lines += [
        "",
        f"* Speed-up of 2 worker processes over 1: **{one['wall'] / two['wall']:.2f}x** in wall time "
        f"(ideal 2 on 2 idle cores); summary.json identical: {one['summary'] == two['summary']}; "
        f"failed cases: {one['failed']} / {two['failed']}.",
        f"* Shipped per task: the pickled function and item, {shipped:,} bytes (the case's hidden truth, the "
        f"settings, the case directory); returned: the scored result, {returned:,} bytes. The data set of a case "
        "is simulated, diagnosed and deleted on the worker; only result.json and truth.json are written, into the "
        "study folder, which on several machines must be a shared folder.",
        f"* Per-task cost of the scheduler: {two['noop'] * 1e3:.2f} ms for a no-op task against "
        f"~{two['cpu'] / CASES:.1f} CPU s per case, so on N machines the study scales with N until N is of order "
        f"(CPU s per case) / (round trip) ~ {two['cpu'] / CASES / max(two['noop'], 1e-6):,.0f} workers kept busy "
        "by one scheduler; before that, the limits are the number of cases (one task each: a 50-case study "
        "uses at most 50 workers) and the per-worker warm-up (imports, surrogate, compiled kernels) paid once "
        "per worker process.",
    ]
    return "\n".join(lines)


if __name__ == "__main__":
    print(main())
