"""Boundary-element solutions that several full-wave test modules check, solved once per session (these modules
travel to one pytest-xdist worker as one unit: ``BOUNDARY_ELEMENT_MODULES`` in tests/conftest.py)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest

P0 = 3000.0
#: Two rigid spheres at the pressure node, side by side along X: ka = 0.05 (a = 60 um at the default 45.65 kHz),
#: centres d = 4a apart (kd = 0.2), 642-vertex icospheres (1,284 DOFs, mirror-reduced).
SPHERE_PAIR_KA, SPHERE_PAIR_KD, SPHERE_PAIR_SUBDIVISIONS = 0.05, 0.2, 3


def sphere_pair(radius: float, distance: float, subdivisions: int) -> list:
    """Icospheres at (-d/2, 0, 0) (A) and (+d/2, 0, 0) (B), exact mirror images of each other in X = 0."""
    import trimesh

    from acousim.fullwave.solver import Body

    s = trimesh.creation.icosphere(subdivisions=subdivisions, radius=radius)
    cb = np.array([0.5 * distance, 0.0, 0.0])
    vb = s.vertices + cb
    mirror = np.array([-1.0, 1.0, 1.0])
    return [Body(vb * mirror, s.faces[:, ::-1].copy(), cb * mirror), Body(vb, s.faces.copy(), cb)]


@dataclass(frozen=True)
class SolvedSpherePair:
    """The solved pair, its exterior field, and the momentum flux (A, B, C of force and torque about B's centre)
    through the half sphere X > 0 of radius d/2 + 2a closed by the mirror disc X = 0: sphere B's share."""

    solution: object
    field: object
    radius: float
    distance: float
    half_force: np.ndarray
    half_torque: np.ndarray


def flux_through(pair_solution, field, surface, centre) -> tuple[np.ndarray, np.ndarray]:
    """``flux_height_structure`` at the medium of the solution and P0."""
    from acousim.fullwave.flux import flux_height_structure

    med = pair_solution.medium
    return flux_height_structure(field, surface, centre, med.density_kg_m3, med.sound_speed_m_s,
                                 2 * np.pi * med.frequency_hz, P0)


@pytest.fixture(scope="session")
def solved_sphere_pair() -> SolvedSpherePair:
    """The sphere pair of :data:`SPHERE_PAIR_KA`, :data:`SPHERE_PAIR_KD`, solved once for the interaction-force test
    (Silva & Bruus) and the momentum-flux tests (acousim.fullwave.flux)."""
    pytest.importorskip("trimesh")
    pytest.importorskip("bempp_cl")
    from acousim.fullwave.flux import ExteriorField, mirror_half_surface
    from acousim.fullwave.solver import solve_scattering
    from acousim.medium import Medium

    medium = Medium()
    a, d = SPHERE_PAIR_KA / medium.wavenumber, SPHERE_PAIR_KD / medium.wavenumber
    sol = solve_scattering(sphere_pair(a, d, SPHERE_PAIR_SUBDIVISIONS), medium)
    field = ExteriorField(sol)
    half = mirror_half_surface(0.5 * d + 2 * a, hinge_height=0.0, half_length=a, h0=0.3 * (0.5 * d - a), n_polar=20)
    force, torque = flux_through(sol, field, half, sol.bodies[1].centre)
    return SolvedSpherePair(sol, field, a, d, force, torque)
