"""The simulation model of a data set, built from the data set's ``meta.json`` through the force-model registry.

Every model of :mod:`acousim.models` can be the simulation (``--model``): ``"gorkov"``, the Gor'kov volume
integral (docs/conventions.md, the acoustic model), and ``"fullwave"``, the boundary-element model of the dimer
from the full-wave table family (docs/fullwave.md).

Keys (all optional, docs/formats.md): side_length_m, particle_density_kg_m3, bulk_modulus_pa,
frequency_hz, sound_speed_m_s, air_density_kg_m3, pressure_amplitude_pa (nominal).
"""
from __future__ import annotations

from acousim.models import ExperimentConditions, force_model_names, static_model
from cubedimer.meta import META_DEFAULTS

__all__ = ["model_from_meta", "simulation_models", "conditions_from_meta"]


def simulation_models() -> tuple[str, ...]:
    """The simulation models a diagnosis or report can calibrate (the registry's names)."""
    return force_model_names()


def conditions_from_meta(meta: dict, pressure_amplitude_pa: float | None = None, mesh_size: float | None = None,
                         gap: float | None = None, edge_radius: float | None = None) -> ExperimentConditions:
    """The experiment of ``meta`` (defaults for missing keys) with the given overrides (None: not set)."""
    return ExperimentConditions.from_meta({**META_DEFAULTS, **meta}, pressure_amplitude_pa=pressure_amplitude_pa,
                                          mesh_size_m=mesh_size, gap_m=gap, edge_radius_m=edge_radius)


def model_from_meta(meta: dict, pressure_amplitude_pa: float | None = None, mesh_size: float | None = None,
                    model: str = "gorkov", gap: float | None = None, edge_radius: float | None = None):
    """The static simulation model of the experiment described by ``meta``.

    Parameters
    ----------
    meta : dict
        The data set's meta.json.
    pressure_amplitude_pa : float, optional
        Overrides the nominal pressure [Pa] (e.g. a calibrated value).
    mesh_size : float, optional
        Tetrahedron size of the Gor'kov model [m] (refused by the full-wave model).
    model : str
        A registered model name (:func:`simulation_models`).
    gap, edge_radius : float, optional
        Hinge gap and edge radius [m] of the full-wave model (refused by the Gor'kov model).

    Returns
    -------
    acousim.static_model.StaticModel

    Raises
    ------
    ValueError
        Unknown model, an option the model does not take, or an experiment outside what the model covers
        (one line, naming the setting).
    """
    from cubedimer.system import require_levitated_dimer
    require_levitated_dimer(meta, "validation")  # a generic two-coordinate set is refused in one line
    conditions = conditions_from_meta(meta, pressure_amplitude_pa, mesh_size, gap, edge_radius)
    return static_model(model, conditions)
