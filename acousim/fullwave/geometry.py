"""Surface meshes for the full-wave model: the posed, gapped, graded cube dimer and arbitrary user meshes.

Dimer (docs/conventions.md sections 2 and 7).  Each cube is meshed once in its body frame
``(u, v, w) in [-s/2, s/2]^3`` with the hinge edge at ``u = -s/2, w = +s/2`` (parallel to v, the hinge
line).  The faces are tensor-product grids of three one-dimensional node sets:

* along u and w: graded geometrically from ``h_hinge`` at the hinge-edge end to ``h_max``;
* along v (the hinge line): ``h_along``, refined to ``h_corner`` at both ends (the hinge-edge corners);
* with ``h_edge`` set, every node set is also graded from ``h_edge`` at both of its ends, so that all twelve edges
  of the cube are resolved, not only the hinge edge (the field is singular at every edge of a sharp cube; the
  hinge stiffness converges monotonically only on such meshes, docs/fullwave.md);
* with an edge radius ``r_e > 0`` the u and w node sets are also refined to ``r_e pi / 8`` within ``r_e`` of
  the hinge edge, and the cube surface is mapped onto the rounded cube by the closest-point map of the
  inner box.  The arcs of the other edges are resolved only by the local element size (they matter far
  less than the hinge edge, and refining all twelve would multiply the cost of the tensor-product faces).

Long, thin triangles along the hinge are deliberate: the wedge field varies fast across the hinge edge
and slowly along it.  Cube B (X > 0) is the body mesh rotated by ``psi_B = pi/4 - phi`` (counter-clockwise
in the (X, Z) plane, phi = pi theta / 4), centred at ``X = (d + g/2) cos(phi)``, ``Z = 0`` relative to the
centre of mass (``d = s / sqrt(2)``): moving each cube by ``g/2`` along the hinge-edge-to-centre line is the
same as lengthening the hinge arm to ``d + g/2``, with both centres at ``Z_com``.  Cube A is the exact mirror
image of cube B in X = 0 (same vertices with X negated, triangles reversed), so the discretisation itself
is mirror symmetric.  The body mesh is fixed and only moved rigidly with theta, so all results are smooth
in theta (no remeshing noise).
"""
from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .solver import Body

__all__ = [
    "DimerMeshSpec",
    "mesh_family",
    "FAMILY_BASE",
    "COARSE_SPEC",
    "DEFAULT_SPEC",
    "hinge_refined_spec",
    "graded_nodes",
    "cube_body_mesh",
    "dimer_bodies",
    "hinge_edge_b",
    "hinge_arm",
    "rounded_cube_volume",
    "split_bodies",
    "check_closed_oriented",
    "volume_centroid",
    "MeshError",
]

log = logging.getLogger(__name__)


class MeshError(ValueError):
    """A user mesh is unusable (open, inconsistently oriented, degenerate)."""


