"""The settings each fitting method owns: :class:`DiscoveryMethodConfig` and :class:`PaperMethodConfig`.

A fit's :class:`fitting.config.FitConfig` holds the stages every method shares (loading, smoothing, attractor
classification) and, as its ``method``, the frozen settings of one registered method
(:class:`fitting.methods.registry.FittingMethod` ``config_type``).  A method's settings say, next to the fields
themselves, which method they belong to (``name``), which of the method-specific command-line options
(:data:`fitting.method_names.METHOD_OPTIONS`) they accept (``options``, each applied by the method
``with_<option>``) and which of their refinements ``--max-evals`` sets (``max_evals_setting``); the fit command,
the report command and :meth:`fitting.config.FitConfig.with_method_option` read these, so an option means the same
everywhere and is refused, in one line, by a method that does not accept it.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any, ClassVar

from cubedimer.config_checks import check_positive, check_that
from .method_names import methods_accepting
from .refinement.long_time import JOINT_REFINE, RefineConfig
from .refinement.output_error import OutputErrorConfig
from .selection.discovery_config import DiscoveryConfig
from .selection.ensemble import EnsembleConfig
from .selection.rules import SelectionConfig
from .selection.sparse_regression import RegressionConfig

__all__ = ["MethodConfig", "DiscoveryMethodConfig", "PaperMethodConfig", "OUTPUT_ERROR_MODES"]

#: ``--output-error``: the discovery's coefficients under model error (``DiscoveryConfig.output_error``):
#: refined by the output error with its support pruned and grown by it (the default), refined only, or the integral
#: form's
OUTPUT_ERROR_MODES: dict[str, OutputErrorConfig | None] = {
    "select": OutputErrorConfig(), "refine": OutputErrorConfig(support_tolerance=None), "off": None}


class MethodConfig:
    """What every method's frozen settings share (a base of frozen dataclasses with the fields below).

    Attributes
    ----------
    name : str (class attribute)
        The registered method these settings belong to (:data:`fitting.methods.registry.METHODS`).
    options : tuple of str (class attribute)
        The method-specific options (:data:`fitting.method_names.METHOD_OPTIONS`) the settings accept; each is
        applied by the method ``with_<option>(value)``.
    max_evals_setting : str (class attribute)
        The field (a :class:`~fitting.refinement.long_time.RefineConfig`) whose ``max_evals`` ``--max-evals`` sets:
        the method's main long-time refinement.
    joint : RefineConfig
        The joint re-optimisation on all runs (of the minimal model, or of a fallback), ``--joint-max-evals``.
    """

    name: ClassVar[str]
    options: ClassVar[tuple[str, ...]] = ()
    max_evals_setting: ClassVar[str] = "joint"
    joint: RefineConfig

    def with_option(self, option: str, value: Any) -> Any:
        """These settings with the method-specific ``option`` set to ``value``; ValueError (one line, to follow the
        option's name) when the method does not accept the option or the value is out of range."""
        if option not in self.options:
            raise ValueError(f"applies to --method {', '.join(methods_accepting(option)) or '(none)'}")
        return getattr(self, f"with_{option}")(value)

    def with_max_evals(self, max_evals: int) -> Any:
        """These settings with ``max_evals`` evaluations of the method's main refinement (``max_evals_setting``)."""
        main = getattr(self, self.max_evals_setting)
        return replace(self, **{self.max_evals_setting: replace(main, max_evals=max_evals)})

    def with_joint_max_evals(self, max_evals: int) -> Any:
        """These settings with ``max_evals`` evaluations of the joint re-optimisation (``joint``)."""
        return replace(self, joint=replace(self.joint, max_evals=max_evals))


@dataclass(frozen=True)
class DiscoveryMethodConfig(MethodConfig):
    """The settings of the default method, integral-form discovery with its long-time polish
    (:mod:`fitting.methods.discovery`).

    Parameters
    ----------
    selection : DiscoveryConfig
        The integral-form discovery, which selects and fits the terms (:func:`fitting.selection.integral_discovery.
        discover_model`).
    polish : RefineConfig
        The long-time polish of the discovered model on all runs (``--max-evals``).
    polish_se : float
        Half-width of the polish box in the discovery's standard errors.
    regression : RegressionConfig
        Its ``matched_filter`` builds the library of the per-run least squares on the selected terms.
    ensemble : EnsembleConfig
        The z-score rule reported beside the selection (model.json ``selection["zscore_rule"]``).
    joint : RefineConfig
        The re-optimisation of a fallback when the polished model blows up.

    Raises
    ------
    ValueError
        One line, on construction: a non-positive ``polish_se``.
    """

    name: ClassVar[str] = "discovery"
    #: ``--heldout-tolerance``, ``--output-error`` and ``--max-terms`` set the discovery's selection
    options: ClassVar[tuple[str, ...]] = ("heldout_tolerance", "output_error", "max_terms")
    #: ``--max-evals`` sets the evaluations of the long-time polish
    max_evals_setting: ClassVar[str] = "polish"

    selection: DiscoveryConfig = field(default_factory=DiscoveryConfig)
    polish: RefineConfig = field(default_factory=lambda: RefineConfig(max_evals=150))
    polish_se: float = 0.5
    regression: RegressionConfig = field(default_factory=RegressionConfig)
    ensemble: EnsembleConfig = field(default_factory=EnsembleConfig)
    joint: RefineConfig = JOINT_REFINE

    def __post_init__(self) -> None:
        check_positive(self, "polish_se")

    def with_heldout_tolerance(self, tolerance: float) -> "DiscoveryMethodConfig":
        """These settings with the discovery's practical threshold ``DiscoveryConfig.heldout_tolerance``;
        ValueError for a tolerance outside [0, 1)."""
        if not 0.0 <= tolerance < 1.0:
            raise ValueError(f"{tolerance:g}: needs a fraction in [0, 1) (0.002 keeps the smallest support within "
                             "0.2 % of the best held-out error)")
        return replace(self, selection=replace(self.selection, heldout_tolerance=float(tolerance)))

    def with_output_error(self, mode: str) -> "DiscoveryMethodConfig":
        """These settings with the discovery's coefficients under model error (``DiscoveryConfig.output_error``) set
        by ``mode`` (:data:`OUTPUT_ERROR_MODES`); ValueError for another mode."""
        if mode not in OUTPUT_ERROR_MODES:
            raise ValueError(f"{mode}: needs one of {', '.join(OUTPUT_ERROR_MODES)}")
        return replace(self, selection=replace(self.selection, output_error=OUTPUT_ERROR_MODES[mode]))

    def with_max_terms(self, max_terms: int) -> "DiscoveryMethodConfig":
        """These settings with at most ``max_terms`` terms per equation (``DiscoveryConfig.max_terms``)."""
        return replace(self, selection=replace(self.selection, max_terms=max_terms))


@dataclass(frozen=True)
class PaperMethodConfig(MethodConfig):
    """The settings of the source paper's method (:mod:`fitting.methods.paper`).

    Parameters
    ----------
    regression : RegressionConfig
        The sparse regression (C0), pooled and per run.
    refine : RefineConfig
        The long-time refinement of every run (``--max-evals``).
    joint : RefineConfig
        The joint re-optimisation of the minimal model (and of a fallback).
    ensemble : EnsembleConfig
        The z-score rule of the per-run ensemble.
    selection : SelectionConfig
        The selection rule of the ensemble (``--selection``) and its backward elimination.
    candidate_joint : RefineConfig
        The joint refinement of the whole candidate support (start of the backward elimination).
    """

    name: ClassVar[str] = "paper"
    #: ``--relative-threshold`` of the per-run regressions
    options: ClassVar[tuple[str, ...]] = ("relative_threshold",)
    #: ``--max-evals`` sets the evaluations of each per-run refinement
    max_evals_setting: ClassVar[str] = "refine"

    regression: RegressionConfig = field(default_factory=RegressionConfig)
    refine: RefineConfig = field(default_factory=RefineConfig)
    joint: RefineConfig = JOINT_REFINE
    ensemble: EnsembleConfig = field(default_factory=EnsembleConfig)
    selection: SelectionConfig = field(default_factory=SelectionConfig)
    candidate_joint: RefineConfig = field(default_factory=lambda: RefineConfig(
        max_evals=300, rel_bound=0.3, abs_bound=0.005, horizons=(0.5, 1.0)))

    def __post_init__(self) -> None:
        # each stage checks its own values; here, that each is the stage's settings (a dict or a name passed by
        # mistake would fail only deep inside the fit)
        for name, kind in (("regression", RegressionConfig), ("refine", RefineConfig), ("joint", RefineConfig),
                           ("ensemble", EnsembleConfig), ("selection", SelectionConfig),
                           ("candidate_joint", RefineConfig)):
            check_that(self, isinstance(getattr(self, name), kind), f"{name} must be a {kind.__name__}")

    def with_relative_threshold(self, relative: bool) -> "PaperMethodConfig":
        """These settings with the regression threshold relative to each equation's signal size (or not)."""
        return replace(self, regression=replace(self.regression, relative_threshold=bool(relative)))
