"""Data-driven model discovery for levitated cube dimers.

Pipeline: load trajectories (:mod:`cubedimer.dataset`), smooth and differentiate
(:mod:`fitting.derivatives`), Poincare sections/maps, spectra and attractor classes, sparse
regression of the accelerations on the 35-term cubic library with pysindy (C0), long-time
refinement against attractor shape, Poincare map and frequency with nlopt, ensemble z-scores, the
significance of the ensemble mean and the minimal model, and paired model comparison.  Independent of ``acousim``.
"""
from .compare import compare_models, cross_coupling_mask, drop_terms, paired_wilcoxon
from .discovery import DiscoveryConfig, DiscoveryResult, discover_model
from .ensemble import EnsembleConfig, mean_pvalues, select_significant_terms, select_terms, term_statistics
from .losses import LossTerms, LossWeights
from .model import PolynomialModel, Scales
from .oracle import NoiseLevels, OracleRun, estimate_tracking_noise, oracle_standard_errors, plan_runs
from .pipeline import FitConfig, FitResult, fit_dataset, fit_runs, prepare_runs
from .refine import RefineConfig, refine
from .selection import SelectionConfig
from .regression import RegressionConfig, fit_regression
from .synthetic import SyntheticConfig, paper_reduced_model, write_dataset

__all__ = [
    "PolynomialModel", "Scales",
    "RegressionConfig", "fit_regression", "RefineConfig", "refine", "LossWeights", "LossTerms",
    "EnsembleConfig", "term_statistics", "select_terms", "select_significant_terms", "mean_pvalues",
    "SelectionConfig", "DiscoveryConfig", "DiscoveryResult", "discover_model",
    "NoiseLevels", "OracleRun", "estimate_tracking_noise", "oracle_standard_errors", "plan_runs",
    "FitConfig", "FitResult", "fit_dataset", "fit_runs", "prepare_runs",
    "compare_models", "cross_coupling_mask", "drop_terms", "paired_wilcoxon",
    "SyntheticConfig", "paper_reduced_model", "write_dataset",
]
