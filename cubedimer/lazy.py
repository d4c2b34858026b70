"""The one lazy-import mechanism of the suite's package ``__init__`` modules (PEP 562 module ``__getattr__``).

A package whose public names live in heavy modules (matplotlib, the whole diagnosis) lists them as
``name -> relative module`` and gets a ``__getattr__`` that imports the module on first use and caches the value::

    __getattr__ = lazy_attributes(__name__, {"build_report": ".pipeline"})
"""
from __future__ import annotations

import sys
from importlib import import_module
from typing import Any, Callable, Mapping

__all__ = ["lazy_attributes"]


def lazy_attributes(package: str, names: Mapping[str, str]) -> Callable[[str], Any]:
    """A module ``__getattr__`` for ``package`` that imports ``names[name]`` (relative to ``package``) on first use.

    Parameters
    ----------
    package : str
        The package's ``__name__``.
    names : mapping of str to str
        Public name -> module that defines it (``".diagnosis"``, ``".report.pipeline"``).
    """
    table = dict(names)

    def __getattr__(name: str) -> Any:
        if name in table:
            value = getattr(import_module(table[name], package), name)
            setattr(sys.modules[package], name, value)  # later look-ups skip this function
            return value
        raise AttributeError(f"module {package!r} has no attribute {name!r}")

    return __getattr__
