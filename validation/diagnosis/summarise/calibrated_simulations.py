"""The calibrated simulations side by side, as stored results: diagnosis.json's ``model_comparison`` and ``overlay``.

A report is a view of stored results: everything its sections print about the simulations is computed here once, from
the diagnosis's problem and fits, and written into diagnosis.json (docs/formats.md):

* :func:`model_comparison_record`: the gaps of every registered force model calibrated on the runs
  (:func:`~validation.diagnosis.summarise.model_comparison.compare_simulation_models`), and per model its calibration,
  its static coefficients over the data's box (least squares on a static sweep,
  :func:`acousim.statics.sweep.fit_static_coefficients`) and the restoring force and torque curves the report plots;
* :func:`overlay_record`: one run's data against the calibrated simulation with the identified effects, started from
  the run's first state (the report's time-series overlay).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Mapping

import numpy as np

from .long_time import simulate_from_first_state

if TYPE_CHECKING:
    from acousim.models import ModelSpec

    from .model_comparison import ModelComparison
    from .result import DiagnosisInternals

__all__ = ["SimulationRecord", "model_comparison_record", "overlay_record", "static_box", "OVERLAY_POINTS",
           "OVERLAY_DURATION_S"]

#: The overlay's frames are thinned to at most this many (diagnosis.json stays small; the plot stays readable).
OVERLAY_POINTS = 800
#: Seconds of the overlay's run simulated [s] (the long-time errors' duration).
OVERLAY_DURATION_S = 2.0
#: Grid of the restoring curves: theta over [-0.9, 0.9] (61 points), y over +-1.3 times the box (41 points).
_CURVE_THETA = np.linspace(-0.9, 0.9, 61)
_CURVE_Y_POINTS, _CURVE_Y_SPAN = 41, 1.3


@dataclass(frozen=True)
class SimulationRecord:
    """One registered force model calibrated on the data set (diagnosis.json ``model_comparison.simulations[i]``).

    Attributes
    ----------
    name, label : the registry name and the model's label in tables and prose
    pressure_amplitude_pa, nominal_pressure_pa : calibrated and nominal pressure amplitude [Pa]
    origin_offset_m : the data's y origin above the model's calibrated Z_eq [m]
    equilibrium_height_m : the calibration's Z_eq at the calibrated pressure [m] (the effects' y origin)
    model_equilibrium_height_m : the calibrated static model's own equilibrium height [m] (below the node: negative)
    wavenumber : the standing wave's wavenumber [1/m]
    static_coefficients, static_std_errors : equation -> term -> value [SI], y from the calibrated Z_eq, fitted over
        ``static_fit_box``
    static_fit_box : the box of the static fit (theta and y ranges)
    parameters : the model's own parameters it was built with (the full-wave hinge gap ``gap_m`` [m]), by field name
    parameter_sources : where each came from: ``"calibrated"`` (the diagnosis's calibration), ``"option"`` or
        ``"model default"``
    curves : the restoring force at theta = 0 (``y_m``, ``yddot``) and torque at y = 0 (``theta``, ``thetaddot``),
        y from the calibrated Z_eq
    """

    name: str
    label: str
    pressure_amplitude_pa: float
    nominal_pressure_pa: float
    origin_offset_m: float
    equilibrium_height_m: float
    model_equilibrium_height_m: float
    wavenumber: float
    static_coefficients: Mapping[str, Mapping[str, float]]
    static_std_errors: Mapping[str, Mapping[str, float]]
    static_fit_box: Mapping[str, Any]
    curves: Mapping[str, list]
    parameters: Mapping[str, float] = None
    parameter_sources: Mapping[str, str] = None

    def to_dict(self) -> dict:
        return {"name": self.name, "label": self.label, "pressure_amplitude_pa": self.pressure_amplitude_pa,
                "nominal_pressure_pa": self.nominal_pressure_pa, "origin_offset_m": self.origin_offset_m,
                "equilibrium_height_m": self.equilibrium_height_m,
                "model_equilibrium_height_m": self.model_equilibrium_height_m, "wavenumber": self.wavenumber,
                "static_coefficients": {eq: dict(v) for eq, v in self.static_coefficients.items()},
                "static_std_errors": {eq: dict(v) for eq, v in self.static_std_errors.items()},
                "static_fit_box": dict(self.static_fit_box), "curves": {k: list(v) for k, v in self.curves.items()},
                "parameters": dict(self.parameters or {}), "parameter_sources": dict(self.parameter_sources or {})}

    @classmethod
    def from_dict(cls, doc: Mapping[str, Any]) -> "SimulationRecord":
        return cls(doc["name"], doc["label"], float(doc["pressure_amplitude_pa"]), float(doc["nominal_pressure_pa"]),
                   float(doc["origin_offset_m"]), float(doc["equilibrium_height_m"]),
                   float(doc["model_equilibrium_height_m"]), float(doc["wavenumber"]),
                   doc["static_coefficients"], doc["static_std_errors"], doc["static_fit_box"], doc["curves"],
                   doc.get("parameters") or {}, doc.get("parameter_sources") or {})


def static_box(states: np.ndarray, origin_offset_m: float) -> tuple[float, float]:
    """The box of the static fits: the 98 % quantiles of |theta| (at most 0.9) and of |y| [m], y of the fitted
    ``states`` (n, 4) measured from the reference model's calibrated Z_eq (``origin_offset_m`` above it)."""
    theta_max = float(min(0.9, np.quantile(np.abs(states[:, 2]), 0.98)))
    y_max = float(np.quantile(np.abs(states[:, 0] + origin_offset_m), 0.98))
    return theta_max, y_max


def model_comparison_record(models: "ModelComparison", internals: "DiagnosisInternals", spec: "ModelSpec", meta: dict,
                            calibration: Mapping[str, Any], states: np.ndarray) -> tuple[dict, dict]:
    """diagnosis.json's ``model_comparison`` and the calibrated static models by name (for the rendered mesh).

    Parameters
    ----------
    models : the side-by-side gaps (:func:`compare_simulation_models` on the diagnosis's problem)
    internals : the diagnosis's problem and fits (its model's row is the diagnosis's final calibration)
    spec : the diagnosis's model and its own options
    meta : the data set's meta.json
    calibration : diagnosis.json's ``calibration`` (the model's calibrated parameters, e.g. the hinge gap)
    states : the fitted runs' states (n, 4), stacked: the box of the static fits (:func:`static_box`)
    """
    from acousim.models import ModelSpec, force_model_type
    from acousim.statics.sweep import fit_static_coefficients, static_sweep

    from ...coefficients import STATIC_GRID_POINTS
    from ...simulation import calibrated_model

    # each simulation at its own calibration: the diagnosis's final one for its model, the bare one for the others
    cals = {k: f.calibration for k, f in models.fits.items() if "+" not in k}
    cals[spec.name] = internals.final.calibration
    reference = models.rows[0].model
    theta_max, y_max = static_box(states, cals[reference].origin_offset_m)
    records, statics = [], {}
    for name, cal in cals.items():
        own = spec if name == spec.name else ModelSpec(name)
        static = calibrated_model(meta, own, cal.pressure_amplitude_pa, calibration if own is spec else None)
        statics[name] = static
        parameters, sources = _own_parameters(own, meta, calibration if own is spec else {}, cal.pressure_amplitude_pa)
        box = static_sweep(static, np.linspace(-theta_max, theta_max, STATIC_GRID_POINTS),
                           np.linspace(-y_max, y_max, STATIC_GRID_POINTS))
        coef = fit_static_coefficients(box, theta_max=theta_max, y_max=y_max)
        plot = static_sweep(static, _CURVE_THETA, np.linspace(-_CURVE_Y_SPAN * y_max, _CURVE_Y_SPAN * y_max,
                                                              _CURVE_Y_POINTS))
        i0, j0 = int(np.argmin(np.abs(plot.theta_grid))), int(np.argmin(np.abs(plot.y_grid)))
        curves = {"y_m": plot.y_grid.tolist(), "yddot": np.asarray(plot["yddot"][i0]).tolist(),
                  "theta": plot.theta_grid.tolist(), "thetaddot": np.asarray(plot["thetaddot"][:, j0]).tolist()}
        records.append(SimulationRecord(name, force_model_type(name).label, cal.pressure_amplitude_pa,
                                        cal.nominal_pressure_pa, cal.origin_offset_m, cal.equilibrium_height_m,
                                        float(static.equilibrium_height), float(static.wave.wavenumber), coef.coefficients, coef.std_errors, coef.box,
                                        curves, parameters, sources).to_dict())
    doc = {**models.to_dict(), "static_box": {"theta_max": theta_max, "y_max_m": y_max,
                                              "definition": "98 % quantiles of the fitted runs' |theta| (at most 0.9) "
                                                            "and |y| from the reference model's calibrated Z_eq"},
           "simulations": records}
    return doc, statics


def _own_parameters(spec: "ModelSpec", meta: dict, calibration: Mapping[str, Any], pressure_pa: float
                    ) -> tuple[dict, dict]:
    """The model's own calibratable parameters as :func:`validation.simulation.calibrated_model` builds it, and where
    each came from."""
    from ...simulation import conditions_from_meta

    conditions = conditions_from_meta(meta, spec, pressure_pa)
    values, sources = {}, {}
    for name, (_, _, default) in spec.type.calibration_ranges(conditions).items():
        if calibration.get(name) is not None:
            values[name] = float(calibration[name])
            sources[name] = "calibrated" if calibration.get(f"{name.rsplit('_', 1)[0]}_calibrated") else (
                "option" if name in dict(spec.options) else "model default")
        elif getattr(conditions, name) is not None:
            values[name], sources[name] = float(getattr(conditions, name)), "option"
        else:
            values[name], sources[name] = float(default), "model default"
    return values, sources


def overlay_record(internals: "DiagnosisInternals", run_index: int = 0, duration_s: float = OVERLAY_DURATION_S,
                   max_points: int = OVERLAY_POINTS) -> dict:
    """diagnosis.json's ``overlay``: the run ``run_index``'s smoothed (t, y, theta) against the calibrated simulation
    with the identified effects, started from its first state, over ``duration_s`` seconds, thinned to at most
    ``max_points`` frames; ``simulated_frames``: how many frames the simulation covers before leaving the trap."""
    run = internals.problem.recorded_runs[run_index]
    t, sim, m, message = simulate_from_first_state(internals.problem, internals.final, run, duration_s)
    step = max(1, int(np.ceil(len(t) / max_points)))
    keep = np.arange(0, len(t), step)
    data = run.state[:len(t)]
    return {"run": run.name, "t_s": t[keep].tolist(), "data": {"y_m": data[keep, 0].tolist(),
                                                               "theta": data[keep, 2].tolist()},
            "first_state": run.state[0].tolist(),
            "simulation": {"y_m": sim[keep, 0].tolist(), "theta": sim[keep, 2].tolist(), "effects": dict(
                internals.final.effects), "simulated_frames": int(np.searchsorted(keep, m)), "message": message}}
