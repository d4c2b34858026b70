"""Full-wave force surrogate: Chebyshev series in theta of the exact height structure (docs/conventions.md section 7).

For every bend theta one boundary-element solve (two right-hand sides) gives the total vertical force
and the bending generalised force as::

    F_Z(theta, Z)     = A_F(theta) + B_F(theta) cos(2 k Z) + C_F(theta) sin(2 k Z)
    Q_theta(theta, Z) = A_Q(theta) + B_Q(theta) cos(2 k Z) + C_Q(theta) sin(2 k Z)

with ``Z = Z_com = Z_eq + y``, ``Q_y = F_Z - M g`` and ``Q_theta = (pi/4)(tau_A + tau_B)``, each cube's
torque about its centre taken positive in the sense that increases its own phi (cube B: +Y, cube A: -Y).
They need not derive from a potential and are used as they are.

Symmetry.  The dimer at -theta is the mirror image in Z (about Z_com) of the dimer at theta, and the
standing wave ``sin(kZ)`` is odd about the node, so for equal cubes ``F_Z(-theta, -Z) = -F_Z(theta, Z)`` and
``Q_theta(-theta, -Z) = -Q_theta(theta, Z)``: A and B are odd in theta and C is even.  The surrogate solves at
the positive half of an even number of Chebyshev points and fills the negative half by this symmetry, so
the symmetry holds exactly.  Note what it does *not* imply: unlike the Gor'kov model (where every
volume element sees only the incident field and C_Q vanishes identically), ``Q_theta(0, Z) = C_Q(0) sin(2kZ)``
need not vanish below the node, so the straight dimer is not exactly an equilibrium in theta.

The coefficient functions are interpolated on ``|theta| <= theta_max`` (Chebyshev points of the first kind
on that interval); outside it the series is extrapolated and the surrogate says nothing reliable.
Forces scale exactly as p0^2 (:meth:`FullwaveSurrogate.with_pressure`).

The table itself, its forces and its file are :mod:`acousim.fullwave.table`; this module builds, caches and ships
tables (:func:`build_fullwave_surrogate`, :func:`cached_fullwave_surrogate`, :func:`default_fullwave_surrogate`).
"""
from __future__ import annotations

import hashlib
import json
import logging
import os
import time
from dataclasses import replace
from pathlib import Path
from typing import Callable

import numpy as np
from numpy.polynomial import chebyshev as cheb
from numpy.typing import NDArray

from cubedimer.cache_lock import cache_entry_lock
from cubedimer.compile_cache import suite_cache_root
from cubedimer.meta import DEFAULT_PARTICLE_DENSITY, DEFAULT_PRESSURE_AMPLITUDE_PA

from ..medium import GRAVITY, Medium
from .geometry import (COARSE_SPEC, DEFAULT_SPEC, DimerMeshSpec, dimer_bodies, hinge_arm,
                       rounded_cube_volume)
from .flux import FLUX_DISC_POINTS, FLUX_DISC_POINTS_RANGE, UNKEYED_FLUX_DISC_POINTS, cube_b_flux_surface, dimer_flux_coefficients  # noqa: F401 (re-exported)
from .mesh_rules import TABLE_SPEC
from .solver import HeightStructure, solve_scattering
from .table import _COMPONENTS, FullwaveSurrogate, _equilibrium_height, _tup

__all__ = [
    "FullwaveSurrogate",
    "build_fullwave_surrogate",
    "cached_fullwave_surrogate",
    "default_fullwave_surrogate",
    "coarse_fullwave_surrogate",
    "dimer_generalized_coefficients",
    "dimer_flux_coefficients",
    "dimer_coefficients",
    "FLUX_DISC_POINTS",
    "UNKEYED_FLUX_DISC_POINTS",
    "FLUX_DISC_POINTS_RANGE",
    "FORCE_METHODS",
    "DEFAULT_TABLE",
    "DEFAULT_BUILD",
    "COARSE_BUILD",
]

log = logging.getLogger(__name__)

#: The shipped table of the default dimer.
DEFAULT_TABLE = Path(__file__).resolve().parent.parent / "data" / "fullwave_default.json"
#: Build arguments of the shipped default table.
DEFAULT_BUILD = {"spec": TABLE_SPEC, "n_half": 7, "theta_max": 0.9}
#: Build arguments of the coarse variant (q = 1, 4 solves; about 35 s with the momentum flux on 2 idle cores after
#: bempp's compilation, which takes about 80 s once per process).
COARSE_BUILD = {"spec": COARSE_SPEC, "n_half": 4, "theta_max": 0.9}

