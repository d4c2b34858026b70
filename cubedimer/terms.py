"""The cubic polynomial library over the state [y, ydot, theta, thetadot] (docs/conventions.md section 6).

Term names follow docs/formats.md: factors in state order, joined by ``*``, powers as ``^n`` for
n >= 2, the constant as ``1``.  There are 35 monomials of degree <= 3 in four variables.
"""
from __future__ import annotations

from functools import lru_cache
from itertools import combinations_with_replacement

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "STATE_NAMES",
    "EQUATION_NAMES",
    "library_exponents",
    "term_name",
    "library_terms",
    "coefficient_label",
    "coefficient_labels",
    "evaluate_library",
    "parse_term",
    "is_velocity_free",
]

STATE_NAMES: tuple[str, ...] = ("y", "ydot", "theta", "thetadot")
EQUATION_NAMES: tuple[str, ...] = ("yddot", "thetaddot")


def library_exponents(degree: int = 3, n_vars: int = 4) -> NDArray[np.int64]:
    """Exponent vectors (n_terms, n_vars) of all monomials up to ``degree``, in canonical order.

    Order: by total degree, then lexicographically by the factors in state order (the order of
    ``itertools.combinations_with_replacement``), starting with the constant.
    """
    rows = [np.zeros(n_vars, dtype=np.int64)]
    for d in range(1, degree + 1):
        for combo in combinations_with_replacement(range(n_vars), d):
            e = np.zeros(n_vars, dtype=np.int64)
            for i in combo:
                e[i] += 1
            rows.append(e)
    return np.array(rows)


def term_name(exponents: ArrayLike, names: tuple[str, ...] = STATE_NAMES) -> str:
    """Canonical name of the monomial with ``exponents`` (e.g. [1, 0, 2, 0] -> ``y*theta^2``)."""
    parts = []
    for n, e in zip(names, np.asarray(exponents, dtype=int)):
        if e == 1:
            parts.append(n)
        elif e > 1:
            parts.append(f"{n}^{e}")
    return "*".join(parts) if parts else "1"


def library_terms(degree: int = 3) -> list[str]:
    """Names of the library's monomials in canonical order (35 for degree 3)."""
    return [term_name(e) for e in library_exponents(degree)]


def coefficient_label(equation: int, term: int, degree: int = 3) -> str:
    """The coefficient of library term ``term`` in equation ``equation`` as ``equation:term`` (``thetaddot:y^2*theta``),
    the form model.json's term lists and the logs use."""
    return f"{EQUATION_NAMES[equation]}:{_terms(degree)[term]}"


def coefficient_labels(degree: int = 3) -> NDArray[np.str_]:
    """(2, n_terms) every coefficient's :func:`coefficient_label`, shaped like a model's coefficient array."""
    return np.array([[coefficient_label(q, j, degree) for j in range(len(_terms(degree)))]
                     for q in range(len(EQUATION_NAMES))])


@lru_cache(maxsize=None)
def _terms(degree: int) -> tuple[str, ...]:
    return tuple(library_terms(degree))


def parse_term(name: str, names: tuple[str, ...] = STATE_NAMES) -> NDArray[np.int64]:
    """Exponent vector of a canonical term name; raises ValueError on an unknown factor."""
    e = np.zeros(len(names), dtype=np.int64)
    if name.strip() == "1":
        return e
    for factor in name.split("*"):
        base, _, power = factor.strip().partition("^")
        if base not in names:
            raise ValueError(f"unknown factor {base!r} in term {name!r}; state variables are {names}")
        e[names.index(base)] += int(power) if power else 1
    return e


def is_velocity_free(name: str) -> bool:
    """True for monomials of theta and y only (those a static simulation can predict)."""
    e = parse_term(name)
    return e[1] == 0 and e[3] == 0


def evaluate_library(state: ArrayLike, degree: int = 3) -> NDArray[np.float64]:
    """Library matrix (n_samples, n_terms) for states (n_samples, 4) [SI]."""
    x = np.atleast_2d(np.asarray(state, dtype=float))
    exps = library_exponents(degree, x.shape[1])
    out = np.ones((x.shape[0], len(exps)))
    for j, e in enumerate(exps):
        for i, p in enumerate(e):
            if p:
                out[:, j] *= x[:, i] ** p
    return out
