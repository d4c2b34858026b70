"""validation: fitted models against the Gor'kov simulation (imports both acousim and fitting).

Public API: :func:`compare_coefficients`, :func:`shift_origin`, :func:`model_from_meta`.
"""
from .coefficients import CoefficientComparison, TermComparison, compare_coefficients, origin_sensitivity, shift_origin
from .simulation import model_from_meta

__all__ = ["CoefficientComparison", "TermComparison", "compare_coefficients", "origin_sensitivity", "shift_origin",
           "model_from_meta"]
