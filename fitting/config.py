"""The settings of a fit, :class:`FitConfig`: one frozen, self-validating config per stage and the method's name."""
from __future__ import annotations

from dataclasses import dataclass, field, replace

from cubedimer.attractors import ClassifyConfig
from cubedimer.config_checks import check_choice, check_positive
from cubedimer.dataset import LoadConfig
from cubedimer.system import SYSTEM_KINDS
from .derivatives.savitzky_golay import SmoothingConfig
from .method_names import DEFAULT_METHOD, METHODS, methods_accepting
from .refinement.long_time import JOINT_REFINE, RefineConfig
from .refinement.output_error import OutputErrorConfig
from .selection.discovery_config import DiscoveryConfig
from .selection.ensemble import EnsembleConfig
from .selection.rules import SelectionConfig
from .selection.sparse_regression import RegressionConfig

__all__ = ["FitConfig", "OUTPUT_ERROR_MODES"]

#: ``--output-error``: the discovery's coefficients under model error (``DiscoveryConfig.output_error``):
#: refined by the output error with its support pruned and grown by it (the default), refined only, or the integral
#: form's
OUTPUT_ERROR_MODES: dict[str, OutputErrorConfig | None] = {
    "select": OutputErrorConfig(), "refine": OutputErrorConfig(support_tolerance=None), "off": None}


@dataclass(frozen=True)
class FitConfig:
    """All settings of the pipeline (every stage has its own frozen config).

    Raises
    ------
    ValueError
        One line, on construction: a method that is not registered (:data:`fitting.methods.registry.METHODS`) or a
        non-positive ``polish_se``.
    """

    #: loading rules; the fit reads levitated dimers and generic two-coordinate systems (cubedimer.system)
    load: LoadConfig = field(default_factory=lambda: LoadConfig(systems=SYSTEM_KINDS))
    smoothing: SmoothingConfig = field(default_factory=SmoothingConfig)
    regression: RegressionConfig = field(default_factory=RegressionConfig)
    refine: RefineConfig = field(default_factory=RefineConfig)
    joint: RefineConfig = JOINT_REFINE
    ensemble: EnsembleConfig = field(default_factory=EnsembleConfig)
    selection: SelectionConfig = field(default_factory=SelectionConfig)
    #: joint refinement of the whole candidate support (start of the backward elimination)
    candidate_joint: RefineConfig = field(default_factory=lambda: RefineConfig(
        max_evals=300, rel_bound=0.3, abs_bound=0.005, horizons=(0.5, 1.0)))
    classify: ClassifyConfig = field(default_factory=ClassifyConfig)
    #: the registered method (:data:`fitting.methods.registry.METHODS`): ``"discovery"``: integral-form discovery
    #: (:func:`fitting.selection.integral_discovery.discover_model`) selects and fits the model, the long-time refinement polishes it
    #: inside a box of ``polish_se`` of its standard errors; ``"paper"``: per-run SINDy and long-time refinement,
    #: ensemble selection (``selection.rule``), joint re-optimisation of the minimal model
    method: str = DEFAULT_METHOD
    discovery: DiscoveryConfig = field(default_factory=DiscoveryConfig)
    #: long-time polish of the discovered model (method "discovery")
    polish: RefineConfig = field(default_factory=lambda: RefineConfig(max_evals=150))
    #: half-width of the polish box in the discovery's standard errors
    polish_se: float = 0.5

    def __post_init__(self) -> None:
        check_choice(self, "method", tuple(METHODS), what="method")
        check_positive(self, "polish_se")

    def with_heldout_tolerance(self, tolerance: float | None) -> "FitConfig":
        """This configuration with the discovery's practical threshold ``DiscoveryConfig.heldout_tolerance`` (None:
        unchanged); ValueError for a method that does not accept the option (``FittingMethod.options``) or a tolerance
        outside [0, 1)."""
        if tolerance is None:
            return self
        if "heldout_tolerance" not in METHODS[self.method].options or not 0.0 <= tolerance < 1.0:
            raise ValueError(f"{tolerance:g}: needs a fraction in [0, 1) and --method "
                             f"{', '.join(methods_accepting('heldout_tolerance'))} (0.002 keeps the "
                             "smallest support within 0.2 % of the best held-out error)")
        return replace(self, discovery=replace(self.discovery, heldout_tolerance=float(tolerance)))

    def with_output_error(self, mode: str | None) -> "FitConfig":
        """This configuration with the discovery's coefficients under model error (``DiscoveryConfig.output_error``)
        set by ``mode`` (:data:`OUTPUT_ERROR_MODES`; None: unchanged); ValueError for another mode or a method that
        does not accept the option."""
        if mode is None:
            return self
        if mode not in OUTPUT_ERROR_MODES or "output_error" not in METHODS[self.method].options:
            raise ValueError(f"{mode}: needs one of {', '.join(OUTPUT_ERROR_MODES)} and --method "
                             f"{', '.join(methods_accepting('output_error'))}")
        return replace(self, discovery=replace(self.discovery, output_error=OUTPUT_ERROR_MODES[mode]))
