"""Full-wave dimer: mirror symmetries, bend parity and the exact height structure.

These are identities of the geometry and of the linear algebra, true on any mesh, so they are checked on
the coarsest graded dimer mesh (``mesh_family(2)``, 264 DOFs); the physics of the hinge (convergence,
gap) is studied by ``python -m acousim convergence`` and stated in docs/fullwave.md."""
from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("bempp_cl")

from acousim.fullwave.geometry import (COARSE_SPEC, check_closed_oriented, cube_body_mesh,  # noqa: E402
                                       dimer_bodies, hinge_refined_spec, mesh_family)
from acousim.fullwave.opencl_probe import OpenCLVerdict  # noqa: E402
from acousim.fullwave.solver import Body, solve_scattering  # noqa: E402
from acousim.fullwave.force_surrogate import dimer_generalized_coefficients  # noqa: E402
from acousim.medium import Medium  # noqa: E402

THETA = 0.3
P0 = 3000.0
Z_TEST = (-0.4e-3, -0.9e-3, 0.25e-3)
SPEC = mesh_family(2.0)  # the coarsest graded mesh of the family: 132 vertices per cube


@pytest.fixture(scope="session")
def coarse_pair():
    """Solutions of the dimer at +THETA and -THETA (mirror-reduced) and at THETA without the reduction."""
    out = {t: solve_scattering(dimer_bodies(t, SPEC)) for t in (THETA, -THETA)}
    out["full"] = solve_scattering(dimer_bodies(THETA, SPEC), use_symmetry=False)
    return out


# bempp's quadrature is not itself mirror symmetric, so an unreduced solve is symmetric to the
# quadrature accuracy only (measured ~4e-4 of the largest component on the q = 1 mesh)
QUADRATURE_SYMMETRY = 2e-3


def test_meshes_closed_and_graded():
    v, f = cube_body_mesh(COARSE_SPEC)
    check_closed_oriented(v, f)
    for body in dimer_bodies(0.4, COARSE_SPEC):
        check_closed_oriented(body.vertices, body.faces)
    # graded: the smallest spacing across the hinge edge is h_hinge, far away it is coarser
    u = np.unique(np.round(v[:, 0] / COARSE_SPEC.side, 9))
    assert np.isclose(u[1] - u[0], COARSE_SPEC.h_hinge)
    assert np.max(np.diff(u)) > 3 * (u[1] - u[0])
    # the gap: hinge edges are g cos(phi) apart
    a, b = dimer_bodies(0.4, COARSE_SPEC)
    dmin = np.min(np.linalg.norm(a.vertices[:, None, :] - b.vertices[None, :, :], axis=2))
    assert np.isclose(dmin, COARSE_SPEC.gap * np.cos(np.pi * 0.4 / 4), rtol=1e-9)


@pytest.mark.parametrize("gap_fraction", [0.01, 0.004, 0.04])
def test_hinge_refined_mesh_resolves_the_gap(gap_fraction):
    """The hinge-refined mesh puts elements g/2 across the hinge edge (within [0.0025 s, 0.02 s]) and 0.03 s
    along it, for any gap; the default dimer's has 4,216 vertices, closed and oriented."""
    side = 500e-6
    spec = hinge_refined_spec(side=side, gap=gap_fraction * side)
    v, f = cube_body_mesh(spec)
    check_closed_oriented(v, f)
    u = np.unique(np.round(v[:, 0] / side, 9))
    assert np.isclose(u[1] - u[0], min(max(gap_fraction / 2, 0.0025), 0.02))
    w = np.unique(np.round(v[np.isclose(v[:, 0], v[:, 0].min()), 1] / side, 9))  # along the hinge line
    assert np.isclose(np.median(np.diff(w)), 0.03, rtol=0.05)
    if gap_fraction == 0.01:
        assert sum(len(b.vertices) for b in dimer_bodies(0.2, spec)) == 4216


