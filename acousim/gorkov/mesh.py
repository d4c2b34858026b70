"""Tetrahedral meshes of the cubes.

A cube surface is built with trimesh, tetrahedralised with pytetwild (fTetWild) and held as a
pyvista ``UnstructuredGrid``.  The unit cube is meshed once per *relative* edge length
``h = edge_length / side`` and cached under ``meshes/`` as VTU; a cube of side s is that mesh
scaled by s, which is exact.  fTetWild keeps the surface only within its envelope (1e-3 of the
bounding-box diagonal), so boundary vertices are snapped back onto the cube faces: each boundary
triangle is assigned to the face its normal points through and its vertices get that face's
coordinate exactly.  After snapping the mesh volume equals s^3 to round-off (checked on load).

The dimer mesh for rendering is the two posed cube meshes side by side (never a boolean union:
the cubes touch along the hinge edge only, which would be non-manifold).
"""
from __future__ import annotations

import os
import tempfile
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from cubedimer.atomic import atomic_save

__all__ = [
    "cube_surface",
    "tetrahedralize_cube",
    "grid_arrays",
    "default_mesh_dir",
    "snap_to_cube_faces",
    "tetrahedralize_surface",
]

#: Relative tolerance of the snap (fTetWild's default envelope is 1e-3 * sqrt(3) of the side).
_SNAP_TOL = 5e-3


def default_mesh_dir() -> Path:
    """Where meshes are cached: ``$ACOUSIM_MESH_DIR`` or the repository's ``meshes/`` folder."""
    env = os.environ.get("ACOUSIM_MESH_DIR")
    if env:
        return Path(env)
    return Path(__file__).resolve().parents[2] / "meshes"


def cube_surface(side: float = 1.0):
    """Closed triangulated surface of an axis-aligned cube of side ``side`` [m] centred at the origin.

    Returns
    -------
    trimesh.Trimesh
    """
    import trimesh

    if not np.isfinite(side) or side <= 0:
        raise ValueError(f"cube side must be positive, got {side!r}")
    return trimesh.creation.box(extents=(side, side, side))


def grid_arrays(grid) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Points (N, 3) and tetrahedra (m, 4) of a tet-only pyvista UnstructuredGrid."""
    import pyvista as pv

    cells = grid.cells_dict.get(pv.CellType.TETRA)
    if cells is None or len(cells) != grid.n_cells:
        raise ValueError("mesh must contain tetrahedra only")
    return np.asarray(grid.points, dtype=float), np.asarray(cells, dtype=np.int64)


def _boundary_faces(cells: NDArray[np.int64]) -> NDArray[np.int64]:
    faces = np.concatenate([cells[:, [0, 1, 2]], cells[:, [0, 1, 3]], cells[:, [0, 2, 3]], cells[:, [1, 2, 3]]])
    key = np.sort(faces, axis=1)
    _, idx, counts = np.unique(key, axis=0, return_index=True, return_counts=True)
    return faces[idx[counts == 1]]


def snap_to_cube_faces(points: NDArray[np.float64], cells: NDArray[np.int64], half: float = 0.5) -> NDArray[np.float64]:
    """Move boundary vertices exactly onto the faces of the cube ``[-half, half]^3``.

    Each boundary triangle is assigned to the cube face whose outward normal is closest to the
    triangle's normal; its vertices get that face's coordinate.  Vertices further than
    ``_SNAP_TOL * 2 half`` from the face they would be moved to raise ``ValueError``.
    """
    pts = points.copy()
    tri = _boundary_faces(cells)
    centroid = pts[tri].mean(axis=1)
    axis = np.argmax(np.abs(centroid), axis=1)
    sign = np.sign(centroid[np.arange(len(tri)), axis])
    target = sign * half
    for a in range(3):
        sel = axis == a
        vid = tri[sel].ravel()
        tv = np.repeat(target[sel], 3)
        off = np.abs(pts[vid, a] - tv)
        if off.size and off.max() > _SNAP_TOL * 2 * half:
            raise ValueError(f"boundary vertex {off.max():.3g} away from its cube face: mesh is not a cube")
        pts[vid, a] = tv
    return pts


def _cache_path(mesh_dir: Path, rel_edge: float) -> Path:
    return mesh_dir / f"unit_cube_h{rel_edge:.4f}.vtu"


def tetrahedralize_surface(vertices: NDArray, faces: NDArray, edge_length: float) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Tetrahedralise a closed triangle surface with fTetWild (pytetwild), positively oriented tets.

    Parameters
    ----------
    vertices : (n, 3) array, faces : (m, 3) int array
        The surface (e.g. ``trimesh.Trimesh.vertices`` / ``.faces``).
    edge_length : float
        Target edge length, in the units of ``vertices``.

    Returns
    -------
    points (N, 3), tetrahedra (M, 4)
    """
    import pytetwild

    # fTetWild writes a scratch surface file into the working directory: run it in a temporary one
    cwd = os.getcwd()
    with tempfile.TemporaryDirectory(prefix="acousim-tetwild-") as scratch:
        os.chdir(scratch)
        try:
            verts, tets = pytetwild.tetrahedralize(
                np.asarray(vertices, dtype=float),
                np.asarray(faces, dtype=np.int32),
                edge_length_abs=float(edge_length),
                vtk_ordering=True,
                quiet=True,
            )
        finally:
            os.chdir(cwd)
    return np.asarray(verts, dtype=float), np.asarray(tets, dtype=np.int64)


