"""Full-wave surrogate: caching, exact symmetry and scalings, the interface, the shipped default table.

The accuracy of the surrogate against direct solves is a study (``python -m acousim convergence
--study surrogate``, numbers in docs/fullwave.md); here a tiny build (two solves on the coarsest mesh) checks
everything that holds for any build."""
from __future__ import annotations

import pickle

import numpy as np
import pytest

pytest.importorskip("bempp_cl")

from acousim.fullwave.geometry import COARSE_SPEC, mesh_family  # noqa: E402
from acousim.fullwave.force_surrogate import (DEFAULT_BUILD, DEFAULT_TABLE, FLUX_DISC_POINTS, FullwaveSurrogate,  # noqa: E402
                                              build_fullwave_surrogate, build_settings_of, build_settings,
                                              cached_fullwave_surrogate, default_fullwave_surrogate)
from acousim.medium import Medium  # noqa: E402

#: Two solves (theta = 0.34 and 0.83) on the coarsest graded mesh (264 DOFs), forces from the momentum flux as in
#: the shipped table (about 6 s per solve after bempp's compilation).
#: The test suite's own table: 2 solves on the coarsest mesh, and the mirror disc of the flux surface at 6 Gauss
#: points per panel (a quarter of the default's cost): what these tests check (the cache, the symmetries, the exact
#: scaling) does not depend on the quadrature.
TINY_BUILD = {"spec": mesh_family(2.0), "n_half": 2, "theta_max": 0.9, "forces": "flux", "flux_disc_points": 6}


@pytest.fixture(scope="session")
def coarse_surrogate(tmp_path_factory):
    """Built from scratch into a temporary cache."""
    cache = tmp_path_factory.mktemp("fullwave_cache")
    return cached_fullwave_surrogate(**TINY_BUILD, cache_dir=cache), cache


def test_coarse_surrogate_cache_and_symmetry(coarse_surrogate):
    sur, cache = coarse_surrogate
    files = list(cache.glob("fullwave_*.json"))
    assert len(files) == 1
    again = cached_fullwave_surrogate(**TINY_BUILD, cache_dir=cache)  # loads, no solve
    assert again.coefficients == sur.coefficients
    # exact symmetry F(-theta, -Z) = -F(theta, Z) (here y = Z - Z_eq)
    for th in (0.2, 0.55):
        z = np.array([-0.3e-3, 0.6e-3])
        for comp in ("fz", "qt"):
            a = sur._harmonic(th, z - sur.z_eq, comp)
            b = sur._harmonic(-th, -z - sur.z_eq, comp)
            np.testing.assert_allclose(b, -a, rtol=1e-12, atol=1e-12 * np.max(np.abs(a)))


def test_processes_that_miss_the_same_table_at_once_build_it_once(coarse_surrogate, tmp_path, monkeypatch):
    """Three workers miss the table at once; the first builds (here 0.5 s), the others wait and load its file."""
    import threading
    import time

    from acousim.fullwave import force_surrogate as module

    sur, _ = coarse_surrogate
    builds = []

    def build(*args, **kwargs):
        builds.append(1)
        time.sleep(0.5)
        return sur

    monkeypatch.setattr(module, "build_fullwave_surrogate", build)
    got = []
    workers = [threading.Thread(target=lambda: got.append(cached_fullwave_surrogate(**TINY_BUILD, cache_dir=tmp_path)))
               for _ in range(3)]
    for w in workers:
        w.start()
    for w in workers:
        w.join(timeout=60)
    assert len(builds) == 1 and len(got) == 3
    assert all(g.coefficients == sur.coefficients for g in got)