def dimer_generalized_coefficients(hs: HeightStructure, theta: float = 0.0, arm: float = 0.0) -> dict[str, NDArray[np.float64]]:
    """(A, B, C) of the total F_Z [N] and of Q_theta [N m] from the per-cube height structure of ``[A, B]``.

    Q_theta is the virtual work per unit theta of every force and torque on the cubes: each cube turns by
    phi = pi theta / 4 about its centre (cube B about +Y, cube A about -Y), and the centres, at
    X = +-arm cos(phi) and Z = Z_com, move horizontally::

        Q_theta = (pi/4) (tau_B,Y - tau_A,Y) - (pi/4) arm sin(phi) (F_B,X - F_A,X)

    The second term is the work of the cubes' horizontal interaction force (zero in the Gor'kov model, whose
    plane standing wave pushes only along Z); ``theta`` and ``arm`` [m] (the hinge arm d + g/2) give it.

    Returns
    -------
    dict
        ``{"fz": array([A, B, C]), "qt": array([A, B, C])}``.
    """
    fz = np.array([hs.force_a[:, 2].sum(), hs.force_b[:, 2].sum(), hs.force_c[:, 2].sum()])
    lever = arm * np.sin(np.pi * float(theta) / 4)
    qt = (np.pi / 4) * np.array([
        (t[1, 1] - t[0, 1]) - lever * (f[1, 0] - f[0, 0])
        for t, f in ((hs.torque_a, hs.force_a), (hs.torque_b, hs.force_b), (hs.torque_c, hs.force_c))
    ])
    return {"fz": fz, "qt": qt}


#: How a table's forces and torques are integrated: the momentum flux through surfaces away from the cubes
#: (default: accurate at sharp edges), or the surface tractions on the cubes (see docs/fullwave.md).
FORCE_METHODS = ("flux", "surface")


def dimer_coefficients(solution, theta: float, spec: DimerMeshSpec, pressure_amplitude_pa: float,
                       forces: str = "flux", flux_disc_points: int = FLUX_DISC_POINTS) -> dict[str, NDArray[np.float64]]:
    """(A, B, C) of F_Z and Q_theta of one solved dimer pose, by ``forces`` (:data:`FORCE_METHODS`)."""
    if forces == "flux":
        return dimer_flux_coefficients(solution, theta, spec, pressure_amplitude_pa, disc_points=flux_disc_points)
    if forces == "surface":
        return dimer_generalized_coefficients(solution.height_structure(pressure_amplitude_pa), theta, hinge_arm(spec))
    raise ValueError(f"unknown force method {forces!r}; choose one of {', '.join(FORCE_METHODS)}")


def chebyshev_half_nodes(n_half: int) -> NDArray[np.float64]:
    """The positive half of the 2 n_half Chebyshev points of the first kind on (-1, 1), increasing."""
    n = 2 * n_half
    t = np.cos(np.pi * (np.arange(n) + 0.5) / n)
    return np.sort(t[t > 0])


def build_settings(spec: DimerMeshSpec, medium: Medium, density: float, n_half: int, theta_max: float,
                   forces: str = "flux", flux_disc_points: int = FLUX_DISC_POINTS) -> dict:
    """The settings a table is keyed by (pressure excluded: tables are rescaled exactly).

    ``flux_disc_points`` is a key only when it differs from :data:`UNKEYED_FLUX_DISC_POINTS` (6, with
    ``forces="flux"``), so that tables built with 6 points keep their keys and file names."""
    out = {
        **spec.settings(), "frequency_hz": medium.frequency_hz, "sound_speed_m_s": medium.sound_speed_m_s,
        "air_density_kg_m3": medium.density_kg_m3, "particle_density_kg_m3": float(density),
        "n_half": int(n_half), "theta_max": float(theta_max), "forces": str(forces),
    }
    if forces == "flux" and int(flux_disc_points) != UNKEYED_FLUX_DISC_POINTS:
        out["flux_disc_points"] = int(flux_disc_points)
    return out


