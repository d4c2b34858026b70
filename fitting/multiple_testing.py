"""Holm's step-down procedure: the one multiple-testing rule of the term selections.

Both selection rules of :mod:`fitting` (the significance of the ensemble mean across runs in
:mod:`fitting.ensemble`, and the pooled integral-form selection in :mod:`fitting.integral_form`)
control the family-wise error rate over the library terms with Holm's rule: sort the p-values,
reject the k-th smallest (k = 1, 2, ...) while ``p_(k) <= alpha / (m - k + 1)``, stop at the first
that fails.  Hypotheses that were removed before testing (e.g. terms already eliminated) count as
the least significant ones: pass their number in ``n_hypotheses``.
"""
from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["holm_level", "holm_reject", "holm_z_threshold"]


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
