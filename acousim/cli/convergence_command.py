"""``python -m acousim convergence``: the convergence studies of the full-wave model
(:mod:`acousim.fullwave.convergence`), one JSON line per row appended to ``--out`` as each row finishes."""
from __future__ import annotations

import argparse
import json
import logging

import numpy as np
from cubedimer.atomic import json_safe
from cubedimer.cli import UserInputError, float_list, prepare_output_file

from ..fullwave import convergence
from ..fullwave.convergence import flux_balance, hinge_quantities, surrogate_errors
from ..fullwave.geometry import mesh_family
from ..fullwave.mesh_record import judge_convergence, mean_refinement_ratio, merge_edge_graded_study, richardson_limit
from ..fullwave.mesh_rules import edge_graded_mesh_spec, family_mesh_spec
from ..fullwave.force_surrogate import COARSE_BUILD, FullwaveSurrogate

__all__ = ["add_parser", "run_study", "load_table"]

log = logging.getLogger(__name__)


def load_table(path: str) -> FullwaveSurrogate:
    """A surrogate table from ``path``, or a one-line :class:`UserInputError` naming the file."""
    try:
        return FullwaveSurrogate.load(path)
    except FileNotFoundError:
        raise UserInputError(f"--table {path}: no such file") from None
    except (ValueError, KeyError, TypeError) as exc:
        raise UserInputError(f"--table {path}: not a full-wave surrogate table ({type(exc).__name__}: {exc})") from None


def _append(path: str, row: dict) -> None:
    with open(path, "a") as fh:  # JSON lines: a row is kept as soon as it is computed
        fh.write(json.dumps(json_safe(row), allow_nan=False) + "\n")


def _run_check(args: argparse.Namespace, levels: list[float]) -> int:
    """The momentum-flux balance (per gap, at the first level) or the surrogate against direct solves."""
    if args.study == "flux":
        for g in float_list(args.gaps, "--gaps"):
            for row in flux_balance(mesh_family(levels[0], gap=g * 500e-6)):
                row.update(level_q=levels[0], gap_over_side=g)
                log.info("flux balance, q = %g, g = %g s, Z = %.2f mm: flux / surface F_Z = %.3f", levels[0], g,
                         row["z_m"] * 1e3, row["ratio_z"])
                _append(args.out, row)
        return 0
    log_row = lambda r: log.info("theta = %.3f: Q_y %.3f %%, Q_theta %.3f %% of max |Q| (%.0f s)", r["theta"],
                                 100 * r["q_y"], 100 * r["q_theta"], r["wall_s"])
    thetas = float_list(args.thetas, "--thetas")
    if args.table:
        row = surrogate_errors(thetas=thetas, surrogate=load_table(args.table), progress=log_row)
        row["table"] = str(args.table)
    else:
        build = dict(COARSE_BUILD, spec=mesh_family(levels[0]))  # level 1 (the default's first) is COARSE_BUILD's mesh
        row = surrogate_errors(build, thetas=thetas, progress=log_row)
        row["level_q"] = levels[0]
    log.info("surrogate (%d solves) against direct solves: Q_y %.2f %%, Q_theta %.2f %% of max |Q| over the box",
             row["solves"], 100 * row["q_y"], 100 * row["q_theta"])
    _append(args.out, row)
    return 0


