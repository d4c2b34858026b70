"""Full-wave solver on two small rigid spheres side by side at the pressure node: the acoustic interaction
(secondary radiation) force against the Rayleigh-limit theory of Silva & Bruus, "Acoustic interaction forces
between small particles in an ideal fluid", Phys. Rev. E 90, 063007 (2014).

Set-up.  Standing wave p_in = p0 sin(kZ), time factor exp(-i w t); two spheres of radius a with centres at
(-d/2, 0, 0) (A) and (+d/2, 0, 0) (B), i.e. both on the node Z = 0, where p_in = 0 and the incident velocity
v_in = grad p_in / (i w rho0) = -i v0 Z_hat, v0 = p0 / (rho0 c0), has its largest amplitude and is perpendicular
to the line of centres.

Formula.  In the Rayleigh limit (ka << 1) the time-averaged force on a small rigid immobile sphere (Gor'kov
contrast factors f1 = f2 = 1) in any irrotational external field (p_e, v_e) is -grad U with
U = V [<p_e^2> / (2 rho0 c0^2) - (3/4) rho0 <v_e^2>], V = 4 pi a^3 / 3, <.> the time average (Gor'kov 1962;
the radiation-damping parts of f1, f2, O((ka)^3), are dropped).  Silva & Bruus
take as external field of sphere B the incident wave plus the wave scattered by sphere A; the interaction force
is the part of -grad U_B linear in A's scattered wave.  At the node:

* A scatters no monopole wave (its strength is proportional to p_in at A, which is zero), only the dipole wave
  of a rigid sphere held fixed in the oscillating flow: velocity potential
  phi_A(r) = (a^3/2) (1 - ikr) e^{ikr} (v_in . r) / r^3, r from A's centre (for kr -> 0 the potential
  of a sphere held in a uniform stream).
* In the plane Z = 0, phi_A (and with it A's scattered pressure i w rho0 phi_A) vanishes, as p_in does: the
  pressure term of U_B does not contribute.  A's scattered velocity there is parallel to v_in:
  v_A = (a^3/2) v_in (1 - ikX) e^{ikX} / X^3 at distance X from A.
* <v_e^2> = |v_in + v_A|^2 / 2; its part linear in v_A is (v0^2 a^3 / 2) (cos kX + kX sin kX) / X^3.  With
  (3/4) rho0 V = pi rho0 a^3 the X-derivative at X = d gives

      F_B,X = -(pi/2) rho0 v0^2 (a^6 / d^4) [3 cos kd + 3 kd sin kd - (kd)^2 cos kd] = -F_A,X,

  i.e. -(3/2) pi rho0 v0^2 a^6 / d^4 (= -6 pi E0 a^6 / d^4, E0 = p0^2 / (4 rho0 c0^2)) times
  1 + (kd)^2/6 + (kd)^4/24 + ...: +0.67 % at kd = 0.2 and +1.06 % at kd = 0.25, so the kd-dependence is kept.
  The kd -> 0 limit is the classical Bjerknes / Weiser-Apfel-Neppiras secondary force of two spheres in an
  oscillating flow perpendicular to their line of centres: for other particles the force carries f2^2, and
  with the low-contrast f2 ~ 2 (rho_p - rho0) / (3 rho0) it reads -4 pi a^6 (rho_p - rho0)^2 v0^2 / (6 rho0 d^4).

Sign: ATTRACTION (F_B,X < 0 with B at +d/2).  The flow past a fixed sphere is faster beside it (1.5 v at its
equator) and slower ahead of and behind it; B sits beside A as seen along the flow, so <v^2> grows towards
A, and a sphere with f2 > 0 moves up the gradient of <v^2> (U = -(3/4) rho0 V <v^2>: the mean Bernoulli
pressure is lowest where the flow is fastest, between the spheres).  With the flow along the line of centres
(one sphere above the other) the same argument gives repulsion.

Beyond the formula.  (i) Multiple scattering: each sphere's dipole is also driven by the other's near field,
(a/d)^3 / 2 of v0, which raises the force by (1 - (a/d)^3/2)^-2 - 1: +1.6 % at d = 4a (ka = 0.05, kd = 0.2),
+0.8 % at d = 5a (kd = 0.25); higher multipoles enter at (a/d)^5 relative, radiation damping at (ka)^3.
(ii) The mesh: the icosphere is inscribed in the sphere and the force scales as a^6 ~ V^2; the 642-vertex
icosphere lacks 0.86 % of the volume, 1.7 % of V^2.  Measured BEM / formula (surface tractions) on 162, 642
and 2,562 vertices per sphere: 0.962, 1.0061, 1.0174 at kd = 0.2 and 0.951, 0.9941, 1.0051 at kd = 0.25;
the differences fall 3.9-fold per halving of h (second order), and the extrapolation to h -> 0 gives 1.021
and 1.009: the 642-vertex mesh is 1.5 % low in both cases, and the exact two-sphere force exceeds the
Rayleigh-limit formula by about the multiple-scattering estimate (+1.6 % / +0.8 %; a further +0.5 % at d = 4a).
"""
from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("trimesh")
pytest.importorskip("bempp_cl")

from acousim.fullwave.solver import solve_scattering  # noqa: E402
from acousim.medium import Medium  # noqa: E402

from .conftest import P0, SPHERE_PAIR_KA, SPHERE_PAIR_KD, sphere_pair  # noqa: E402

# the mirror-reduced solve of 1,284 DOFs and its flux through the half sphere (shared with test_fullwave_flux.py,
# conftest.py), and one unreduced solve of 324 DOFs: about 12 s CPU after bempp's compilation
pytestmark = pytest.mark.slow

