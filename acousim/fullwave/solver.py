"""Sound-hard boundary-element scattering of the standing wave and the radiation force (docs/conventions.md section 7).

Method
------
The total pressure ``p`` (complex amplitude, time factor ``exp(-i w t)``) on the surface ``S`` of a set
of rigid, immobile, closed bodies solves the exterior Helmholtz problem with ``dp/dn = 0`` on ``S``.
With bempp-cl's double-layer operator ``D`` and hypersingular operator ``W`` (``W = -d/dn D``), the
Burton-Miller boundary integral equation of the second kind reads::

    (I/2 - D - (i/k) W) p = p_in - (i/k) dp_in/dn        on S

discretised with continuous piecewise-linear (P1) elements and Galerkin testing, assembled densely
and LU-factorised once.  The dense assembly runs on bempp-cl's OpenCL backend when an OpenCL CPU driver is
installed (``pip install cubedimer[opencl]``: pyopencl and pocl), otherwise on its numba backend; both give the
same matrix to rounding (:func:`assembly_device`).

Exact height structure
----------------------
The geometry is given in local coordinates ``r'`` around a reference point that sits at the lab
height ``Z_ref`` above the pressure node.  There ``p_in = p0 [sin(k Z_ref) cos(k z') + cos(k Z_ref) sin(k z')]``,
so the surface field is ``p = p0 [sin(k Z_ref) p_c + cos(k Z_ref) p_s]`` with ``p_c``, ``p_s`` the
solutions for the incident fields ``cos(k z')`` and ``sin(k z')`` (two right-hand sides, one
factorisation).  Forces are quadratic in ``p``; with ``F[p, q]`` the symmetric bilinear form of the
force, every force and torque component is::

    F(Z_ref) = A + B cos(2 k Z_ref) + C sin(2 k Z_ref),
    A = p0^2 (F[c,c] + F[s,s]) / 2,  B = p0^2 (F[s,s] - F[c,c]) / 2,  C = p0^2 F[c,s]

Force and torque
----------------
On each body (outward normal ``n``, time-averaged quantities)::

    F   = - int [ |p|^2 / (4 rho0 c0^2) - rho0 |v|^2 / 4 ] n dS
    tau = - int (r - c) x n [ same bracket ] dS,     v = grad p / (i w rho0)

with ``v`` tangential on a sound-hard surface: the surface gradient of the P1 pressure (constant per
triangle).  ``|p|^2`` and the lever arm are integrated with a 6-point, degree-4 triangle rule.
"""
from __future__ import annotations

import functools
import logging
import os
import time
import warnings
from dataclasses import dataclass, field
from typing import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.linalg import lu_factor, lu_solve

from ..medium import Medium

__all__ = [
    "Body",
    "HeightStructure",
    "ScatteringSolution",
    "solve_scattering",
    "assembly_device",
    "AssemblyBackendError",
    "BEM_DEVICE_ENV",
    "surface_force_density",
    "triangle_rule",
]

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class Body:
    """One closed, outward-oriented triangulated body in local coordinates.

    Parameters
    ----------
    vertices : ndarray (n, 3)
        Vertex coordinates [m] relative to the reference point of the problem.
    faces : ndarray (m, 3)
        Triangles (vertex indices), counter-clockwise seen from outside.
    centre : ndarray (3,)
        Point [m] the torque is taken about (e.g. the volume centroid).
    """

    vertices: NDArray[np.float64]
    faces: NDArray[np.int64]
    centre: NDArray[np.float64]

    def __post_init__(self) -> None:
        v = np.ascontiguousarray(self.vertices, float)
        f = np.ascontiguousarray(self.faces, np.int64)
        c = np.asarray(self.centre, float).reshape(3)
        if v.ndim != 2 or v.shape[1] != 3 or f.ndim != 2 or f.shape[1] != 3:
            raise ValueError("a body needs vertices (n, 3) and faces (m, 3)")
        if f.size and (f.min() < 0 or f.max() >= len(v)):
            raise ValueError("face indices out of range")
        object.__setattr__(self, "vertices", v)
        object.__setattr__(self, "faces", f)
        object.__setattr__(self, "centre", c)