@pytest.mark.parametrize("h_edge", [0.04, 0.01])
def test_edge_graded_mesh_resolves_every_edge(h_edge):
    """With ``h_edge`` every axis is graded to h_edge at both ends (all twelve edges), the hinge edge keeps its
    own finer size, the mesh stays closed, and its settings survive the round trip; without it the mesh is
    unchanged."""
    import dataclasses

    from acousim.fullwave.geometry import DimerMeshSpec

    spec = dataclasses.replace(COARSE_SPEC, h_edge=h_edge)
    v, f = cube_body_mesh(spec)
    check_closed_oriented(v, f)
    for axis in range(3):
        nodes = np.unique(np.round(v[:, axis] / spec.side, 9))
        first, last = nodes[1] - nodes[0], nodes[-1] - nodes[-2]
        hinge_end = {0: spec.h_hinge, 1: spec.h_corner, 2: spec.h_hinge}[axis]
        ends = sorted([first, last])
        assert np.isclose(ends[0], min(h_edge, hinge_end), rtol=1e-6)
        assert ends[1] <= h_edge * (1 + 1e-6)
    assert DimerMeshSpec.from_settings(spec.settings()) == spec
    assert "h_edge" not in COARSE_SPEC.settings()
    assert DimerMeshSpec.from_settings(COARSE_SPEC.settings()) == COARSE_SPEC


def test_mirror_symmetry_between_cubes(coarse_pair):
    """Cube A is the mirror image of B in X = 0: F_A = (-Fx, Fy, Fz)_B and tau_A = (tx, -ty, -tz)_B;
    the Y-mirror of the whole dimer kills F_Y, tau_X and tau_Z.  Checked on the unreduced solve (where
    nothing enforces it) to quadrature accuracy, and exactly on the mirror-reduced one."""
    for key, tol in (("full", QUADRATURE_SYMMETRY), (THETA, 1e-9)):
        hs = coarse_pair[key].height_structure(P0)
        for z in Z_TEST:
            f, t = hs.force(z), hs.torque(z)
            fs, ts = np.max(np.abs(f)), np.max(np.abs(t))
            np.testing.assert_allclose(f[0], f[1] * [-1, 1, 1], atol=tol * fs)
            np.testing.assert_allclose(t[0], t[1] * [1, -1, -1], atol=tol * ts)
            assert np.max(np.abs(f[:, 1])) < tol * fs
            assert np.max(np.abs(t[:, [0, 2]])) < tol * ts


def test_mirror_reduction_matches_full_solve(coarse_pair):
    """The quarter-size mirror-reduced system gives the unreduced answer (to quadrature accuracy)."""
    a = dimer_generalized_coefficients(coarse_pair[THETA].height_structure(P0))
    b = dimer_generalized_coefficients(coarse_pair["full"].height_structure(P0))
    for c in ("fz", "qt"):
        np.testing.assert_allclose(a[c], b[c], atol=5e-3 * np.max(np.abs(b[c])))


def test_bend_parity(coarse_pair):
    """The dimer at -theta is the Z-mirror of the one at theta, and sin(kZ) is odd about the node:
    F_Z(-theta, -Z) = -F_Z(theta, Z), Q_theta(-theta, -Z) = -Q_theta(theta, Z)."""
    gp = dimer_generalized_coefficients(coarse_pair[THETA].height_structure(P0))
    gm = dimer_generalized_coefficients(coarse_pair[-THETA].height_structure(P0))
    for c in ("fz", "qt"):
        scale = np.max(np.abs(gp[c]))
        np.testing.assert_allclose(gm[c], gp[c] * [-1, -1, 1], atol=QUADRATURE_SYMMETRY * scale)


def test_height_structure_against_direct_solves(coarse_pair):
    """A + B cos(2kZ) + C sin(2kZ) from the COM-centred solve equals a direct solve with the dimer
    placed at Z in absolute coordinates (incident field sin(kZ) itself)."""
    hs = coarse_pair[THETA].height_structure(P0)
    for z in (-0.7e-3, 0.4e-3):
        bodies = [Body(b.vertices + [0, 0, z], b.faces, b.centre + [0, 0, z]) for b in dimer_bodies(THETA, SPEC)]
        direct = solve_scattering(bodies)
        f, t = direct.forces_at(0.0, P0)
        np.testing.assert_allclose(f, hs.force(z), rtol=0, atol=1e-7 * np.max(np.abs(f)))
        np.testing.assert_allclose(t, hs.torque(z), rtol=0, atol=1e-7 * np.max(np.abs(t)))


