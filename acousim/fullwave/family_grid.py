"""The family's grid: its nodes in (ks, g/s), the meshes they are built on, and the reference settings.

A node is one (ks, g/s) with its build settings (:class:`FamilyNode`); its table is one
:class:`~acousim.fullwave.surrogate.FullwaveSurrogate` built at the reference side and air (:data:`REFERENCE`),
from which every other dimer with the same ks and g/s follows by exact scaling (:mod:`acousim.fullwave.family`).

Meshes.  The field of a sharp cube is singular at every edge (|v| ~ r^-1/3).  Two mesh rules exist:

* the **hinge-graded** rule (:func:`family_mesh_spec`): graded towards the hinge edges only, elements of 0.125 s
  elsewhere.  Its hinge stiffness is 3-4 % soft (``mesh_convergence.json``);
* the **edge-graded** rule (:func:`edge_graded_mesh_spec`): every size of the hinge-graded rule times a level q,
  and each cube graded towards all twelve edges from :data:`EDGE_GRADED_H_EDGE` q s.  On these meshes the
  hinge stiffness converges monotonically, with Richardson limits that predict a held-out finest level within
  0.2 %.  :data:`FAMILY_MESH_LEVELS` gives the level of each gap node, chosen from that study so that the
  stated mesh error (the distance from the limit plus the size of the extrapolation) stays below 2 %.
"""
from __future__ import annotations

import os
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Sequence

import numpy as np

from ..medium import Medium
from .geometry import DimerMeshSpec
from .surrogate import FLUX_DISC_POINTS, FLUX_DISC_POINTS_RANGE

__all__ = [
    "FAMILY_KS", "FAMILY_GAP_RATIOS", "FAMILY_DIR", "FAMILY_BUILD", "REFERENCE", "BUILD_HINT", "MESH_CONVERGENCE_FILE",
    "EDGE_GRADED_H_EDGE", "FAMILY_MESH_LEVELS", "EDGE_GRADED_FAMILY_DIR", "FamilyRangeError", "FamilyTableError", "family_mesh_spec",
    "family_mesh_level", "edge_graded_mesh_spec", "FamilyNode", "node_path", "family_nodes",
]

#: The family directory's record of the mesh-convergence study per gap row (``python -m acousim convergence --study
#: mesh --mesh-rule family-uniform`` and ``family-edges``): ``{"gap_rows": [{"gap_over_side", "stated_error", ...}]}``.
MESH_CONVERGENCE_FILE = "mesh_convergence.json"


def _lobatto(lo: float, hi: float, n: int) -> tuple[float, ...]:
    x = np.cos(np.pi * np.arange(n)[::-1] / (n - 1))
    return tuple(float(v) for v in 0.5 * (lo + hi) + 0.5 * (hi - lo) * x)


#: ks nodes (sides 400-700 um at 40-50 kHz).  Chosen from measured interpolation errors: on the g/s = 0.05 row of
#: the 4-point Chebyshev-Lobatto grid (0.3, 0.3875, 0.5625, 0.65), the quadratic through three of the nodes reproduces
#: the left-out interior one within 1.2e-4 (F_Z) and 8.3e-4 (Q_theta) of their maxima over |theta| <= 0.9 and every
#: height below the node, so three nodes suffice; the fourth (0.5625) is kept as a check point (docs/fullwave.md).
FAMILY_KS: tuple[float, ...] = (0.3, 0.3875, 0.65)
#: g/s nodes: 4 Chebyshev-Lobatto points in log(g/s) on [0.01, 0.05].
FAMILY_GAP_RATIOS: tuple[float, ...] = tuple(round(float(np.exp(v)), 6)
                                             for v in _lobatto(np.log(0.01), np.log(0.05), 4))
#: Where the shipped node tables live (the hinge-graded family).
FAMILY_DIR = Path(__file__).resolve().parent.parent / "data" / "fullwave_family"
#: Where ``python -m acousim family build`` builds the edge-graded family by default (resumably, node by node);
#: it replaces the hinge-graded family once every node and check table is built.
EDGE_GRADED_FAMILY_DIR = Path(__file__).resolve().parent.parent / "data" / "fullwave_family_edge_graded"
#: Theta series of every node: n_half solves on |theta| <= theta_max (2 n_half Chebyshev terms).
FAMILY_BUILD = {"n_half": 6, "theta_max": 0.9, "flux_disc_points": FLUX_DISC_POINTS}
#: The physical settings the nodes are built at (any others follow by the exact scaling).
REFERENCE = {"side_m": 500e-6, "sound_speed_m_s": 343.0, "air_density_kg_m3": 1.204,
             "particle_density_kg_m3": 2160.0, "pressure_amplitude_pa": 3000.0}
#: The command that builds tables (named in every out-of-range message).
BUILD_HINT = "python -m acousim family build"


#: Element size at every cube edge, as a fraction of the side, of level q = 1 of the edge-graded rule.
EDGE_GRADED_H_EDGE = 0.02
#: (g/s, q): the edge-graded level of each gap node.  Each is the coarsest measured level whose stated mesh
#: error of the hinge stiffness (distance from the Richardson limit plus the extrapolation's size, at ks = 0.418)
#: is below 2 % with a margin: 1.32 % (g/s 0.01, q 1, 5,380 DOFs), 0.92 % (0.01495, q 0.7, 6,196),
#: 1.25 % (0.0334, q 0.5, 6,164) and 1.71 % (0.05, q 0.5, 5,812) (docs/fullwave.md).
FAMILY_MESH_LEVELS: tuple[tuple[float, float], ...] = ((0.01, 1.0), (0.014953, 0.7), (0.033437, 0.5), (0.05, 0.5))