def triangle_rule() -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Symmetric 6-point triangle quadrature, exact for polynomials of degree 4.

    Returns
    -------
    bary : ndarray (6, 3)
        Barycentric coordinates of the nodes.
    weights : ndarray (6,)
        Weights summing to 1 (multiply by the triangle area).
    """
    a1, w1 = 0.445948490915965, 0.223381589678011
    a2, w2 = 0.091576213509771, 0.109951743655322
    b1, b2 = 1.0 - 2.0 * a1, 1.0 - 2.0 * a2
    bary = np.array([[a1, a1, b1], [a1, b1, a1], [b1, a1, a1], [a2, a2, b2], [a2, b2, a2], [b2, a2, a2]])
    weights = np.array([w1, w1, w1, w2, w2, w2])
    return bary, weights


@dataclass(frozen=True)
class HeightStructure:
    """Force and torque of every body as ``A + B cos(2 k Z) + C sin(2 k Z)``.

    Attributes
    ----------
    force_a, force_b, force_c : ndarray (n_bodies, 3)
        Coefficients of the force [N].
    torque_a, torque_b, torque_c : ndarray (n_bodies, 3)
        Coefficients of the torque about each body's ``centre`` [N m].
    two_k : float
        2k [1/m].
    pressure_amplitude_pa : float
        p0 [Pa] the coefficients belong to (they scale as p0^2).
    centres : ndarray (n_bodies, 3)
        The torque reference points in local coordinates [m].
    """

    force_a: NDArray[np.float64]
    force_b: NDArray[np.float64]
    force_c: NDArray[np.float64]
    torque_a: NDArray[np.float64]
    torque_b: NDArray[np.float64]
    torque_c: NDArray[np.float64]
    two_k: float
    pressure_amplitude_pa: float
    centres: NDArray[np.float64]

    def force(self, z_ref: ArrayLike) -> NDArray[np.float64]:
        """Forces [N], shape ``z_ref.shape + (n_bodies, 3)``, with the reference point at height ``z_ref`` [m]."""
        return self._eval(self.force_a, self.force_b, self.force_c, z_ref)

    def torque(self, z_ref: ArrayLike) -> NDArray[np.float64]:
        """Torques [N m] about each body's centre, shape ``z_ref.shape + (n_bodies, 3)``."""
        return self._eval(self.torque_a, self.torque_b, self.torque_c, z_ref)

    def _eval(self, a: NDArray, b: NDArray, c: NDArray, z_ref: ArrayLike) -> NDArray[np.float64]:
        z = np.asarray(z_ref, float)[..., None, None]
        return a + b * np.cos(self.two_k * z) + c * np.sin(self.two_k * z)

    def with_pressure(self, pressure_amplitude_pa: float) -> "HeightStructure":
        """The same coefficients at another pressure amplitude (exact p0^2 scaling)."""
        r = (float(pressure_amplitude_pa) / self.pressure_amplitude_pa) ** 2
        return HeightStructure(
            r * self.force_a, r * self.force_b, r * self.force_c, r * self.torque_a, r * self.torque_b,
            r * self.torque_c, self.two_k, float(pressure_amplitude_pa), self.centres,
        )


