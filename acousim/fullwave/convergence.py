"""Convergence of the full-wave hinge against mesh size, hinge gap and edge radius.

For one geometry and mesh, two boundary-element solves (theta = 0 and theta = delta) give, through the
exact height structure and the bend parity (A, B odd and C even in theta, see
:mod:`acousim.fullwave.force_surrogate`):

* the theta = 0 vertical force ``F_Z = C_F sin(2kZ)``, hence Z_eq (F_Z = M g) and f_y;
* the hinge stiffness ``dQ_theta/dtheta = A_Q'(0) + B_Q'(0) cos(2kZ_eq)`` at (theta, y) = (0, 0)
  (``A_Q'(0) ~ A_Q(delta) / delta``, error O(delta^2));
* the Taylor coefficients of thetaddot = Q_theta / I: ``1``, ``y``, ``theta``, ``y*theta``, ``y^2*theta``.

The mesh study ends with :func:`judge_convergence` of the hinge stiffness (monotone corrections, observed
order >= 1, finest two levels within 2 %).  Run ``python -m acousim convergence --help``; the
tables of docs/fullwave.md were made with it.
"""
from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np
from cubedimer.meta import DEFAULT_PARTICLE_DENSITY, DEFAULT_PRESSURE_AMPLITUDE_PA

from ..medium import GRAVITY, Medium
from .geometry import DimerMeshSpec, dimer_bodies, mesh_family, rounded_cube_volume
from .mesh_record import CONVERGED_WITHIN, judge_convergence, richardson_limit, stated_mesh_error  # noqa: F401 (re-exported)
from .mesh_rules import EDGE_GRADED_H_EDGE  # noqa: F401 (re-exported)
from .flux import ExteriorField, enclosing_sphere_surface, flux_height_structure
from .solver import solve_scattering
from .force_surrogate import COARSE_BUILD, FullwaveSurrogate, build_fullwave_surrogate, dimer_coefficients

__all__ = ["mesh_family", "hinge_quantities", "judge_convergence", "richardson_limit", "stated_mesh_error",
           "flux_balance", "surrogate_errors", "CONVERGED_WITHIN", "EDGE_GRADED_H_EDGE"]


def hinge_quantities(spec: DimerMeshSpec, medium: Medium = Medium(),
                     pressure_amplitude_pa: float = DEFAULT_PRESSURE_AMPLITUDE_PA,
                     particle_density: float = DEFAULT_PARTICLE_DENSITY, gravity: float = GRAVITY, delta: float = 0.02,
                     forces: str = "flux") -> dict:
    """Z_eq, F_Z amplitude, hinge stiffness and thetaddot Taylor coefficients of one mesh (two solves).

    Returns
    -------
    dict
        ``dofs``, ``wall_s``, ``z_eq_m``, ``fz_amplitude_n`` (|C_F(0)|), ``f_y_hz``, ``stiffness_nm``
        (dQ_theta/dtheta at the equilibrium height), ``f_theta_hz`` (from the stiffness alone) and
        ``thetaddot`` (dict of Taylor coefficients, SI); ``forces`` is how forces and torques were integrated
        (:data:`acousim.fullwave.force_surrogate.FORCE_METHODS`).
    """
    t0 = time.perf_counter()
    two_k = 2 * medium.wavenumber
    g0 = dimer_coefficients(solve_scattering(dimer_bodies(0.0, spec), medium), 0.0, spec, pressure_amplitude_pa, forces)
    sol = solve_scattering(dimer_bodies(delta, spec), medium)
    gd = dimer_coefficients(sol, delta, spec, pressure_amplitude_pa, forces)
    m = particle_density * rounded_cube_volume(spec.side, spec.edge_radius)
    mass = 2 * m
    c_f = g0["fz"][2]
    ratio = mass * gravity / c_f
    if not -1 < ratio < 0:
        raise ValueError("the field cannot levitate this dimer")
    z_eq = float(np.arcsin(ratio) / two_k)  # in (-lambda/8, 0): C_F < 0 there
    ph = two_k * z_eq
    c, s = np.cos(ph), np.sin(ph)
    i0 = (np.pi / 4) ** 2 * 2 * m * spec.side**2 / 6
    a1, b1 = gd["qt"][0] / delta, gd["qt"][1] / delta  # A_Q'(0), B_Q'(0)
    cq0 = g0["qt"][2]
    stiff = a1 + b1 * c
    k_y = -two_k * c_f * c  # -dF_Z/dZ
    thetaddot = {
        "1": cq0 * s / i0,
        "y": two_k * cq0 * c / i0,
        "theta": stiff / i0,
        "y*theta": -two_k * b1 * s / i0,
        "y^2*theta": -(two_k**2) * b1 * c / (2 * i0),
    }
    return {
        "dofs": int(sol.n_dofs), "wall_s": time.perf_counter() - t0, "z_eq_m": z_eq, "fz_amplitude_n": abs(float(c_f)),
        "f_y_hz": float(np.sqrt(k_y / mass) / (2 * np.pi)) if k_y > 0 else float("nan"),
        "stiffness_nm": float(stiff),
        "f_theta_hz": float(np.sqrt(-stiff / i0) / (2 * np.pi)) if stiff < 0 else float("nan"),
        "thetaddot": {k: float(v) for k, v in thetaddot.items()}, "spec": spec.settings(), "forces": forces,
    }


