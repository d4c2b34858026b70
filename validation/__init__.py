"""validation: fitted models and data against the simulation (the Gor'kov and the full-wave force models of
:mod:`acousim.models`); imports acousim, fitting and cubedimer.

Public API

* coefficient comparison: :func:`compare_coefficients`, :func:`shift_origin`, :func:`origin_sensitivity`,
  :class:`CoefficientComparison`, :class:`TermComparison`; the simulation of a data set, :func:`model_from_meta`;
* the sim-to-real gap diagnosis (:mod:`validation.diagnosis`): :func:`diagnose_dataset`,
  :func:`write_diagnosis` (its files), :class:`DiagnoseConfig`, :data:`CANDIDATE_EFFECTS` and the result types
  :class:`DiagnosisInternals`, :class:`GapFit`, :class:`Calibration`, :class:`Identification`;
* the blind check of the diagnosis (:mod:`validation.blind`): :class:`BlindConfig`, :func:`run_blind`,
  :func:`blind_table`;
* the report (:mod:`validation.report`): :func:`build_report`.

The diagnosis, blind check and report are imported on first use.
"""
from __future__ import annotations

from cubedimer.lazy import lazy_attributes
from cubedimer.distribution import __version__

from .coefficients import CoefficientComparison, TermComparison, compare_coefficients, origin_sensitivity, shift_origin
from .simulation import model_from_meta

_LAZY = {
    "diagnose_dataset": ".diagnosis", "write_diagnosis": ".report.sections.gap_diagnosis", "DiagnoseConfig": ".diagnosis",
    "CANDIDATE_EFFECTS": ".diagnosis", "DiagnosisInternals": ".diagnosis", "GapFit": ".diagnosis",
    "Calibration": ".diagnosis", "Identification": ".diagnosis",
    "BlindConfig": ".blind", "run_blind": ".blind", "blind_table": ".blind",
    "build_report": ".report.build",
}

__all__ = ["CoefficientComparison", "TermComparison", "compare_coefficients", "origin_sensitivity", "shift_origin",
           "model_from_meta", *_LAZY]

__getattr__ = lazy_attributes(__name__, _LAZY)


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
