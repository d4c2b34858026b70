"""Off-screen pyvista rendering of the posed dimer mesh coloured by the Gor'kov potential density.

Works headless: VTK uses EGL (Mesa llvmpipe) when ``VTK_DEFAULT_OPENGL_WINDOW=vtkEGLRenderWindow``
is set before VTK loads, which this module does if the variable is unset.
"""
from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from ..field import gorkov_potential_density
from .forces import GorkovDimer

__all__ = ["posed_dimer_mesh", "render_dimer"]

os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")


def posed_dimer_mesh(model: GorkovDimer, theta: float, y: float):
    """The two cube meshes rigidly posed at (theta, y), merged into one pyvista UnstructuredGrid.

    Coordinates in micrometres; point data ``u`` is the Gor'kov potential density [J/m^3] and
    cell data ``cube`` is 0 for cube A, 1 for cube B.  (The cubes share only the hinge edge; the
    two grids are appended, not fused.)
    """
    import pyvista as pv

    z_com = float(y) + model.equilibrium_height
    rot = model.dimer.cube_rotations(float(theta))
    off = model.dimer.centre_offsets(float(theta))
    parts = []
    for i, grid in enumerate(model.cube_meshes):
        g = grid.copy()
        pts = np.asarray(grid.points) @ rot[i].T + off[i] + np.array([0.0, 0.0, z_com])
        g.points = pts * 1e6
        g.point_data["u"] = gorkov_potential_density(pts[:, 2], model.wave)
        g.cell_data["cube"] = np.full(g.n_cells, i)
        parts.append(g)
    return parts[0].merge(parts[1], merge_points=False)


def render_dimer(model: GorkovDimer, theta: float, y: float, path: str | os.PathLike, window_size=(900, 700)) -> Path:
    """Render the posed dimer (camera along the hinge, +Y) to a PNG, written atomically.

    The colour is the Gor'kov potential density u(Z) [J/m^3]; a line marks the pressure node
    (Z = 0) when it is in view.
    """
    import pyvista as pv

    pv.OFF_SCREEN = True
    mesh = posed_dimer_mesh(model, theta, y)
    plotter = pv.Plotter(off_screen=True, window_size=list(window_size))
    plotter.set_background("white")
    plotter.add_mesh(
        mesh,
        scalars="u",
        cmap="viridis",
        show_edges=True,
        edge_color="#333333",
        line_width=0.3,
        scalar_bar_args={"title": "u [J/m^3]", "color": "black", "vertical": True, "position_x": 0.86},
    )
    b = mesh.bounds
    span = max(b[1] - b[0], b[5] - b[4])
    z_eq_um = model.equilibrium_height * 1e6
    plotter.add_text(
        f"theta = {theta:+.2f}, y = {y * 1e6:+.0f} um  (Z_com = {z_eq_um + y * 1e6:+.0f} um from the pressure node)",
        font_size=10,
        color="black",
    )
    plotter.show_bounds(xtitle="X [um]", ytitle="Y [um]", ztitle="Z [um]", color="black", font_size=8)
    centre = np.array([(b[0] + b[1]) / 2, (b[2] + b[3]) / 2, (b[4] + b[5]) / 2])
    plotter.camera.position = tuple(centre - np.array([0.0, 4.0 * span, 0.0]))
    plotter.camera.focal_point = tuple(centre)
    plotter.camera.up = (0.0, 0.0, 1.0)
    plotter.camera.parallel_projection = True
    plotter.reset_camera()
    from cubedimer.atomic import atomic_save

    path = Path(path)
    atomic_save(path, lambda tmp: plotter.screenshot(str(tmp)))
    plotter.close()
    return path
