"""``python -m acousim force``: the full-wave radiation force and torque on every body of a surface mesh (docs/formats.md)."""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
from cubedimer.atomic import json_text, write_json
from cubedimer.cli import UserInputError, prepare_output_file
from cubedimer.meta import (DEFAULT_AIR_DENSITY_KG_M3, DEFAULT_FREQUENCY_HZ, DEFAULT_PRESSURE_AMPLITUDE_PA,
                            DEFAULT_SOUND_SPEED_M_S)

__all__ = ["add_parser", "run_force", "force_on_mesh"]


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        "force",
        help="full-wave radiation force and torque on any closed surface mesh",
        description=(
            "Boundary-element (Burton-Miller, bempp-cl) solution of the sound-hard scattering of the standing "
            "wave p0 sin(kZ) by every closed body (connected component) of a triangle surface mesh in any format "
            "trimesh reads (coordinates in metres), shifted up by --z above the pressure node. Writes JSON with "
            "each body's volume centroid [m], time-averaged radiation force [N] and torque about the centroid "
            "[N m] (docs/conventions.md section 7), in the shifted mesh coordinates. Inviscid, free field, rigid and "
            "immobile bodies."
        ),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    p.add_argument("--mesh", required=True, help="surface mesh file (STL, OBJ, PLY, OFF, ...)")
    p.add_argument("--z", required=True, type=float, help="height [m] of the mesh origin above the pressure node")
    p.add_argument("--pressure", type=float, default=DEFAULT_PRESSURE_AMPLITUDE_PA, help="pressure amplitude p0 [Pa]")
    p.add_argument("--frequency", type=float, default=DEFAULT_FREQUENCY_HZ, help="drive frequency [Hz]")
    p.add_argument("--sound-speed", type=float, default=DEFAULT_SOUND_SPEED_M_S, help="speed of sound c0 [m/s]")
    p.add_argument("--air-density", type=float, default=DEFAULT_AIR_DENSITY_KG_M3, help="air density rho0 [kg/m^3]")
    p.add_argument("--out", default=None, help="output JSON file (default: stdout)")
    p.set_defaults(func=run_force)


def _load_mesh(path: str):
    import trimesh

    p = Path(path)
    if not p.is_file():
        raise UserInputError(f"--mesh {path}: no such file")
    try:
        mesh = trimesh.load(p, force="mesh", process=False)
    except Exception as exc:  # trimesh raises many kinds for unreadable files
        raise UserInputError(f"--mesh {path}: cannot read as a surface mesh ({type(exc).__name__}: {exc})".splitlines()[0]) from None
    v = np.asarray(getattr(mesh, "vertices", np.zeros((0, 3))), float)
    f = np.asarray(getattr(mesh, "faces", np.zeros((0, 3))), np.int64)
    if len(f) == 0:
        raise UserInputError(f"--mesh {path}: no triangles found")
    return v, f


def force_on_mesh(vertices, faces, z: float, pressure_amplitude_pa: float, medium, name: str = "mesh") -> dict:
    """Force/torque JSON dict of docs/formats.md for a mesh [m] shifted up by ``z`` [m] (raises MeshError)."""
    from ..fullwave.geometry import split_bodies
    from ..fullwave.solver import solve_scattering
    from ..fullwave.statics import MODEL_NAME

    bodies = split_bodies(vertices, faces, name)
    sol = solve_scattering(bodies, medium)
    hs = sol.height_structure(pressure_amplitude_pa)
    forces, torques = hs.force(z), hs.torque(z)
    shift = np.array([0.0, 0.0, z])
    out = []
    for i, b in enumerate(bodies):
        out.append({
            "centroid_m": (b.centre + shift).tolist(),
            "force_n": forces[i].tolist(),
            "torque_nm": torques[i].tolist(),
            "n_vertices": int(len(b.vertices)),
            "n_triangles": int(len(b.faces)),
        })
    return {
        "model": MODEL_NAME,
        "bodies": out,
        "settings": {
            "z_m": float(z), "pressure_amplitude_pa": float(pressure_amplitude_pa),
            "frequency_hz": medium.frequency_hz, "sound_speed_m_s": medium.sound_speed_m_s,
            "air_density_kg_m3": medium.density_kg_m3, "wavenumber_1_m": medium.wavenumber,
            "incident_field": "p0 sin(kZ), time factor exp(-i w t)",
            "formulation": "Burton-Miller, P1 Galerkin, bempp-cl dense numba", "dofs": sol.n_dofs,
            "boundary_condition": "sound-hard (rigid, immobile)", "torque_about": "volume centroid of each body",
        },
    }


def run_force(args: argparse.Namespace) -> int:
    """Validate, solve, write JSON atomically (nothing is written on an error)."""
    from ..medium import Medium
    from ..fullwave.geometry import MeshError

    for name, unit in (("pressure", "Pa"), ("frequency", "Hz"), ("sound_speed", "m/s"), ("air_density", "kg/m^3")):
        v = getattr(args, name)
        if not np.isfinite(v) or v <= 0:
            raise UserInputError(f"--{name.replace('_', '-')} must be positive, got {v:g} {unit}")
    if not np.isfinite(args.z):
        raise UserInputError("--z must be finite")
    if args.out is not None:
        prepare_output_file(args.out)
    v, f = _load_mesh(args.mesh)
    medium = Medium(frequency_hz=args.frequency, sound_speed_m_s=args.sound_speed, density_kg_m3=args.air_density)
    try:
        result = force_on_mesh(v, f, args.z, args.pressure, medium, name=Path(args.mesh).name)
    except MeshError as exc:
        raise UserInputError(str(exc)) from None
    result["settings"]["mesh"] = str(args.mesh)
    if args.out is None:
        sys.stdout.write(json_text(result))
    else:
        write_json(args.out, result)
    return 0
