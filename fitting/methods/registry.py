"""The registry of model-discovery methods: what ``--method`` and :class:`fitting.config.FitConfig` ``method`` choose.

A method is an object satisfying :class:`FittingMethod`: a name, a one-line summary (the command-line help
lists it), the class of its own frozen settings (``config_type``, :mod:`fitting.method_settings`: what
:class:`fitting.config.FitConfig` ``method`` holds, with the command-line options that set them),
``fit(prepared, scales, config, context)``, which turns prepared runs into one :class:`fitting.results.FitResult`,
and ``describe(result)``, its own account of that result
(:class:`fitting.description.MethodDescription`: the report's paragraph, table and figures of the fit).  It is
registered once with :func:`register_method`; the fit command, the report command and
:func:`fitting.fit.fit_runs` read :data:`METHODS` (like scipy's ``solve_ivp`` ``METHODS``; the names live in
:mod:`fitting.method_names`, which the configuration checks against), so a registered method is selectable
everywhere without further changes.

The built-in entries are ``"discovery"`` (:mod:`fitting.methods.discovery`, the default) and ``"paper"``
(:mod:`fitting.methods.paper`); importing :mod:`fitting` registers both.
"""
from __future__ import annotations

import os
from dataclasses import dataclass
from typing import Protocol, Sequence, runtime_checkable

from cubedimer.executor import ExecutorConfig
from cubedimer.load_config import LOAD_OPTIONS
from cubedimer.setting_options import SettingOption, field_value
from ..config import FitConfig
from ..description import MethodDescription
from ..method_names import (DEFAULT_METHOD, METHODS, get_method, method_names, method_options, methods_accepting,
                            methods_help)
from ..method_settings import MethodConfig
from ..model import Scales
from ..results import FitResult, PreparedRun
from ..uncertainty.oracle import NoiseLevels

__all__ = ["FitContext", "FittingMethod", "METHODS", "DEFAULT_METHOD", "register_method", "method_names",
           "get_method", "method_options", "methods_accepting", "methods_help"]


@dataclass(frozen=True)
class FitContext:
    """Where and how a method runs (everything but the data and the settings).

    Parameters
    ----------
    executor : ExecutorConfig, optional
        Where parallel work runs (:func:`cubedimer.executor.map_ordered`; default: local processes).
    cache_dir : path-like, optional
        Directory of per-run results that a rerun resumes from (methods that have per-run work; None: no cache).
    progress : bool
        Show progress bars of parallel work.
    noise : NoiseLevels, optional
        Tracking noise of the data for the oracle standard errors (default: estimated from the runs).
    """

    executor: ExecutorConfig | None = None
    cache_dir: str | os.PathLike | None = None
    progress: bool = True
    noise: NoiseLevels | None = None


@runtime_checkable
class FittingMethod(Protocol):
    """A model-discovery method.

    Attributes
    ----------
    name : str
        The registry key (``--method NAME``).
    summary : str
        One sentence for the command-line help.
    config_type : type
        The class of the method's frozen settings (a :class:`~fitting.method_settings.MethodConfig` whose
        ``name`` is the method's): what :class:`~fitting.config.FitConfig` ``method`` holds, what model.json's
        ``settings`` records under the method's name, the command-line options that set them (``options``, declared
        beside the fields: :class:`cubedimer.setting_options.SettingOption`; every command that fits offers them)
        and which refinement ``--max-evals`` sets (``max_evals_setting``).
    """

    name: str
    summary: str
    config_type: type

    def fit(self, prepared: Sequence[PreparedRun], scales: Scales, config: FitConfig,
            context: FitContext) -> FitResult:
        """Select and fit the model of the prepared runs; the result has every field the method produces."""
        ...

    def describe(self, result: FitResult) -> MethodDescription:
        """The method's account of ``result`` (one of its own fits): how the model was found and what it is, in the
        words and with the numbers of model.json."""
        ...


def register_method(method: FittingMethod) -> FittingMethod:
    """Add ``method`` to :data:`METHODS` under ``method.name`` (replacing an entry of that name); returns it.

    Raises
    ------
    TypeError
        ``method`` does not satisfy :class:`FittingMethod`, its ``config_type`` is not the settings of a method of
        its name, or an option its settings declare cannot join the fit's parser (a flag of the loader's, a field
        the settings lack, a flag another method declares with another type).
    """
    if not isinstance(method, FittingMethod) or not isinstance(method.name, str) or not method.name:
        raise TypeError(f"{method!r} is not a FittingMethod (name, summary, config_type, fit, describe)")
    if not (isinstance(method.config_type, type) and issubclass(method.config_type, MethodConfig)
            and method.config_type.name == method.name):
        raise TypeError(f"{method.name}: config_type must be a MethodConfig whose name is {method.name!r}, got "
                        f"{method.config_type!r}")
    _check_options(method)
    METHODS[method.name] = method
    return method


def _check_options(method: FittingMethod) -> None:
    """The method's command-line options can join the fit's parser: each a SettingOption on a field of its settings,
    none a flag of the loader's or ``--method``, and a flag another method declares too taken the same way."""
    settings = method.config_type()
    taken = {o.flag for o in LOAD_OPTIONS} | {"--method"}
    for option in method.config_type.command_options():
        if not isinstance(option, SettingOption):
            raise TypeError(f"{method.name}: its settings' options must be SettingOption declarations, got {option!r}")
        if option.flag in taken:
            raise TypeError(f"{method.name}: {option.flag} is an option of the fit's loading or of --method")
        try:
            field_value(settings, option.field)
        except AttributeError:
            raise TypeError(f"{method.name}: {option.flag} sets {option.field!r}, which its settings do not have") from None
        other = next((o for m in METHODS.values() if m.name != method.name
                      for o in m.config_type.command_options() if o.flag == option.flag), None)
        if other is not None and (other.type, other.is_switch, other.metavar) != (option.type, option.is_switch,
                                                                                  option.metavar):
            raise TypeError(f"{method.name}: {option.flag} is declared by another method with another type")
