"""``python -m acousim force``: JSON contract, one-line errors, no partial output."""
from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

trimesh = pytest.importorskip("trimesh")
pytest.importorskip("bempp_cl")

REPO = Path(__file__).resolve().parents[3]


def run_here(capsys, *args: str) -> tuple[int, str, str]:
    """In this process, so the bempp compilation is shared with the other full-wave tests."""
    from acousim.cli import main

    code = main(["force", *args])
    cap = capsys.readouterr()
    return code, cap.out, cap.err


def two_spheres(path: Path) -> None:
    a = trimesh.creation.icosphere(subdivisions=1, radius=100e-6)
    b = trimesh.creation.icosphere(subdivisions=1, radius=100e-6)
    b.apply_translation([400e-6, 0, 0])
    trimesh.util.concatenate([a, b]).export(path)


def test_force_json_contract(tmp_path, capsys):
    mesh = tmp_path / "pair.stl"
    two_spheres(mesh)
    out = tmp_path / "force.json"
    code, _, err = run_here(capsys, "--mesh", str(mesh), "--z", "-0.4e-3", "--pressure", "2000", "--out", str(out))
    assert code == 0, err
    data = json.loads(out.read_text())
    assert set(data) >= {"bodies", "settings"}
    assert len(data["bodies"]) == 2
    for body in data["bodies"]:
        assert set(body) >= {"centroid_m", "force_n", "torque_nm"}
        assert len(body["centroid_m"]) == len(body["force_n"]) == len(body["torque_nm"]) == 3
        assert np.isclose(body["centroid_m"][2], -0.4e-3, atol=1e-9)
        assert body["force_n"][2] > 0  # below the node the force points up, towards it
    c = [b["centroid_m"][0] for b in data["bodies"]]
    assert sorted(np.round(c, 7)) == [0.0, 4e-4]
    assert data["settings"]["pressure_amplitude_pa"] == 2000.0
    assert data["settings"]["z_m"] == -0.4e-3
    # stdout without --out gives the same JSON
    code, text, _ = run_here(capsys, "--mesh", str(mesh), "--z", "-0.4e-3", "--pressure", "2000")
    assert code == 0 and json.loads(text)["bodies"] == data["bodies"]


def test_force_open_mesh_one_line_error(tmp_path, capsys):
    s = trimesh.creation.icosphere(subdivisions=1, radius=100e-6)
    s.faces = s.faces[1:]
    mesh = tmp_path / "open.stl"
    s.export(mesh)
    out = tmp_path / "force.json"
    code, _, err = run_here(capsys, "--mesh", str(mesh), "--z", "0", "--out", str(out))
    assert code == 2
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "not closed" in lines[0], err
    assert not out.exists() and list(tmp_path.iterdir()) == [mesh]


def test_force_inverted_mesh_and_bad_arguments(tmp_path, capsys):
    s = trimesh.creation.icosphere(subdivisions=1, radius=100e-6)
    s.faces = s.faces[:, ::-1]
    mesh = tmp_path / "inv.obj"
    s.export(mesh)
    for args, fragment in (
        (("--mesh", str(mesh), "--z", "0"), "inward"),
        (("--mesh", str(tmp_path / "missing.stl"), "--z", "0"), "no such file"),
        (("--mesh", str(mesh), "--z", "0", "--pressure", "-3"), "--pressure"),
        (("--mesh", str(mesh), "--z", "0", "--out", str(mesh / "f.json")), "--out"),  # under a file
    ):
        code, out, err = run_here(capsys, *args)
        assert code == 2 and out == "", (args, err)
        assert len(err.strip().splitlines()) == 1 and fragment in err, (args, err)


def test_python_dash_m_entry_point(tmp_path):
    """``python -m acousim force`` exists (an argument error exits before any solve)."""
    r = subprocess.run([sys.executable, "-m", "acousim", "force", "--mesh", str(tmp_path / "missing.stl"), "--z", "0"],
                       cwd=REPO, capture_output=True, text=True, timeout=600)
    assert r.returncode == 2 and r.stderr.strip().splitlines() == [f"error: --mesh {tmp_path / 'missing.stl'}: no such file"]


@pytest.mark.parametrize("device,reason", [
    ("opencl", "the OpenCL backend does not work here (the trial assembly failed (killed by signal 6)"),
    ("gpu", "choose numba, opencl or auto"),
])
def test_a_backend_that_cannot_be_used_is_one_line_and_exit_2(tmp_path, capsys, monkeypatch, device, reason):
    from acousim.fullwave import solver
    from acousim.fullwave.opencl_probe import OpenCLVerdict

    monkeypatch.setattr(solver, "_opencl_verdict",
                        lambda: OpenCLVerdict(False, "the trial assembly failed (killed by signal 6): no message", "k"))
    monkeypatch.setenv(solver.BEM_DEVICE_ENV, device)
    mesh, out = tmp_path / "pair.stl", tmp_path / "force.json"
    two_spheres(mesh)
    code, _, err = run_here(capsys, "--mesh", str(mesh), "--z", "0", "--out", str(out))
    assert code == 2 and err.count("\n") == 1 and reason in err and "Traceback" not in err
    assert not out.exists()
