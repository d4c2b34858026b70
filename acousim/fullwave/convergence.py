"""Convergence of the full-wave hinge against mesh size, hinge gap and edge radius.

For one geometry and mesh, two boundary-element solves (theta = 0 and theta = delta) give, through the
exact height structure and the bend parity (A, B odd and C even in theta, see
:mod:`acousim.fullwave.surrogate`):

* the theta = 0 vertical force ``F_Z = C_F sin(2kZ)``, hence Z_eq (F_Z = M g) and f_y;
* the hinge stiffness ``dQ_theta/dtheta = A_Q'(0) + B_Q'(0) cos(2kZ_eq)`` at (theta, y) = (0, 0)
  (``A_Q'(0) ~ A_Q(delta) / delta``, error O(delta^2));
* the Taylor coefficients of thetaddot = Q_theta / I: ``1``, ``y``, ``theta``, ``y*theta``, ``y^2*theta``.

The mesh study ends with :func:`judge_convergence` of the hinge stiffness (monotone corrections, observed
order >= 1, finest two levels within 2 %).  Run ``python -m acousim convergence --help``; the
tables of docs/fullwave.md were made with it.
"""
from __future__ import annotations

import argparse
import json
import logging
import time
from collections.abc import Callable

import numpy as np
from cubedimer.atomic import json_safe
from cubedimer.cli import UserInputError, float_list, prepare_output_file

from ..medium import GRAVITY, Medium
from .geometry import DimerMeshSpec, dimer_bodies, mesh_family, rounded_cube_volume
from .mesh_record import (CONVERGED_WITHIN, judge_convergence, mean_refinement_ratio,  # noqa: F401 (re-exported)
                          merge_edge_graded_study, richardson_limit, stated_mesh_error)
from .mesh_rules import EDGE_GRADED_H_EDGE, edge_graded_mesh_spec, family_mesh_spec
from .flux import ExteriorField, enclosing_sphere_surface, flux_height_structure
from .solver import solve_scattering
from .surrogate import COARSE_BUILD, FullwaveSurrogate, build_fullwave_surrogate, dimer_coefficients

__all__ = ["mesh_family", "hinge_quantities", "judge_convergence", "richardson_limit", "stated_mesh_error",
           "flux_balance", "surrogate_errors", "CONVERGED_WITHIN", "EDGE_GRADED_H_EDGE", "add_parser", "run_study"]


log = logging.getLogger(__name__)

def hinge_quantities(spec: DimerMeshSpec, medium: Medium = Medium(), pressure_amplitude_pa: float = 3000.0,
                     particle_density: float = 2160.0, gravity: float = GRAVITY, delta: float = 0.02,
                     forces: str = "flux") -> dict:
    """Z_eq, F_Z amplitude, hinge stiffness and thetaddot Taylor coefficients of one mesh (two solves).

    Returns
    -------
    dict
        ``dofs``, ``wall_s``, ``z_eq_m``, ``fz_amplitude_n`` (|C_F(0)|), ``f_y_hz``, ``stiffness_nm``
        (dQ_theta/dtheta at the equilibrium height), ``f_theta_hz`` (from the stiffness alone) and
        ``thetaddot`` (dict of Taylor coefficients, SI); ``forces`` is how forces and torques were integrated
        (:data:`acousim.fullwave.surrogate.FORCE_METHODS`).
    """
    t0 = time.perf_counter()
    two_k = 2 * medium.wavenumber
    g0 = dimer_coefficients(solve_scattering(dimer_bodies(0.0, spec), medium), 0.0, spec, pressure_amplitude_pa, forces)
    sol = solve_scattering(dimer_bodies(delta, spec), medium)
    gd = dimer_coefficients(sol, delta, spec, pressure_amplitude_pa, forces)
    m = particle_density * rounded_cube_volume(spec.side, spec.edge_radius)
    mass = 2 * m
    c_f = g0["fz"][2]
    ratio = mass * gravity / c_f
    if not -1 < ratio < 0:
        raise ValueError("the field cannot levitate this dimer")
    z_eq = float(np.arcsin(ratio) / two_k)  # in (-lambda/8, 0): C_F < 0 there
    ph = two_k * z_eq
    c, s = np.cos(ph), np.sin(ph)
    i0 = (np.pi / 4) ** 2 * 2 * m * spec.side**2 / 6
    a1, b1 = gd["qt"][0] / delta, gd["qt"][1] / delta  # A_Q'(0), B_Q'(0)
    cq0 = g0["qt"][2]
    stiff = a1 + b1 * c
    k_y = -two_k * c_f * c  # -dF_Z/dZ
    thetaddot = {
        "1": cq0 * s / i0,
        "y": two_k * cq0 * c / i0,
        "theta": stiff / i0,
        "y*theta": -two_k * b1 * s / i0,
        "y^2*theta": -(two_k**2) * b1 * c / (2 * i0),
    }
    return {
        "dofs": int(sol.n_dofs), "wall_s": time.perf_counter() - t0, "z_eq_m": z_eq, "fz_amplitude_n": abs(float(c_f)),
        "f_y_hz": float(np.sqrt(k_y / mass) / (2 * np.pi)) if k_y > 0 else float("nan"),
        "stiffness_nm": float(stiff),
        "f_theta_hz": float(np.sqrt(-stiff / i0) / (2 * np.pi)) if stiff < 0 else float("nan"),
        "thetaddot": {k: float(v) for k, v in thetaddot.items()}, "spec": spec.settings(), "forces": forces,
    }