def test_opencl_and_numba_backends_solve_the_same_field(monkeypatch):
    """bempp-cl's two backends (auto picks OpenCL when a CPU device exists) give the same surface field: the same
    Galerkin matrix to rounding (1e-10 relative: the LU of a well-conditioned Burton-Miller matrix amplifies the
    ~1e-15 assembly differences by its condition number, far below that)."""
    from acousim.fullwave import solver

    verdict = solver._opencl_verdict()  # a trial assembly in a child process: a broken driver cannot crash this one
    if not verdict.works:
        pytest.skip(f"the OpenCL backend does not work here: {verdict.reason}")
    out = {}
    for device in ("numba", "opencl"):
        monkeypatch.setenv(solver.BEM_DEVICE_ENV, device)
        out[device] = solve_scattering(dimer_bodies(THETA, SPEC))
        assert out[device].timings["device"] == device
    for name in ("p_cos", "p_sin"):
        a, b = getattr(out["numba"], name), getattr(out["opencl"], name)
        np.testing.assert_allclose(b, a, rtol=0, atol=1e-10 * np.abs(a).max())


def test_one_numba_thread_compiles_the_assembly_kernels_serially(coarse_pair, monkeypatch):
    """With one numba thread (``make test``'s NUMBA_NUM_THREADS=1) bempp-cl's parallel assembly kernels are compiled
    as plain loops, which saves a third of their compilation (57 s -> 37 s of CPU on one core) and gives the same
    matrix bit for bit (measured: p_cos and p_sin of the coarse dimer, reduced and unreduced, identical); with more
    threads they stay parallel.  The switch touches only kernels not yet compiled."""
    import sys
    from types import SimpleNamespace

    import numba
    from bempp_cl.core import numba_kernels

    from acousim.fullwave import solver

    assembly = ("default_sparse_kernel", "default_scalar_regular_kernel", "helmholtz_hypersingular_regular",
                "default_scalar_singular_kernel", "helmholtz_hypersingular_singular")  # all parallel in bempp-cl
    kernels = [getattr(numba_kernels, name) for name in assembly]
    assert all(k.overloads for k in kernels)  # the Burton-Miller solves of the fixture compiled every one
    single = numba.config.NUMBA_NUM_THREADS == 1
    assert [k.targetoptions["parallel"] for k in kernels] == [not single] * len(kernels)

    def kernel(parallel: bool, compiled: bool = False) -> SimpleNamespace:
        return SimpleNamespace(targetoptions={"parallel": parallel}, overloads={"signature": 1} if compiled else {})

    fake = {"parallel": kernel(True), "serial": kernel(False), "compiled": kernel(True, compiled=True)}
    monkeypatch.setitem(sys.modules, "bempp_cl.core.numba_kernels", SimpleNamespace(**fake))
    monkeypatch.setattr(sys.modules["bempp_cl.core"], "numba_kernels", SimpleNamespace(**fake))
    try:
        for threads, switched in ((4, 0), (1, 1)):
            monkeypatch.setattr(numba.config, "NUMBA_NUM_THREADS", threads)
            solver.serial_kernels_when_single_threaded.cache_clear()
            assert solver.serial_kernels_when_single_threaded() == switched
    finally:
        solver.serial_kernels_when_single_threaded.cache_clear()
    assert {name: k.targetoptions["parallel"] for name, k in fake.items()} == \
        {"parallel": False, "serial": False, "compiled": True}


@pytest.mark.parametrize("value,expected", [("numba", "numba"), ("NUMBA", "numba")])
def test_assembly_device_honours_the_environment(monkeypatch, value, expected):
    from acousim.fullwave import solver

    monkeypatch.setenv(solver.BEM_DEVICE_ENV, value)
    assert solver.assembly_device() == expected


def test_assembly_device_refuses_what_it_cannot_do(monkeypatch):
    from acousim.fullwave import solver

    monkeypatch.setenv(solver.BEM_DEVICE_ENV, "gpu")
    with pytest.raises(solver.AssemblyBackendError, match="choose numba, opencl or auto"):
        solver.assembly_device()
    monkeypatch.setattr(solver, "_opencl_verdict", lambda: OpenCLVerdict(False, "pyopencl finds no OpenCL CPU device", "k"))
    monkeypatch.setenv(solver.BEM_DEVICE_ENV, "opencl")
    with pytest.raises(solver.AssemblyBackendError, match="does not work here .pyopencl finds no OpenCL CPU device"):
        solver.assembly_device()
    monkeypatch.setenv(solver.BEM_DEVICE_ENV, "auto")
    assert solver.assembly_device() == "numba"


