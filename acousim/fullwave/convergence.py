"""Convergence of the full-wave hinge against mesh size, hinge gap and edge radius.

For one geometry and mesh, two boundary-element solves (theta = 0 and theta = delta) give, through the
exact height structure and the bend parity (A, B odd and C even in theta, see
:mod:`acousim.fullwave.surrogate`):

* the theta = 0 vertical force ``F_Z = C_F sin(2kZ)``, hence Z_eq (F_Z = M g) and f_y;
* the hinge stiffness ``dQ_theta/dtheta = A_Q'(0) + B_Q'(0) cos(2kZ_eq)`` at (theta, y) = (0, 0)
  (``A_Q'(0) ~ A_Q(delta) / delta``, error O(delta^2));
* the Taylor coefficients of thetaddot = Q_theta / I: ``1``, ``y``, ``theta``, ``y*theta``, ``y^2*theta``.

Run ``python -m acousim.fullwave.convergence --help``; the tables of docs/fullwave.md were made with it.
"""
from __future__ import annotations

import argparse
import json
import logging
import sys
import time
from dataclasses import replace

import numpy as np

from ..medium import GRAVITY, Medium
from .geometry import DimerMeshSpec, dimer_bodies, mesh_family, rounded_cube_volume
from .solver import solve_scattering
from .surrogate import dimer_generalized_coefficients

__all__ = ["mesh_family", "hinge_quantities", "main"]

log = logging.getLogger(__name__)

def hinge_quantities(spec: DimerMeshSpec, medium: Medium = Medium(), pressure_amplitude_pa: float = 3000.0,
                     particle_density: float = 2160.0, gravity: float = GRAVITY, delta: float = 0.02) -> dict:
    """Z_eq, F_Z amplitude, hinge stiffness and thetaddot Taylor coefficients of one mesh (two solves).

    Returns
    -------
    dict
        ``dofs``, ``wall_s``, ``z_eq_m``, ``fz_amplitude_n`` (|C_F(0)|), ``f_y_hz``, ``stiffness_nm``
        (dQ_theta/dtheta at the equilibrium height), ``f_theta_hz`` (from the stiffness alone) and
        ``thetaddot`` (dict of Taylor coefficients, SI).
    """
    t0 = time.perf_counter()
    two_k = 2 * medium.wavenumber
    g0 = dimer_generalized_coefficients(solve_scattering(dimer_bodies(0.0, spec), medium).height_structure(pressure_amplitude_pa))
    sol = solve_scattering(dimer_bodies(delta, spec), medium)
    gd = dimer_generalized_coefficients(sol.height_structure(pressure_amplitude_pa))
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
        "thetaddot": {k: float(v) for k, v in thetaddot.items()}, "spec": spec.settings(),
    }


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m acousim.fullwave.convergence", description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--study", choices=("mesh", "gap", "edge"), required=True)
    p.add_argument("--levels", default="1,0.7,0.5,0.35", help="mesh levels q (mesh study) or the one level used")
    p.add_argument("--gaps", default="0.04,0.02,0.01,0.005", help="gaps as fractions of the side (gap study)")
    p.add_argument("--radii", default="0,0.01,0.02,0.04", help="edge radii as fractions of the side (edge study)")
    p.add_argument("--out", required=True, help="JSON lines output (appended per row)")
    args = p.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(message)s")
    for name in ("bempp", "numba"):
        logging.getLogger(name).setLevel(logging.WARNING)
    levels = [float(x) for x in args.levels.split(",")]
    rows = []
    if args.study == "mesh":
        rows = [("q", q, mesh_family(q)) for q in levels]
    elif args.study == "gap":
        rows = [("gap_over_side", g, mesh_family(levels[0], gap=g * 500e-6)) for g in (float(x) for x in args.gaps.split(","))]
    else:
        rows = [("edge_radius_over_side", r, mesh_family(levels[0], edge_radius=r * 500e-6)) for r in (float(x) for x in args.radii.split(","))]
    for key, val, spec in rows:
        res = hinge_quantities(spec)
        res[key] = val
        res["level_q"] = levels[0] if args.study != "mesh" else val
        log.info("%s = %g: %d DOFs, stiffness %.5g N m, f_theta %.3f Hz, f_y %.3f Hz, y^2*theta %.4g, %.0f s", key, val,
                 res["dofs"], res["stiffness_nm"], res["f_theta_hz"], res["f_y_hz"], res["thetaddot"]["y^2*theta"], res["wall_s"])
        with open(args.out, "a") as fh:
            fh.write(json.dumps(res) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