@dataclass(frozen=True)
class DimerMeshSpec:
    """Geometry and mesh of the full-wave dimer.

    Parameters
    ----------
    side : float
        Cube side s [m].
    gap : float or None
        Hinge gap g [m]; default 0.01 s.
    edge_radius : float
        Edge rounding radius r_e [m] (0: sharp cube).
    h_hinge : float
        Element size across the hinge edge, as a fraction of s.
    h_max : float
        Largest element size across the faces, as a fraction of s.
    h_along : float
        Element size along the hinge line (v direction), as a fraction of s.
    h_corner : float
        Element size along v at the two ends of the hinge edge, as a fraction of s.
    growth : float
        Ratio of neighbouring element sizes in the graded directions (> 1).
    h_edge : float or None
        Element size at every edge of the cube, as a fraction of s, graded away with ``growth`` (None: only the
        hinge edge is graded).  The field of a sharp cube is singular at all twelve edges (``|v| ~ r^-1/3``).
    """

    side: float = 500e-6
    gap: float | None = None
    edge_radius: float = 0.0
    h_hinge: float = 0.005
    h_max: float = 0.1
    h_along: float = 0.1
    h_corner: float = 0.03
    growth: float = 1.4
    h_edge: float | None = None

    def __post_init__(self) -> None:
        if not np.isfinite(self.side) or self.side <= 0:
            raise ValueError(f"side must be positive, got {self.side!r} m")
        if self.gap is None:
            object.__setattr__(self, "gap", 0.01 * float(self.side))
        if not np.isfinite(self.gap) or self.gap < 0:
            raise ValueError(f"gap must be >= 0, got {self.gap!r} m")
        if not 0 <= self.edge_radius < 0.25 * self.side:
            raise ValueError(f"edge radius must lie in [0, s/4), got {self.edge_radius!r} m")
        for name in ("h_hinge", "h_max", "h_along", "h_corner", "h_edge"):
            v = getattr(self, name)
            if v is None and name == "h_edge":
                continue
            if not 0 < v <= 0.5:
                raise ValueError(f"{name} must lie in (0, 0.5] (fraction of the side), got {v!r}")
        if not 1.0 < self.growth <= 3.0:
            raise ValueError(f"growth must lie in (1, 3], got {self.growth!r}")

    def settings(self) -> dict:
        """The spec as a JSON-ready dict (all lengths in metres or fractions of the side; ``h_edge`` only when set)."""
        out = {
            "side_m": float(self.side), "gap_m": float(self.gap), "edge_radius_m": float(self.edge_radius),
            "h_hinge": self.h_hinge, "h_max": self.h_max, "h_along": self.h_along, "h_corner": self.h_corner,
            "growth": self.growth,
        }
        if self.h_edge is not None:
            out["h_edge"] = self.h_edge
        return out

    @classmethod
    def from_settings(cls, settings: dict) -> "DimerMeshSpec":
        """The spec of :meth:`settings` (extra keys, such as a table's medium settings, are ignored)."""
        h_edge = settings.get("h_edge")
        return cls(side=float(settings["side_m"]), gap=float(settings["gap_m"]),
                   edge_radius=float(settings["edge_radius_m"]), h_edge=None if h_edge is None else float(h_edge),
                   **{k: float(settings[k]) for k in ("h_hinge", "h_max", "h_along", "h_corner", "growth")})


#: The base of the mesh family of :func:`mesh_family` (level q = 1).
FAMILY_BASE = dict(h_hinge=0.04, h_max=0.25, h_along=0.25, h_corner=0.12, growth=1.6)


def mesh_family(q: float, side: float = 500e-6, gap: float | None = None, edge_radius: float = 0.0) -> DimerMeshSpec:
    """The mesh of refinement level ``q``: every element size of :data:`FAMILY_BASE` times q, growth fixed.

    q = 2 is the coarsest (264 DOFs), q = 1 the coarse mesh (536 DOFs), the standard q = 0.5 (1,368 DOFs); the
    shipped tables use the edge-graded meshes of :mod:`acousim.fullwave.mesh_rules`; see docs/fullwave.md.
    """
    b = FAMILY_BASE
    return DimerMeshSpec(side=side, gap=gap, edge_radius=edge_radius, h_hinge=b["h_hinge"] * q, h_max=b["h_max"] * q,
                         h_along=b["h_along"] * q, h_corner=b["h_corner"] * q, growth=b["growth"])


#: The standard mesh of the studies (level q = 0.5, 1,368 DOFs; see docs/fullwave.md for its convergence).
DEFAULT_SPEC = mesh_family(0.5)


def hinge_refined_spec(side: float = 500e-6, gap: float | None = None, edge_radius: float = 0.0) -> DimerMeshSpec:
    """A hinge-graded mesh refined along the hinge line: the faces of ``mesh_family(0.5)``, and at the hinge edges
    elements g/2 across (kept within [0.0025 s, 0.02 s]), 0.03 s along and 0.015 s at the edges' ends (4,216 DOFs
    for the default dimer; ``python -m acousim table --mesh hinge``).

    With the faces fixed, the hinge stiffness converges monotonically under refinement along the hinge line, and
    this mesh is within about 1 % of that limit; refining the faces as well raises it further (by 2 % for faces of
    0.0625 s), so that on this mesh the 5 um default gap's hinge is about 3 % soft.  The shipped tables use the
    edge-graded meshes instead (:data:`acousim.fullwave.mesh_rules.TABLE_SPEC`; docs/fullwave.md).
    """
    g = 0.01 * side if gap is None else float(gap)
    return DimerMeshSpec(side=side, gap=g, edge_radius=edge_radius, h_hinge=min(max(0.5 * g / side, 0.0025), 0.02),
                         h_max=0.125, h_along=0.03, h_corner=0.015, growth=1.6)


#: Coarse mesh (q = 1) of the studies and of the coarse surrogate build.
COARSE_SPEC = mesh_family(1.0)


