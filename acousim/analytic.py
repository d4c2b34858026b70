"""Closed-form reference results (independent of any mesh), used to check the mesh integrals.

* :func:`cube_potential_energy`: the Gor'kov energy of a cube of any orientation in the (X, Z)
  plane, from the exact Fourier transform of a cube (a product of sincs).
* :func:`dimer_potential_energy` and :func:`dimer_generalized_forces`: the same for the
  mirror-symmetric dimer of docs/conventions.md, with Q_theta by differentiating the closed form.
* :func:`sphere_force_z`: volume-integrated force on a sphere, with its finite-size factor.
* :func:`point_particle_force_z` and :func:`vertical_trap_frequency`; :func:`nominal_trap_frequency` of a
  data set's meta.json (the loader's plausibility estimate).
"""
from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray
from cubedimer.meta import DEFAULT_PARTICLE_DENSITY

from .field import StandingWave
from .medium import GRAVITY

__all__ = [
    "cube_form_factor",
    "cube_potential_energy",
    "dimer_potential_energy",
    "dimer_generalized_forces",
    "sphere_force_z",
    "point_particle_force_z",
    "vertical_trap_frequency",
    "nominal_trap_frequency",
]


def _sinc(x: NDArray) -> NDArray:
    return np.sinc(np.asarray(x) / np.pi)


def _dsinc(x: NDArray) -> NDArray:
    x = np.asarray(x, float)
    small = np.abs(x) < 1e-4
    xs = np.where(small, 1.0, x)
    return np.where(small, -x / 3.0, (np.cos(xs) - np.sin(xs) / xs) / xs)


def cube_form_factor(ks: ArrayLike, psi: ArrayLike) -> NDArray[np.float64]:
    """S = (1/V) * integral over the cube of cos(2k dz), for a cube turned by psi about the Y axis.

    ``S = sinc(ks cos psi) sinc(ks sin psi)`` with sinc(x) = sin(x)/x: the cube's Fourier transform
    at wavevector 2k Z-hat.  Dimensionless.
    """
    ks, psi = np.asarray(ks, float), np.asarray(psi, float)
    return _sinc(ks * np.cos(psi)) * _sinc(ks * np.sin(psi))


def cube_potential_energy(side: float, psi: ArrayLike, z_centre: ArrayLike, wave: StandingWave) -> NDArray[np.float64]:
    """Exact volume integral of u(Z) over a cube of side ``side`` [m] turned by ``psi`` [rad] about Y,
    centred at height ``z_centre`` [m] above the node.  Returns joules."""
    a0, a2 = wave.harmonic_coefficients
    k = wave.wavenumber
    v = side**3
    return v * (a0 - a2 * np.cos(2 * k * np.asarray(z_centre, float)) * cube_form_factor(k * side, psi))


def dimer_potential_energy(side: float, theta: ArrayLike, z_com: ArrayLike, wave: StandingWave) -> NDArray[np.float64]:
    """U_ac [J] of the mirror-symmetric dimer: both centres at Z_com, cubes turned by +-(pi/4 - phi)."""
    phi = np.pi * np.asarray(theta, float) / 4
    return 2.0 * cube_potential_energy(side, np.pi / 4 - phi, z_com, wave)


