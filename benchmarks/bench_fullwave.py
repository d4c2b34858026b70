"""Full-wave (boundary-element) model: assembly and solve time against degrees of freedom, the momentum-flux
post-processing (compiled kernel against the plain numpy sum over sources), the coarse surrogate's build
time, hinge accuracy against mesh size, and a full-wave against a Gor'kov sweep.

Accuracy is relative to the finest level run here (q = 0.35), so it is a self-convergence measure;
docs/fullwave.md has the full study with Richardson estimates.  The first boundary-element call of a
process compiles bempp-cl's numba kernels (about a minute on 2 cores); it is timed separately.
"""
from __future__ import annotations

import time

import numpy as np


def _numpy_sources(field, x):
    """The quadrature nodes, normals and weighted densities the compiled kernel uses for the field point ``x``,
    found level by level in numpy (split where ``x`` is nearer than ``near_ratio`` sizes)."""
    from acousim.fullwave.solver import triangle_rule

    bary, wq = triangle_rule()
    tri = field._vertices[field._faces]  # (m, 3, 3)
    dens = field._density[field._faces]  # (m, 3, 2)
    cr = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    nrm, area = cr / np.linalg.norm(cr, axis=1)[:, None], 0.5 * np.linalg.norm(cr, axis=1)
    size = np.max(np.linalg.norm(tri - np.roll(tri, 1, axis=1), axis=2), axis=1)
    nodes, normals, weights = [], [], []
    for level in range(field.max_depth + 1):
        h = size * 0.5**level
        far = np.linalg.norm(x - tri.mean(1), axis=1) - 0.5 * h >= field.near_ratio * h
        if level == field.max_depth:
            far[:] = True
        nodes.append(np.einsum("qj,mjk->mqk", bary, tri[far]).reshape(-1, 3))
        normals.append(np.repeat(nrm[far], len(wq), axis=0))
        weights.append((area[far, None, None] * 0.25**level * wq[None, :, None]
                        * np.einsum("qj,mjc->mqc", bary, dens[far])).reshape(-1, 2))
        a, b, c = tri[~far, 0], tri[~far, 1], tri[~far, 2]
        ab, bc, ca = 0.5 * (a + b), 0.5 * (b + c), 0.5 * (c + a)
        da, db, dc = dens[~far, 0], dens[~far, 1], dens[~far, 2]
        dab, dbc, dca = 0.5 * (da + db), 0.5 * (db + dc), 0.5 * (dc + da)
        tri = np.concatenate([np.stack(t, 1) for t in ((a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca))])
        dens = np.concatenate([np.stack(t, 1) for t in ((da, dab, dca), (dab, db, dbc), (dca, dbc, dc), (dab, dbc, dca))])
        nrm, area, size = (np.tile(nrm[~far], (4, 1)), np.tile(area[~far], 4), np.tile(size[~far], 4))
        if not len(tri):
            break
    return np.concatenate(nodes), np.concatenate(normals), np.concatenate(weights)


def _numpy_double_layer(field, points):
    """The exterior scattered field as a numpy sum over sources, one field point at a time, with the same
    adaptive quadrature (the alternative the compiled kernel of :func:`acousim.fullwave.flux.double_layer_potential`
    replaces)."""
    k = field.k
    val = np.zeros((len(points), 2), complex)
    grad = np.zeros((len(points), 3, 2), complex)
    for i, x in enumerate(points):
        y, nrm, wd = _numpy_sources(field, x)
        d = x - y
        r2 = np.einsum("qk,qk->q", d, d)
        r = np.sqrt(r2)
        e = np.exp(1j * k * r) / (4 * np.pi)
        f = e * (1j * k * r - 1) / (r2 * r)
        fp = e * (-k * k * r2 - 3j * k * r + 3) / (r2 * r2)
        nd = np.einsum("qk,qk->q", nrm, d)
        val[i] = (-f * nd) @ wd
        grad[i] = (-(fp[:, None] * (nd / r)[:, None] * d + f[:, None] * nrm)).T @ wd
    return val, grad


