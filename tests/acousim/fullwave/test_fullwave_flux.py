"""Forces and torques from the momentum flux away from the bodies (acousim.fullwave.flux) against the surface
integrals on smooth bodies, where the surface integral is accurate."""
from __future__ import annotations

import numpy as np
import pytest

trimesh = pytest.importorskip("trimesh")
pytest.importorskip("bempp_cl")

from acousim.fullwave.flux import (ExteriorField, enclosing_sphere_surface, flux_height_structure,  # noqa: E402
                                   mirror_half_surface)
from acousim.fullwave.solver import Body, solve_scattering  # noqa: E402
from acousim.medium import Medium  # noqa: E402

pytestmark = pytest.mark.slow  # one solve of 1,284 DOFs and two flux evaluations: about 5 s after bempp's compilation

MEDIUM = Medium()
P0 = 3000.0
RADIUS = 150e-6  # sphere radius [m]: ka = 0.13
CENTRE_X = 200e-6  # sphere B at X = +200 um, A its mirror image: a 100 um gap between them


@pytest.fixture(scope="module")
def sphere_pair():
    """Two icospheres (642 vertices each, mirror symmetric in X, Y and Z) side by side, solved once."""
    s = trimesh.creation.icosphere(subdivisions=3, radius=RADIUS)
    cb = np.array([CENTRE_X, 0.0, 0.0])
    vb = s.vertices + cb
    va = vb * np.array([-1.0, 1.0, 1.0])
    bodies = [Body(va, s.faces[:, ::-1].copy(), cb * np.array([-1.0, 1.0, 1.0])), Body(vb, s.faces.copy(), cb)]
    sol = solve_scattering(bodies, MEDIUM)
    return sol, ExteriorField(sol)


def _flux(sol, field, surface, centre):
    med = sol.medium
    return flux_height_structure(field, surface, centre, med.density_kg_m3, med.sound_speed_m_s,
                                 2 * np.pi * med.frequency_hz, P0)


def test_flux_through_an_enclosing_sphere_is_the_total_surface_force(sphere_pair):
    """Momentum conservation on smooth bodies: the flux through a sphere around both equals the summed surface
    forces (A, B, C of F_X and F_Z) within 0.5 % of the force amplitude (the surface integral's P1 velocity on
    642-vertex spheres; an asymmetric egg of the same mesh agrees to 0.1 %)."""
    sol, field = sphere_pair
    force, _ = _flux(sol, field, enclosing_sphere_surface(0.8e-3, n_polar=20), np.zeros(3))
    hs = sol.height_structure(P0)
    surface = np.stack([hs.force_a.sum(0), hs.force_b.sum(0), hs.force_c.sum(0)])
    scale = np.abs(surface[:, 2]).max()
    np.testing.assert_allclose(force[:, [0, 2]], surface[:, [0, 2]], atol=5e-3 * scale)


def test_mirror_half_surface_gives_one_bodys_force_and_torque(sphere_pair):
    """Sphere B alone from the flux through the half sphere X > 0 closed by the mirror disc: its horizontal
    interaction force and vertical force equal its surface integral within 1 % of the vertical amplitude, and
    its torque about its centre vanishes (pressure tractions on a sphere point through the centre) to 1 % of
    force times radius."""
    sol, field = sphere_pair
    cb = sol.bodies[1].centre
    half = mirror_half_surface(0.8e-3, hinge_height=0.0, half_length=RADIUS, h0=0.3 * (CENTRE_X - RADIUS), n_polar=20)
    force, torque = _flux(sol, field, half, cb)
    hs = sol.height_structure(P0)
    surface = np.stack([hs.force_a[1], hs.force_b[1], hs.force_c[1]])
    scale = np.abs(surface[:, 2]).max()
    np.testing.assert_allclose(force[:, [0, 2]], surface[:, [0, 2]], atol=1e-2 * scale)
    assert np.abs(surface[:, 0]).max() > 0.02 * scale  # the interaction force is there to be checked
    assert np.abs(torque[:, 1]).max() < 1e-2 * scale * RADIUS
