"""Off-screen rendering of the posed dimer mesh (headless, EGL)."""
import numpy as np
import pytest


def test_posed_mesh_geometry(default_model):
    from acousim.gorkov.render import posed_dimer_mesh

    mesh = posed_dimer_mesh(default_model, 0.3, 0.0)
    assert mesh.n_cells == default_model.n_tetrahedra
    z = np.asarray(mesh.points)[:, 2] * 1e-6
    np.testing.assert_allclose(z.mean(), default_model.equilibrium_height, atol=50e-6)  # node mean, not volume mean
    u = mesh.point_data["u"]
    # the whole dimer is below the node (Z < 0), where u = A0 - A2 cos(2kZ) falls towards the node
    assert z.max() < 0
    assert np.all(np.diff(u[np.argsort(z)]) <= 1e-9)


def test_render_writes_png(default_model, tmp_path):
    pytest.importorskip("pyvista")
    from acousim.gorkov.render import render_dimer

    path = render_dimer(default_model, 0.3, 0.0, tmp_path / "dimer.png", window_size=(400, 300))
    import matplotlib.image as mpimg

    img = mpimg.imread(path)
    assert img.shape[:2] == (300, 400)
    colours = np.unique((img[..., :3] * 255).astype(int).reshape(-1, 3), axis=0)
    assert len(colours) > 50  # a coloured mesh, not a blank frame
    assert not list(tmp_path.glob(".*"))  # no temporary file left behind