def dimer_generalized_forces(
    side: float, theta: ArrayLike, z_com: ArrayLike, wave: StandingWave, density: float = DEFAULT_PARTICLE_DENSITY,
    gravity: float = GRAVITY
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """(F_Z [N], Q_y [N], Q_theta [N m]) of the symmetric dimer from the closed form.

    Q_theta = -dU/dtheta at fixed Z_com, differentiated analytically.
    """
    theta = np.asarray(theta, float)
    z = np.asarray(z_com, float)
    a0, a2 = wave.harmonic_coefficients
    k = wave.wavenumber
    ks = k * side
    v2 = 2 * side**3
    psi = np.pi / 4 - np.pi * theta / 4
    s = cube_form_factor(ks, psi)
    force = -v2 * a2 * 2 * k * np.sin(2 * k * z) * s
    # dS/dpsi
    ds = ks * (-np.sin(psi) * _dsinc(ks * np.cos(psi)) * _sinc(ks * np.sin(psi))
               + np.cos(psi) * _sinc(ks * np.cos(psi)) * _dsinc(ks * np.sin(psi)))
    dpsi_dtheta = -np.pi / 4
    # U = v2 (a0 - a2 cos(2kz) S)  ->  -dU/dtheta = v2 a2 cos(2kz) dS/dpsi dpsi/dtheta
    q_theta = v2 * a2 * np.cos(2 * k * z) * ds * dpsi_dtheta
    q_y = force - density * v2 * gravity
    return force, q_y, q_theta


def sphere_force_z(radius: float, height: ArrayLike, wave: StandingWave) -> NDArray[np.float64]:
    """Volume-integrated Gor'kov force [N] on a sphere of radius a centred at height h:

    ``F_Z = -3 Phi V k E_ac sin(2kh) * 3 j1(2ka) / (2ka)``.
    """
    from scipy.special import spherical_jn

    k = wave.wavenumber
    x = 2 * k * radius
    v = 4.0 / 3.0 * np.pi * radius**3
    size_factor = 3 * spherical_jn(1, x) / x
    return point_particle_force_z(v, height, wave) * size_factor


def point_particle_force_z(volume: float, height: ArrayLike, wave: StandingWave) -> NDArray[np.float64]:
    """Small-particle Gor'kov force [N]: ``F_Z = -3 Phi V k E_ac sin(2kh)``."""
    k = wave.wavenumber
    return -3 * wave.acoustic_contrast * volume * k * wave.acoustic_energy_density * np.sin(2 * k * np.asarray(height, float))


def vertical_trap_frequency(mass: float, volume: float, wave: StandingWave, gravity: float = GRAVITY, size_factor: float = 1.0) -> float:
    """Small-amplitude vertical trap frequency [Hz] of a particle of ``mass`` and ``volume``.

    F_Z = -F0 sin(2kZ) with F0 = 3 Phi V k E_ac * size_factor; equilibrium sin(2kZ_eq) = -M g / F0;
    stiffness 2k F0 cos(2kZ_eq).  ``size_factor`` is the finite-size form factor (1 for a point,
    3 j1(2ka)/(2ka) for a sphere, the cube form factor S for cubes).
    """
    k = wave.wavenumber
    f0 = 3 * wave.acoustic_contrast * volume * k * wave.acoustic_energy_density * size_factor
    ratio = mass * gravity / f0
    if ratio >= 1:
        raise ValueError("field too weak to levitate the particle")
    stiffness = 2 * k * f0 * np.sqrt(1 - ratio**2)
    return float(np.sqrt(stiffness / mass) / (2 * np.pi))


def nominal_trap_frequency(meta) -> float:
    """Small-particle Gor'kov estimate of the vertical trap frequency [Hz] at a data set's nominal pressure.

    ``meta`` is a validated meta.json mapping (:func:`cubedimer.meta.read_meta`; defaults stand in for missing
    keys).  For a particle small against the wavelength, u(Z) = E [f1 sin^2 kZ - 3/2 f2 cos^2 kZ] per unit
    volume with E = p0^2 / (4 rho0 c0^2); the levitation height solves E k (f1 + 3/2 f2) sin(-2 k Z_eq) = rho_p g
    and the stiffness per unit mass there is omega^2 = 2 E k^2 (f1 + 3/2 f2) cos(2 k Z_eq) / rho_p.  Independent
    of the particle's size and shape to leading order (the cube dimer's finite size lowers it by ~3 % at the
    defaults).  NaN when the field cannot levitate the particle.  The data-set loader takes it as its
    ``trap_frequency`` plausibility estimate (:class:`cubedimer.dataset.LoadConfig`).
    """
    import math

    from cubedimer.meta import META_DEFAULTS

    m = {**META_DEFAULTS, **dict(meta)}
    rho0, c0, f = m["air_density_kg_m3"], m["sound_speed_m_s"], m["frequency_hz"]
    rho_p, k_p, p0 = m["particle_density_kg_m3"], m["bulk_modulus_pa"], m["pressure_amplitude_pa"]
    f1 = 1.0 - rho0 * c0**2 / k_p
    f2 = 2.0 * (rho_p - rho0) / (2.0 * rho_p + rho0)
    k = 2.0 * math.pi * f / c0
    e = p0**2 / (4.0 * rho0 * c0**2)
    strength = e * k * (f1 + 1.5 * f2)
    s = rho_p * GRAVITY / strength
    if not 0 <= s < 1:
        return float("nan")
    omega2 = 2.0 * e * k**2 * (f1 + 1.5 * f2) * math.sqrt(1.0 - s * s) / rho_p
    return math.sqrt(omega2) / (2.0 * math.pi)
