"""bempp-cl's two assembly backends for the full-wave solve: numba (always there) against OpenCL on the CPU (pocl,
``pip install cubedimer[opencl]``), one core each, on the family's edge-graded dimer meshes at g/s = 0.05.

Each backend's first call compiles its kernels (numba: every process; pocl: once, then cached on disk); it is
timed separately.  The solutions of the two backends are compared.
"""
from __future__ import annotations

import os
import time

import numpy as np

from cubedimer.meta import META_DEFAULTS

#: the default dimer's cube side [m] (docs/conventions.md)
SIDE = META_DEFAULTS["side_length_m"]

os.environ.setdefault("POCL_MAX_PTHREAD_COUNT", "1")  # before pocl starts: one core, as numba below

LEVELS = (1.4, 1.0, 0.7)
GAP = 0.05


def main() -> str:
    import numba

    from acousim.fullwave import solver
    from acousim.fullwave.family_grid import FamilyNode, edge_graded_mesh_spec
    from acousim.fullwave.geometry import dimer_bodies

    verdict = solver._opencl_verdict()
    if not verdict.works:
        return ("## bem_backends: numba against OpenCL assembly\n\nThe OpenCL backend does not work here "
                f"({verdict.reason}; `pip install -e '.[opencl]'`); nothing measured.")
    numba.set_num_threads(1)
    medium = FamilyNode(0.418, GAP).medium
    before = os.environ.get(solver.BEM_DEVICE_ENV)
    first, rows = {}, []
    try:
        for device in ("numba", "opencl"):  # first calls: compilation
            os.environ[solver.BEM_DEVICE_ENV] = device
            t0 = time.perf_counter()
            solver.solve_scattering(dimer_bodies(0.3, edge_graded_mesh_spec(SIDE, GAP * SIDE, 2.0)), medium)
            first[device] = time.perf_counter() - t0
        for q in LEVELS:
            bodies = dimer_bodies(0.3, edge_graded_mesh_spec(SIDE, GAP * SIDE, q))
            sol = {}
            for device in ("numba", "opencl"):
                os.environ[solver.BEM_DEVICE_ENV] = device
                sol[device] = solver.solve_scattering(bodies, medium)
            a, b = sol["numba"].p_cos, sol["opencl"].p_cos
            tn, to = sol["numba"].timings["assembly_s"], sol["opencl"].timings["assembly_s"]
            rows.append(f"| {q:g} | {sol['numba'].n_dofs:,} | {tn:.1f} | {to:.1f} | {tn / to:.2f} | "
                        f"{np.abs(a - b).max() / np.abs(a).max():.1e} |")
    finally:
        if before is None:
            os.environ.pop(solver.BEM_DEVICE_ENV, None)
        else:
            os.environ[solver.BEM_DEVICE_ENV] = before
    return "\n".join([
        "## bem_backends: numba against OpenCL assembly of the full-wave solve",
        "",
        f"Mirror-reduced Burton-Miller assembly (a quarter of the rows) of the dimer at theta = 0.3 on the edge-graded "
        f"meshes at g/s = {GAP} (`edge_graded_mesh_spec`), ks = 0.418, one core per backend "
        f"(`CUBEDIMER_BEM_DEVICE=numba|opencl`). First calls (kernel compilation and one small solve): numba "
        f"{first['numba']:.1f} s, OpenCL {first['opencl']:.1f} s. Command: `python -m benchmarks --only bem_backends`.",
        "",
        "| level q | DOFs | numba assembly [s] | OpenCL assembly [s] | speed-up | max. rel. difference of the field |",
        "|---|---|---|---|---|---|",
        *rows,
    ])


if __name__ == "__main__":
    print(main())
