"""``python -m acousim family {build,info}``: the full-wave table family over (ks, g/s) (docs/fullwave.md)."""
from __future__ import annotations

import argparse
import logging

from cubedimer.cli import UserInputError, add_executor_arguments, executor_config

from .family import (BUILD_HINT, FAMILY_BUILD, FAMILY_DIR, FAMILY_GAP_RATIOS, FAMILY_KS, FamilyNode,
                     FamilyRangeError, FamilyTableError, FullwaveFamily, build_family, family_nodes, node_path)

__all__ = ["add_parser"]

log = logging.getLogger(__name__)


def _floats(text: str, option: str) -> list[float]:
    try:
        values = [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise UserInputError(f"{option} {text!r}: expected comma-separated numbers") from None
    if not values:
        raise UserInputError(f"{option}: no value given")
    return values


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
    b.add_argument("--ks", default=",".join(f"{v:g}" for v in FAMILY_KS),
                   help="ks nodes (wavenumber x side), comma-separated")
    b.add_argument("--gap-ratio", default=",".join(f"{v:g}" for v in FAMILY_GAP_RATIOS),
                   help="g/s nodes (hinge gap / side), comma-separated")
    b.add_argument("--n-half", type=int, default=FAMILY_BUILD["n_half"],
                   help="boundary-element solves per node (theta > 0; the series has 2 n_half terms)")
    b.add_argument("--theta-max", type=float, default=FAMILY_BUILD["theta_max"],
                   help="half-width of the theta range of every node table")
    b.add_argument("--no-progress", action="store_true", help="no progress bar")
    add_executor_arguments(b, "One task is one node table.")
    b.set_defaults(func=run_build)
    i = sub.add_parser("info", help="list the node tables and the range they cover")
    i.add_argument("--family", default=str(FAMILY_DIR), help="directory of the node tables")
    i.set_defaults(func=run_info)


def run_build(args: argparse.Namespace) -> int:
    ks = _floats(args.ks, "--ks")
    gaps = _floats(args.gap_ratio, "--gap-ratio")
    if args.n_half < 2:
        raise UserInputError(f"--n-half {args.n_half}: at least 2 solves are needed")
    if not 0 < args.theta_max < 1:
        raise UserInputError(f"--theta-max {args.theta_max}: must lie in (0, 1)")
    try:
        nodes = family_nodes(ks, gaps, args.n_half, args.theta_max)
    except ValueError as exc:
        raise UserInputError(f"{exc} (options --ks / --gap-ratio)") from None
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
        print(f"ks {k:.4f}  g/s {g:.5f}  {int(ba.get('dofs', 0)):5d} DOFs  {float(ba.get('wall_s', 0)):7.0f} s")
    print(f"covers {fam.describe_range()}")
    return 0