def _check_common(sur: FullwaveSurrogate) -> None:
    q_y, _ = sur.generalized_forces(0.0, 0.0)
    assert abs(q_y) < 1e-9 * sur.mass * sur.gravity
    assert -np.pi / (4 * sur.wavenumber) < sur.z_eq < 0
    s2 = sur.with_pressure(2 * sur.pressure_amplitude_pa)
    np.testing.assert_allclose(s2.coefficient_values(0.3, "qt"), 4 * sur.coefficient_values(0.3, "qt"), rtol=1e-14)
    assert abs(s2.generalized_forces(0.0, 0.0)[0]) < 1e-9 * sur.mass * sur.gravity
    assert s2.z_eq > sur.z_eq  # a stronger field holds the dimer closer to the node
    p = pickle.loads(pickle.dumps(sur))
    assert p == sur
    f_y, f_t = sur.linear_frequencies()
    assert np.isfinite(f_y) and f_y > 0
    assert sur.escape_height() < 0
    assert np.isclose(float(sur.hinge_inertia(0.0)), sur.inertia_const)
    eps = 1e-6
    d = (sur.hinge_inertia(0.3 + eps) - sur.hinge_inertia(0.3 - eps)) / (2 * eps)
    assert np.isclose(float(sur.hinge_inertia_derivative(0.3)), float(d), rtol=1e-6)


def test_coarse_surrogate_interface(coarse_surrogate):
    sur, _ = coarse_surrogate
    _check_common(sur)
    assert sur.build_accuracy["solves"] == TINY_BUILD["n_half"]


def test_shipped_default_table():
    """The table in the repository is the default build (settings as DEFAULT_BUILD, the flux disc at the default
    12 Gauss points per panel), so that a default request finds it instead of building one."""
    assert DEFAULT_TABLE.exists()
    sur = default_fullwave_surrogate()
    b = DEFAULT_BUILD
    assert build_settings_of(sur) == build_settings(b["spec"], Medium(), 2160.0, b["n_half"], b["theta_max"])
    assert sur.flux_disc_points == FLUX_DISC_POINTS == 12
    _check_common(sur)
    tay = sur.taylor_coefficients()
    assert tay["thetaddot"]["theta"] < 0  # the full-wave hinge is restoring
    assert np.isclose(sur.with_pressure(3300.0).with_pressure(3000.0).z_eq, sur.z_eq, rtol=1e-9)


def test_build_rejects_bad_box():
    with pytest.raises(ValueError):
        build_fullwave_surrogate(COARSE_SPEC, theta_max=1.0)


def test_dimensionless_coefficients_depend_on_ks_only(coarse_surrogate):
    """The exact scaling of the table family (acousim.fullwave.family): a dimer 1.3 times larger at a frequency
    chosen for the same ks, in air of another sound speed and density and at another pressure, has the same
    dimensionless (A, B, C) of F_Z and Q_theta (forces in units of p0^2 s^2 / (rho0 c0^2), torques of
    p0^2 s^3 / (rho0 c0^2)): one direct solve at the tiny table's first theta node against that node."""
    from dataclasses import replace

    from acousim.fullwave.family import force_scale
    from acousim.fullwave.geometry import dimer_bodies
    from acousim.fullwave.solver import solve_scattering
    from acousim.fullwave.force_surrogate import dimer_coefficients

    sur, _ = coarse_surrogate
    s0 = sur.settings["side_m"]
    ks = sur.wavenumber * s0
    side, c0, rho0, p0 = 1.3 * s0, 300.0, 1.0, 4000.0
    medium = Medium(frequency_hz=ks * c0 / (2 * np.pi * side), sound_speed_m_s=c0, density_kg_m3=rho0)
    spec = replace(TINY_BUILD["spec"], side=side, gap=1.3 * TINY_BUILD["spec"].gap)
    i = len(sur.nodes["theta"]) // 2  # the first positive node
    theta = sur.nodes["theta"][i]
    other = dimer_coefficients(solve_scattering(dimer_bodies(theta, spec), medium), theta, spec, p0, "flux",
                               TINY_BUILD["flux_disc_points"])
    unit0, unit1 = force_scale(s0, sur.medium, sur.pressure_amplitude_pa), force_scale(side, medium, p0)
    for comp, lever in (("fz", 1.0), ("qt", None)):
        ref = np.asarray(sur.nodes[comp][i]) / (unit0 * (s0 if lever is None else 1.0))
        got = np.asarray(other[comp]) / (unit1 * (side if lever is None else 1.0))
        # the same mesh in units of s and the same ks: equal to the solver's round-off
        np.testing.assert_allclose(got, ref, rtol=0, atol=1e-9 * np.abs(ref).max())