def flux_balance(spec: DimerMeshSpec, theta: float = 0.3, heights=(-0.4e-3, 0.9e-3), radius: float = 1.2e-3,
                 pressure_amplitude_pa: float = DEFAULT_PRESSURE_AMPLITUDE_PA, n_polar: int = 20) -> list[dict]:
    """Total force on the dimer from the per-cube surface tractions against the momentum flux through an
    enclosing sphere of ``radius`` [m] (:mod:`acousim.fullwave.flux`), at each height [m].

    The two must agree (momentum conservation in the inviscid fluid); docs/fullwave.md states how far
    the surface tractions do not on sharp cube edges.

    Returns
    -------
    list of dict
        Per height: ``z_m``, ``surface_n`` and ``flux_n`` (total force vectors [N]; the flux's Y component is
        not evaluated, the field being mirror symmetric in Y) and ``ratio_z`` (flux / surface of the vertical
        component).
    """
    sol = solve_scattering(dimer_bodies(theta, spec))
    hs = sol.height_structure(pressure_amplitude_pa)
    med = sol.medium
    force, _ = flux_height_structure(ExteriorField(sol), enclosing_sphere_surface(radius, n_polar), np.zeros(3),
                                     med.density_kg_m3, med.sound_speed_m_s, 2 * np.pi * med.frequency_hz,
                                     pressure_amplitude_pa)
    rows = []
    for z in heights:
        surface = hs.force(z).sum(axis=0)
        flux = force[0] + force[1] * np.cos(hs.two_k * z) + force[2] * np.sin(hs.two_k * z)
        flux[1] = np.nan
        rows.append({"z_m": float(z), "surface_n": surface.tolist(), "flux_n": flux.tolist(),
                     "ratio_z": float(flux[2] / surface[2])})
    return rows


def surrogate_errors(build: dict = COARSE_BUILD, thetas=(0.17, 0.71), y=np.linspace(-1.0e-3, 0.8e-3, 13),
                     pressure_amplitude_pa: float = DEFAULT_PRESSURE_AMPLITUDE_PA, surrogate: FullwaveSurrogate | None = None,
                     progress: Callable[[dict], None] | None = None) -> dict:
    """Errors of a surrogate against direct solves at bends ``thetas`` that are not Chebyshev nodes, over
    heights ``y`` [m] above Z_eq (same mesh on both sides).

    Parameters
    ----------
    build : dict
        Keyword arguments of :func:`build_fullwave_surrogate` (``spec``, ``n_half``, ``theta_max``,
        ``forces``); ignored when ``surrogate`` is given.
    thetas : sequence of float
        Bends of the direct solves.
    y : array_like
        Heights above Z_eq [m].
    pressure_amplitude_pa : float
        p0 [Pa] of the comparison.
    surrogate : FullwaveSurrogate, optional
        An existing table (e.g. the shipped one); its settings give the mesh and the force method.
    progress : callable, optional
        Called with the row of each bend as it finishes (``theta``, ``q_y``, ``q_theta``, ``wall_s``).

    Returns
    -------
    dict
        ``q_y`` and ``q_theta``: the largest error relative to max |Q| over the box
        |theta| <= theta_max, y in the range given (the table's target is 0.005); ``per_theta``: the
        same per bend.
    """
    if surrogate is None:
        sur = build_fullwave_surrogate(**build, pressure_amplitude_pa=pressure_amplitude_pa)
    else:
        sur = surrogate.with_pressure(pressure_amplitude_pa)
    spec, forces = DimerMeshSpec.from_settings(sur.settings), sur.settings.get("forces", "flux")
    y = np.asarray(y, float)
    tt, yy = np.meshgrid(np.linspace(-sur.theta_max, sur.theta_max, 19), y, indexing="ij")
    qy_box, qt_box = (np.max(np.abs(q)) for q in sur.generalized_forces(tt, yy))
    rows = []
    for theta in thetas:
        t0 = time.perf_counter()
        sol = solve_scattering(dimer_bodies(theta, spec), sur.medium)
        g = dimer_coefficients(sol, theta, spec, pressure_amplitude_pa, forces, sur.flux_disc_points)  # as the table
        ph = sur.two_k * (y + sur.z_eq)
        direct = {c: g[c][0] + g[c][1] * np.cos(ph) + g[c][2] * np.sin(ph) for c in ("fz", "qt")}
        q_y, q_t = sur.generalized_forces(theta, y)
        row = {"theta": float(theta),
               "q_y": float(np.max(np.abs(q_y - (direct["fz"] - sur.mass * sur.gravity)))) / qy_box,
               "q_theta": float(np.max(np.abs(q_t - direct["qt"]))) / qt_box,
               "wall_s": time.perf_counter() - t0}
        rows.append(row)
        if progress is not None:
            progress(row)
    return {"q_y": max(r["q_y"] for r in rows), "q_theta": max(r["q_theta"] for r in rows), "solves": int(sur.settings["n_half"]),
            "thetas": [float(t) for t in thetas], "per_theta": rows}
