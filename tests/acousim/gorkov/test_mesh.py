"""Cube meshes: tet-only, exact cube after snapping, cached, scaled."""
import numpy as np
import pytest

from acousim.gorkov.mesh import grid_arrays, snap_to_cube_faces, tetrahedralize_cube
from acousim.gorkov.quadrature import tetrahedron_volumes


@pytest.mark.parametrize("side", [400e-6, 500e-6, 700e-6])
def test_cube_mesh_is_exact_cube(side):
    grid = tetrahedralize_cube(side, 0.2 * side)
    pts, cells = grid_arrays(grid)
    vol = tetrahedron_volumes(pts, cells)
    assert np.all(vol > 0), "inverted tetrahedra"
    # snapping puts every boundary vertex on a face: the volume is exact to round-off
    np.testing.assert_allclose(vol.sum(), side**3, rtol=1e-12)
    np.testing.assert_allclose(pts.min(axis=0), -side / 2, rtol=1e-12)
    np.testing.assert_allclose(pts.max(axis=0), side / 2, rtol=1e-12)
    assert len(cells) > 500


def test_snap_rejects_a_non_cube():
    import trimesh

    from acousim.gorkov.mesh import tetrahedralize_surface

    sphere = trimesh.creation.icosphere(subdivisions=2, radius=0.5)
    with pytest.raises(ValueError, match="not a cube"):
        snap_to_cube_faces(*tetrahedralize_surface(sphere.vertices, sphere.faces, 0.3))


def test_mesh_cache_reused(tmp_path):
    a = tetrahedralize_cube(1.0, 0.3, mesh_dir=tmp_path)
    b = tetrahedralize_cube(2.0, 0.6, mesh_dir=tmp_path)  # same relative edge length: same cached mesh, scaled
    assert len(list(tmp_path.glob("*.vtu"))) == 1
    assert a.n_cells == b.n_cells
    np.testing.assert_allclose(np.asarray(b.points), 2 * np.asarray(a.points), rtol=1e-14)


@pytest.mark.parametrize("side,edge", [(-1.0, 0.1), (1.0, -0.1), (1.0, 5.0)])
def test_bad_mesh_arguments(side, edge, tmp_path):
    with pytest.raises(ValueError):
        tetrahedralize_cube(side, edge, mesh_dir=tmp_path)
