"""The settings of a fit, :class:`FitConfig`: the stages every method shares and the method's own settings."""
from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any

from cubedimer.attractors import ClassifyConfig
from cubedimer.config_checks import check_that
from cubedimer.dataset import LoadConfig
from cubedimer.system import SYSTEM_KINDS
from .derivatives.savitzky_golay import SmoothingConfig
from .method_names import METHODS, get_method
from .method_settings import OUTPUT_ERROR_MODES, DiscoveryMethodConfig, MethodConfig, PaperMethodConfig

__all__ = ["FitConfig", "OUTPUT_ERROR_MODES", "MethodConfig", "DiscoveryMethodConfig", "PaperMethodConfig"]


@dataclass(frozen=True)
class FitConfig:
    """All settings of a fit: the shared stages, each with its own frozen config, and the method's settings.

    Parameters
    ----------
    load : LoadConfig
        Loading rules; the fit reads levitated dimers and generic two-coordinate systems (cubedimer.system).
    smoothing : SmoothingConfig
        Smoothing and differentiation of every run (:func:`fitting.fit.prepare_runs`).
    classify : ClassifyConfig
        The attractor classification of every run.
    method : MethodConfig
        The settings of the registered method that fits (:data:`fitting.methods.registry.METHODS`, its
        ``config_type``): :class:`~fitting.method_settings.DiscoveryMethodConfig` (the default, integral-form
        discovery polished by the long-time refinement) or :class:`~fitting.method_settings.PaperMethodConfig`
        (per-run SINDy and long-time refinement, ensemble selection, joint re-optimisation of the minimal model).
        ``FitConfig.for_method(name)`` gives a method's default settings.

    Raises
    ------
    ValueError
        One line, on construction: ``method`` is not the settings of a registered method.
    """

    load: LoadConfig = field(default_factory=lambda: LoadConfig(systems=SYSTEM_KINDS))
    smoothing: SmoothingConfig = field(default_factory=SmoothingConfig)
    classify: ClassifyConfig = field(default_factory=ClassifyConfig)
    method: MethodConfig = field(default_factory=DiscoveryMethodConfig)

    def __post_init__(self) -> None:
        registered = METHODS.get(getattr(self.method, "name", None))
        check_that(self, registered is not None and isinstance(self.method, registered.config_type),
                   f"method must be the settings of a registered method ({', '.join(METHODS)}), e.g. "
                   f"FitConfig.for_method('paper') or PaperMethodConfig(); got {self.method!r}")

    @classmethod
    def for_method(cls, name: str, **shared: Any) -> "FitConfig":
        """The default settings of the registered method ``name`` (and the shared stages ``shared``); ValueError
        (one line, listing the choices) for a method that is not registered."""
        return cls(method=get_method(name).config_type(), **shared)

    @property
    def method_name(self) -> str:
        """The registered name of the method that fits."""
        return self.method.name

    def with_method_option(self, option: str, value: Any) -> "FitConfig":
        """This configuration with the command-line option ``option`` of the method's settings (an argparse
        destination, ``"heldout_tolerance"``: ``MethodConfig.command_options``) set to ``value`` (None: unchanged);
        ValueError (one line, to follow the option's flag) for a method that does not accept the option or a value
        out of range."""
        if value is None:
            return self
        return replace(self, method=self.method.with_option(option, value))

    def with_heldout_tolerance(self, tolerance: float | None) -> "FitConfig":
        """This configuration with the discovery's practical threshold ``DiscoveryConfig.heldout_tolerance`` (None:
        unchanged): :meth:`with_method_option` ``("heldout_tolerance", tolerance)``."""
        return self.with_method_option("heldout_tolerance", tolerance)

    def with_output_error(self, mode: str | None) -> "FitConfig":
        """This configuration with the discovery's coefficients under model error (``DiscoveryConfig.output_error``)
        set by ``mode`` (:data:`OUTPUT_ERROR_MODES`; None: unchanged): :meth:`with_method_option`
        ``("output_error", mode)``."""
        return self.with_method_option("output_error", mode)

    def with_max_evals(self, max_evals: int | None, joint: bool = False) -> "FitConfig":
        """This configuration with ``max_evals`` evaluations of the method's main long-time refinement
        (``MethodConfig.max_evals_setting``) and, if ``joint``, of its joint re-optimisation too (None: unchanged)."""
        if max_evals is None:
            return self
        method = self.method.with_max_evals(max_evals)
        return replace(self, method=method.with_joint_max_evals(max_evals) if joint else method)
