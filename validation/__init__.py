"""validation: fitted models and data against the Gor'kov simulation (imports acousim, fitting and cubedimer).

Public API

* coefficient comparison: :func:`compare_coefficients`, :func:`shift_origin`, :func:`origin_sensitivity`,
  :class:`CoefficientComparison`, :class:`TermComparison`; the simulation of a data set, :func:`model_from_meta`;
* the sim-to-real gap diagnosis (:mod:`validation.diagnosis`): :func:`diagnose_dataset`,
  :func:`write_diagnosis`, :class:`DiagnoseConfig`, :data:`CANDIDATE_EFFECTS` and the result types
  :class:`DiagnosisInternals`, :class:`GapFit`, :class:`Calibration`, :class:`Identification`;
* the blind check of the diagnosis (:mod:`validation.blind`): :class:`BlindConfig`, :func:`run_blind`,
  :func:`blind_table`;
* the report (:mod:`validation.report`): :func:`build_report`.

The diagnosis, blind check and report are imported on first use.
"""
from __future__ import annotations

from importlib import import_module

from .coefficients import CoefficientComparison, TermComparison, compare_coefficients, origin_sensitivity, shift_origin
from .simulation import model_from_meta

_LAZY = {
    "diagnose_dataset": ".diagnosis", "write_diagnosis": ".diagnosis", "DiagnoseConfig": ".diagnosis",
    "CANDIDATE_EFFECTS": ".diagnosis", "DiagnosisInternals": ".diagnosis", "GapFit": ".diagnosis",
    "Calibration": ".diagnosis", "Identification": ".diagnosis",
    "BlindConfig": ".blind", "run_blind": ".blind", "blind_table": ".blind",
    "build_report": ".report.pipeline",
}

__all__ = ["CoefficientComparison", "TermComparison", "compare_coefficients", "origin_sensitivity", "shift_origin",
           "model_from_meta", *_LAZY]


def __getattr__(name: str):
    if name in _LAZY:
        value = getattr(import_module(_LAZY[name], __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
