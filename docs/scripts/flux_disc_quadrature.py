"""Q_theta of one family pose against the flux surface's quadrature, the mesh and the assembly order (docs/fullwave.md,
"The cause" and "What the right quadrature gives").

For each gap g/s, one boundary-element solve of the dimer bent to ``--theta`` at ``--ks`` on the family's mesh
(``family_mesh_spec``, every size times ``--refine``; bempp's regular quadrature order ``--order``), then the
height structure (A, B, C) of Q_theta [N m] from the momentum flux through cube B's half sphere closed by the mirror
disc, with ``--disc-points`` Gauss points per disc panel.  With the family's four gap nodes and one gap between them,
it also prints how far the cubic in log(g/s) through the nodes misses the direct value, relative to max |Q_theta|
over the check table's box.  Prints one JSON line per (gap, disc points).

    python docs/scripts/flux_disc_quadrature.py --gaps 0.01,0.014953,0.0224,0.033437,0.05 --disc-points 6,12
    python docs/scripts/flux_disc_quadrature.py --gaps 0.0224 --refine 0.7
    python docs/scripts/flux_disc_quadrature.py --gaps 0.0224 --order 8
"""
from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np


def pose_torques(ks: float, gap_ratio: float, theta: float, refine: float, disc_points: list[int]) -> dict[int, list]:
    """{disc points: [A, B, C] of Q_theta [N m]} of one solve (the tables' flux, ``dimer_flux_coefficients``)."""
    from acousim.fullwave.family import REFERENCE, FamilyNode, family_mesh_spec
    from acousim.fullwave.flux import dimer_flux_coefficients
    from acousim.fullwave.geometry import dimer_bodies
    from acousim.fullwave.solver import solve_scattering

    node = FamilyNode(ks, gap_ratio)
    side = REFERENCE["side_m"]
    spec = family_mesh_spec(side, gap_ratio * side, refine=refine, refine_faces=True)
    sol = solve_scattering(dimer_bodies(theta, spec), node.medium)
    return {n: dimer_flux_coefficients(sol, theta, spec, REFERENCE["pressure_amplitude_pa"], disc_points=n)["qt"].tolist()
            for n in disc_points}


def cubic_miss(values: dict[float, np.ndarray], nodes: list[float], target: float, check: Path) -> float:
    """Largest |cubic in log g through the nodes - direct| over the check's heights, over max |Q_theta| of the check."""
    chk = json.loads(check.read_text())
    z = chk["z_eq"] + np.linspace(-1.0e-3, 0.8e-3, 19)

    def q(c):
        return c[0] + c[1] * np.cos(chk["two_k"] * z) + c[2] * np.sin(chk["two_k"] * z)

    q_max = max(np.max(np.abs(q(np.asarray(c)))) for c in chk["nodes"]["qt"])
    x, xt = np.log(nodes), np.log(target)
    weights = [np.prod([(xt - x[j]) / (x[k] - x[j]) for j in range(len(x)) if j != k]) for k in range(len(x))]
    predicted = sum(w * values[g] for w, g in zip(weights, nodes))
    return float(np.max(np.abs(q(predicted) - q(values[target]))) / q_max)


def main() -> None:
    from acousim.fullwave.family import FAMILY_DIR, FAMILY_GAP_RATIOS

    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--ks", type=float, default=0.475, help="wavenumber times side (default %(default)s)")
    p.add_argument("--theta", type=float, default=float(0.9 * np.cos(np.pi / 24)),
                   help="bend (default: the tables' outermost Chebyshev node, %(default).4f)")
    p.add_argument("--gaps", default="0.0224", help="comma-separated g/s")
    p.add_argument("--refine", type=float, default=1.0, help="every mesh size times this (default 1: the family's)")
    p.add_argument("--order", type=int, default=4, help="bempp's regular quadrature order (default %(default)s)")
    p.add_argument("--disc-points", default="6,12", help="Gauss points per disc panel, comma-separated (the tables: 6)")
    p.add_argument("--check", default=None, help="check table for the normaliser (default: the family's at 0.475, 0.0224)")
    args = p.parse_args()
    import bempp_cl.api as bempp

    bempp.GLOBAL_PARAMETERS.quadrature.regular = args.order
    gaps = [float(g) for g in args.gaps.split(",")]
    points = [int(n) for n in args.disc_points.split(",")]
    values: dict[int, dict[float, np.ndarray]] = {n: {} for n in points}
    for g in gaps:
        t0 = time.perf_counter()
        res = pose_torques(args.ks, g, args.theta, args.refine, points)
        for n, qt in res.items():
            values[n][g] = np.asarray(qt)
            print(json.dumps({"ks": args.ks, "gap_over_side": g, "theta": args.theta, "refine": args.refine,
                              "order": args.order, "disc_points": n, "q_theta_abc_nm": qt,
                              "wall_s": round(time.perf_counter() - t0, 1)}), flush=True)
    nodes = [g for g in gaps if any(np.isclose(g, FAMILY_GAP_RATIOS, rtol=1e-3))]
    between = [g for g in gaps if g not in nodes]
    check = Path(args.check) if args.check else Path(FAMILY_DIR) / "checks" / "ks0.4750_g0.02240.json"
    if len(nodes) == 4 and between:
        for n in points:
            for g in between:
                print(f"disc points {n}: the cubic in log(g/s) through the gap nodes misses g/s = {g} by "
                      f"{100 * cubic_miss(values[n], nodes, g, check):.2f} % of max |Q_theta|")


if __name__ == "__main__":
    main()