@dataclass(frozen=True)
class ScatteringSolution:
    """Surface pressures of the two incident parts and everything needed to post-process them.

    Attributes
    ----------
    vertices : ndarray (n, 3)
        All vertices [m] (local coordinates); the P1 degrees of freedom.
    faces : ndarray (m, 3)
        All triangles.
    body_of_face : ndarray (m,)
        Index of the body each triangle belongs to.
    p_cos, p_sin : ndarray (n,) complex
        Total surface pressure per unit p0 for the incident fields ``cos(k z')`` and ``sin(k z')``.
    medium : Medium
    bodies : tuple of Body
    timings : dict
        Wall times [s] of assembly and solve.
    """

    vertices: NDArray[np.float64]
    faces: NDArray[np.int64]
    body_of_face: NDArray[np.int64]
    p_cos: NDArray[np.complex128]
    p_sin: NDArray[np.complex128]
    medium: Medium
    bodies: tuple
    space: object = field(repr=False, compare=False, default=None)
    timings: dict = field(default_factory=dict, compare=False)

    @property
    def n_dofs(self) -> int:
        """Number of P1 degrees of freedom."""
        return int(len(self.vertices))

    def surface_pressure(self, z_ref: float, pressure_amplitude_pa: float = 1.0) -> NDArray[np.complex128]:
        """Total surface pressure [Pa] at the vertices with the reference point at height ``z_ref`` [m]."""
        k = self.medium.wavenumber
        return pressure_amplitude_pa * (np.sin(k * z_ref) * self.p_cos + np.cos(k * z_ref) * self.p_sin)

    def height_structure(self, pressure_amplitude_pa: float = 1.0) -> HeightStructure:
        """A, B, C of every body's force and torque at ``pressure_amplitude_pa`` [Pa]."""
        fcc, tcc = self._bilinear(self.p_cos, self.p_cos)
        fss, tss = self._bilinear(self.p_sin, self.p_sin)
        fcs, tcs = self._bilinear(self.p_cos, self.p_sin)
        p2 = float(pressure_amplitude_pa) ** 2
        centres = np.array([b.centre for b in self.bodies])
        return HeightStructure(
            force_a=p2 * 0.5 * (fcc + fss), force_b=p2 * 0.5 * (fss - fcc), force_c=p2 * fcs,
            torque_a=p2 * 0.5 * (tcc + tss), torque_b=p2 * 0.5 * (tss - tcc), torque_c=p2 * tcs,
            two_k=2.0 * self.medium.wavenumber, pressure_amplitude_pa=float(pressure_amplitude_pa), centres=centres,
        )

    def forces_at(self, z_ref: float, pressure_amplitude_pa: float = 1.0) -> tuple[NDArray, NDArray]:
        """(forces [N], torques [N m]) per body, (n_bodies, 3) each, by direct post-processing at one height."""
        p = self.surface_pressure(z_ref, pressure_amplitude_pa)
        return self._bilinear(p, p)

    def _bilinear(self, p: NDArray, q: NDArray) -> tuple[NDArray, NDArray]:
        dens, pts, w_area, normals = surface_force_density(self.vertices, self.faces, p, q, self.medium)
        nb = len(self.bodies)
        forces = np.zeros((nb, 3))
        torques = np.zeros((nb, 3))
        # traction t = -dens * n per quadrature node
        trac = -(dens[:, :, None] * normals[:, None, :])  # (m, q, 3)
        for b, body in enumerate(self.bodies):
            sel = self.body_of_face == b
            wq = w_area[sel]
            forces[b] = np.einsum("mq,mqk->k", wq, trac[sel])
            lever = pts[sel] - body.centre
            torques[b] = np.einsum("mq,mqk->k", wq, np.cross(lever, trac[sel]))
        return forces, torques


def surface_force_density(
    vertices: NDArray, faces: NDArray, p: NDArray, q: NDArray, medium: Medium
) -> tuple[NDArray, NDArray, NDArray, NDArray]:
    """The symmetric bilinear radiation-stress density ``Re[p q*]/(4 rho0 c0^2) - rho0 Re[v_p . v_q*]/4``.

    Parameters
    ----------
    vertices, faces : ndarray
        The triangulation [m].
    p, q : ndarray (n,) complex
        P1 nodal pressures [Pa].
    medium : Medium

    Returns
    -------
    dens : ndarray (m, 6)
        Density [Pa] at the quadrature nodes of every triangle.
    points : ndarray (m, 6, 3)
        Quadrature nodes [m].
    weights : ndarray (m, 6)
        Quadrature weights times triangle areas [m^2].
    normals : ndarray (m, 3)
        Unit normals from the triangle orientation.
    """
    rho0, c0 = medium.density_kg_m3, medium.sound_speed_m_s
    omega = 2.0 * np.pi * medium.frequency_hz
    x = vertices[faces]  # (m, 3, 3)
    e1, e2 = x[:, 1] - x[:, 0], x[:, 2] - x[:, 0]
    cr = np.cross(e1, e2)
    two_area = np.linalg.norm(cr, axis=1)
    normals = cr / two_area[:, None]
    bary, w = triangle_rule()
    points = np.einsum("qj,mjk->mqk", bary, x)
    pv, qv = p[faces], q[faces]  # (m, 3)
    pq = np.einsum("qj,mj->mq", bary, pv) * np.conj(np.einsum("qj,mj->mq", bary, qv))
    # surface gradient of a P1 function: J (J^T J)^-1 [f1 - f0, f2 - f0]
    g11, g12, g22 = (e1 * e1).sum(1), (e1 * e2).sum(1), (e2 * e2).sum(1)
    det = g11 * g22 - g12**2

    def grad(f: NDArray) -> NDArray:
        d1, d2 = f[:, 1] - f[:, 0], f[:, 2] - f[:, 0]
        a = (g22 * d1 - g12 * d2) / det
        b = (-g12 * d1 + g11 * d2) / det
        return a[:, None] * e1 + b[:, None] * e2

    gp, gq = grad(pv), grad(qv)
    vv = np.real(np.sum(gp * np.conj(gq), axis=1)) / (omega * rho0) ** 2  # Re[v_p . v_q*]
    dens = np.real(pq) / (4 * rho0 * c0**2) - rho0 * vv[:, None] / 4
    weights = 0.5 * two_area[:, None] * w[None, :]
    return dens, points, weights, normals