MEDIUM = Medium()
#: (ka, kd): a = 60 um, d = 4a at the default 45.65 kHz (conftest.py's solved sphere pair, 642 vertices per sphere;
#: 162 vertices give BEM / formula = 0.962 and 0.951, which fail the 3 % target), the closer of the two pairs
#: measured (d = 5a: 0.9941, below).
CASES = ((SPHERE_PAIR_KA, SPHERE_PAIR_KD),)


def interaction_force(ka: float, kd: float) -> float:
    """F_B,X [N] of the module docstring (Silva & Bruus 2014, Rayleigh limit, f1 = f2 = 1, pressure node)."""
    k = MEDIUM.wavenumber
    a, d = ka / k, kd / k
    rho0 = MEDIUM.density_kg_m3
    v0 = P0 / (rho0 * MEDIUM.sound_speed_m_s)
    bracket = 3 * np.cos(kd) + 3 * kd * np.sin(kd) - kd**2 * np.cos(kd)
    return -0.5 * np.pi * rho0 * v0**2 * a**6 / d**4 * bracket


@pytest.fixture(scope="module")
def pair_solutions(solved_sphere_pair):
    return {CASES[0]: solved_sphere_pair.solution}


def test_formula_limits():
    """The formula's near-field limit is -(3/2) pi rho0 v0^2 a^6 / d^4 and its kd-correction is 1 + (kd)^2/6."""
    k = MEDIUM.wavenumber
    a, d = 0.05 / k, 1e-4 / k
    v0 = P0 / (MEDIUM.density_kg_m3 * MEDIUM.sound_speed_m_s)
    near = -1.5 * np.pi * MEDIUM.density_kg_m3 * v0**2 * a**6 / d**4
    assert interaction_force(0.05, 1e-4) == pytest.approx(near, rel=1e-8)
    for kd in (0.2, 0.25):
        near = interaction_force(0.05, 1e-4) * (1e-4 / kd) ** 4
        assert interaction_force(0.05, kd) / near == pytest.approx(1 + kd**2 / 6 + kd**4 / 24, rel=1e-5)


@pytest.mark.parametrize("ka, kd", CASES)
def test_interaction_force_matches_silva_bruus(pair_solutions, ka, kd):
    """Attraction of the Rayleigh-limit magnitude within 3 %, equal and opposite on the two spheres.

    Measured BEM / formula (surface tractions, 642-vertex icospheres): 1.0061 at (ka, kd) = (0.05, 0.2) and
    0.9941 at (0.05, 0.25): the mesh's -1.5 % (second order in h; 162 vertices give -3.8 % and -4.9 % against the
    formula and fail) against the +2.1 % and +0.9 % by which the extrapolated full-wave force exceeds the
    Rayleigh-limit formula (multiple scattering, module docstring).  3 % is the check's target; it holds either
    effect alone, whichever sign their sum has.
    """
    f = pair_solutions[ka, kd].height_structure(P0).force(0.0)  # (body, component) at the node
    ref = interaction_force(ka, kd)
    assert ref < 0  # attraction: B (at +d/2) is pulled towards -X
    assert abs(f[1, 0] / ref - 1) < 0.03, (f[1, 0], ref)
    assert abs(f[0, 0] + f[1, 0]) < 1e-6 * abs(ref)  # mirror images: F_A,X = -F_B,X (exact in a reduced solve)
    # no other component at the node: the primary force (along Z) vanishes there
    assert np.max(np.abs(f[:, 1:])) < 1e-6 * abs(ref)


def test_primary_force_is_there_and_vanishes_at_the_node(pair_solutions):
    """The interaction is a small difference: the primary force's amplitude (C of F_Z) is ~7 (kd = 0.2) and
    ~17 (kd = 0.25) times the interaction force, yet F_Z at the node is zero to 1e-6 of the interaction."""
    for (ka, kd), sol in pair_solutions.items():
        hs = sol.height_structure(P0)
        ref = abs(interaction_force(ka, kd))
        assert np.all(np.abs(hs.force_c[:, 2]) > 5 * ref)
        assert np.max(np.abs(hs.force(0.0)[:, 2])) < 1e-6 * ref


def test_momentum_flux_agrees_with_surface_tractions(solved_sphere_pair):
    """At kd = 0.2 (the interaction 1/7 of the primary force's amplitude) the interaction force on B from the
    momentum flux through the half sphere X > 0 (radius d/2 + 2a) closed by the mirror disc X = 0 equals the
    surface-traction force within 1 % (measured -0.28 % on these meshes; -0.27 % at kd = 0.25, -0.07 % on 2,562-vertex
    and -1.0 % on 162-vertex ones): the small difference is integrated consistently by both methods."""
    force = solved_sphere_pair.half_force
    flux_x = force[0, 0] + force[1, 0]  # A + B cos(0): at the node
    surf_x = solved_sphere_pair.solution.height_structure(P0).force(0.0)[1, 0]
    assert abs(flux_x / surf_x - 1) < 0.01, (flux_x, surf_x)


def test_unreduced_solve_is_mirror_symmetric():
    """Without the mirror reduction (coarse 162-vertex spheres, ka = 0.05, kd = 0.2) F_A,X = -F_B,X to 1e-6 of
    the interaction force (measured 1e-10), and the Y and Z components at the node vanish to 1e-6 of it (1e-8)."""
    k = MEDIUM.wavenumber
    ka, kd = CASES[-1]
    sol = solve_scattering(sphere_pair(ka / k, kd / k, 2), MEDIUM, use_symmetry=False)
    assert sol.timings["symmetry"] == ""
    f = sol.height_structure(P0).force(0.0)
    assert f[1, 0] < 0 < f[0, 0]
    assert abs(f[0, 0] + f[1, 0]) < 1e-6 * abs(f[1, 0])
    assert np.max(np.abs(f[:, 1:])) < 1e-6 * abs(f[1, 0])