def flux_balance(spec: DimerMeshSpec, theta: float = 0.3, heights=(-0.4e-3, 0.9e-3), radius: float = 1.2e-3,
                 pressure_amplitude_pa: float = 3000.0, n_polar: int = 20) -> list[dict]:
    """Total force on the dimer from the per-cube surface tractions against the momentum flux through an
    enclosing sphere of ``radius`` [m] (:mod:`acousim.fullwave.flux`), at each height [m].

    The two must agree (momentum conservation in the inviscid fluid); docs/fullwave.md states how far
    the surface tractions do not on sharp cube edges.

    Returns
    -------
    list of dict
        Per height: ``z_m``, ``surface_n`` and ``flux_n`` (total force vectors [N]; the flux's Y component is
        not evaluated, the field being mirror symmetric in Y) and ``ratio_z`` (flux / surface of the vertical
        component).
    """
    sol = solve_scattering(dimer_bodies(theta, spec))
    hs = sol.height_structure(pressure_amplitude_pa)
    med = sol.medium
    force, _ = flux_height_structure(ExteriorField(sol), enclosing_sphere_surface(radius, n_polar), np.zeros(3),
                                     med.density_kg_m3, med.sound_speed_m_s, 2 * np.pi * med.frequency_hz,
                                     pressure_amplitude_pa)
    rows = []
    for z in heights:
        surface = hs.force(z).sum(axis=0)
        flux = force[0] + force[1] * np.cos(hs.two_k * z) + force[2] * np.sin(hs.two_k * z)
        flux[1] = np.nan
        rows.append({"z_m": float(z), "surface_n": surface.tolist(), "flux_n": flux.tolist(),
                     "ratio_z": float(flux[2] / surface[2])})
    return rows


def surrogate_errors(build: dict = COARSE_BUILD, thetas=(0.17, 0.71), y=np.linspace(-1.0e-3, 0.8e-3, 13),
                     pressure_amplitude_pa: float = 3000.0, surrogate: FullwaveSurrogate | None = None,
                     progress: Callable[[dict], None] | None = None) -> dict:
    """Errors of a surrogate against direct solves at bends ``thetas`` that are not Chebyshev nodes, over
    heights ``y`` [m] above Z_eq (same mesh on both sides).

    Parameters
    ----------
    build : dict
        Keyword arguments of :func:`build_fullwave_surrogate` (``spec``, ``n_half``, ``theta_max``,
        ``forces``); ignored when ``surrogate`` is given.
    thetas : sequence of float
        Bends of the direct solves.
    y : array_like
        Heights above Z_eq [m].
    pressure_amplitude_pa : float
        p0 [Pa] of the comparison.
    surrogate : FullwaveSurrogate, optional
        An existing table (e.g. the shipped one); its settings give the mesh and the force method.
    progress : callable, optional
        Called with the row of each bend as it finishes (``theta``, ``q_y``, ``q_theta``, ``wall_s``).

    Returns
    -------
    dict
        ``q_y`` and ``q_theta``: the largest error relative to max |Q| over the box
        |theta| <= theta_max, y in the range given (the issue's target is 0.005); ``per_theta``: the
        same per bend.
    """
    if surrogate is None:
        sur = build_fullwave_surrogate(**build, pressure_amplitude_pa=pressure_amplitude_pa)
    else:
        sur = surrogate.with_pressure(pressure_amplitude_pa)
    spec, forces = DimerMeshSpec.from_settings(sur.settings), sur.settings.get("forces", "flux")
    y = np.asarray(y, float)
    tt, yy = np.meshgrid(np.linspace(-sur.theta_max, sur.theta_max, 19), y, indexing="ij")
    qy_box, qt_box = (np.max(np.abs(q)) for q in sur.generalized_forces(tt, yy))
    rows = []
    for theta in thetas:
        t0 = time.perf_counter()
        sol = solve_scattering(dimer_bodies(theta, spec), sur.medium)
        g = dimer_coefficients(sol, theta, spec, pressure_amplitude_pa, forces, sur.flux_disc_points)  # as the table
        ph = sur.two_k * (y + sur.z_eq)
        direct = {c: g[c][0] + g[c][1] * np.cos(ph) + g[c][2] * np.sin(ph) for c in ("fz", "qt")}
        q_y, q_t = sur.generalized_forces(theta, y)
        row = {"theta": float(theta),
               "q_y": float(np.max(np.abs(q_y - (direct["fz"] - sur.mass * sur.gravity)))) / qy_box,
               "q_theta": float(np.max(np.abs(q_t - direct["qt"]))) / qt_box,
               "wall_s": time.perf_counter() - t0}
        rows.append(row)
        if progress is not None:
            progress(row)
    return {"q_y": max(r["q_y"] for r in rows), "q_theta": max(r["q_theta"] for r in rows), "solves": int(sur.settings["n_half"]),
            "thetas": [float(t) for t in thetas], "per_theta": rows}


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
                              "surrogate)", description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
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
