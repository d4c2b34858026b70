"""The rocked and translated full-wave dimer (acousim.fullwave.antisymmetric_loads): the posed geometry's mirror symmetry and
translation invariance (no boundary-element solve: the incident wave's surface tractions), the central difference
of one solve's loads, and the stiffness table's theta-parity."""
import math

import numpy as np
import pytest

from acousim.fullwave.geometry import DimerMeshSpec, hinge_arm
from acousim.fullwave.antisymmetric_loads import RockingStiffness, pose_stiffness, rocked_dimer_bodies, rocking_rotation
from acousim.fullwave.solver import surface_force_density
from acousim.medium import Medium

S = 500e-6


def test_stiffness_table_parity_and_exact_polynomials():
    """Coefficients that are polynomials of the stated parity are reproduced exactly, and the negative bends follow
    K_psipsi(-theta, -Z) = K_psipsi(theta, Z), K_xpsi(-theta, -Z) = -K_xpsi(theta, Z)."""
    th = np.array([0.0, 0.2, 0.4, 0.6, 0.8])
    kpp = np.stack([1 + 0.5 * th**2, -2 + th**4, 0.3 * th - 0.1 * th**3], 1)
    kxp = np.stack([0.2 * th, th**3, 0.7 + th**2], 1)
    table = RockingStiffness(th, kpp, kxp, two_k=2.0 * Medium().wavenumber, pressure_amplitude_pa=3000.0)
    z = -3e-4
    for t in (0.1, 0.5):
        a, b = table.at(t, z), table.at(-t, -z)
        np.testing.assert_allclose(b[0], a[0], rtol=1e-12)
        np.testing.assert_allclose(b[1], -a[1], rtol=1e-12)
    c, s = np.cos(table.two_k * z), np.sin(table.two_k * z)
    t = 0.5
    np.testing.assert_allclose(table.at(t, z)[0], 1 + 0.5 * t**2 + (-2 + t**4) * c + (0.3 * t - 0.1 * t**3) * s,
                               rtol=1e-12)
    # p0^2 scaling
    np.testing.assert_allclose(table.at(t, z, 6000.0)[0], 4 * table.at(t, z)[0], rtol=1e-14)
    with pytest.raises(ValueError, match="increasing"):
        RockingStiffness(th[::-1], kpp, kxp, 1.0, 3000.0)


def test_pose_stiffness_reads_the_central_difference():
    force = np.array([[1.0, 0, 5.0], [2.0, 0, 6.0], [3.0, 0, 7.0]])
    torque = np.array([[0, -4.0, 0], [0, 8.0, 0], [0, 0.5, 0]])
    k = pose_stiffness(force, torque, 0.02)
    np.testing.assert_allclose(k["k_psipsi"], [200.0, -400.0, -25.0])
    np.testing.assert_allclose(k["k_xpsi"], [-50.0, -100.0, -150.0])
    np.testing.assert_allclose(k["fz"], [5.0, 6.0, 7.0])


def _incident_loads(bodies, psi_centre=np.zeros(3)):
    """Total force and torque about the centre of mass of the incident wave alone (no scattering), by the surface
    tractions: the posed geometry's symmetry, without a boundary-element solve."""
    med = Medium()
    k = med.wavenumber
    v = np.concatenate([b.vertices for b in bodies])
    off = np.cumsum([0] + [len(b.vertices) for b in bodies])
    f = np.concatenate([b.faces + o for b, o in zip(bodies, off[:-1])])
    z_ref = -2.2e-4
    p = np.sin(k * (z_ref + v[:, 2])).astype(complex)
    dens, pts, w, nrm = surface_force_density(v, f, p, p, med)
    trac = -(dens[:, :, None] * nrm[:, None, :])
    return np.einsum("mq,mqk->k", w, trac), np.einsum("mq,mqk->k", w, np.cross(pts - psi_centre, trac))


def test_the_symmetric_pose_has_no_sideways_force_or_rocking_torque():
    """The mesh is mirror symmetric in X = 0, so F_X and tau_Y vanish at psi = 0 (to rounding: 1e-12 of F_Z); a
    rocked pose and its mirror image (-psi) give opposite F_X and tau_Y, and a translation along X leaves the loads
    of the X-independent wave unchanged."""
    spec = DimerMeshSpec(side=S, h_hinge=0.08, h_max=0.25, h_along=0.25, h_corner=0.12, growth=1.6)
    f0, t0 = _incident_loads(rocked_dimer_bodies(0.3, 0.0, 0.0, spec))
    scale = abs(f0[2])
    assert scale > 0
    np.testing.assert_allclose([f0[0], t0[1] / S], 0.0, atol=1e-12 * scale)
    fp, tp = _incident_loads(rocked_dimer_bodies(0.3, 0.05, 0.0, spec))
    fm, tm = _incident_loads(rocked_dimer_bodies(0.3, -0.05, 0.0, spec))
    assert abs(tp[1]) > 1e-6 * scale * S  # a rocked dimer feels a torque
    np.testing.assert_allclose([fm[0], tm[1]], [-fp[0], -tp[1]], rtol=1e-10, atol=1e-14 * scale)
    shift = 40e-6
    fx, tx = _incident_loads(rocked_dimer_bodies(0.3, 0.05, shift, spec), np.array([shift, 0.0, 0.0]))
    np.testing.assert_allclose(fx, fp, rtol=1e-9, atol=1e-12 * scale)
    np.testing.assert_allclose(tx, tp, rtol=1e-9, atol=1e-12 * scale * S)
    # the rotation is right-handed about +Y: +X goes to -Z
    np.testing.assert_allclose(rocking_rotation(0.1) @ [1.0, 0, 0], [math.cos(0.1), 0, -math.sin(0.1)], atol=1e-15)
    np.testing.assert_allclose(rocked_dimer_bodies(0.0, 0.0, 0.0, spec)[1].centre[0], hinge_arm(spec), rtol=1e-14)
