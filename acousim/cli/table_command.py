"""``python -m acousim table``: build one full-wave surrogate table (JSON) of a cube dimer (docs/fullwave.md)."""
from __future__ import annotations

import argparse
import logging

from cubedimer.cli import positive_float, positive_int, prepare_output_file
from cubedimer.meta import DEFAULT_PRESSURE_AMPLITUDE_PA, DEFAULT_SIDE_LENGTH_M

from ..fullwave.force_surrogate import DEFAULT_BUILD, FLUX_DISC_POINTS, FLUX_DISC_POINTS_RANGE, FORCE_METHODS, build_fullwave_surrogate

__all__ = ["add_parser"]

log = logging.getLogger(__name__)


def add_parser(subparsers) -> None:
    """``table``: one full-wave table (boundary-element solves over theta) written as JSON."""
    p = subparsers.add_parser(
        "table",
        help="build one full-wave surrogate table (JSON) of a cube dimer",
        description=("Solve the scattering by both cubes with boundary elements at n-half orientations (theta > 0) and "
                     "write the Chebyshev-in-theta table of the forces and torque that the full-wave model reads "
                     "(acousim/data/fullwave_default.json is one). About half an hour on 2 cores at the default mesh; "
                     "docs/fullwave.md."),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    p.add_argument("--out", required=True, help="output JSON")
    p.add_argument("--mesh", choices=("edges", "hinge"), default="edges",
                   help="edges: graded towards all twelve edges of each cube, the shipped tables' rule "
                        "(edge_graded_mesh_spec; --level is its q, default the family's level at this g/s), whose "
                        "hinge stiffness is within 2 %% of its mesh-converged limit; hinge: graded towards the hinge "
                        "edges only (hinge_refined_spec, or mesh_family(q) with --level), 3-5 %% soft")
    p.add_argument("--level", type=positive_float, default=None,
                   help="mesh level q of the edge-graded mesh, or of mesh_family with --mesh hinge (1: coarse, "
                        "0.5: standard)")
    p.add_argument("--n-half", type=positive_int, default=DEFAULT_BUILD["n_half"], help="solves (theta > 0)")
    p.add_argument("--theta-max", type=positive_float, default=DEFAULT_BUILD["theta_max"],
                   help="interpolation half-width")
    p.add_argument("--side", type=positive_float, default=DEFAULT_SIDE_LENGTH_M, help="cube side [m]")
    p.add_argument("--gap", type=positive_float, default=None, help="hinge gap [m] (default 0.01 side)")
    p.add_argument("--edge-radius", type=float, default=0.0, help="edge radius [m]")
    p.add_argument("--pressure", type=positive_float, default=DEFAULT_PRESSURE_AMPLITUDE_PA,
                   help="pressure amplitude [Pa]")
    p.add_argument("--forces", choices=FORCE_METHODS, default="flux",
                   help="force integration: momentum flux away from the cubes, or surface tractions (docs/fullwave.md)")
    lo, hi = FLUX_DISC_POINTS_RANGE
    p.add_argument("--flux-disc-points", type=int, default=FLUX_DISC_POINTS, choices=range(lo, hi + 1), metavar="N",
                   help=f"Gauss points per panel of the flux surface's mirror disc, {lo}..{hi} (12 converge the hinge "
                        "torque at the folding barrier, 6 leave it 3-5 %% off there; docs/fullwave.md)")
    p.set_defaults(func=run_table)


def run_table(args: argparse.Namespace) -> int:
    """Build the table the options describe and write it to ``--out``."""
    from ..fullwave.geometry import hinge_refined_spec, mesh_family

    prepare_output_file(args.out, "--out")
    for name in ("bempp", "numba"):  # their INFO lines would drown the build's own
        logging.getLogger(name).setLevel(logging.WARNING)
    if args.mesh == "edges":
        from ..fullwave.mesh_rules import edge_graded_mesh_spec

        gap = 0.01 * args.side if args.gap is None else args.gap
        spec = edge_graded_mesh_spec(args.side, gap, args.level, edge_radius=args.edge_radius)
    elif args.level is None:
        spec = hinge_refined_spec(side=args.side, gap=args.gap, edge_radius=args.edge_radius)
    else:
        spec = mesh_family(args.level, side=args.side, gap=args.gap, edge_radius=args.edge_radius)
    sur = build_fullwave_surrogate(spec, n_half=args.n_half, theta_max=args.theta_max,
                                   pressure_amplitude_pa=args.pressure, forces=args.forces,
                                   flux_disc_points=args.flux_disc_points)
    sur.build_accuracy["command"] = "python -m acousim table " + " ".join(
        f"--{k.replace('_', '-')} {v}" for k, v in vars(args).items() if k not in ("func", "command") and v is not None)
    sur.save(args.out)
    f_y, f_t = sur.linear_frequencies()
    log.info("wrote %s: %d DOFs, %d solves, %.0f s; f_y %.3f Hz, f_theta %.3f Hz", args.out, sur.build_accuracy["dofs"],
             args.n_half, sur.build_accuracy["wall_s"], f_y, f_t)
    return 0
