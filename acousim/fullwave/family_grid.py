"""The family's grid: its nodes in (ks, g/s), the meshes they are built on, and the reference settings.

A node is one (ks, g/s) with its build settings (:class:`FamilyNode`); its table is one
:class:`~acousim.fullwave.force_surrogate.FullwaveSurrogate` built at the reference side and air (:data:`REFERENCE`),
from which every other dimer with the same ks and g/s follows by exact scaling (:mod:`acousim.fullwave.family`).

Meshes.  A node is built on one of the two mesh rules of :mod:`acousim.fullwave.mesh_rules` (re-exported here):
the hinge-graded rule (``mesh_level`` None) or the edge-graded rule at the level of its gap.
"""
from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Sequence

import numpy as np
from cubedimer.meta import (DEFAULT_AIR_DENSITY_KG_M3, DEFAULT_PARTICLE_DENSITY, DEFAULT_PRESSURE_AMPLITUDE_PA,
                            DEFAULT_SIDE_LENGTH_M, DEFAULT_SOUND_SPEED_M_S)

from ..medium import Medium
from .geometry import DimerMeshSpec
from .mesh_rules import (EDGE_GRADED_H_EDGE, FAMILY_MESH_LEVELS, edge_graded_mesh_spec, family_mesh_level,
                         family_mesh_spec)
from .force_surrogate import FLUX_DISC_POINTS, FLUX_DISC_POINTS_RANGE

__all__ = [
    "FAMILY_KS", "FAMILY_GAP_RATIOS", "FAMILY_DIR", "FAMILY_BUILD", "REFERENCE", "BUILD_HINT", "MESH_CONVERGENCE_FILE",
    "EDGE_GRADED_H_EDGE", "FAMILY_MESH_LEVELS", "FamilyRangeError", "FamilyTableError", "family_mesh_spec",
    "family_mesh_level", "edge_graded_mesh_spec", "FamilyNode", "node_path", "family_nodes",
]

#: The family directory's record of the mesh-convergence study per gap row (``python -m acousim convergence --study
#: mesh --mesh-rule family-uniform`` and ``family-edges``): ``{"gap_rows": [{"gap_over_side", "stated_error", ...}]}``.
MESH_CONVERGENCE_FILE = "mesh_convergence.json"


def _lobatto(lo: float, hi: float, n: int) -> tuple[float, ...]:
    x = np.cos(np.pi * np.arange(n)[::-1] / (n - 1))
    return tuple(float(v) for v in 0.5 * (lo + hi) + 0.5 * (hi - lo) * x)


#: ks nodes (sides 400-700 um at 40-50 kHz: ks 0.293-0.641).  Chosen from measured interpolation errors: on the
#: g/s = 0.05 row of the 4-point Chebyshev-Lobatto grid (0.3, 0.3875, 0.5625, 0.65), the quadratic through three of
#: the nodes reproduces the left-out interior one within 1.2e-4 (F_Z) and 8.3e-4 (Q_theta) of their maxima over
#: |theta| <= 0.9 and every height below the node, so three nodes suffice; the lowest node was then moved from 0.3
#: to 0.28 to cover a 400-um dimer at 40 kHz, and the quadratic through (0.28, 0.3875, 0.65) reproduces the 0.3 row's
#: tables (kept as check tables, like 0.5625) within 0.011 % of max |Q| (docs/fullwave.md).
FAMILY_KS: tuple[float, ...] = (0.28, 0.3875, 0.65)
#: g/s nodes: 4 Chebyshev-Lobatto points in log(g/s) on [0.01, 0.05].
FAMILY_GAP_RATIOS: tuple[float, ...] = tuple(round(float(np.exp(v)), 6)
                                             for v in _lobatto(np.log(0.01), np.log(0.05), 4))
#: Where the shipped node tables live (edge-graded meshes), with their check tables (``checks/``), the measured
#: interpolation errors (``accuracy.json``) and the mesh-convergence record (``mesh_convergence.json``).
FAMILY_DIR = Path(__file__).resolve().parent.parent / "data" / "fullwave_family"
#: Theta series of every node: n_half solves on |theta| <= theta_max (2 n_half Chebyshev terms).
FAMILY_BUILD = {"n_half": 6, "theta_max": 0.9, "flux_disc_points": FLUX_DISC_POINTS}
#: The physical settings the nodes are built at (any others follow by the exact scaling).
REFERENCE = {"side_m": DEFAULT_SIDE_LENGTH_M, "sound_speed_m_s": DEFAULT_SOUND_SPEED_M_S,
             "air_density_kg_m3": DEFAULT_AIR_DENSITY_KG_M3,
             "particle_density_kg_m3": DEFAULT_PARTICLE_DENSITY, "pressure_amplitude_pa": DEFAULT_PRESSURE_AMPLITUDE_PA}
#: The command that builds tables (named in every out-of-range message).
BUILD_HINT = "python -m acousim family build"


class FamilyRangeError(ValueError):
    """A condition lies outside what the shipped (or given) family covers; one line."""


class FamilyTableError(ValueError):
    """A node table is corrupt or was built with other settings than the family's; one line naming the file."""


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
        from .force_surrogate import build_settings

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
                 flux_disc_points: int = FAMILY_BUILD["flux_disc_points"], edge_graded: bool = True,
                 points: Sequence[tuple[float, float]] | None = None) -> list[FamilyNode]:
    """The grid's nodes in build order: the largest gap first, so that a partial build covers a rectangle of the
    family as early as possible.  ``edge_graded``: on the edge-graded mesh at :func:`family_mesh_level` (else the
    hinge-graded mesh).  ``points``: exactly these (ks, g/s) pairs instead of the grid ``ks`` x ``gap_ratios``
    (check points between the nodes), in the given order."""
    pairs = [(k, g) for g in sorted(gap_ratios, reverse=True) for k in ks] if points is None else list(points)
    return [FamilyNode(float(k), float(g), n_half, theta_max, flux_disc_points,
                       family_mesh_level(g) if edge_graded else None)
            for k, g in pairs]