def build_fullwave_surrogate(
    spec: DimerMeshSpec = DEFAULT_SPEC,
    medium: Medium = Medium(),
    particle_density: float = DEFAULT_PARTICLE_DENSITY,
    pressure_amplitude_pa: float = DEFAULT_PRESSURE_AMPLITUDE_PA,
    gravity: float = GRAVITY,
    n_half: int = 5,
    theta_max: float = 0.9,
    progress: Callable[[int, int, float], None] | None = None,
    forces: str = "flux",
    flux_disc_points: int = FLUX_DISC_POINTS,
) -> FullwaveSurrogate:
    """Build the surrogate from ``n_half`` boundary-element solves (theta > 0), mirrored by symmetry.

    Parameters
    ----------
    spec : DimerMeshSpec
        Geometry (side, gap, edge radius) and mesh.
    medium : Medium
        Air and frequency.
    particle_density : float
        rho_p [kg/m^3] (mass and inertia only: the cubes are rigid and immobile acoustically).
    pressure_amplitude_pa : float
        p0 [Pa].
    gravity : float
        g [m/s^2].
    n_half : int
        Solves; the Chebyshev series has 2 n_half terms on [-theta_max, theta_max].
    theta_max : float
        Interpolation half-width in theta, in (0, 1).
    progress : callable, optional
        Called as ``progress(i, n_half, seconds)`` after each solve.
    forces : {"flux", "surface"}
        How forces and torques are integrated (:data:`FORCE_METHODS`).
    flux_disc_points : int
        Gauss points per panel of the flux surface's mirror disc (:data:`FLUX_DISC_POINTS`).

    Returns
    -------
    FullwaveSurrogate
    """
    if not 0 < theta_max < 1:
        raise ValueError(f"theta_max must lie in (0, 1), got {theta_max!r}")
    if n_half < 2:
        raise ValueError("n_half must be >= 2")
    t_pos = chebyshev_half_nodes(n_half)
    vals = {c: np.zeros((n_half, 3)) for c in _COMPONENTS}
    t_start = time.perf_counter()
    dofs = 0
    timings = []
    for i, t in enumerate(t_pos):
        t0 = time.perf_counter()
        bodies = dimer_bodies(t * theta_max, spec)
        sol = solve_scattering(bodies, medium)
        dofs = sol.n_dofs
        gen = dimer_coefficients(sol, t * theta_max, spec, pressure_amplitude_pa, forces, flux_disc_points)
        for c in _COMPONENTS:
            vals[c][i] = gen[c]
        timings.append(time.perf_counter() - t0)
        log.info("full-wave surrogate: theta = %.4f done (%d/%d, %.1f s)", t * theta_max, i + 1, n_half, timings[-1])
        if progress is not None:
            progress(i + 1, n_half, timings[-1])
    # mirror: A, B odd and C even in theta
    parity = np.array([-1.0, -1.0, 1.0])
    t_all = np.concatenate([-t_pos[::-1], t_pos])
    full = {c: np.concatenate([parity * vals[c][::-1], vals[c]]) for c in _COMPONENTS}
    deg = 2 * n_half - 1
    coefs = {}
    for c in _COMPONENTS:
        series = [cheb.chebfit(t_all, full[c][:, j], deg) for j in range(3)]
        # exact parities: A, B odd (even terms 0), C even (odd terms 0)
        series[0][0::2] = 0.0
        series[1][0::2] = 0.0
        series[2][1::2] = 0.0
        coefs[c] = tuple(_tup(s) for s in series)
    s = spec.side
    vol = rounded_cube_volume(s, spec.edge_radius)
    m = particle_density * vol
    arm = hinge_arm(spec)
    # I = (pi/4)^2 [2 (m s^2/6) + 2 m arm^2 sin^2 phi] (sharp-cube moment of inertia about the centre)
    i_const = (np.pi / 4) ** 2 * 2 * m * s**2 / 6
    i_sin2 = (np.pi / 4) ** 2 * 2 * m * arm**2
    settings = build_settings(spec, medium, particle_density, n_half, theta_max, forces, flux_disc_points)
    settings.update(pressure_amplitude_pa=float(pressure_amplitude_pa), gravity_m_s2=float(gravity), model="fullwave")
    sur = FullwaveSurrogate(
        coefficients=coefs, theta_max=float(theta_max), two_k=2 * medium.wavenumber, wavenumber=medium.wavenumber,
        z_eq=-np.pi / (4 * medium.wavenumber), mass=2 * m, gravity=float(gravity), inertia_const=i_const,
        inertia_sin2=i_sin2, pressure_amplitude_pa=float(pressure_amplitude_pa), settings=settings,
        nodes={"theta": (t_all * theta_max).tolist(), **{c: full[c].tolist() for c in _COMPONENTS}},
    )
    z_eq = _equilibrium_height(sur)
    build = {
        "dofs": int(dofs), "solves": int(n_half), "wall_s": time.perf_counter() - t_start,
        "solve_wall_s": [float(x) for x in timings], "chebyshev_terms": 2 * n_half,
    }
    return replace(sur, z_eq=z_eq, settings=dict(settings, equilibrium_height_m=z_eq), build_accuracy=build)


def _cache_dir() -> Path:
    env = os.environ.get("ACOUSIM_FULLWAVE_CACHE")
    if env:
        return Path(env)
    return suite_cache_root() / "fullwave"


