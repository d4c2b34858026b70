"""The settings each fitting method owns: :class:`DiscoveryMethodConfig` and :class:`PaperMethodConfig`.

A fit's :class:`fitting.config.FitConfig` holds the stages every method shares (loading, smoothing, attractor
classification) and, as its ``method``, the frozen settings of one registered method
(:class:`fitting.methods.registry.FittingMethod` ``config_type``).  A method's settings say, next to the fields
themselves, which method they belong to (``name``), the command-line options that set them (``options``:
:class:`cubedimer.setting_options.SettingOption` declarations, each naming its flag, the field it sets, its type or
choices and its help; the default is read from the field) and which of their refinements ``--max-evals`` sets
(``max_evals_setting``, :meth:`MethodConfig.command_options`).  The fit's parser is generated from the declarations
of the registered methods (:mod:`fitting.options`), so the fit command and the report command offer every method's
options, an option means the same everywhere, and a method whose settings do not declare it refuses it in one line.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, ClassVar

from cubedimer.config_checks import check_positive, check_that
from cubedimer.setting_options import SettingOption, positive_int
from .method_names import methods_accepting
from .refinement.long_time import JOINT_REFINE, RefineConfig
from .refinement.output_error import OutputErrorConfig
from .selection.discovery_config import DiscoveryConfig
from .selection.ensemble import EnsembleConfig
from .selection.rules import SELECTION_RULES, SelectionConfig, selection_rule_names
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
    options : tuple of SettingOption (class attribute)
        The method's own command-line options, each setting one field of these settings
        (:class:`cubedimer.setting_options.SettingOption`); :meth:`command_options` adds the refinement's.
    max_evals_setting : str (class attribute)
        The field (a :class:`~fitting.refinement.long_time.RefineConfig`) whose ``max_evals`` ``--max-evals`` sets:
        the method's main long-time refinement.
    max_evals_meaning : str (class attribute)
        That refinement in words, for the help of ``--max-evals``.
    joint : RefineConfig
        The joint re-optimisation on all runs (of the minimal model, or of a fallback), ``--joint-max-evals``.
    """

    name: ClassVar[str]
    options: ClassVar[tuple[SettingOption, ...]] = ()
    max_evals_setting: ClassVar[str] = "joint"
    max_evals_meaning: ClassVar[str] = "the joint re-optimisation"
    joint: RefineConfig

    @classmethod
    def command_options(cls) -> tuple[SettingOption, ...]:
        """Every command-line option of these settings: the refinement's ``--max-evals`` (of the main refinement,
        ``max_evals_setting``) and ``--joint-max-evals``, then the method's own ``options``."""
        return (SettingOption("--max-evals", f"{cls.max_evals_setting}.max_evals", type=positive_int, metavar="N",
                              help=f"objective evaluations of {cls.max_evals_meaning} (default {{default}})"),
                SettingOption("--joint-max-evals", "joint.max_evals", type=positive_int, metavar="N",
                              help="evaluations of the joint re-optimisation (default {default})"),
                *cls.options)

    @classmethod
    def command_option(cls, dest: str) -> SettingOption | None:
        """The command-line option of these settings whose argparse destination is ``dest`` (None: none)."""
        return next((o for o in cls.command_options() if o.dest == dest), None)

    def with_option(self, option: str, value: Any) -> Any:
        """These settings with the option ``option`` (a flag's destination, ``"heldout_tolerance"``) set to
        ``value``; ValueError (one line, to follow the option's flag) when the method does not accept the option or
        the value is out of range."""
        declared = self.command_option(option)
        if declared is None:
            raise ValueError(f"applies to --method {', '.join(methods_accepting(option)) or '(none)'}")
        return declared.applied(self, value)

    def with_max_evals(self, max_evals: int) -> Any:
        """These settings with ``max_evals`` evaluations of the method's main refinement (``max_evals_setting``)."""
        return self.with_option("max_evals", max_evals)

    def with_joint_max_evals(self, max_evals: int) -> Any:
        """These settings with ``max_evals`` evaluations of the joint re-optimisation (``joint``)."""
        return self.with_option("joint_max_evals", max_evals)


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
    options: ClassVar[tuple[SettingOption, ...]] = (
        SettingOption(
            "--heldout-tolerance", "selection.heldout_tolerance", type=float, metavar="FRACTION",
            valid=lambda v: 0.0 <= v < 1.0,
            requirement="needs a fraction in [0, 1) (0.002 keeps the smallest support within 0.2 % of the best "
                        "held-out error)",
            help="keep the smallest support whose held-out error (5-fold over runs) is within FRACTION of the best "
                 "on the elimination path (default {default}: the best itself, every term the data resolve). A "
                 "practical threshold for data whose truth is not sparse in the library (real dimers): 0.002 gives "
                 "the 11-term Gor'kov form on the paper-like twin, but also drops weak true terms near the "
                 "information limit; model.json's Pareto front shows the trade-off. In equations under model error "
                 "it widens the held-out rule's allowance, and the output error drops a term that raises the "
                 "trajectories' RMS misfit by at most FRACTION and adds none that lowers it by less (0.02-0.05 "
                 "there: one to three terms fewer per model at long-time errors 0-14 %% higher on average, up to 2.3 "
                 "times on single 4-run data sets; docs/fitting.md)"),
        SettingOption(
            "--output-error", "selection.output_error", choices=OUTPUT_ERROR_MODES,
            help="for equations whose residual is model error (a truth not sparse in the library; default "
                 "{default}): 'select' refines the coefficients so that the model's trajectories follow the runs "
                 "over 5-period segments, then drops the terms those trajectories do not need and adds those they "
                 "need (a slow nonlinear damping, say); 'refine' only refines; 'off' keeps the integral form's "
                 "coefficients and support"),
        SettingOption(
            "--max-terms", "selection.max_terms", type=positive_int, metavar="N",
            help="at most N terms per equation, the front's point at that size (model.json's discovery.front; "
                 "default: the discovery's own selection)"),
    )
    #: ``--max-evals`` sets the evaluations of the long-time polish
    max_evals_setting: ClassVar[str] = "polish"
    max_evals_meaning: ClassVar[str] = "the long-time polish of the discovered model"

    selection: DiscoveryConfig = field(default_factory=DiscoveryConfig)
    polish: RefineConfig = field(default_factory=lambda: RefineConfig(max_evals=150))
    polish_se: float = 0.5
    regression: RegressionConfig = field(default_factory=RegressionConfig)
    ensemble: EnsembleConfig = field(default_factory=EnsembleConfig)
    joint: RefineConfig = JOINT_REFINE

    def __post_init__(self) -> None:
        check_positive(self, "polish_se")


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
    #: ``--selection``, the ensemble's rule, and ``--relative-threshold`` of the per-run regressions
    options: ClassVar[tuple[SettingOption, ...]] = (
        SettingOption("--selection", "selection.rule", choices=lambda: selection_rule_names("paper"),
                      help=lambda: "term selection of the per-run ensemble (default {default}): " + "; ".join(
                          f"'{r.name}': {r.summary}" for r in SELECTION_RULES.values() if "paper" in r.methods)),
        SettingOption("--relative-threshold", "regression.relative_threshold", switch=True,
                      help="apply the regression threshold to each equation relative to its signal size (for a "
                           "hinge much slower than the vertical oscillation, whose scaled theta coefficients are "
                           "all small)"),
    )
    #: ``--max-evals`` sets the evaluations of each per-run refinement
    max_evals_setting: ClassVar[str] = "refine"
    max_evals_meaning: ClassVar[str] = "each run's long-time refinement"

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
