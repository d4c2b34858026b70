"""The installed distribution ``cubedimer``: its version and its top-level import names.

The distribution installs five top-level packages (:data:`IMPORT_NAMES`).  Two of these names are also the names
of unrelated distributions on the Python package index (``fitting`` and ``validation``), and any distribution may
ship a top-level package of the same name.  Installed into the same environment, the other one's files replace or
shadow the suite's without an error.  :func:`foreign_import_names` finds such clashes and
:func:`warn_foreign_import_names` (called once when :mod:`cubedimer` is imported) warns about them. Install the suite
in an environment of its own (README, "Install").
"""
from __future__ import annotations

import importlib.metadata
import importlib.util
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Mapping, Sequence

__all__ = ["DISTRIBUTION", "IMPORT_NAMES", "ImportNameClash", "ImportNameWarning", "distribution_version",
           "foreign_import_names", "warn_foreign_import_names", "__version__"]

#: The distribution's name on the package index.
DISTRIBUTION = "cubedimer"
#: The top-level packages the distribution installs (pyproject.toml, ``[tool.hatch.build.targets.wheel]``).
IMPORT_NAMES = ("cubedimer", "acousim", "fitting", "validation", "tracking")


def distribution_version() -> str:
    """The installed version of the distribution (from its metadata); ``"0+unknown"`` when the sources run without
    being installed (e.g. only on ``PYTHONPATH``)."""
    try:
        return importlib.metadata.version(DISTRIBUTION)
    except importlib.metadata.PackageNotFoundError:
        return "0+unknown"


#: The version every package of the suite reports as ``__version__`` and every console script with ``--version``.
__version__ = distribution_version()


class ImportNameWarning(UserWarning):
    """One of the suite's top-level names belongs to, or resolves to, another distribution's files."""


@dataclass(frozen=True)
class ImportNameClash:
    """A top-level name of the suite that another installation also claims.

    Attributes
    ----------
    name : str
        The import name (e.g. ``"fitting"``).
    distributions : tuple of str
        Other installed distributions whose files contain this top-level package or module.
    location : str or None
        Where ``import name`` resolves when that is outside the folder holding the suite's ``cubedimer`` package
        (another installation shadows the suite's), else None.
    """

    name: str
    distributions: tuple[str, ...]
    location: str | None

    def message(self) -> str:
        """One line: the name, who else claims it, and what to do."""
        who = []
        if self.distributions:
            who.append("the installed distribution(s) " + ", ".join(self.distributions) + " also provide it")
        if self.location:
            who.append(f"'import {self.name}' resolves to {self.location}")
        return (f"top-level name {self.name!r} of {DISTRIBUTION}: " + "; ".join(who) + f". The suite's {self.name} "
                f"may be replaced or shadowed: install {DISTRIBUTION} in an environment of its own")


def _resolved_outside(name: str, home: Path) -> str | None:
    """Where ``name`` is found when that is not the folder ``home`` (the one holding the suite's packages)."""
    try:
        spec = importlib.util.find_spec(name)
    except (ImportError, ValueError):
        return None
    if spec is None:
        return None
    places = list(spec.submodule_search_locations or []) or ([spec.origin] if spec.origin else [])
    for place in places:
        if Path(place).resolve().parent != home:
            return str(Path(place))
    return None


def foreign_import_names(names: Sequence[str] = IMPORT_NAMES,
                         owners: Mapping[str, Sequence[str]] | None = None,
                         home: Path | None = None) -> list[ImportNameClash]:
    """The suite's top-level names that other installed distributions also provide, or that resolve elsewhere.

    Parameters
    ----------
    names : sequence of str
        The import names to check (default: the five the distribution installs).
    owners : mapping of str to sequence of str, optional
        Top-level name -> distributions providing it; default :func:`importlib.metadata.packages_distributions`
        (which reads every installed distribution's file list: about 0.1 s).
    home : Path, optional
        The folder holding the suite's packages; default the parent folder of this ``cubedimer`` package.

    Returns
    -------
    list of ImportNameClash
        Empty when every name is the suite's alone.
    """
    owners = importlib.metadata.packages_distributions() if owners is None else owners
    home = Path(__file__).resolve().parent.parent if home is None else home
    found = []
    for name in names:
        others = tuple(sorted({d for d in owners.get(name, ()) if d.lower() != DISTRIBUTION}))
        location = _resolved_outside(name, home)
        if others or location:
            found.append(ImportNameClash(name, others, location))
    return found


def warn_foreign_import_names() -> list[ImportNameClash]:
    """Warn (:class:`ImportNameWarning`, one line per name) about every clash :func:`foreign_import_names` finds;
    never raises: a broken distribution's metadata only skips the check."""
    try:
        clashes = foreign_import_names()
    except Exception:  # noqa: BLE001 - a check of the environment must never stop the import
        return []
    for clash in clashes:
        warnings.warn(clash.message(), ImportNameWarning, stacklevel=2)
    return clashes
