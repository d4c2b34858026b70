"""Data-driven model discovery for levitated cube dimers (independent of ``acousim``).

Two registered methods (:data:`METHODS`, :class:`FitConfig` ``method``): ``"discovery"`` (default) selects and
fits the terms of the 35-term cubic library on the integral form pooled over runs, with model-based column states
(:func:`discover_model`), then polishes the coefficients with the long-time refinement (attractor shape, Poincare
map, frequency; nlopt) and checks the attractors; ``"paper"`` is the source paper's pipeline: per-run sparse
regression with pysindy (C0), long-time refinement per run, ensemble selection by a registered rule
(:data:`SELECTION_RULES`) and joint re-optimisation of the minimal model.  Public API:

* fitting a data set: :func:`fit_dataset` (load and fit, no output files), :func:`fit_runs`, :func:`prepare_runs`,
  :class:`FitConfig` and the stage configs, :class:`FitResult` (with the method's own ``extras``, e.g.
  :class:`EnsembleExtras`), :func:`write_fit` (model.json and figures), :class:`NoSaneModelError`;
* the registries: :data:`METHODS`, :class:`FittingMethod` (with :class:`MethodDescription`, a method's account of its
  result), :class:`FitContext`, :func:`register_method`;
  :data:`SELECTION_RULES`, :class:`SelectionRule`, :func:`register_selection_rule`;
* the model: :class:`PolynomialModel`, :class:`Scales`; the discovery: :func:`discover_model`;
* oracle standard errors and the run planner: :class:`NoiseLevels`, :func:`oracle_standard_errors`,
  :func:`plan_runs` with its :class:`PlanConfig`;
* paired comparison of a variant: :func:`compare_models`; synthetic data: :func:`paper_reduced_model`,
  :func:`write_dataset`, :class:`SyntheticConfig`, and the generic-system example :func:`write_generic_example`
  (:func:`generic_example_model`).

The building blocks (regression, refinement, ensemble statistics, Holm's rule) are in their modules.
"""
import cubedimer  # noqa: F401  (first: sets up the compile cache, cubedimer.compile_cache)
from cubedimer.distribution import __version__
from .compare import compare_models
from .config import FitConfig
from .derivatives import SmoothingConfig
from .description import MethodDescription
from .discovery import DiscoveryConfig, DiscoveryResult, discover_model
from .ensemble import EnsembleConfig
from .final_checks import NoSaneModelError
from .fit_output import write_fit
from .losses import LossWeights
from .methods import METHODS, FitContext, FittingMethod, register_method
from .model import PolynomialModel, Scales
from .oracle import NoiseLevels, oracle_standard_errors
from .pipeline import fit_dataset, fit_runs, prepare_runs
from .refine import RefineConfig
from .regression import RegressionConfig
from .results import EnsembleExtras, FitResult
from .run_planning import PlanConfig, plan_runs
from .selection import SelectionConfig
from .selection_rules import SELECTION_RULES, SelectionRule, register_selection_rule
from .synthetic import SyntheticConfig, generic_example_model, paper_reduced_model, write_dataset, write_generic_example

__all__ = [
    "fit_dataset", "fit_runs", "prepare_runs", "FitConfig", "FitResult", "EnsembleExtras", "write_fit",
    "NoSaneModelError",
    "SmoothingConfig", "RegressionConfig", "RefineConfig", "LossWeights", "EnsembleConfig", "SelectionConfig",
    "DiscoveryConfig",
    "METHODS", "FittingMethod", "MethodDescription", "FitContext", "register_method",
    "SELECTION_RULES", "SelectionRule", "register_selection_rule",
    "PolynomialModel", "Scales", "discover_model", "DiscoveryResult",
    "NoiseLevels", "oracle_standard_errors", "plan_runs", "PlanConfig",
    "compare_models", "SyntheticConfig", "paper_reduced_model", "write_dataset", "generic_example_model",
    "write_generic_example",
]
