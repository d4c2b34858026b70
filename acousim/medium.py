"""Acoustic medium and particle material, and the Gor'kov contrast factors.

Defaults are those of docs/conventions.md section 1 (air at room temperature, NaCl, the
source paper's 45.650 kHz levitator).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from cubedimer.config_checks import check_positive
from cubedimer.meta import (DEFAULT_AIR_DENSITY_KG_M3, DEFAULT_BULK_MODULUS_PA, DEFAULT_FREQUENCY_HZ,
                            DEFAULT_PARTICLE_DENSITY, DEFAULT_SOUND_SPEED_M_S)

__all__ = ["Medium", "ParticleMaterial", "contrast_factors", "GRAVITY"]

#: Standard gravity [m/s^2] (docs/conventions.md section 1).
GRAVITY = 9.81


@dataclass(frozen=True)
class Medium:
    """The fluid carrying the standing wave.

    Parameters
    ----------
    frequency_hz : float
        Drive frequency f [Hz].
    sound_speed_m_s : float
        Speed of sound c0 [m/s].
    density_kg_m3 : float
        Fluid density rho0 [kg/m^3].
    """

    frequency_hz: float = DEFAULT_FREQUENCY_HZ
    sound_speed_m_s: float = DEFAULT_SOUND_SPEED_M_S
    density_kg_m3: float = DEFAULT_AIR_DENSITY_KG_M3

    def __post_init__(self) -> None:
        for name in ("frequency_hz", "sound_speed_m_s", "density_kg_m3"):
            check_positive(self, name)

    @property
    def wavelength(self) -> float:
        """Acoustic wavelength lambda = c0 / f [m]."""
        return self.sound_speed_m_s / self.frequency_hz

    @property
    def wavenumber(self) -> float:
        """Wavenumber k = 2 pi / lambda [1/m]."""
        return 2.0 * np.pi / self.wavelength

    @property
    def bulk_modulus(self) -> float:
        """Adiabatic bulk modulus rho0 c0^2 [Pa]."""
        return self.density_kg_m3 * self.sound_speed_m_s**2


@dataclass(frozen=True)
class ParticleMaterial:
    """Material of the levitated cubes.

    Parameters
    ----------
    density_kg_m3 : float
        Particle density rho_p [kg/m^3] (NaCl: 2160).
    bulk_modulus_pa : float
        Particle bulk modulus K_p [Pa] (NaCl: 24.9 GPa).
    """

    density_kg_m3: float = DEFAULT_PARTICLE_DENSITY
    bulk_modulus_pa: float = DEFAULT_BULK_MODULUS_PA

    def __post_init__(self) -> None:
        for name in ("density_kg_m3", "bulk_modulus_pa"):
            check_positive(self, name)


def contrast_factors(medium: Medium, material: ParticleMaterial) -> tuple[float, float]:
    """Monopole and dipole contrast factors of the Gor'kov potential.

    Returns
    -------
    f1, f2 : float
        ``f1 = 1 - rho0 c0^2 / K_p`` (compressibility contrast) and
        ``f2 = 2 (rho_p - rho0) / (2 rho_p + rho0)`` (density contrast), both dimensionless.
    """
    f1 = 1.0 - medium.bulk_modulus / material.bulk_modulus_pa
    rho_p, rho0 = material.density_kg_m3, medium.density_kg_m3
    f2 = 2.0 * (rho_p - rho0) / (2.0 * rho_p + rho0)
    return float(f1), float(f2)