class FamilyRangeError(ValueError):
    """A condition lies outside what the shipped (or given) family covers; one line."""


class FamilyTableError(ValueError):
    """A node table is corrupt or was built with other settings than the family's; one line naming the file."""


def family_mesh_spec(side: float, gap: float, edge_radius: float = 0.0, refine: float = 1.0,
                     refine_faces: bool = False) -> DimerMeshSpec:
    """The gap-resolving mesh of the family nodes.

    The faces are those of ``mesh_family(0.5)`` (largest element 0.125 s, growth 1.6).  At the hinge edges the
    elements are ``g/2`` across (kept within [0.0025 s, 0.02 s]) and ``3 g`` along the hinge line (at most
    0.125 s), halved at the edges' ends: the aspect ratio of the elements that face each other across the gap
    is the same at every gap.  At g = 0.01 s this is the shipped default table's mesh (``TABLE_SPEC``).  The hinge
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


@dataclass(frozen=True)
class FamilyNode:
    """One family node: the dimensionless parameters and the build settings.

    ``mesh_level`` is the level q of the edge-graded mesh (:func:`edge_graded_mesh_spec`); ``None`` is the
    hinge-graded mesh (:func:`family_mesh_spec`).  :func:`family_nodes` gives the levels of
    :data:`FAMILY_MESH_LEVELS`.
    """

    ks: float
    gap_ratio: float
    n_half: int = FAMILY_BUILD["n_half"]
    theta_max: float = FAMILY_BUILD["theta_max"]
    flux_disc_points: int = FAMILY_BUILD["flux_disc_points"]
    mesh_level: float | None = None

    def __post_init__(self) -> None:
        if not (np.isfinite(self.ks) and 0.05 <= self.ks <= 2.0):
            raise ValueError(f"ks must lie in [0.05, 2], got {self.ks!r}")
        if not (np.isfinite(self.gap_ratio) and 0.0 < self.gap_ratio <= 0.5):
            raise ValueError(f"g/s must lie in (0, 0.5], got {self.gap_ratio!r}")
        lo, hi = FLUX_DISC_POINTS_RANGE
        if not (isinstance(self.flux_disc_points, (int, np.integer)) and lo <= self.flux_disc_points <= hi):
            raise ValueError(f"flux disc points must be a whole number in {lo}..{hi}, got {self.flux_disc_points!r}")
        if self.mesh_level is not None and not (np.isfinite(self.mesh_level) and 0.1 <= self.mesh_level <= 4.0):
            raise ValueError(f"the mesh level q must lie in [0.1, 4], got {self.mesh_level!r}")

    @property
    def medium(self) -> Medium:
        """The reference air at the frequency that gives this ks on the reference side."""
        s, c = REFERENCE["side_m"], REFERENCE["sound_speed_m_s"]
        return Medium(frequency_hz=self.ks * c / (2 * np.pi * s), sound_speed_m_s=c,
                      density_kg_m3=REFERENCE["air_density_kg_m3"])

    @property
    def spec(self) -> DimerMeshSpec:
        s = REFERENCE["side_m"]
        if self.mesh_level is None:
            return family_mesh_spec(s, self.gap_ratio * s)
        return edge_graded_mesh_spec(s, self.gap_ratio * s, self.mesh_level)

    @classmethod
    def from_table(cls, sur) -> "FamilyNode":
        """The node a table claims to be (its build record and settings), to be checked with ``_matches``."""
        ba, st = sur.build_accuracy, sur.settings
        h_edge = st.get("h_edge")
        level = None if h_edge is None else round(float(h_edge) / EDGE_GRADED_H_EDGE, 9)
        return cls(float(ba["ks"]), float(ba["gap_ratio"]), int(st["n_half"]), float(st["theta_max"]),
                   sur.flux_disc_points, level)

    def expected_settings(self) -> dict:
        """The keyed build settings a table of this node must carry."""
        from .surrogate import build_settings

        return build_settings(self.spec, self.medium, REFERENCE["particle_density_kg_m3"], self.n_half,
                              self.theta_max, "flux", self.flux_disc_points)

    @property
    def name(self) -> str:
        return f"ks{self.ks:.4f}_g{self.gap_ratio:.5f}"


def node_path(directory: str | os.PathLike, node: FamilyNode) -> Path:
    """The node's table file in ``directory``."""
    return Path(directory) / f"{node.name}.json"



def family_nodes(ks: Sequence[float] = FAMILY_KS, gap_ratios: Sequence[float] = FAMILY_GAP_RATIOS,
                 n_half: int = FAMILY_BUILD["n_half"], theta_max: float = FAMILY_BUILD["theta_max"],
                 flux_disc_points: int = FAMILY_BUILD["flux_disc_points"], edge_graded: bool = True) -> list[FamilyNode]:
    """The grid's nodes in build order: the largest gap first, so that a partial build covers a rectangle of the
    family as early as possible.  ``edge_graded``: on the edge-graded mesh at :func:`family_mesh_level` (else the
    hinge-graded mesh)."""
    return [FamilyNode(float(k), float(g), n_half, theta_max, flux_disc_points,
                       family_mesh_level(g) if edge_graded else None)
            for g in sorted(gap_ratios, reverse=True) for k in ks]
