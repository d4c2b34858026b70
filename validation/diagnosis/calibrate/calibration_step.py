"""The diagnosis's first step, calibrate: the problem at the calibrated model (y's orientation, the model's own
parameters the data may determine, a pressure drift within runs), :func:`calibration_step`."""
from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import TYPE_CHECKING

from ..prepare.problem import DiagnosisProblem
from ..prepare.runs import prepare_diagnosis_runs
from .drift import detect_pressure_drift
from .model_parameters import calibrate_model_parameters
from .orientation import check_y_orientation

if TYPE_CHECKING:
    from acousim.models import ModelSpec

    from ..steps import DiagnoseConfig

__all__ = ["Calibrated", "calibration_step"]

logger = logging.getLogger(__name__)


@dataclass(frozen=True, eq=False)
class Calibrated:
    """The calibration step's outcome: the problem at the calibrated model, with what it decided."""

    problem: DiagnosisProblem
    conditions: object  #: the experiment conditions with the model's calibrated parameters
    parameters: dict  #: ParameterCalibration by field name
    data_warnings: list
    drift: object  #: DriftTest or None


def calibration_step(dataset, conditions, model, spec: "ModelSpec", config: "DiagnoseConfig", log) -> Calibrated:
    """The calibrated problem: from the starting ``model`` (the spec's at its default parameters), y's orientation,
    the model's own parameters the data may determine, and a pressure drift within runs (followed by the
    simulation)."""
    mtype = spec.type
    problem = DiagnosisProblem.from_recorded(model.interpolated(), prepare_diagnosis_runs(dataset),
                                             config.max_frames_per_run)
    data_warnings = []
    if config.check_orientation:
        orientation, flipped = check_y_orientation(problem, dataset, config.max_frames_per_run)
        if orientation.inverted:  # a flipped axis is never reported as new physics: the diagnosis uses -y
            warning = orientation.warning()
            logger.warning("%s", warning["message"])
            data_warnings.append(warning)
            problem = flipped
    # the model's own parameters the data may determine (the full-wave hinge gap), unless given; a pressure drift
    # found with the starting model is followed by every trial model (it is detected again below on the final one)
    calibrated_later = {n for n in mtype.calibration_ranges(conditions) if getattr(conditions, n) is None}
    first_drift = None
    if calibrated_later and config.drift is not None:
        first = detect_pressure_drift(problem, config.drift)
        first_drift = first.drift if first.detected else None
    conditions, parameters = calibrate_model_parameters(spec, conditions, problem.recorded_runs,
                                                        config.max_frames_per_run, log, drift=first_drift)
    if parameters:
        model = spec.static(conditions)
        problem = DiagnosisProblem.from_recorded(model.interpolated(), problem.recorded_runs,
                                                 config.max_frames_per_run)
    log("%d runs; calibrating pressure and height origin (first: a drift of the pressure within runs?)",
        len(problem.runs))
    drift = detect_pressure_drift(problem, config.drift) if config.drift is not None else None
    if drift is not None and drift.detected:
        log("pressure drift detected (relative amplitude %.3g, time scale %.2g s, p = %.2g): the simulation "
            "follows it", drift.relative_amplitude, drift.time_scale_s, drift.p_value)
        problem = problem.with_drift(drift.drift)
    return Calibrated(problem, conditions, parameters, data_warnings, drift)
