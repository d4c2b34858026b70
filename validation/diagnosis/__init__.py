"""Diagnose the sim-to-real gap: where it lies, which unmodelled effect causes it, how far it shrinks.

"Sim" is the Gor'kov model of docs/conventions.md section 4 (or the full-wave model of section 7) calibrated to the data; "real" is any data set in
the docs/formats.md format.  Every candidate effect of docs/conventions.md section 5 is linear in its parameters, so
every fit here is a linear least-squares problem at the measured states.  One module per step:

* :mod:`~validation.diagnosis.preparation`: runs -> smoothed states, accelerations, noise levels and
  the integral-form data (:func:`prepare_diagnosis_runs`, :class:`RunAccelerations`);
* :mod:`~validation.diagnosis.problem`: :class:`DiagnosisProblem`, the model and runs of one data set
  and what is computed once for them;
* :mod:`~validation.diagnosis.simulation_model`: the simulation's terms at the measured states;
* :mod:`~validation.diagnosis.candidates`: the candidate effects as linear regressors;
* :mod:`~validation.diagnosis.calibration`: pressure and origin from the vertical equation;
* :mod:`~validation.diagnosis.orientation`: whether y points down, told by the trap's asymmetry;
* :mod:`~validation.diagnosis.drift`: the pressure per time window within runs, and the test of its drift;
* :mod:`~validation.diagnosis.gap_model`: the calibrated simulation plus effects, fitted
  (:func:`fit_gap_model`), and its residuals;
* :mod:`~validation.diagnosis.metrics`: the gap components and the scalar gap;
* :mod:`~validation.diagnosis.statistics` and :mod:`~validation.diagnosis.identification`: held-out
  (K-fold) identification with the sign-flip test and practical thresholds;
* :mod:`~validation.diagnosis.discovery`: the library terms that carry what no candidate explains, and the
  energy-balance form of the dissipations;
* :mod:`~validation.diagnosis.joint_model`: the identified candidates judged against the discovered terms, and the
  final joint model of the identified effects with them (:func:`~validation.diagnosis.joint_model.joint_estimates`);
* :mod:`~validation.diagnosis.localization`: where the residual lies (terms, regions, time scales);
* :mod:`~validation.diagnosis.long_time`: attractor, Poincare and frequency errors;
* :mod:`~validation.diagnosis.verdicts`: every candidate's verdict, ranked;
* :mod:`~validation.diagnosis.result`: the typed result, :class:`Diagnosis` (``to_json``/``from_json``: diagnosis.json);
* :mod:`~validation.diagnosis.pipeline`: :func:`diagnose` of a loaded data set as named steps (calibrate, identify,
  discover, summarise), :func:`diagnose_dataset` of a path (its files: :func:`validation.report.write_diagnosis`);
* :mod:`~validation.diagnosis.model_comparison`: the gaps of Gor'kov, Gor'kov + fitted pair scattering and
  the full-wave model side by side (:func:`compare_simulation_models`).

The method, its tests and the blind check are described in docs/diagnosis.md.
"""
from __future__ import annotations

from .calibration import Calibration
from .candidates import CANDIDATE_EFFECTS, effect_regressors
from .discovery import Discovery
from .drift import PressureDrift
from .gap_model import GapFit
from .identification import Identification
from .long_time import LongTimeGap
from .model_comparison import ModelComparison, ModelGap, compare_simulation_models
from .pipeline import DiagnoseConfig, EXPLAINED_GAP, diagnose, diagnose_dataset, load_for_diagnosis
from .problem import DiagnosisProblem
from .result import Diagnosis, DiagnosisInternals, EffectVerdict

__all__ = [
    "diagnose", "diagnose_dataset", "load_for_diagnosis", "Diagnosis", "EffectVerdict", "DiagnoseConfig",
    "DiagnosisInternals", "EXPLAINED_GAP", "CANDIDATE_EFFECTS", "effect_regressors",
    "compare_simulation_models", "ModelComparison", "ModelGap", "DiagnosisProblem", "GapFit", "Calibration",
    "Identification", "Discovery", "PressureDrift", "LongTimeGap",
]
