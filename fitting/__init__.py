"""Data-driven model discovery for levitated cube dimers.

Two registered methods (:data:`METHODS`, :class:`FitConfig` ``method``): ``"discovery"`` (default) selects and fits the terms of the
35-term cubic library on the integral form pooled over runs, with model-based column states
(:func:`discover_model`), then polishes the coefficients with the long-time refinement (attractor shape,
Poincare map, frequency; nlopt) and checks the attractors; ``"paper"`` is the source paper's pipeline:
per-run sparse regression with pysindy (C0), long-time refinement per run, ensemble selection and joint
re-optimisation of the minimal model.  Also: oracle standard errors and a run planner, paired model
comparison, synthetic data.  Independent of ``acousim``.
"""
from .compare import compare_models, cross_coupling_mask, drop_terms, paired_wilcoxon
from .discovery import DiscoveryConfig, DiscoveryResult, discover_model
from .ensemble import EnsembleConfig, mean_pvalues, select_significant_terms, select_terms, term_statistics
from .losses import LossTerms, LossWeights
from .model import PolynomialModel, Scales
from .oracle import NoiseLevels, OracleRun, estimate_tracking_noise, oracle_aliases, oracle_standard_errors
from .run_planning import plan_runs
from .config import FitConfig
from .fit_output import model_json, write_fit
from .final_checks import NoSaneModelError
from .methods import METHODS, FitContext, FittingMethod, register_method
from .pipeline import fit_dataset, fit_runs, prepare_runs
from .results import FitResult
from .selection_rules import SELECTION_RULES, SelectionRule, register_selection_rule
from .refine import RefineConfig, refine
from .selection import SelectionConfig
from .regression import RegressionConfig, fit_regression
from .synthetic import SyntheticConfig, paper_reduced_model, write_dataset

__all__ = [
    "PolynomialModel", "Scales",
    "RegressionConfig", "fit_regression", "RefineConfig", "refine", "LossWeights", "LossTerms",
    "EnsembleConfig", "term_statistics", "select_terms", "select_significant_terms", "mean_pvalues",
    "SelectionConfig", "DiscoveryConfig", "DiscoveryResult", "discover_model",
    "NoiseLevels", "OracleRun", "estimate_tracking_noise", "oracle_aliases", "oracle_standard_errors", "plan_runs",
    "METHODS", "FittingMethod", "FitContext", "register_method", "SELECTION_RULES", "SelectionRule",
    "register_selection_rule", "FitConfig", "FitResult", "NoSaneModelError", "fit_dataset", "fit_runs", "prepare_runs",
    "model_json", "write_fit",
    "compare_models", "cross_coupling_mask", "drop_terms", "paired_wilcoxon",
    "SyntheticConfig", "paper_reduced_model", "write_dataset",
]