def _rhs(space_vertices: NDArray, faces: NDArray, k: float) -> NDArray[np.complex128]:
    """Galerkin right-hand sides ``int phi_i (p_in - (i/k) dp_in/dn) dS`` for p_in = cos(kz), sin(kz); (n, 2)."""
    x = space_vertices[faces]
    cr = np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0])
    two_area = np.linalg.norm(cr, axis=1)
    nz = cr[:, 2] / two_area
    bary, w = triangle_rule()
    z = np.einsum("qj,mj->mq", bary, x[:, :, 2])
    g_cos = np.cos(k * z) - (1j / k) * (-k * np.sin(k * z)) * nz[:, None]
    g_sin = np.sin(k * z) - (1j / k) * (k * np.cos(k * z)) * nz[:, None]
    out = np.zeros((len(space_vertices), 2), complex)
    for col, g in enumerate((g_cos, g_sin)):
        # (m, q) values times weights, distributed to the three vertices by the barycentric basis
        contrib = np.einsum("mq,q,qj->mj", g, w, bary) * (0.5 * two_area)[:, None]
        np.add.at(out[:, col], faces.ravel(), contrib.ravel())
    return out


#: Environment variable choosing the dense assembly's backend: ``numba``, ``opencl`` or ``auto`` (the default:
#: OpenCL when its trial assembly works here, :mod:`acousim.fullwave.opencl_probe`, else numba).
BEM_DEVICE_ENV = "CUBEDIMER_BEM_DEVICE"


class AssemblyBackendError(RuntimeError):
    """The backend named in :data:`BEM_DEVICE_ENV` cannot be used here (one line: why, and what to set instead)."""


_OPENCL_FAILED = False  # set when an OpenCL assembly failed in this process


@functools.lru_cache(maxsize=1)
def _opencl_verdict():
    from .opencl_probe import opencl_verdict

    return opencl_verdict()


def assembly_device() -> str:
    """The bempp-cl backend of the dense assembly: ``"opencl"`` or ``"numba"``, from :data:`BEM_DEVICE_ENV`.

    ``auto`` (the default) takes OpenCL only when a trial assembly on the OpenCL device has run in a child process
    (:func:`acousim.fullwave.opencl_probe.opencl_verdict`, cached per environment: a driver that aborts or fails
    is treated as absent), numba otherwise.  ``opencl`` asks for OpenCL or nothing.  Both backends assemble the
    same matrices to rounding (a test compares them where the probe succeeds); OpenCL is about twice as fast on
    one core (``make bench``).  Set ``POCL_MAX_PTHREAD_COUNT=1`` when several solves run side by side, as
    numba's ``NUMBA_NUM_THREADS=1``.

    Raises
    ------
    AssemblyBackendError
        An unknown value, or ``opencl`` where the trial assembly does not work (one line, with the reason).
    """
    choice = os.environ.get(BEM_DEVICE_ENV, "auto").strip().lower() or "auto"
    if choice not in ("auto", "numba", "opencl"):
        raise AssemblyBackendError(f"{BEM_DEVICE_ENV}={choice!r}: choose numba, opencl or auto")
    if choice == "numba":
        return "numba"
    verdict = _opencl_verdict()
    if choice == "opencl" and not verdict.works:
        raise AssemblyBackendError(f"{BEM_DEVICE_ENV}=opencl, but the OpenCL backend does not work here "
                                   f"({verdict.reason}); install a working driver (pip install pyopencl "
                                   f"pocl-binary-distribution), or set {BEM_DEVICE_ENV}=numba or auto")
    return "opencl" if verdict.works else "numba"


def import_bempp():
    """``bempp_cl.api``, imported with its start-up notice (printed to stdout) sent to the log instead, and with its
    numba kernels compiled serially when numba has a single thread (:func:`serial_kernels_when_single_threaded`)."""
    import contextlib
    import io

    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        import bempp_cl.api as bempp
    if buf.getvalue().strip():
        log.debug("bempp-cl: %s", buf.getvalue().strip())
    serial_kernels_when_single_threaded()
    return bempp


