"""The simulation model of a data set, built from the data set's ``meta.json``.

Two simulation models (docs/formats.md ``--model``): ``"gorkov"``, the Gor'kov volume integral of docs/conventions.md
section 3 (:class:`acousim.GorkovDimer`), and ``"fullwave"``, the boundary-element table of the default dimer
(docs/conventions.md section 7, :class:`acousim.fullwave.FullwaveDimer`).

Keys (all optional, docs/formats.md): side_length_m, particle_density_kg_m3, bulk_modulus_pa,
frequency_hz, sound_speed_m_s, air_density_kg_m3, pressure_amplitude_pa (nominal).
"""
from __future__ import annotations

from acousim import CubeDimer, GorkovDimer, Medium, ParticleMaterial, StandingWave
from cubedimer.meta import META_DEFAULTS

__all__ = ["model_from_meta", "SIMULATION_MODELS"]

#: The simulation models a diagnosis or report can calibrate.
SIMULATION_MODELS = ("gorkov", "fullwave")


def model_from_meta(meta: dict, pressure_amplitude_pa: float | None = None, mesh_size: float | None = None,
                    model: str = "gorkov"):
    """The simulation model of the experiment described by ``meta`` (docs/conventions.md defaults for missing keys).

    Parameters
    ----------
    meta : dict
        The data set's meta.json.
    pressure_amplitude_pa : float, optional
        Overrides the nominal pressure [Pa] (e.g. a calibrated value).
    mesh_size : float, optional
        Tetrahedron size of the Gor'kov model [m] (refused for the full-wave model).
    model : {"gorkov", "fullwave"}
        Which simulation model.

    Returns
    -------
    acousim.GorkovDimer or acousim.fullwave.FullwaveDimer

    Raises
    ------
    ValueError
        Unknown model, or an experiment the full-wave table was not built for
        (:class:`acousim.fullwave.statics.TableMismatch`, naming the setting).
    """
    meta = {**META_DEFAULTS, **meta}
    p0 = pressure_amplitude_pa if pressure_amplitude_pa is not None else meta["pressure_amplitude_pa"]
    if model == "fullwave":
        from acousim.fullwave.statics import default_fullwave_dimer

        if mesh_size is not None:
            raise ValueError("a mesh size applies to the Gor'kov model only, not to the full-wave table")
        fw = default_fullwave_dimer(float(p0))
        fw.check_experiment(meta)
        return fw
    if model != "gorkov":
        raise ValueError(f"unknown simulation model {model!r}; choose one of {', '.join(SIMULATION_MODELS)}")
    material = ParticleMaterial(
        density_kg_m3=meta["particle_density_kg_m3"],
        bulk_modulus_pa=meta["bulk_modulus_pa"],
    )
    medium = Medium(
        frequency_hz=meta["frequency_hz"],
        sound_speed_m_s=meta["sound_speed_m_s"],
        density_kg_m3=meta["air_density_kg_m3"],
    )
    dimer = CubeDimer(meta["side_length_m"], material=material)
    return GorkovDimer(dimer, StandingWave(p0, medium, material), mesh_size=mesh_size)
