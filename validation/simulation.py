"""The simulation model of a data set: a :class:`acousim.models.ModelSpec` (the chosen model and its own options)
at the experiment of the data set's ``meta.json``, through the force-model registry.

Every model of :mod:`acousim.models` can be the simulation (``--model``): ``"gorkov"``, the Gor'kov volume
integral (docs/conventions.md, the acoustic model), and ``"fullwave"``, the boundary-element model of the dimer
from the full-wave table family (docs/fullwave.md).

Keys (all optional, docs/formats.md): side_length_m, particle_density_kg_m3, bulk_modulus_pa,
frequency_hz, sound_speed_m_s, air_density_kg_m3, pressure_amplitude_pa (nominal).
"""
from __future__ import annotations

from acousim.models import ExperimentConditions, ModelSpec, force_model_names
from cubedimer.meta import META_DEFAULTS

__all__ = ["model_from_meta", "simulation_models", "conditions_from_meta", "calibrated_model"]


def simulation_models() -> tuple[str, ...]:
    """The simulation models a diagnosis or report can calibrate (the registry's names)."""
    return force_model_names()


def conditions_from_meta(meta: dict, spec: ModelSpec = ModelSpec(), pressure_amplitude_pa: float | None = None
                         ) -> ExperimentConditions:
    """The experiment of ``meta`` (the docs/conventions.md defaults for missing keys) with the model's own options
    and, if given, another pressure amplitude [Pa] (e.g. a calibrated one)."""
    return spec.conditions({**META_DEFAULTS, **meta}, pressure_amplitude_pa=pressure_amplitude_pa)


def model_from_meta(meta: dict, spec: ModelSpec = ModelSpec(), pressure_amplitude_pa: float | None = None):
    """The static simulation model of the experiment described by ``meta``.

    Parameters
    ----------
    meta : dict
        The data set's meta.json.
    spec : ModelSpec
        The model and its own options (default: the Gor'kov model with its defaults).
    pressure_amplitude_pa : float, optional
        Overrides the nominal pressure [Pa] (e.g. a calibrated value).

    Returns
    -------
    acousim.static_model.StaticModel

    Raises
    ------
    ValueError
        An experiment outside what the model covers (one line, naming the setting), or a generic two-coordinate
        data set (not a levitated dimer).
    """
    from cubedimer.system import require_levitated_dimer
    require_levitated_dimer(meta, "validation")  # a generic two-coordinate set is refused in one line
    return spec.static(conditions_from_meta(meta, spec, pressure_amplitude_pa))


def calibrated_model(meta: dict, spec: ModelSpec, pressure_amplitude_pa: float, calibration: dict | None = None):
    """The static model of ``spec`` at a calibrated pressure [Pa], with the model's own parameters that a diagnosis
    calibrated (``calibration``: diagnosis.json's ``calibration``, which records every calibratable parameter by
    field name; None or a missing field: the spec's value or the model's default)."""
    from dataclasses import replace

    conditions = conditions_from_meta(meta, spec, pressure_amplitude_pa)
    fixed = {n: (calibration or {}).get(n) for n in spec.type.calibration_ranges(conditions)}
    return spec.static(replace(conditions, **{n: v for n, v in fixed.items() if v is not None}))