def run_study(args: argparse.Namespace) -> int:
    """Run the chosen study, appending one JSON line per row to ``--out`` as each row finishes."""
    levels = float_list(args.levels, "--levels")
    if not all(v > 0 for v in levels):
        raise UserInputError("--levels must be positive")
    prepare_output_file(args.out)
    for name in ("bempp", "numba"):
        logging.getLogger(name).setLevel(logging.WARNING)
    if args.study in ("flux", "surrogate"):
        return _run_check(args, levels)
    if args.study == "mesh" and args.mesh_rule == "family-edges":
        rows = [("q", q, edge_graded_mesh_spec(500e-6, args.gap * 500e-6, q)) for q in levels]
    elif args.study == "mesh" and args.mesh_rule in ("family", "family-uniform"):
        faces = args.mesh_rule != "family"
        rows = [("q", q, family_mesh_spec(500e-6, args.gap * 500e-6, refine=q, refine_faces=faces)) for q in levels]
    elif args.study == "mesh":
        rows = [("q", q, mesh_family(q, gap=args.gap * 500e-6)) for q in levels]
    elif args.study == "gap":
        rows = [("gap_over_side", g, mesh_family(levels[0], gap=g * 500e-6)) for g in float_list(args.gaps, "--gaps")]
    else:
        rows = [("edge_radius_over_side", r, mesh_family(levels[0], gap=args.gap * 500e-6, edge_radius=r * 500e-6))
                for r in float_list(args.radii, "--radii")]
    if args.merge_into and not (args.study == "mesh" and args.mesh_rule == "family-edges" and len(levels) >= 3):
        raise UserInputError("--merge-into: only a mesh study with --mesh-rule family-edges and at least three --levels "
                             "is merged into a family's record")
    if args.merge_into and args.family_level is not None and not any(np.isclose(args.family_level, levels, rtol=1e-9)):
        raise UserInputError(f"--family-level {args.family_level:g}: must be one of --levels {args.levels}")
    stiffness, done = [], []
    for key, val, spec in rows:
        res = hinge_quantities(spec)
        res[key] = val
        res["level_q"] = levels[0] if args.study != "mesh" else val
        if args.study in ("mesh", "edge"):
            res.update(gap_over_side=args.gap, mesh_rule=args.mesh_rule)
        done.append(res)
        log.info("%s = %g: %d DOFs, stiffness %.5g N m, f_theta %.3f Hz, f_y %.3f Hz, y^2*theta %.4g, %.0f s", key, val,
                 res["dofs"], res["stiffness_nm"], res["f_theta_hz"], res["f_y_hz"], res["thetaddot"]["y^2*theta"], res["wall_s"])
        _append(args.out, res)
        stiffness.append(res["stiffness_nm"])
    if args.study == "mesh" and len(levels) >= 3:
        ratio = mean_refinement_ratio(levels)
        verdict = judge_convergence(stiffness, ratio)
        log.info("hinge stiffness over q = %s (mean refinement ratio %.2f): corrections %s, monotone %s, order %.2f, "
                 "finest two levels %.2f %% apart: %s", args.levels, ratio,
                 ", ".join(f"{c:+.2%}" for c in verdict["corrections"]), verdict["monotone"], verdict["order"],
                 100 * verdict["finest_difference"], "converged" if verdict["converged"] else "NOT converged")
        try:
            fit = richardson_limit(levels, stiffness)
        except ValueError as exc:
            log.info("no Richardson limit: %s", exc)
        else:
            log.info("Richardson limit of the finest three levels %.5g N m (order %.2f); the finest level is %.2f %% from it",
                     fit["limit"], fit["order"], 100 * fit["finest_error"])
    if args.merge_into:
        row = merge_edge_graded_study(args.merge_into, args.gap, done, args.family_level)
        log.info("merged into %s: g/s = %g states a hinge-stiffness mesh error of %.2f %%", args.merge_into, args.gap,
                 100 * row["stated_error"])
    return 0


def add_parser(subparsers) -> None:
    """``python -m acousim convergence --study {mesh,gap,edge,flux,surrogate} --out FILE.jsonl [...]``."""
    p = subparsers.add_parser("convergence", help="convergence studies of the full-wave model (mesh, gap, edge, flux, "
                              "surrogate)", description=convergence.__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--study", choices=("mesh", "gap", "edge", "flux", "surrogate"), required=True,
                   help="mesh, gap, edge: hinge quantities against mesh level, gap, edge radius; flux: surface "
                   "integrals against the momentum flux through an enclosing sphere (per gap); surrogate: the "
                   "coarse surrogate against direct solves")
    p.add_argument("--levels", default="1,0.7,0.5,0.35", help="mesh levels q (mesh study) or the one level used")
    p.add_argument("--mesh-rule", choices=("uniform", "family", "family-uniform", "family-edges"), default="uniform",
                   help="mesh study: refine mesh_family(q) (every element size times q); the family's gap-resolving "
                        "mesh (acousim.fullwave.family.family_mesh_spec) with its hinge sizes times q (family); "
                        "that mesh with every size, faces included, times q (family-uniform); or that mesh graded "
                        "towards all twelve edges of each cube as well, from 0.02 q s (family-edges)")
    p.add_argument("--gaps", default="0.04,0.02,0.01,0.005", help="gaps as fractions of the side (gap, flux study)")
    p.add_argument("--gap", type=float, default=0.01, help="the gap as a fraction of the side (mesh, edge study)")
    p.add_argument("--radii", default="0,0.01,0.02,0.04", help="edge radii as fractions of the side (edge study)")
    p.add_argument("--thetas", default="0.17,0.71", help="bends of the direct solves (surrogate study)")
    p.add_argument("--table", default=None,
                   help="surrogate study: check this table (e.g. acousim/data/fullwave_default.json) instead of "
                   "building the coarse one")
    p.add_argument("--out", required=True, help="JSON lines output (appended per row)")
    p.add_argument("--merge-into", default=None, metavar="FILE",
                   help="mesh study with --mesh-rule family-edges: merge the finished study into a family's "
                        "mesh_convergence.json (its gap row's edge_graded entry and stated error; written atomically)")
    p.add_argument("--family-level", type=float, default=None, metavar="Q",
                   help="with --merge-into: the family is built on the edge-graded mesh at this level (one of "
                        "--levels); its stated error is measured from it")
    p.set_defaults(func=run_study)