@functools.lru_cache(maxsize=1)
def serial_kernels_when_single_threaded() -> int:
    """Compile bempp-cl's numba-parallel assembly kernels as plain loops when numba has one thread
    (``NUMBA_NUM_THREADS=1``, as ``make test`` and side-by-side solves run); returns how many were switched.

    With one thread the parallel loops run serially anyway, so the result is the same matrix (a test compares the
    two bit for bit), but their parallel compilation costs about 20 s of the 57 s that bempp-cl's kernels take to
    compile at the first assembly of every process (one core).  With several threads nothing changes.  Kernels
    already compiled are left as they are."""
    import numba

    if numba.config.NUMBA_NUM_THREADS != 1:
        return 0
    from bempp_cl.core import numba_kernels

    switched = 0
    for value in vars(numba_kernels).values():
        options = getattr(value, "targetoptions", None)
        if isinstance(options, dict) and options.get("parallel") and not getattr(value, "overloads", True):
            options["parallel"] = False
            switched += 1
    return switched


def mirror_maps(vertices: NDArray, faces: NDArray, rtol: float = 1e-9) -> dict[str, NDArray[np.int64]]:
    """Vertex permutations of the mirrors X -> -X and Y -> -Y that map the triangulation onto itself.

    Returns
    -------
    dict
        ``{"x": perm, "y": perm}`` for each mirror under which the vertex set and the triangle set are
        invariant (``vertices[perm[i]]`` is the mirror image of ``vertices[i]``).
    """
    from scipy.spatial import cKDTree

    scale = float(np.max(np.ptp(vertices, axis=0)))
    tree = cKDTree(vertices)
    face_set = {tuple(sorted(f)) for f in faces.tolist()}
    out = {}
    for name, axis in (("x", 0), ("y", 1)):
        mirrored = vertices.copy()
        mirrored[:, axis] *= -1
        dist, perm = tree.query(mirrored)
        if np.max(dist) > rtol * scale or len(np.unique(perm)) != len(perm):
            continue
        if all(tuple(sorted(perm[f])) in face_set for f in faces.tolist()):
            out[name] = perm.astype(np.int64)
    return out


def _burton_miller_matrix(bempp, space, test_space, k: float) -> tuple[NDArray[np.complex128], str]:
    """The dense Galerkin matrix of ``I/2 - D - (i/k) W`` (trial ``space``, test ``test_space``) on the backend of
    :func:`assembly_device`, and the backend it was assembled on; under ``auto``, an OpenCL failure (a driver that
    cannot build the kernels) falls back to numba with a warning, for the rest of the process."""
    global _OPENCL_FAILED
    device = "numba" if _OPENCL_FAILED else assembly_device()
    while True:
        opts = dict(assembler="dense", device_interface=device)
        try:
            ident = bempp.operators.boundary.sparse.identity(space, space, test_space)
            dlp = bempp.operators.boundary.helmholtz.double_layer(space, space, test_space, k, **opts)
            hyp = bempp.operators.boundary.helmholtz.hypersingular(space, space, test_space, k, **opts)
            with warnings.catch_warnings():  # pocl's compiler notes on bempp's kernels, harmless
                warnings.filterwarnings("ignore", message="Non-empty compiler output")
                return (0.5 * ident - dlp - (1j / k) * hyp).weak_form().to_dense(), device
        except Exception as exc:
            if device != "opencl" or os.environ.get(BEM_DEVICE_ENV, "").strip().lower() == "opencl":
                raise
            log.warning("OpenCL assembly failed (%s: %s); assembling on numba instead", type(exc).__name__, exc)
            _OPENCL_FAILED, device = True, "numba"


