"""Data-driven model discovery for levitated cube dimers (independent of ``acousim``).

Two registered methods (:data:`METHODS`, :class:`FitConfig` ``method``): ``"discovery"`` (default) selects and
fits the terms of the 35-term cubic library on the integral form pooled over runs, with model-based column states
(:func:`discover_model`), then polishes the coefficients with the long-time refinement (attractor shape, Poincare
map, frequency; nlopt) and checks the attractors; ``"paper"`` is the source paper's pipeline: per-run sparse
regression with pysindy (C0), long-time refinement per run, ensemble selection by a registered rule
(:data:`SELECTION_RULES`) and joint re-optimisation of the minimal model.  Public API:

* fitting a data set: :func:`fit_dataset` (load and fit, no output files), :func:`fit_runs`, :func:`prepare_runs`
  (the fit's view of the data set's one preparation, :func:`prepare_dataset` and its :class:`PreparedDataset`),
  :class:`FitConfig` with each method's own settings (:class:`DiscoveryMethodConfig`, :class:`PaperMethodConfig`,
  both :class:`MethodConfig`) and the stage configs, :class:`FitResult` (with the method's own ``extras``, e.g.
  :class:`EnsembleExtras`), :func:`write_fit` (model.json and figures), :func:`recorded_settings` (a model.json's
  settings in today's layout, whatever release wrote them), :class:`NoSaneModelError`;
* the registries: :data:`METHODS`, :class:`FittingMethod` (with :class:`MethodDescription`, a method's account of its
  result), :class:`FitContext`, :func:`register_method`;
  :data:`SELECTION_RULES`, :class:`SelectionRule`, :func:`register_selection_rule`;
* the model: :class:`PolynomialModel`, :class:`Scales`; the discovery: :func:`discover_model`;
* oracle standard errors and the run planner: :class:`NoiseLevels`, :func:`oracle_standard_errors`,
  :func:`plan_runs` with its :class:`PlanConfig`;
* paired comparison of a variant: :func:`compare_models`; synthetic data: :func:`paper_reduced_model`,
  :func:`write_dataset`, :class:`SyntheticConfig`, and the generic-system example :func:`write_generic_example`
  (:func:`generic_example_model`).

The building blocks are laid out as the fit runs, one subpackage per step (docs/architecture.md):
:mod:`fitting.derivatives` (smoothing, derivatives, the integral form) -> :mod:`fitting.methods` (the registry and
the two methods) -> :mod:`fitting.selection` (which terms) -> :mod:`fitting.refinement` (their coefficients over
many periods) -> :mod:`fitting.uncertainty` (oracle standard errors, the fallback, the run planner) ->
:mod:`fitting.output` (model.json and figures).  The model (:mod:`fitting.model`, :mod:`fitting.integrate`), the
settings (:mod:`fitting.config`), the results and Holm's rule (:mod:`fitting.multiple_testing`) are shared by all.
"""
import cubedimer  # noqa: F401  (first: sets up the compile cache, cubedimer.compile_cache)
from cubedimer.distribution import __version__
from .compare import compare_models
from .config import FitConfig
from .derivatives.preparation import PreparedDataset, prepare_dataset
from .derivatives.savitzky_golay import SmoothingConfig
from .description import MethodDescription
from .fit import fit_dataset, fit_runs, prepare_runs
from .methods.registry import METHODS, FitContext, FittingMethod, register_method
from .method_settings import DiscoveryMethodConfig, MethodConfig, PaperMethodConfig
from .model import PolynomialModel, Scales
from .output.model_file import recorded_settings, write_fit
from .refinement.long_time import RefineConfig
from .refinement.losses import LossWeights
from .results import EnsembleExtras, FitResult
from .selection.discovery_config import DiscoveryConfig
from .selection.ensemble import EnsembleConfig
from .selection.integral_discovery import DiscoveryResult, discover_model
from .selection.rules import SELECTION_RULES, SelectionConfig, SelectionRule, register_selection_rule
from .selection.sparse_regression import RegressionConfig
from .synthetic import SyntheticConfig, generic_example_model, paper_reduced_model, write_dataset, write_generic_example
from .uncertainty.final_checks import NoSaneModelError
from .uncertainty.oracle import NoiseLevels, oracle_standard_errors
from .uncertainty.run_planning import PlanConfig, plan_runs

__all__ = [
    "fit_dataset", "fit_runs", "prepare_runs", "prepare_dataset", "PreparedDataset", "FitConfig", "MethodConfig", "DiscoveryMethodConfig",
    "PaperMethodConfig", "FitResult", "EnsembleExtras", "write_fit", "recorded_settings", "NoSaneModelError",
    "SmoothingConfig", "RegressionConfig", "RefineConfig", "LossWeights", "EnsembleConfig", "SelectionConfig",
    "DiscoveryConfig",
    "METHODS", "FittingMethod", "MethodDescription", "FitContext", "register_method",
    "SELECTION_RULES", "SelectionRule", "register_selection_rule",
    "PolynomialModel", "Scales", "discover_model", "DiscoveryResult",
    "NoiseLevels", "oracle_standard_errors", "plan_runs", "PlanConfig",
    "compare_models", "SyntheticConfig", "paper_reduced_model", "write_dataset", "generic_example_model",
    "write_generic_example",
]
