"""Closed-form reference results (independent of any mesh), used to check the mesh integrals.

* :func:`cube_potential_energy`: the Gor'kov energy of a cube of any orientation in the (X, Z)
  plane, from the exact Fourier transform of a cube (a product of sincs).
* :func:`dimer_potential_energy` and :func:`dimer_generalized_forces`: the same for the
  mirror-symmetric dimer of PHYSICS.md, with Q_theta by differentiating the closed form.
* :func:`sphere_force_z`: volume-integrated force on a sphere, with its finite-size factor.
* :func:`point_particle_force_z` and :func:`vertical_trap_frequency`.
"""
from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .field import StandingWave

__all__ = [
    "cube_form_factor",
    "cube_potential_energy",
    "dimer_potential_energy",
    "dimer_generalized_forces",
    "sphere_force_z",
    "point_particle_force_z",
    "vertical_trap_frequency",
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
    side: float, theta: ArrayLike, z_com: ArrayLike, wave: StandingWave, density: float = 2160.0, gravity: float = 9.81
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


def vertical_trap_frequency(mass: float, volume: float, wave: StandingWave, gravity: float = 9.81, size_factor: float = 1.0) -> float:
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