def _symmetric_matrix(bempp, grid, space, vertices: NDArray, faces: NDArray, k: float, maps: dict) -> tuple | None:
    """Assemble only the rows of the representative vertices (X >= 0, Y >= 0 for the mirrors in ``maps``) and
    fold the columns over each vertex orbit.  Returns (reduced matrix, representatives, orbit matrix, backend) or None
    when the mesh does not conform to the mirror planes."""
    n = len(vertices)
    tol = 1e-9 * float(np.max(np.ptp(vertices, axis=0)))
    region = np.ones(n, bool)
    for name, axis in (("x", 0), ("y", 1)):
        if name in maps:
            region &= vertices[:, axis] >= -tol
    support = np.flatnonzero(region[faces].all(axis=1))
    reps = np.flatnonzero(region)
    if not np.array_equal(np.unique(faces[support]), reps):
        return None
    # orbit of every vertex -> its representative
    group = [np.arange(n)]
    for perm in maps.values():
        group += [perm[g] for g in group]
    rep_of = np.full(n, -1, np.int64)
    rep_index = -np.ones(n, np.int64)
    rep_index[reps] = np.arange(reps.size)
    for g in group:
        hit = region[g] & (rep_of < 0)
        rep_of[hit] = g[hit]
    # g maps i to g[i]; rep_of[i] is the member of i's orbit in the region
    if np.any(rep_of < 0):
        return None
    fold = np.zeros((n, reps.size))
    fold[np.arange(n), rep_index[rep_of]] = 1.0
    dual = bempp.function_space(grid, "P", 1, support_elements=support, include_boundary_dofs=True,
                                truncate_at_segment_edge=False)
    # dof -> vertex map of the restricted test space
    l2g = np.asarray(dual.local2global)
    sup = np.asarray(dual.support_elements)
    dof_vertex = -np.ones(dual.global_dof_count, np.int64)
    used = np.asarray(dual.local_multipliers)[sup] != 0
    dof_vertex[l2g[sup][used]] = faces[sup][used]
    if np.any(dof_vertex < 0) or not np.array_equal(np.sort(dof_vertex), reps):
        return None
    rows, device = _burton_miller_matrix(bempp, space, dual, k)  # (n_dofs_dual, n)
    order = np.argsort(rep_index[dof_vertex])
    return rows[order] @ fold, reps, fold, device


def solve_scattering(bodies: Sequence[Body], medium: Medium = Medium(), use_symmetry: bool = True) -> ScatteringSolution:
    """Solve the sound-hard scattering of ``cos(k z')`` and ``sin(k z')`` by ``bodies`` (one LU factorisation).

    Parameters
    ----------
    bodies : sequence of Body
        Closed, outward-oriented surfaces in local coordinates [m] (the reference point is z' = 0).
    medium : Medium
        Frequency, sound speed and density.
    use_symmetry : bool
        When the triangulation is mirror symmetric in X = 0 and/or Y = 0 (as the dimer meshes are), the
        incident field is too, so the solution is: assemble only the rows of the vertices with X, Y >= 0
        and fold the columns over the mirror images (a quarter of the dense assembly for both mirrors).

    Returns
    -------
    ScatteringSolution
        Use :meth:`ScatteringSolution.height_structure` for forces and torques at every height.
    """
    bempp = import_bempp()  # imported here: the import is slow and prints a Gmsh notice

    k = medium.wavenumber
    offsets = np.cumsum([0] + [len(b.vertices) for b in bodies])
    vertices = np.concatenate([b.vertices for b in bodies])
    faces = np.concatenate([b.faces + o for b, o in zip(bodies, offsets[:-1])])
    body_of_face = np.concatenate([np.full(len(b.faces), i) for i, b in enumerate(bodies)])
    t0 = time.perf_counter()
    grid = bempp.Grid(vertices.T.copy(), faces.T.astype(np.uint32).copy())
    space = bempp.function_space(grid, "P", 1)
    gv = np.asarray(grid.vertices).T
    ge = np.asarray(grid.elements).T.astype(np.int64)
    if gv.shape != vertices.shape or not np.array_equal(ge, faces) or not np.array_equal(space.local2global, ge):
        raise RuntimeError("bempp reordered the grid; the P1 degrees of freedom no longer match the vertices")
    rhs = _rhs(vertices, faces, k)
    maps = mirror_maps(vertices, faces) if use_symmetry else {}
    reduced = _symmetric_matrix(bempp, grid, space, vertices, faces, k, maps) if maps else None
    if reduced is not None:
        matrix, reps, fold, device = reduced
        t1 = time.perf_counter()
        sol = fold @ lu_solve(lu_factor(matrix, check_finite=False), rhs[reps], check_finite=False)
        sym = "".join(sorted(maps))
    else:
        matrix, device = _burton_miller_matrix(bempp, space, space, k)
        t1 = time.perf_counter()
        sol = lu_solve(lu_factor(matrix, check_finite=False), rhs, check_finite=False)
        sym = ""
    t2 = time.perf_counter()
    log.info("full-wave solve: %d DOFs (mirror symmetry: %s), assembly %.1f s (%s), LU + 2 solves %.2f s",
             len(vertices), sym or "none", t1 - t0, device, t2 - t1)
    return ScatteringSolution(
        vertices=vertices, faces=faces, body_of_face=body_of_face, p_cos=sol[:, 0], p_sin=sol[:, 1],
        medium=medium, bodies=tuple(bodies), space=space, timings={"assembly_s": t1 - t0, "solve_s": t2 - t1, "symmetry": sym,
                                                          "device": device},
    )
