"""``python -m acousim family {build,info}``: the full-wave table family over (ks, g/s) (docs/fullwave.md)."""
from __future__ import annotations

import argparse
import logging

from cubedimer.cli import UserInputError, add_executor_arguments, executor_config, float_list

from ..fullwave.family import (BUILD_HINT, FAMILY_BUILD, FAMILY_DIR, FAMILY_GAP_RATIOS, FAMILY_KS,
                     FamilyNode, FamilyTableError, FullwaveFamily, build_family, family_nodes)
from ..fullwave.mesh_rules import FAMILY_MESH_LEVELS
from ..fullwave.flux import FLUX_DISC_POINTS_RANGE

__all__ = ["add_parser"]

log = logging.getLogger(__name__)


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        "family",
        help="build or inspect the full-wave table family over (ks, g/s)",
        description=(
            "The full-wave model (boundary elements) depends on the dimer only through ks (wavenumber x side) and "
            "g/s (hinge gap / side); side, frequency, sound speed, air density and pressure are exact scalings. "
            "'build' computes the node tables (one Chebyshev-in-theta table per (ks, g/s), minutes to a quarter "
            "of an hour each on 2 cores), resumably: nodes already on disk are kept, each finished node is "
            "written at once. 'info' lists the nodes and the covered range."
        ),
    )
    sub = p.add_subparsers(dest="family_command", required=True, metavar="ACTION")
    b = sub.add_parser("build", help="build the missing node tables (resumable, parallel over nodes)",
                       description="Build every missing node table of the grid --ks x --gap-ratio into --out. "
                                   "Rerun the same command to resume an interrupted build.",
                       formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    b.add_argument("--out", default=str(FAMILY_DIR), help="directory of the node tables")
    b.add_argument("--mesh", choices=("edges", "hinge"), default="edges",
                   help="edges: meshes graded towards all twelve edges of each cube, at the level q of each gap ("
                        + ", ".join(f"g/s {g:g}: q {q:g}" for g, q in FAMILY_MESH_LEVELS)
                        + "; interpolated in log g/s between them), whose hinge stiffness is within 2 %% of its "
                          "mesh-converged limit (the shipped family's rule); hinge: graded towards the hinge edges only (3-5 %% soft)")
    b.add_argument("--ks", default=",".join(f"{v:g}" for v in FAMILY_KS),
                   help="ks nodes (wavenumber x side), comma-separated")
    b.add_argument("--gap-ratio", default=",".join(f"{v:g}" for v in FAMILY_GAP_RATIOS),
                   help="g/s nodes (hinge gap / side), comma-separated")
    b.add_argument("--points", default=None, metavar="KS:G,...",
                   help="build exactly these (ks, g/s) pairs instead of the grid --ks x --gap-ratio (e.g. check points "
                        "between the nodes for 'check')")
    b.add_argument("--n-half", type=int, default=FAMILY_BUILD["n_half"],
                   help="boundary-element solves per node (theta > 0; the series has 2 n_half terms)")
    b.add_argument("--theta-max", type=float, default=FAMILY_BUILD["theta_max"],
                   help="half-width of the theta range of every node table")
    b.add_argument("--flux-disc-points", type=int, default=FAMILY_BUILD["flux_disc_points"],
                   help="Gauss points per panel of the flux surface's mirror disc (12 converge the hinge torque at "
                        "the folding barrier, 6 leave it 3-5 %% off there, docs/fullwave.md; existing tables built "
                        "otherwise are rebuilt)")
    b.add_argument("--no-progress", action="store_true", help="no progress bar")
    add_executor_arguments(b, "One task is one node table.")
    b.set_defaults(func=run_build)
    c = sub.add_parser("check", help="measure the interpolation error against direct-solve tables between the nodes",
                       description="Compare the family's interpolation with every check table it covers (tables built "
                                   "with 'build --points' between the nodes, and the shipped default dimer's table) on "
                                   "|theta| <= 0.9 and y -1.0..+0.8 mm, print the errors and write them to "
                                   "FAMILY/accuracy.json, which every interpolated model then states.",
                       formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    c.add_argument("--family", default=str(FAMILY_DIR), help="directory of the node tables")
    c.add_argument("--checks", default=str(FAMILY_DIR / "checks"), help="directory of the check tables")
    c.set_defaults(func=run_check)
    i = sub.add_parser("info", help="list the node tables and the range they cover")
    i.add_argument("--family", default=str(FAMILY_DIR), help="directory of the node tables")
    i.set_defaults(func=run_info)


def run_build(args: argparse.Namespace) -> int:
    if args.n_half < 2:
        raise UserInputError(f"--n-half {args.n_half}: at least 2 solves are needed")
    if not 0 < args.theta_max < 1:
        raise UserInputError(f"--theta-max {args.theta_max}: must lie in (0, 1)")
    lo, hi = FLUX_DISC_POINTS_RANGE
    if not lo <= args.flux_disc_points <= hi:
        raise UserInputError(f"--flux-disc-points {args.flux_disc_points}: must lie in {lo}..{hi} (the shipped "
                             f"family: {FAMILY_BUILD['flux_disc_points']}, which converge the folding barrier)")
    try:
        points = None
        if args.points:
            points = [p.split(":") for p in args.points.split(",") if p.strip()]
            if any(len(p) != 2 for p in points):
                raise UserInputError(f"--points {args.points!r}: expected KS:G pairs separated by commas")
            points = [(float(k), float(g)) for k, g in points]
        nodes = family_nodes(float_list(args.ks, "--ks"), float_list(args.gap_ratio, "--gap-ratio"), args.n_half,
                             args.theta_max, args.flux_disc_points, edge_graded=args.mesh == "edges", points=points)
    except ValueError as exc:
        raise UserInputError(f"{exc} (options --ks / --gap-ratio / --points)") from None
    summary = build_family(args.out, nodes, executor_config(args), progress=not args.no_progress)
    built = [s for s in summary if s["built"]]
    print(f"{len(nodes)} node table(s) in {args.out}: {len(built)} built now "
          f"({sum(s['wall_s'] for s in built):.0f} s of work), {len(nodes) - len(built)} already there")
    return 0


def run_info(args: argparse.Namespace) -> int:
    try:
        fam = FullwaveFamily(args.family)
    except FamilyTableError as exc:
        raise UserInputError(str(exc)) from None
    for (k, g), sur in sorted(fam.tables.items()):
        ba = sur.build_accuracy
        level = FamilyNode.from_table(sur).mesh_level
        mesh = "hinge-graded mesh" if level is None else f"edge-graded mesh q {level:g}"
        print(f"ks {k:.4f}  g/s {g:.5f}  {int(ba.get('dofs', 0)):5d} DOFs  {float(ba.get('wall_s', 0)):7.0f} s  {mesh}")
    print(f"covers {fam.describe_range()}")
    return 0


def run_check(args: argparse.Namespace) -> int:
    from pathlib import Path

    from cubedimer.atomic import write_json

    from ..fullwave.family import family_accuracy, load_node
    from ..fullwave.force_surrogate import DEFAULT_TABLE

    try:
        fam = FullwaveFamily(args.family)
        checks = [load_node(p) for p in sorted(Path(args.checks).glob("*.json"))] + [load_node(DEFAULT_TABLE)]
    except FamilyTableError as exc:
        raise UserInputError(str(exc)) from None
    if fam.empty:
        raise UserInputError(f"{args.family}: {fam.describe_range()}; build the family first ({BUILD_HINT})")
    acc = family_accuracy(fam, checks)
    for r in acc["checks"]:
        print(f"ks {r['ks']:.4f}  g/s {r['gap_over_side']:.4f}: Q_y {100 * r['q_y']:.3f} %, Q_theta "
              f"{100 * r['q_theta']:.3f} % of max ({100 * r['q_theta_inner']:.3f} % over the inner 80 % of theta); f_y {100 * r['f_y']:+.3f} %, f_theta {100 * r['f_theta']:+.3f} %, "
              f"stiffness {100 * r['stiffness']:+.3f} %")
    write_json(Path(args.family) / "accuracy.json", acc)
    print(f"{acc['summary']['n_checks']} check(s) inside {fam.describe_range()} -> {Path(args.family) / 'accuracy.json'}")
    return 0