def graded_nodes(length: float, size_at: "callable") -> NDArray[np.float64]:
    """Nodes on [0, length] with local spacing ``size_at(x)`` (both in the same units).

    Marches ``x_{i+1} = x_i + size_at(x_i)``, then stretches the interior nodes so that the last
    interval ends exactly at ``length`` (it is merged with its neighbour when it would be shorter
    than half a local size).
    """
    xs = [0.0]
    while True:
        h = float(size_at(xs[-1]))
        if xs[-1] + h >= length - 1e-12 * length:
            break
        xs.append(xs[-1] + h)
    # last interval (length - xs[-1]) <= h; drop the last node if that interval is tiny
    if len(xs) > 1 and length - xs[-1] < 0.5 * float(size_at(xs[-1])):
        xs.pop()
    x = np.array(xs + [length])
    return x


def _axis_nodes(spec: DimerMeshSpec, kind: str) -> NDArray[np.float64]:
    """One-dimensional node set in [-s/2, s/2] (fractions of s scaled to metres).

    kind: ``"to_minus"`` (graded towards -s/2), ``"to_plus"`` (towards +s/2) or ``"along"``.
    """
    s = spec.side
    r = spec.edge_radius / s
    h_round = max(r * np.pi / 8, 1e-4) if r > 0 else np.inf
    g = spec.growth - 1.0

    def size(x: float) -> float:  # x in [0, 1] from the -s/2 end
        if kind == "to_minus":
            h = min(spec.h_max, spec.h_hinge + g * x)
        elif kind == "to_plus":
            h = min(spec.h_max, spec.h_hinge + g * (1.0 - x))
        else:
            h = min(spec.h_along, spec.h_corner + g * min(x, 1.0 - x))
        if r > 0 and kind != "along":  # resolve the rounded hinge edge; other arcs take the local size
            d_hinge = x if kind == "to_minus" else 1.0 - x
            h = min(h, h_round + g * max(0.0, d_hinge - r))
        if spec.h_edge is not None:  # every edge of the cube: both ends of every axis
            h = min(h, spec.h_edge + g * min(x, 1.0 - x))
        # never step over more than what the far end allows
        return max(h, 1e-6)

    if spec.h_edge is not None:  # fine at both ends: march from each end to the middle
        left = graded_nodes(0.5, size)
        x = np.concatenate([left, 1.0 - graded_nodes(0.5, lambda t: size(1.0 - t))[::-1][1:]])
    elif kind == "to_plus":  # march from the fine end
        x = 1.0 - graded_nodes(1.0, lambda t: size(1.0 - t))[::-1]
    elif kind == "along":  # half from the end to the middle, mirrored: an even number of intervals
        half = graded_nodes(0.5, size)
        x = np.concatenate([half, 1.0 - half[::-1][1:]])
    else:
        x = graded_nodes(1.0, size)
    return (x - 0.5) * s


def cube_body_mesh(spec: DimerMeshSpec) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """The graded surface mesh of one cube in its body frame, hinge edge at (u, w) = (-s/2, +s/2).

    Returns
    -------
    vertices : ndarray (n, 3)
        Body coordinates (u, v, w) [m], cube centred at the origin.
    faces : ndarray (m, 3)
        Outward-oriented triangles.
    """
    nu = _axis_nodes(spec, "to_minus")
    nv = _axis_nodes(spec, "along")
    nw = _axis_nodes(spec, "to_plus")
    axes = (nu, nv, nw)
    shape = tuple(len(a) for a in axes)
    index = -np.ones(shape, np.int64)
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), -1)
    boundary = np.zeros(shape, bool)
    for ax in range(3):
        sl = [slice(None)] * 3
        sl[ax] = 0
        boundary[tuple(sl)] = True
        sl[ax] = -1
        boundary[tuple(sl)] = True
    index[boundary] = np.arange(boundary.sum())
    vertices = grid[boundary]
    faces = []
    for ax in range(3):
        a1, a2 = [a for a in range(3) if a != ax]
        for end, sign in ((0, -1.0), (-1, 1.0)):
            sl = [slice(None)] * 3
            sl[ax] = end
            idx = index[tuple(sl)]  # (n_a1, n_a2)
            q00, q10, q01, q11 = idx[:-1, :-1], idx[1:, :-1], idx[:-1, 1:], idx[1:, 1:]
            # split every quad along the diagonal through its corner nearest the face centre: the
            # pattern is then invariant under every symmetry of the cube that maps faces to faces
            c1 = 0.5 * (axes[a1][:-1] + axes[a1][1:])
            c2 = 0.5 * (axes[a2][:-1] + axes[a2][1:])
            main = (c1[:, None] * c2[None, :]) >= 0  # nearest corner is q00 or q11
            tri_main = np.concatenate([np.stack([q00, q10, q11], -1)[main], np.stack([q00, q11, q01], -1)[main]])
            tri_anti = np.concatenate([np.stack([q00, q10, q01], -1)[~main], np.stack([q10, q11, q01], -1)[~main]])
            tri = np.concatenate([tri_main, tri_anti]).reshape(-1, 3)
            # orient outwards: the normal must point along sign * e_ax
            x = vertices[tri]
            nrm = np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0])
            flip = nrm[:, ax] * sign < 0
            tri[flip] = tri[flip][:, ::-1]
            faces.append(tri)
    faces = np.concatenate(faces)
    if spec.edge_radius > 0:
        vertices = _round_box(vertices, spec.side, spec.edge_radius)
    return vertices, faces


