"""The names of the registered fitting methods: what ``--method`` and :class:`fitting.config.FitConfig` ``method``
choose.

:data:`METHODS` maps a name to its :class:`fitting.methods.registry.FittingMethod`; :func:`fitting.methods.registry.register_method`
adds to it.  This module imports nothing of the fitting, so the configuration checks names against it and the
method protocol (whose signatures name the configuration and the result) builds on both without an import circle.
"""
from __future__ import annotations

from typing import Any

__all__ = ["METHODS", "DEFAULT_METHOD", "method_names", "get_method", "method_options", "methods_accepting",
           "methods_help"]

#: The method a fit uses unless told otherwise.
DEFAULT_METHOD = "discovery"

#: name -> method, in registration order (the default first).
METHODS: dict[str, Any] = {}  # values: fitting.methods.registry.FittingMethod


def method_names() -> tuple[str, ...]:
    """The registered method names (the ``--method`` choices)."""
    return tuple(METHODS)


def get_method(name: str) -> Any:
    """The registered method ``name``; ValueError (one line, listing the choices) if there is none."""
    try:
        return METHODS[name]
    except KeyError:
        raise ValueError(f"unknown method {name!r} (use one of {', '.join(METHODS)})") from None


def method_options() -> tuple[str, ...]:
    """The command-line options of the registered methods' settings (argparse destinations, ``"max_evals"``, in the
    order of the methods and of their declarations: ``MethodConfig.command_options``)."""
    return tuple(dict.fromkeys(o.dest for m in METHODS.values() for o in m.config_type.command_options()))


def methods_accepting(option: str) -> tuple[str, ...]:
    """The registered methods whose settings declare the option ``option`` (an argparse destination,
    :func:`method_options`)."""
    return tuple(name for name, m in METHODS.items() if m.config_type.command_option(option) is not None)


def methods_help() -> str:
    """``'name' (summary), ...`` of every registered method, for a command's ``--method`` help."""
    return "; ".join(f"'{m.name}'{' (default)' if m.name == DEFAULT_METHOD else ''}: {m.summary}"
                     for m in METHODS.values())
