"""The simulation model of a data set: the Gor'kov dimer built from the data set's ``meta.json``.

Keys (all optional, FORMATS.md): side_length_m, particle_density_kg_m3, bulk_modulus_pa,
frequency_hz, sound_speed_m_s, air_density_kg_m3, pressure_amplitude_pa (nominal).
"""
from __future__ import annotations

import json
from pathlib import Path

from acousim import CubeDimer, GorkovDimer, Medium, ParticleMaterial, StandingWave

__all__ = ["read_meta", "model_from_meta"]

_KEYS = {
    "side_length_m": float,
    "particle_density_kg_m3": float,
    "bulk_modulus_pa": float,
    "frequency_hz": float,
    "sound_speed_m_s": float,
    "air_density_kg_m3": float,
    "pressure_amplitude_pa": float,
}


def read_meta(data_dir: str | Path) -> dict:
    """The data set's meta.json as a dict ({} if absent). Raises ValueError naming the file if unreadable."""
    path = Path(data_dir) / "meta.json"
    if not path.exists():
        return {}
    try:
        meta = json.loads(path.read_text())
    except (OSError, json.JSONDecodeError) as exc:
        raise ValueError(f"{path}: cannot read meta.json ({exc})") from None
    if not isinstance(meta, dict):
        raise ValueError(f"{path}: meta.json must hold a JSON object")
    for key, typ in _KEYS.items():
        if key in meta:
            try:
                meta[key] = typ(meta[key])
            except (TypeError, ValueError):
                raise ValueError(f"{path}: {key} must be a number, got {meta[key]!r}") from None
            if not meta[key] > 0:
                raise ValueError(f"{path}: {key} must be positive, got {meta[key]!r}")
    return meta


def model_from_meta(meta: dict, pressure_amplitude_pa: float | None = None, mesh_size: float | None = None) -> GorkovDimer:
    """GorkovDimer for the experiment described by ``meta`` (PHYSICS.md defaults for missing keys).

    ``pressure_amplitude_pa`` overrides the nominal pressure (e.g. a calibrated value).
    """
    material = ParticleMaterial(
        density_kg_m3=meta.get("particle_density_kg_m3", 2160.0),
        bulk_modulus_pa=meta.get("bulk_modulus_pa", 24.9e9),
    )
    medium = Medium(
        frequency_hz=meta.get("frequency_hz", 45_650.0),
        sound_speed_m_s=meta.get("sound_speed_m_s", 343.0),
        density_kg_m3=meta.get("air_density_kg_m3", 1.204),
    )
    p0 = pressure_amplitude_pa if pressure_amplitude_pa is not None else meta.get("pressure_amplitude_pa", 3000.0)
    dimer = CubeDimer(meta.get("side_length_m", 500e-6), material=material)
    return GorkovDimer(dimer, StandingWave(p0, medium, material), mesh_size=mesh_size)
