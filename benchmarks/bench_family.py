"""The full-wave table family: the resumable family build on 1 against 2 local worker processes, and what a lab
dimer costs once the family exists (interpolation and scaling to a physical surrogate) against reading a
direct-solve table from disk.

The build is timed on two small nodes (g/s = 0.05 on the hinge-graded mesh, 1,368 DOFs, 2 solves each instead of 6) so that the
benchmark finishes in minutes; a real node's time per solve is in the table too (from the shipped nodes' build
records).  Each worker process compiles bempp-cl's kernels once (about a minute): that is part of the wall time,
as it is in a real build.
"""
from __future__ import annotations

import os
import tempfile
import time
from pathlib import Path

import numpy as np

NODES = ((0.35, 0.05), (0.45, 0.05))
N_HALF = 2


def _build(workers: int, directory: Path) -> float:
    from acousim.fullwave.family import FamilyNode, build_family
    from cubedimer.executor import ExecutorConfig

    nodes = [FamilyNode(k, g, n_half=N_HALF) for k, g in NODES]
    t0 = time.perf_counter()
    build_family(directory, nodes, ExecutorConfig(workers=workers), progress=False)
    return time.perf_counter() - t0


def _best(fn, repeat: int = 5) -> float:
    best = np.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


def main() -> str:
    from acousim.fullwave.family import FAMILY_DIR, FullwaveFamily, _family
    from acousim.fullwave.force_surrogate import DEFAULT_TABLE, FullwaveSurrogate
    from acousim.medium import Medium

    load_before = os.getloadavg()[0]
    with tempfile.TemporaryDirectory() as d:
        walls = {w: _build(w, Path(d) / f"w{w}") for w in (1, 2)}
        resumed = _build(2, Path(d) / "w2")  # everything on disk: nothing is solved
    load_after = os.getloadavg()[0]
    fam = FullwaveFamily(FAMILY_DIR)
    lines = [
        "## family: the full-wave table family",
        "",
        f"Build of {len(NODES)} nodes (g/s = 0.05, hinge-graded mesh of 1,368 DOFs, {N_HALF} solves each), on 1 and 2 local worker processes "
        f"(`python -m acousim family build --workers N`); machine load average before / after {load_before:.1f} / "
        f"{load_after:.1f}. Command: `python -m benchmarks --only family`.",
        "",
        "| workers | wall [s] | speed-up |",
        "|---|---|---|",
        f"| 1 | {walls[1]:.0f} | 1.00 |",
        f"| 2 | {walls[2]:.0f} | {walls[1] / walls[2]:.2f} |",
        f"| 2, resumed (all nodes on disk) | {resumed:.2f} | - |",
        "",
    ]
    if not fam.empty:
        rows = []
        for (k, g), sur in sorted(fam.tables.items()):
            ba = sur.build_accuracy
            rows.append(f"| {k:.4f} | {g:.5f} | {ba.get('dofs', 0)} | {ba.get('solves', 0)} | "
                        f"{float(ba.get('wall_s', 0)) / max(int(ba.get('solves', 1)), 1):.0f} | {float(ba.get('wall_s', 0)):.0f} |")
        lines += ["Shipped nodes, as built (`python -m acousim family build`, 2 workers on 2 cores; the wall times "
                  "include other jobs sharing the cores):", "",
                  "| ks | g/s | DOFs | solves | wall per solve [s] | node wall [s] |", "|---|---|---|---|---|---|", *rows, ""]
        (k0, k1), (g0, g1) = fam.ranges()
        med = Medium(frequency_hz=42_000.0)
        side = 0.5 * (k0 + k1) / med.wavenumber
        gap = np.sqrt(g0 * g1) * side
        _family.cache_clear()
        t_family = _best(lambda: FullwaveFamily(FAMILY_DIR), 3)
        t_interp = _best(lambda: fam.surrogate(side, gap, med))
        t_table = _best(lambda: FullwaveSurrogate.load(DEFAULT_TABLE))
        lines += [f"A lab dimer from the family ({side * 1e6:.0f} um at 42 kHz, g = {gap * 1e6:.1f} um): reading "
                  f"the family {1e3 * t_family:.0f} ms once per process, then {1e3 * t_interp:.1f} ms per dimer "
                  f"(interpolation, scaling, equilibrium height), against {1e3 * t_table:.1f} ms to read one "
                  "direct-solve table from disk and minutes to build one."]
    return "\n".join(lines)
