"""The simulation model of a data set: the Gor'kov dimer built from the data set's ``meta.json``.

Keys (all optional, FORMATS.md): side_length_m, particle_density_kg_m3, bulk_modulus_pa,
frequency_hz, sound_speed_m_s, air_density_kg_m3, pressure_amplitude_pa (nominal).
"""
from __future__ import annotations

from acousim import CubeDimer, GorkovDimer, Medium, ParticleMaterial, StandingWave
from cubedimer.meta import META_DEFAULTS

__all__ = ["model_from_meta"]


def model_from_meta(meta: dict, pressure_amplitude_pa: float | None = None, mesh_size: float | None = None) -> GorkovDimer:
    """GorkovDimer for the experiment described by ``meta`` (PHYSICS.md defaults for missing keys).

    ``pressure_amplitude_pa`` overrides the nominal pressure (e.g. a calibrated value).
    """
    meta = {**META_DEFAULTS, **meta}
    material = ParticleMaterial(
        density_kg_m3=meta["particle_density_kg_m3"],
        bulk_modulus_pa=meta["bulk_modulus_pa"],
    )
    medium = Medium(
        frequency_hz=meta["frequency_hz"],
        sound_speed_m_s=meta["sound_speed_m_s"],
        density_kg_m3=meta["air_density_kg_m3"],
    )
    p0 = pressure_amplitude_pa if pressure_amplitude_pa is not None else meta["pressure_amplitude_pa"]
    dimer = CubeDimer(meta["side_length_m"], material=material)
    return GorkovDimer(dimer, StandingWave(p0, medium, material), mesh_size=mesh_size)