def _round_box(points: NDArray, side: float, radius: float) -> NDArray[np.float64]:
    """Map points of the cube surface onto the cube with edges and corners rounded by ``radius``."""
    a = 0.5 * side - radius
    q = np.clip(points, -a, a)
    d = points - q
    n = np.linalg.norm(d, axis=1, keepdims=True)
    return q + radius * d / n


def rounded_cube_volume(side: float, radius: float) -> float:
    """Volume [m^3] of a cube of side ``side`` with edges and corners rounded by ``radius`` [m]."""
    a = side - 2 * radius
    return float(a**3 + 6 * a**2 * radius + 3 * np.pi * a * radius**2 + 4 / 3 * np.pi * radius**3)


def _rotation_b(phi: float) -> NDArray[np.float64]:
    psi = np.pi / 4 - phi
    c, s = np.cos(psi), np.sin(psi)
    return np.array([[c, 0.0, -s], [0.0, 1.0, 0.0], [s, 0.0, c]])


def dimer_bodies(theta: float, spec: DimerMeshSpec = DEFAULT_SPEC) -> list[Body]:
    """Cubes A and B posed at bend ``theta``, coordinates relative to the centre of mass [m].

    Returns
    -------
    list of Body
        ``[A, B]``; each ``centre`` is its cube centre (the torque reference point).
    """
    v, f = _body_mesh_cached(spec)
    phi = np.pi * float(theta) / 4
    centre_b = np.array([hinge_arm(spec) * np.cos(phi), 0.0, 0.0])
    vb = v @ _rotation_b(phi).T + centre_b
    va = vb * np.array([-1.0, 1.0, 1.0])
    return [Body(va, f[:, ::-1].copy(), centre_b * np.array([-1.0, 1.0, 1.0])), Body(vb, f.copy(), centre_b)]


def hinge_arm(spec: DimerMeshSpec) -> float:
    """The hinge arm d + g/2 [m]: distance from the hinge line to each cube's centre."""
    return spec.side / np.sqrt(2.0) + 0.5 * spec.gap


def hinge_edge_b(theta: float, spec: DimerMeshSpec = DEFAULT_SPEC) -> NDArray[np.float64]:
    """Midpoint (3,) [m] of cube B's hinge edge at bend ``theta``, in the coordinates of :func:`dimer_bodies`."""
    phi = np.pi * float(theta) / 4
    centre_b = np.array([hinge_arm(spec) * np.cos(phi), 0.0, 0.0])
    return _rotation_b(phi) @ np.array([-0.5 * spec.side, 0.0, 0.5 * spec.side]) + centre_b


_MESH_CACHE: dict = {}


def _body_mesh_cached(spec: DimerMeshSpec) -> tuple[NDArray, NDArray]:
    if spec not in _MESH_CACHE:
        _MESH_CACHE[spec] = cube_body_mesh(spec)
        log.debug("cube mesh: %d vertices, %d triangles", len(_MESH_CACHE[spec][0]), len(_MESH_CACHE[spec][1]))
    return _MESH_CACHE[spec]


