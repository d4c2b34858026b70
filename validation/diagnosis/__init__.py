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
  final joint model of the identified effects with them (:func:`joint_estimates`);
* :mod:`~validation.diagnosis.localization`: where the residual lies (terms, regions, time scales);
* :mod:`~validation.diagnosis.long_time`: attractor, Poincare and frequency errors;
* :mod:`~validation.diagnosis.pipeline`: :func:`diagnose_dataset` (its files: :func:`validation.report.write_diagnosis`);
* :mod:`~validation.diagnosis.model_comparison`: the gaps of Gor'kov, Gor'kov + fitted pair scattering and
  the full-wave model side by side (:func:`compare_simulation_models`).

The method, its tests and the blind check are described in docs/diagnosis.md.
"""
from __future__ import annotations

from .calibration import Calibration, calibrate
from .candidates import CANDIDATE_EFFECTS, effect_regressors
from .discovery import (DiscoveredTerm, Discovery, discover_terms, discovered_equations, dissipative_terms,
                        joint_estimates, judge_candidates)
from .drift import DriftSettings, DriftTest, PressureDrift, detect_pressure_drift
from .gap_model import EnergyResidual, GapFit, IntegralResidual, apply_gap_model, fit_gap_model, predicted_accelerations
from .identification import (CandidateTest, Identification, IdentificationRound, PracticalThresholds, held_out_gaps,
                             identify_effects)
from .localization import localize_residuals
from .long_time import LongTimeGap, long_time_gaps
from .model_comparison import ModelComparison, ModelGap, compare_simulation_models
from .metrics import (GapComponent, fit_components, fit_gaps, gap_components, gap_definition, noise_floors,
                      scalar_gap, short_time_gaps)
from .pipeline import EXPLAINED_GAP, DiagnoseConfig, DiagnosisInternals, diagnose_dataset
from .preparation import PositionIntegrals, RunAccelerations, prepare_diagnosis_runs
from .problem import DiagnosisProblem
from .statistics import sign_flip_pvalue, wilcoxon_greater_pvalue

__all__ = [
    "CANDIDATE_EFFECTS", "effect_regressors",
    "RunAccelerations", "PositionIntegrals", "prepare_diagnosis_runs", "DiagnosisProblem",
    "Calibration", "calibrate",
    "DiscoveredTerm", "Discovery", "discover_terms", "dissipative_terms", "discovered_equations", "judge_candidates", "joint_estimates",
    "DriftSettings", "DriftTest", "PressureDrift", "detect_pressure_drift",
    "GapFit", "EnergyResidual", "IntegralResidual", "fit_gap_model", "apply_gap_model", "predicted_accelerations",
    "GapComponent", "gap_components", "fit_components", "gap_definition", "short_time_gaps", "noise_floors", "fit_gaps", "scalar_gap",
    "PracticalThresholds", "CandidateTest", "IdentificationRound", "Identification", "held_out_gaps", "identify_effects",
    "localize_residuals", "LongTimeGap", "long_time_gaps", "ModelGap", "ModelComparison", "compare_simulation_models",
    "sign_flip_pvalue", "wilcoxon_greater_pvalue",
    "DiagnoseConfig", "DiagnosisInternals", "diagnose_dataset", "EXPLAINED_GAP",
]
