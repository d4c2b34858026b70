"""Holm's step-down procedure and the backward elimination along it: the one multiple-testing rule of the selections.

The selection rules of :mod:`fitting` (the significance of the ensemble mean across runs in
:mod:`fitting.selection.ensemble`, the pooled integral-form selection in :mod:`fitting.derivatives.integral_form`, the discovery's
support search in :mod:`fitting.selection.support_search`) and the diagnosis's library search
(:mod:`validation.diagnosis.discover.library_terms`) control the family-wise error rate over the library terms with Holm's rule: sort the p-values,
reject the k-th smallest (k = 1, 2, ...) while ``p_(k) <= alpha / (m - k + 1)``, stop at the first
that fails.  Hypotheses that were removed before testing (e.g. terms already eliminated) count as
the least significant ones: pass their number in ``n_hypotheses``.  :func:`holm_all_significant` is the one
stopping check and :func:`holm_backward_elimination` the one elimination path (velocity terms first).
"""
from __future__ import annotations

from typing import Callable, Iterator, Sequence, TypeVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

#: What a backward elimination's score function returns beside the |z| (e.g. the least-squares fit).
Fit = TypeVar("Fit")

__all__ = ["holm_level", "holm_reject", "holm_z_threshold", "holm_all_significant", "holm_backward_elimination"]


def holm_level(alpha: float, n_hypotheses: int, rank: int) -> float:
    """Level Holm's rule asks of the ``rank``-th smallest of ``n_hypotheses`` p-values (rank from 1)."""
    if not 1 <= rank <= n_hypotheses:
        raise ValueError(f"rank must lie in [1, {n_hypotheses}], got {rank}")
    return alpha / (n_hypotheses - rank + 1)


def holm_reject(pvalues: ArrayLike, alpha: float, n_hypotheses: int | None = None) -> NDArray[np.bool_]:
    """Which hypotheses Holm's step-down rule rejects at family-wise level ``alpha``.

    Parameters
    ----------
    pvalues : array_like
        p-values of the hypotheses tested (any shape; NaN counts as 1).
    alpha : float
        Family-wise error rate.
    n_hypotheses : int, optional
        Size of the family (default: the number of p-values); hypotheses beyond those given count as
        the least significant ones.

    Returns
    -------
    ndarray of bool, the shape of ``pvalues``
    """
    p = np.nan_to_num(np.asarray(pvalues, float), nan=1.0)
    m = p.size if n_hypotheses is None else int(n_hypotheses)
    if m < p.size:
        raise ValueError(f"n_hypotheses = {m} is smaller than the {p.size} p-values given")
    flat = p.ravel()
    order = np.argsort(flat, kind="stable")
    reject = np.zeros(flat.size, bool)
    for rank, idx in enumerate(order, 1):
        if flat[idx] <= holm_level(alpha, m, rank):
            reject[idx] = True
        else:
            break
    return reject.reshape(p.shape)


def holm_z_threshold(alpha: float, n_hypotheses: int, rank: int) -> float:
    """|z| a two-sided normal test needs to pass Holm's level for the ``rank``-th most significant term:
    Bonferroni (alpha / n) for the first, alpha for the n-th."""
    from scipy.special import ndtri

    return float(ndtri(1.0 - 0.5 * holm_level(alpha, n_hypotheses, rank)))


def holm_all_significant(abs_z: ArrayLike, alpha: float, n_hypotheses: int) -> bool:
    """Whether Holm's rule over ``n_hypotheses`` declares every one of the terms with two-sided normal ``|z|``
    significant (the hypotheses not given, e.g. terms dropped before, count as the least significant ones).

    Parameters
    ----------
    abs_z : array_like
        |z| of the terms tested (NaN counts as 0).
    alpha : float
        Family-wise error rate.
    n_hypotheses : int
        Size of the family; 0 (nothing free to test) is vacuously significant.
    """
    from scipy.special import ndtr

    if n_hypotheses == 0:
        return True
    z = np.nan_to_num(np.abs(np.asarray(abs_z, float)), nan=0.0)
    return bool(holm_reject(2.0 * ndtr(-z), alpha, n_hypotheses).all())


def holm_backward_elimination(score: Callable[[list[int]], tuple[NDArray[np.float64], Fit]], columns: Sequence[int],
                              velocity: NDArray[np.bool_], removable: NDArray[np.bool_],
                              velocity_z: float) -> Iterator[tuple[list[int], NDArray[np.float64], Fit]]:
    """Backward elimination with velocity terms first: the one elimination path of the term selections.

    Starting from ``columns``, yields ``(support, |z|, fit)`` of the current support (``score(support)``) before
    every step; the caller stops where its rule is met (e.g. :func:`holm_all_significant`).  A step drops the
    removable term of smallest |z|, except that while a removable velocity term is below ``velocity_z`` (the
    Bonferroni level) the least significant velocity term goes: a conservative field is the default hypothesis,
    and on harmonic y motion y^2*theta and ydot^2*theta are nearly collinear and would otherwise be chosen between
    by noise.  Ends after the support in which nothing is removable (the forced terms, or none: ``score`` is then
    called with an empty support).

    Parameters
    ----------
    score : callable
        ``score(support) -> (|z| per column of support, fit)`` (NaN-free |z|).
    columns : sequence of int
        The starting support (column indices).
    velocity, removable : ndarray of bool, indexed by column
        Which columns have a velocity factor; which may be dropped (the others are forced).
    velocity_z : float
        |z| below which a velocity term goes first (:func:`holm_z_threshold` at rank 1).
    """
    keep = list(columns)
    while True:
        absz, fit = score(keep)
        yield list(keep), absz, fit
        idx = np.asarray(keep, dtype=int)
        free = np.flatnonzero(removable[idx])
        if not free.size:
            return
        weak_velocity = free[velocity[idx][free] & (absz[free] < velocity_z)]
        pool = weak_velocity if weak_velocity.size else free
        keep.pop(int(pool[np.argmin(absz[pool])]))
