"""Diagnose the sim-to-real gap: where it lies, which unmodelled effect causes it, how far it shrinks.

"Sim" is the Gor'kov model of docs/conventions.md section 4 (or the full-wave model of section 7) calibrated to the data; "real" is any data set in
the docs/formats.md format.  Every candidate effect of docs/conventions.md section 5 is linear in its parameters, so
every fit here is a linear least-squares problem at the measured states.  One subpackage per step, run in this
order by :func:`~validation.diagnosis.steps.diagnose` (:mod:`~validation.diagnosis.steps`, with
:func:`diagnose_dataset` of a path; its files: :func:`validation.report.write_diagnosis`):

* :mod:`~validation.diagnosis.prepare`: the runs' states and accelerations (the diagnosis's view of the data set's
  one preparation, :func:`fitting.derivatives.preparation.prepare_dataset`, which the fit reads too), the problem, the simulation's terms at
  the measured states and the candidate effects as linear regressors, computed once;
* :mod:`~validation.diagnosis.calibrate`: pressure, origin, orientation, the model's own parameters and the pressure
  drift; the calibrated simulation plus effects (:func:`fit_gap_model`) and the gap metrics;
* :mod:`~validation.diagnosis.identify`: held-out (K-fold) identification of the candidate effects with the sign-flip
  test and practical thresholds, and the backward check;
* :mod:`~validation.diagnosis.discover`: the library terms no candidate explains, and the joint model of the
  identified effects with them;
* :mod:`~validation.diagnosis.summarise`: every candidate's verdict, localisation, long-time errors, the comparison of
  the simulation models (:func:`compare_simulation_models`) and the typed result, :class:`Diagnosis`.

The method, its tests and the blind check are described in docs/diagnosis.md.
"""
from __future__ import annotations

from .calibrate.calibration import Calibration
from .calibrate.drift import PressureDrift
from .calibrate.gap_model import GapFit
from .discover.library_terms import Discovery
from .identify.identification import Identification
from .prepare.candidate_effects import CANDIDATE_EFFECTS, effect_regressors
from .prepare.problem import DiagnosisProblem
from .steps import (DiagnoseConfig, DiagnosisStart, EXPLAINED_GAP, diagnose, diagnose_dataset, load_for_diagnosis,
                    start_diagnosis)
from .summarise.long_time import LongTimeGap
from .summarise.model_comparison import ModelComparison, ModelGap, compare_simulation_models
from .summarise.result import Diagnosis, DiagnosisInternals, EffectVerdict

__all__ = [
    "diagnose", "diagnose_dataset", "start_diagnosis", "DiagnosisStart", "load_for_diagnosis", "Diagnosis", "EffectVerdict", "DiagnoseConfig",
    "DiagnosisInternals", "EXPLAINED_GAP", "CANDIDATE_EFFECTS", "effect_regressors",
    "compare_simulation_models", "ModelComparison", "ModelGap", "DiagnosisProblem", "GapFit", "Calibration",
    "Identification", "Discovery", "PressureDrift", "LongTimeGap",
]