# ---------------------------------------------------------------------- arbitrary user meshes
def check_closed_oriented(vertices: ArrayLike, faces: ArrayLike, name: str = "mesh") -> None:
    """Raise :class:`MeshError` (one line) unless the triangulation is closed, consistently and outwards oriented.

    Every edge must be shared by exactly two triangles that traverse it in opposite directions,
    and the enclosed (signed) volume must be positive.
    """
    v = np.asarray(vertices, float)
    f = np.asarray(faces, np.int64)
    if len(f) < 4:
        raise MeshError(f"{name}: a closed body needs at least 4 triangles, got {len(f)}")
    x = v[f]
    area2 = np.linalg.norm(np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0]), axis=1)
    if np.any(area2 <= 1e-14 * np.max(area2)):
        raise MeshError(f"{name}: {int(np.sum(area2 <= 1e-14 * np.max(area2)))} degenerate (zero-area) triangles")
    directed = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
    und = np.sort(directed, axis=1)
    _, counts = np.unique(und, axis=0, return_counts=True)
    if np.any(counts != 2):
        n_open = int(np.sum(counts == 1))
        raise MeshError(
            f"{name}: not closed ({n_open} boundary edges, {int(np.sum(counts > 2))} edges shared by more than two triangles)"
        )
    _, dcounts = np.unique(directed, axis=0, return_counts=True)
    if np.any(dcounts != 1):
        raise MeshError(f"{name}: triangles are not consistently oriented ({int(np.sum(dcounts > 1))} edges traversed twice the same way)")
    vol = _signed_volume(v, f)
    if vol <= 0:
        raise MeshError(f"{name}: triangles are oriented inwards (signed volume {vol:.3g} m^3); flip them")


def _signed_volume(v: NDArray, f: NDArray) -> float:
    x = v[f]
    return float(np.einsum("ij,ij->i", x[:, 0], np.cross(x[:, 1], x[:, 2])).sum() / 6.0)


def volume_centroid(vertices: ArrayLike, faces: ArrayLike) -> tuple[float, NDArray[np.float64]]:
    """(volume [m^3], centroid [m]) of the solid bounded by a closed, outward-oriented triangulation."""
    v = np.asarray(vertices, float)
    f = np.asarray(faces, np.int64)
    ref = v.mean(axis=0)
    x = v[f] - ref
    vol6 = np.einsum("ij,ij->i", x[:, 0], np.cross(x[:, 1], x[:, 2]))
    vol = vol6.sum() / 6.0
    centroid = (vol6[:, None] * x.sum(axis=1)).sum(axis=0) / (24.0 * vol) + ref
    return float(vol), centroid


def split_bodies(vertices: ArrayLike, faces: ArrayLike, name: str = "mesh") -> list[Body]:
    """Split a surface mesh into its closed bodies (connected components), each checked and with its
    volume centroid as torque reference.

    Raises
    ------
    MeshError
        When a component is open, inconsistently or inwards oriented, or degenerate.
    """
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    v = np.asarray(vertices, float)
    f = np.asarray(faces, np.int64)
    if v.ndim != 2 or v.shape[1] != 3 or f.ndim != 2 or f.shape[1] != 3 or len(f) == 0:
        raise MeshError(f"{name}: needs a triangle surface mesh")
    if not np.all(np.isfinite(v)):
        raise MeshError(f"{name}: vertex coordinates are not all finite")
    # merge duplicate vertices (many formats store triangles soup-like)
    uniq, inverse = np.unique(np.round(v / (1e-9 * np.ptp(v) + 1e-300)).astype(np.int64), axis=0, return_inverse=True)
    inverse = inverse.ravel()
    first = np.zeros(len(uniq), np.int64)
    first[inverse[::-1]] = np.arange(len(v))[::-1]
    v, f = v[first], inverse[f]
    n = len(v)
    rows = np.concatenate([f[:, 0], f[:, 1], f[:, 2]])
    cols = np.concatenate([f[:, 1], f[:, 2], f[:, 0]])
    ncomp, labels = connected_components(coo_matrix((np.ones(rows.size), (rows, cols)), shape=(n, n)), directed=False)
    bodies = []
    face_label = labels[f[:, 0]]
    for c in range(ncomp):
        fc = f[face_label == c]
        if len(fc) == 0:
            continue  # unused vertex
        used = np.unique(fc)
        remap = -np.ones(n, np.int64)
        remap[used] = np.arange(used.size)
        vc, fc = v[used], remap[fc]
        check_closed_oriented(vc, fc, f"{name} (body {len(bodies)})")
        _, centroid = volume_centroid(vc, fc)
        bodies.append(Body(vc, fc, centroid))
    return bodies
