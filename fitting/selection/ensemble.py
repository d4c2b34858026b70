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

The z-score compares the mean with the *spread of single runs*; it does not grow with the number
of runs, so a term that one short run cannot determine (per-run z ~ 1-1.5 for a term contributing a
few per cent of the acceleration, measured even for least squares on the true support) is dropped
however many runs show it.  :func:`select_significant_terms` asks the question that does use the
ensemble: is the mean coefficient across runs different from zero?  It applies the one-sample
t-test (``t = mean / (std / sqrt(R))`` with R - 1 degrees of freedom, i.e. z sqrt(R)) to every term
that is non-zero in at least one run, with the Holm-Bonferroni correction over those terms at
family-wise level ``alpha``.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np
from numpy.typing import NDArray

from cubedimer.config_checks import check_positive
from cubedimer.terms import EQUATION_NAMES
from ..model import TERMS, PolynomialModel, damping_mask
from ..multiple_testing import holm_reject

__all__ = ["EnsembleConfig", "TermStatistics", "term_statistics", "select_terms", "select_significant_terms",
           "mean_pvalues", "Z_CAP", "least_squares_on_support"]

Z_CAP = 1e6


@dataclass(frozen=True)
class EnsembleConfig:
    """Selection rule: keep terms with z > ``z_threshold``; optionally always the damping terms."""

    z_threshold: float = 3.0
    keep_damping: bool = True

    def __post_init__(self) -> None:
        check_positive(self, "z_threshold")


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
        mask |= damping_mask()
    return mask


def mean_pvalues(stats: TermStatistics) -> NDArray[np.float64]:
    """Two-sided p-values (2, 35) of the one-sample t-test "mean coefficient = 0" across the runs
    (t = z sqrt(R), R - 1 degrees of freedom); 1 for terms that are zero in every run."""
    from scipy.stats import t as student_t

    r = stats.n_runs
    p = 2.0 * student_t.sf(stats.zscore * np.sqrt(r), r - 1)  # t = z sqrt(R); z is capped at Z_CAP, p ~ 0 there
    return np.where(stats.inclusion > 0, p, 1.0)


def select_significant_terms(stats: TermStatistics, alpha: float = 0.01, keep_damping: bool = True) -> NDArray[np.bool_]:
    """Terms whose mean coefficient across runs is significantly non-zero (module docstring): Holm-Bonferroni
    over the terms present in at least one run, family-wise level ``alpha``; plus the damping terms."""
    p = mean_pvalues(stats)
    tested = stats.inclusion > 0
    mask = np.zeros(p.shape, bool)
    mask[tested] = holm_reject(p[tested], alpha)
    if keep_damping:
        mask |= damping_mask()
    return mask


def least_squares_on_support(X: Sequence[NDArray], A: Sequence[NDArray], mask: NDArray[np.bool_],
                             library: Sequence[NDArray] | None = None) -> NDArray[np.float64]:
    """Ordinary least squares of the stacked accelerations on the masked library columns.

    Parameters
    ----------
    X, A : list of ndarray
        Scaled states (n_i, 4) and accelerations (n_i, 2) of every run.
    mask : (2, 35) bool
    library : list of ndarray (n_i, 35), optional
        Precomputed library per run (e.g. :func:`fitting.selection.sparse_regression.scaled_library` with the
        matched filter); default: evaluated at ``X``.

    Returns
    -------
    ndarray (2, 35)
        Scaled coefficients, zero outside ``mask``.
    """
    from cubedimer.terms import evaluate_library

    Theta = np.vstack(library if library is not None else [evaluate_library(x) for x in X])
    acc = np.vstack(A)
    out = np.zeros(mask.shape)
    for q in range(2):
        cols = np.flatnonzero(mask[q])
        if cols.size:
            out[q, cols] = np.linalg.lstsq(Theta[:, cols], acc[:, q], rcond=None)[0]
    return out
