"""The single-node standing wave and the Gor'kov potential density (docs/conventions.md section 3).

The pressure node is at Z = 0; ``p(Z, t) = p0 sin(kZ) cos(wt)``.  The Gor'kov potential energy per
unit particle volume is::

    u(Z) = E_ac [ f1 sin^2(kZ) - (3/2) f2 cos^2(kZ) ],      E_ac = p0^2 / (4 rho0 c0^2)
         = E_ac [ (f1 - 3 f2 / 2) / 2  -  (f1 + 3 f2 / 2) / 2 * cos(2kZ) ]

and only its Z derivative is non-zero: ``du/dZ = E_ac k (f1 + 3 f2 / 2) sin(2kZ)``.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from cubedimer.meta import DEFAULT_PRESSURE_AMPLITUDE_PA

from .medium import Medium, ParticleMaterial, contrast_factors

__all__ = ["StandingWave", "gorkov_potential_density", "gorkov_potential_gradient"]


@dataclass(frozen=True)
class StandingWave:
    """A plane standing wave along Z acting on particles of one material.

    Parameters
    ----------
    pressure_amplitude_pa : float
        Pressure amplitude p0 [Pa] (default 3 kPa, docs/conventions.md section 1).
    medium : Medium
        The fluid.
    material : ParticleMaterial
        The particle material (enters through the contrast factors).
    """

    pressure_amplitude_pa: float = DEFAULT_PRESSURE_AMPLITUDE_PA
    medium: Medium = field(default_factory=Medium)
    material: ParticleMaterial = field(default_factory=ParticleMaterial)

    def __post_init__(self) -> None:
        p0 = self.pressure_amplitude_pa
        if not np.isfinite(p0) or p0 <= 0:
            raise ValueError(f"pressure amplitude must be positive and finite, got {p0!r} Pa")

    @property
    def wavenumber(self) -> float:
        """k [1/m]."""
        return self.medium.wavenumber

    @property
    def acoustic_energy_density(self) -> float:
        """E_ac = p0^2 / (4 rho0 c0^2) [J/m^3]."""
        m = self.medium
        return self.pressure_amplitude_pa**2 / (4.0 * m.density_kg_m3 * m.sound_speed_m_s**2)

    @property
    def contrast_factors(self) -> tuple[float, float]:
        """(f1, f2), dimensionless."""
        return contrast_factors(self.medium, self.material)

    @property
    def acoustic_contrast(self) -> float:
        """Phi = f1 / 3 + f2 / 2 (dimensionless)."""
        f1, f2 = self.contrast_factors
        return f1 / 3.0 + f2 / 2.0

    @property
    def harmonic_coefficients(self) -> tuple[float, float]:
        """(A0, A2) [J/m^3] such that ``u(Z) = A0 - A2 cos(2kZ)``.

        A0 = E_ac (f1 - 3 f2/2) / 2 and A2 = E_ac (f1 + 3 f2/2) / 2 = 3 Phi E_ac / 2.
        """
        f1, f2 = self.contrast_factors
        e = self.acoustic_energy_density
        return 0.5 * e * (f1 - 1.5 * f2), 0.5 * e * (f1 + 1.5 * f2)

    def with_pressure(self, pressure_amplitude_pa: float) -> "StandingWave":
        """The same wave at another pressure amplitude."""
        return StandingWave(pressure_amplitude_pa, self.medium, self.material)


def gorkov_potential_density(z: ArrayLike, wave: StandingWave) -> NDArray[np.float64]:
    """Gor'kov potential energy per unit particle volume u(Z) [J/m^3].

    Parameters
    ----------
    z : array_like
        Height above the pressure node [m].
    wave : StandingWave
        Field and material.
    """
    z = np.asarray(z, dtype=float)
    f1, f2 = wave.contrast_factors
    kz = wave.wavenumber * z
    return wave.acoustic_energy_density * (f1 * np.sin(kz) ** 2 - 1.5 * f2 * np.cos(kz) ** 2)


def gorkov_potential_gradient(z: ArrayLike, wave: StandingWave) -> NDArray[np.float64]:
    """Analytic gradient du/dZ [J/m^4] of the Gor'kov potential density (the only non-zero component).

    The force density on the particle is ``-du/dZ`` along +Z [N/m^3].
    """
    z = np.asarray(z, dtype=float)
    _, a2 = wave.harmonic_coefficients
    k = wave.wavenumber
    return 2.0 * k * a2 * np.sin(2.0 * k * z)
