"""The two mesh rules of the full-wave tables of a dimer with a hinge gap g.

The field of a sharp cube is singular at every edge (|v| ~ r^-1/3), and the hinge torque lives in the g-wide gap
between two of them, so the mesh decides how close a table's hinge stiffness is to its mesh-converged limit.

* The **hinge-graded** rule (:func:`family_mesh_spec`): graded towards the hinge edges only, elements of 0.125 s
  elsewhere.  The hinge stiffness on it does not converge under refinement of the faces; it is 3-5 % soft.
* The **edge-graded** rule (:func:`edge_graded_mesh_spec`): every size of the hinge-graded rule times a level q,
  and each cube graded towards all twelve edges from :data:`EDGE_GRADED_H_EDGE` q s.  On these meshes the hinge
  stiffness converges monotonically; :data:`FAMILY_MESH_LEVELS` gives the level at each gap node of the family,
  chosen so that its stated mesh error stays below 2 % (docs/fullwave.md, "The nodes' meshes").
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from .geometry import DimerMeshSpec

__all__ = ["EDGE_GRADED_H_EDGE", "FAMILY_MESH_LEVELS", "family_mesh_spec", "family_mesh_level", "edge_graded_mesh_spec",
           "TABLE_SPEC"]

#: Element size at every cube edge, as a fraction of the side, of level q = 1 of the edge-graded rule.
EDGE_GRADED_H_EDGE = 0.02
#: (g/s, q): the edge-graded level of each gap node.  Each is the coarsest measured level whose stated mesh
#: error of the hinge stiffness (distance from the Richardson limit plus the extrapolation's size, at ks = 0.418)
#: is below 2 % with a margin: 1.33 % (g/s 0.01, q 1, 5,380 DOFs), 0.93 % (0.01495, q 0.7, 6,196),
#: 1.26 % (0.0334, q 0.5, 6,164) and 1.72 % (0.05, q 0.5, 5,812), as ``mesh_convergence.json`` states them.
FAMILY_MESH_LEVELS: tuple[tuple[float, float], ...] = ((0.01, 1.0), (0.014953, 0.7), (0.033437, 0.5), (0.05, 0.5))


def family_mesh_spec(side: float, gap: float, edge_radius: float = 0.0, refine: float = 1.0,
                     refine_faces: bool = False) -> DimerMeshSpec:
    """The gap-resolving mesh of the family nodes.

    The faces are those of ``mesh_family(0.5)`` (largest element 0.125 s, growth 1.6).  At the hinge edges the
    elements are ``g/2`` across (kept within [0.0025 s, 0.02 s]) and ``3 g`` along the hinge line (at most
    0.125 s), halved at the edges' ends: the aspect ratio of the elements that face each other across the gap
    is the same at every gap.  At g = 0.01 s this is :func:`~acousim.fullwave.geometry.hinge_refined_spec`.  The hinge
    stiffness on these meshes is not converged under refinement of the faces; each gap row's measured mesh error
    is in ``mesh_convergence.json`` (docs/fullwave.md).

    ``refine`` scales the three hinge sizes for the mesh-convergence study of each gap node; with
    ``refine_faces`` it scales the faces' largest element as well (every size times ``refine``: a uniformly
    refined sequence of the same mesh).
    """
    r = float(gap) / float(side)
    along = min(0.125, 3.0 * r) * refine
    return DimerMeshSpec(side=side, gap=gap, edge_radius=edge_radius,
                         h_hinge=min(max(0.5 * r, 0.0025), 0.02) * refine,
                         h_max=0.125 * (refine if refine_faces else 1.0), h_along=along, h_corner=0.5 * along,
                         growth=1.6)


def family_mesh_level(gap_ratio: float) -> float:
    """The edge-graded level q at ``gap_ratio`` (g/s): :data:`FAMILY_MESH_LEVELS` interpolated linearly in
    log(g/s), held at the end values outside; a check point between two gap nodes gets a level between theirs."""
    r = float(gap_ratio)
    if not (np.isfinite(r) and r > 0):
        raise ValueError(f"g/s must be positive, got {gap_ratio!r}")
    g, q = np.array(FAMILY_MESH_LEVELS).T
    return float(np.interp(np.log(r), np.log(g), q))


def edge_graded_mesh_spec(side: float, gap: float, level: float | None = None, edge_radius: float = 0.0) -> DimerMeshSpec:
    """The edge-graded mesh at level ``level`` (q; default :func:`family_mesh_level` of g/s): every size of
    :func:`family_mesh_spec` times q, and each cube graded towards all twelve edges from
    ``EDGE_GRADED_H_EDGE * q * s`` with the same growth."""
    q = family_mesh_level(gap / side) if level is None else float(level)
    if not (np.isfinite(q) and q > 0):
        raise ValueError(f"the mesh level must be positive, got {level!r}")
    spec = family_mesh_spec(side, gap, edge_radius, refine=q, refine_faces=True)
    return replace(spec, h_edge=EDGE_GRADED_H_EDGE * q)


#: The mesh of the shipped default dimer's table (``acousim/data/fullwave_default.json``): the edge-graded mesh of
#: the 500 um dimer with g = 0.01 s at the family's level there (q = 1, 5,380 DOFs).
TABLE_SPEC = edge_graded_mesh_spec(500e-6, 5e-6)