def _flux_rows(solution, theta: float, spec) -> list[str]:
    """Time the flux post-processing of one node, and the numpy sum on a subset of its field points."""
    from acousim.fullwave.flux import ExteriorField
    from acousim.fullwave.force_surrogate import cube_b_flux_surface

    pts = cube_b_flux_surface(solution, theta, spec).points
    field = ExteriorField(solution)
    field.scattered(pts[:64])  # compile or load the kernel
    t0 = time.perf_counter()
    val, grad = field.scattered(pts)
    kernel_s = time.perf_counter() - t0
    sub = np.random.default_rng(0).choice(len(pts), 48, replace=False)
    t0 = time.perf_counter()
    v_np, g_np = _numpy_double_layer(field, pts[sub])
    numpy_s = (time.perf_counter() - t0) / len(sub) * len(pts)
    diff = max(np.max(np.abs(v_np - val[sub])) / np.max(np.abs(val)), np.max(np.abs(g_np - grad[sub])) / np.max(np.abs(grad)))
    return [
        f"| {solution.n_dofs} | {len(pts)} | {kernel_s:.1f} | {numpy_s:.0f} (from 48 points) | {numpy_s / kernel_s:.1f} | {diff:.0e} |",
    ]


def main() -> str:
    from acousim.fullwave.convergence import hinge_quantities, mesh_family
    from acousim.fullwave.geometry import dimer_bodies
    from acousim.fullwave.solver import solve_scattering
    from acousim.fullwave.force_surrogate import COARSE_BUILD, build_fullwave_surrogate
    from acousim.gorkov.energy_surrogate import cached_surrogate

    t0 = time.perf_counter()
    solve_scattering(dimer_bodies(0.1, mesh_family(1.0)))
    compile_s = time.perf_counter() - t0

    lines = [
        "## fullwave: boundary-element solves, surrogate build, hinge accuracy, sweep speed",
        "",
        f"First call (numba compilation + one coarse solve): {compile_s:.1f} s.",
        "",
        "| level q | DOFs | mirror-reduced unknowns | assembly [s] | LU + 2 solves [s] | stiffness dQ_theta/dtheta [N m] | rel. diff. to q = 0.35 | Z_eq [um] | f_theta / f_y |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    rows = []
    for q in (1.0, 0.7, 0.5, 0.35):
        sol = solve_scattering(dimer_bodies(0.1, mesh_family(q)))
        hq = hinge_quantities(mesh_family(q))
        rows.append((q, sol.n_dofs, sol.timings["assembly_s"], sol.timings["solve_s"], hq))
    ref = rows[-1][4]["stiffness_nm"]
    for q, n, ta, ts, hq in rows:
        lines.append(
            f"| {q:.2f} | {n} | ~{n // 4} | {ta:.1f} | {ts:.2f} | {hq['stiffness_nm']:.4e} | "
            f"{abs(hq['stiffness_nm'] / ref - 1):.1e} | {hq['z_eq_m'] * 1e6:.1f} | {hq['f_theta_hz'] / hq['f_y_hz']:.3f} |"
        )
    lines += [
        "",
        "Momentum-flux post-processing of one node (theta = 0.3; cube B's half sphere and mirror disc, the exterior "
        "field, elements split recursively near a field point): the compiled kernel against the same quadrature as a numpy "
        "sum over sources per field point.",
        "",
        "| DOFs | field points | compiled kernel [s] | numpy [s] | speed-up | max. rel. difference |",
        "|---|---|---|---|---|---|",
    ]
    for q in (1.0, 0.5):
        spec = mesh_family(q)
        lines += _flux_rows(solve_scattering(dimer_bodies(0.3, spec)), 0.3, spec)
    t0 = time.perf_counter()
    sur = build_fullwave_surrogate(**COARSE_BUILD)
    build_s = time.perf_counter() - t0
    theta = np.linspace(-0.9, 0.9, 41)
    y = np.linspace(-200e-6, 200e-6, 41)
    tt, yy = np.meshgrid(theta, y, indexing="ij")
    t0 = time.perf_counter()
    for _ in range(20):
        sur.generalized_forces(tt, yy)
    fw_sweep = (time.perf_counter() - t0) / 20
    gk = cached_surrogate()
    t0 = time.perf_counter()
    for _ in range(20):
        gk.generalized_forces(tt, yy)
    gk_sweep = (time.perf_counter() - t0) / 20
    lines += [
        "",
        f"Coarse surrogate ({COARSE_BUILD['n_half']} solves, {sur.build_accuracy['dofs']} DOFs): built in {build_s:.1f} s.",
        f"41 x 41 (theta, y) sweep from the surrogates: full-wave {fw_sweep * 1e3:.2f} ms, Gor'kov {gk_sweep * 1e3:.2f} ms "
        "(both are Chebyshev x harmonic tables; the cost of the full-wave model is in building its table).",
    ]
    return "\n".join(lines)


if __name__ == "__main__":
    print(main())
