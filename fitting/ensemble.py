"""Ensemble statistics over per-run refined models and the selection of the minimal model.

For every library term and equation, over the R refined per-run models (a term absent from a
run's model counts as a zero coefficient):

* z-score ``z = |mean| / std`` (sample standard deviation, ddof = 1).  A term whose
  coefficient is consistent across runs has a large z; a term that is fitted with random
  sign/size (noise, collinearity) has z ~ 1 or below.  ``std = 0`` gives z = 0 if the mean
  is 0 and :data:`Z_CAP` otherwise (finite, so it can be written to JSON).
* inclusion frequency: the fraction of runs whose model has the term.

Selected: ``z > z_threshold`` (default 3) plus the viscous damping terms (ydot in yddot,
thetadot in thetaddot), which are always kept because a long-time model without dissipation
cannot have attracting sets.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np
from numpy.typing import NDArray

from .library import EQUATION_NAMES
from .model import DAMPING_TERMS, TERMS, PolynomialModel

__all__ = ["EnsembleConfig", "TermStatistics", "term_statistics", "select_terms", "Z_CAP",
           "least_squares_on_support"]

Z_CAP = 1e6


@dataclass(frozen=True)
class EnsembleConfig:
    """Selection rule: keep terms with z > ``z_threshold``; optionally always the damping terms."""

    z_threshold: float = 3.0
    keep_damping: bool = True


@dataclass(frozen=True, eq=False)
class TermStatistics:
    """Per-term statistics (arrays of shape (2, 35), SI where dimensional)."""

    mean: NDArray[np.float64]
    std: NDArray[np.float64]
    zscore: NDArray[np.float64]
    inclusion: NDArray[np.float64]
    n_runs: int

    def as_dict(self, array: NDArray) -> dict[str, dict[str, float]]:
        """``{"yddot": {term: value, ...}, "thetaddot": {...}}`` for every library term."""
        return {eq: {t: float(v) for t, v in zip(TERMS, array[q])} for q, eq in enumerate(EQUATION_NAMES)}


def term_statistics(models: Sequence[PolynomialModel]) -> TermStatistics:
    """z-scores and inclusion frequencies of every term over the per-run models."""
    c = np.array([m.coef for m in models])
    if c.shape[0] < 2:
        raise ValueError("z-scores need at least two runs")
    mean = c.mean(axis=0)
    std = c.std(axis=0, ddof=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        z = np.where(std > 0, np.abs(mean) / std, np.where(mean != 0, Z_CAP, 0.0))
    z = np.minimum(z, Z_CAP)
    return TermStatistics(mean=mean, std=std, zscore=z, inclusion=np.mean(c != 0, axis=0), n_runs=c.shape[0])


def select_terms(stats: TermStatistics, config: EnsembleConfig = EnsembleConfig()) -> NDArray[np.bool_]:
    """Boolean mask (2, 35) of the minimal model's terms."""
    mask = stats.zscore > config.z_threshold
    if config.keep_damping:
        for q, eq in enumerate(EQUATION_NAMES):
            mask[q, TERMS.index(DAMPING_TERMS[eq])] = True
    return mask


def least_squares_on_support(X: Sequence[NDArray], A: Sequence[NDArray], mask: NDArray[np.bool_]) -> NDArray[np.float64]:
    """Ordinary least squares of the stacked accelerations on the masked library columns.

    Parameters
    ----------
    X, A : list of ndarray
        Scaled states (n_i, 4) and accelerations (n_i, 2) of every run.
    mask : (2, 35) bool

    Returns
    -------
    ndarray (2, 35)
        Scaled coefficients, zero outside ``mask``.
    """
    from .library import evaluate_library

    Theta = np.vstack([evaluate_library(x) for x in X])
    acc = np.vstack(A)
    out = np.zeros(mask.shape)
    for q in range(2):
        cols = np.flatnonzero(mask[q])
        if cols.size:
            out[q, cols] = np.linalg.lstsq(Theta[:, cols], acc[:, q], rcond=None)[0]
    return out