def _key(settings: dict) -> str:
    return hashlib.sha1(json.dumps(settings, sort_keys=True).encode()).hexdigest()[:16]


def cached_fullwave_surrogate(
    spec: DimerMeshSpec = DEFAULT_SPEC,
    medium: Medium = Medium(),
    particle_density: float = DEFAULT_PARTICLE_DENSITY,
    pressure_amplitude_pa: float = DEFAULT_PRESSURE_AMPLITUDE_PA,
    gravity: float = GRAVITY,
    n_half: int = 5,
    theta_max: float = 0.9,
    cache_dir: str | os.PathLike | None = None,
    forces: str = "flux",
    flux_disc_points: int = FLUX_DISC_POINTS,
) -> FullwaveSurrogate:
    """The surrogate for these settings: the shipped default table, a cached table, or a new build (saved).

    The cache directory is ``$ACOUSIM_FULLWAVE_CACHE``, else ``$XDG_CACHE_HOME/cubedimer/fullwave`` (default
    ``~/.cache/cubedimer/fullwave``), one JSON file per settings hash.

    Tables are keyed by geometry, mesh, medium, density and build settings; the pressure amplitude is
    applied afterwards by the exact p0^2 scaling.  Processes that miss the same table at once build it once: the
    others wait for the first (:func:`cubedimer.cache_lock.cache_entry_lock`) and load its table.
    """
    key_settings = build_settings(spec, medium, particle_density, n_half, theta_max, forces, flux_disc_points)
    cached = Path(cache_dir or _cache_dir()) / f"fullwave_{_key(key_settings)}.json"
    sur = _stored_table(DEFAULT_TABLE, key_settings, gravity)
    if sur is None:
        with cache_entry_lock(cached, "this full-wave table"):  # a process that waited finds the first one's table
            sur = _stored_table(cached, key_settings, gravity)
            if sur is None:
                sur = build_fullwave_surrogate(spec, medium, particle_density, pressure_amplitude_pa, gravity, n_half,
                                               theta_max, forces=forces, flux_disc_points=flux_disc_points)
                try:
                    sur.save(cached)
                except OSError as exc:  # read-only install: keep the result in memory only
                    log.warning("could not cache the full-wave surrogate: %s", exc)
    return sur if sur.pressure_amplitude_pa == pressure_amplitude_pa else sur.with_pressure(pressure_amplitude_pa)


def _stored_table(path: Path, key_settings: dict, gravity: float) -> FullwaveSurrogate | None:
    """The table stored at ``path`` when it exists, can be read and was built with these settings, else None.

    A cached table that cannot be read is passed over with a warning, never fatal; the shipped default table must be
    readable."""
    if not path.exists():
        return None
    try:
        sur = FullwaveSurrogate.load(path)
    except Exception as exc:  # a cached table that cannot be read is rebuilt, never fatal
        if path == DEFAULT_TABLE:
            raise
        log.warning("the cached full-wave table %s cannot be read (%s: %s); building it again", path,
                    type(exc).__name__, exc)
        return None
    if build_settings_of(sur) != key_settings or sur.gravity != gravity:
        return None
    log.debug("full-wave surrogate from %s", path)
    return sur


def build_settings_of(sur: FullwaveSurrogate) -> dict:
    """The keyed build settings stored in a table."""
    s = sur.settings
    keys = list(build_settings(DEFAULT_SPEC, Medium(), DEFAULT_PARTICLE_DENSITY, 2, 0.5,
                               flux_disc_points=UNKEYED_FLUX_DISC_POINTS))
    out = {k: s.get(k) for k in keys}
    if s.get("h_edge") is not None:  # keyed only when set (meshes graded towards every edge)
        out["h_edge"] = s["h_edge"]
    if sur.flux_disc_points != UNKEYED_FLUX_DISC_POINTS:
        out["flux_disc_points"] = sur.flux_disc_points
    return out


def default_fullwave_surrogate(pressure_amplitude_pa: float = DEFAULT_PRESSURE_AMPLITUDE_PA) -> FullwaveSurrogate:
    """The shipped default dimer's table (side 500 um, g = 0.01 s, r_e = 0, 45.65 kHz) at p0 [Pa]."""
    sur = FullwaveSurrogate.load(DEFAULT_TABLE)
    return sur if pressure_amplitude_pa == sur.pressure_amplitude_pa else sur.with_pressure(pressure_amplitude_pa)


def coarse_fullwave_surrogate(**kwargs) -> FullwaveSurrogate:
    """The coarse variant (:data:`COARSE_BUILD`), cached on disk like any other."""
    return cached_fullwave_surrogate(**{**COARSE_BUILD, **kwargs})