def _bempp_without_opencl(monkeypatch):
    """bempp-cl as the solver sees it, except that the OpenCL kernels fail to build (as with a broken driver)."""
    from types import SimpleNamespace

    from acousim.fullwave import solver

    real = solver.import_bempp()

    def failing_on_opencl(operator):
        def build(*args, device_interface="numba", **kwargs):
            if device_interface == "opencl":
                raise RuntimeError("clBuildProgram failed")
            return operator(*args, device_interface=device_interface, **kwargs)
        return build

    h = real.operators.boundary.helmholtz
    helmholtz = SimpleNamespace(double_layer=failing_on_opencl(h.double_layer),
                                hypersingular=failing_on_opencl(h.hypersingular))
    fake = SimpleNamespace(Grid=real.Grid, function_space=real.function_space,
                           operators=SimpleNamespace(boundary=SimpleNamespace(sparse=real.operators.boundary.sparse,
                                                                              helmholtz=helmholtz)))
    monkeypatch.setattr(solver, "import_bempp", lambda: fake)
    monkeypatch.setattr(solver, "_opencl_verdict", lambda: OpenCLVerdict(True, "trial assembly ran", "k"))
    monkeypatch.setattr(solver, "_OPENCL_FAILED", False)


def test_failed_opencl_assembly_falls_back_to_numba_under_auto(monkeypatch, caplog, coarse_pair):
    """Under ``auto`` an OpenCL assembly that fails is redone on numba, with a warning, and the solution records
    the backend it was really assembled on; the field is numba's (the same operations: equal to rounding)."""
    from acousim.fullwave import solver

    _bempp_without_opencl(monkeypatch)
    monkeypatch.setenv(solver.BEM_DEVICE_ENV, "auto")
    with caplog.at_level("WARNING", logger=solver.__name__):
        sol = solve_scattering(dimer_bodies(THETA, SPEC))
    assert sol.timings["device"] == "numba"
    assert "OpenCL assembly failed" in caplog.text and solver._OPENCL_FAILED
    ref = coarse_pair[THETA]  # solved on numba (tests/conftest.py sets the backend)
    for name in ("p_cos", "p_sin"):
        a = getattr(ref, name)
        np.testing.assert_allclose(getattr(sol, name), a, rtol=0, atol=1e-12 * np.abs(a).max())


def test_failed_opencl_assembly_is_an_error_when_opencl_was_asked_for(monkeypatch):
    """``CUBEDIMER_BEM_DEVICE=opencl`` means OpenCL or nothing: the failure is raised, not hidden by a fallback."""
    from acousim.fullwave import solver

    _bempp_without_opencl(monkeypatch)
    monkeypatch.setenv(solver.BEM_DEVICE_ENV, "opencl")
    with pytest.raises(RuntimeError, match="clBuildProgram failed"):
        solve_scattering(dimer_bodies(THETA, SPEC))
    assert not solver._OPENCL_FAILED


def test_a_driver_that_aborts_the_trial_assembly_means_numba_with_the_same_field(monkeypatch, coarse_pair):
    """A driver whose kernel compilation aborts the process (as pocl's LLVM does on some processors) is found out
    by the trial assembly in a child process: under ``auto`` the solve then runs on numba, in this process, and
    gives numba's field; nothing is raised and this process survives."""
    from acousim.fullwave import opencl_probe, solver

    aborting_driver = "import os; os.abort()"  # what the child does when the driver's compiler aborts
    monkeypatch.setattr(opencl_probe, "_opencl_device_found", lambda: True)
    real_probe = opencl_probe.run_probe
    monkeypatch.setattr(opencl_probe, "run_probe", lambda: real_probe(aborting_driver))
    monkeypatch.setattr(solver, "_opencl_verdict", opencl_probe.opencl_verdict)
    monkeypatch.setenv(solver.BEM_DEVICE_ENV, "auto")
    verdict = opencl_probe.opencl_verdict(refresh=True)
    assert not verdict.works and "signal 6" in verdict.reason
    sol = solve_scattering(dimer_bodies(THETA, SPEC))
    assert sol.timings["device"] == "numba"
    ref = coarse_pair[THETA]
    for name in ("p_cos", "p_sin"):
        a = getattr(ref, name)
        np.testing.assert_allclose(getattr(sol, name), a, rtol=0, atol=1e-12 * np.abs(a).max())  # same arithmetic