def _mesh_unit_cube(rel_edge: float):
    import pyvista as pv

    surf = cube_surface(1.0)
    verts, tets = tetrahedralize_surface(surf.vertices, surf.faces, rel_edge)
    tets = np.asarray(tets, dtype=np.int64)
    verts = snap_to_cube_faces(np.asarray(verts, dtype=float), tets)
    cells = np.hstack([np.full((len(tets), 1), 4, dtype=np.int64), tets]).ravel()
    grid = pv.UnstructuredGrid(cells, np.full(len(tets), pv.CellType.TETRA, dtype=np.uint8), verts)
    grid.field_data["relative_edge_length"] = np.array([rel_edge])
    grid.field_data["generator"] = np.array(["trimesh.creation.box + pytetwild.tetrahedralize + face snap"])
    return grid


def _check_unit_cube(grid, origin: str) -> None:
    from .quadrature import tetrahedron_volumes

    pts, cells = grid_arrays(grid)
    vol = tetrahedron_volumes(pts, cells)
    if np.any(vol <= 0):
        raise ValueError(f"{origin}: {int(np.sum(vol <= 0))} inverted or flat tetrahedra")
    if abs(vol.sum() - 1.0) > 1e-9 or np.abs(pts).max() > 0.5 + 1e-12:
        raise ValueError(f"{origin}: mesh is not the unit cube (volume {vol.sum():.12f})")


def tetrahedralize_cube(side: float, edge_length: float, mesh_dir: Path | str | None = None, use_cache: bool = True):
    """Tetrahedral mesh of an axis-aligned cube of side ``side`` centred at the origin.

    Parameters
    ----------
    side : float
        Cube side [m].
    edge_length : float
        Target tetrahedron edge length [m] (passed to fTetWild relative to the side).
    mesh_dir : path, optional
        Cache folder (default: :func:`default_mesh_dir`).  The unit-cube mesh for the relative
        edge length ``edge_length / side`` (rounded to 4 digits) is read from there if present,
        otherwise generated and written atomically.
    use_cache : bool
        Set False to force a fresh tetrahedralisation (fTetWild is not deterministic: tet counts
        vary by ~10 % between calls).

    Returns
    -------
    pyvista.UnstructuredGrid
        Tet-only grid in body coordinates [m], cube faces at +-side/2.
    """
    import pyvista as pv

    if not np.isfinite(side) or side <= 0:
        raise ValueError(f"cube side must be positive, got {side!r} m")
    if not np.isfinite(edge_length) or edge_length <= 0:
        raise ValueError(f"mesh edge length must be positive, got {edge_length!r} m")
    rel = round(float(edge_length) / float(side), 4)
    if not 0.01 <= rel <= 1.0:
        raise ValueError(
            f"mesh edge length {edge_length:g} m is {rel:g} of the side {side:g} m; use 0.01-1 of the side"
        )
    mesh_dir = Path(mesh_dir) if mesh_dir is not None else default_mesh_dir()
    path = _cache_path(mesh_dir, rel)
    grid = None
    if use_cache and path.exists():
        grid = pv.read(path)
        _check_unit_cube(grid, str(path))
    if grid is None:
        grid = _mesh_unit_cube(rel)
        _check_unit_cube(grid, "fresh fTetWild mesh")
        if use_cache:
            try:
                atomic_save(path, lambda tmp: grid.save(tmp))
            except OSError:
                pass  # a read-only cache is not an error: the mesh is still returned
    scaled = grid.copy()
    scaled.points = np.asarray(grid.points) * float(side)
    return scaled
