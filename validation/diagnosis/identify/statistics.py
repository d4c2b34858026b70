"""Significance tests of the held-out improvements: sign-flip permutation test and Wilcoxon signed rank.

Both test the one-sided hypothesis "the per-run differences are larger than zero" on one value per
held-out run.  The sign-flip test uses the size of each run's difference, not only its rank: runs with
little motion in the affected coordinate carry almost no signal and, with random signs but small
sizes, barely move it, where they cost the Wilcoxon signed-rank test whole ranks.  The sign-flip test
decides; the Wilcoxon p-value is reported beside it.
"""
from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

__all__ = ["sign_flip_pvalue", "wilcoxon_greater_pvalue", "smallest_sign_flip_pvalue", "runs_needed", "format_p",
           "P_FLOOR"]

#: Below this a p-value is stated as a bound: double precision cannot tell smaller tail probabilities apart
#: (1 - 1e-16 rounds to 1), and "p = 0" would read as a certainty no finite data give.
P_FLOOR = 1e-16


def format_p(p: float, digits: int = 2) -> str:
    """A p-value as prose: ``"p = 0.034"``, or ``"p < 1e-16"`` below :data:`P_FLOOR` (never ``"p = 0"``)."""
    p = float(p)
    if not np.isfinite(p):
        return "p undefined"
    return f"p < {P_FLOOR:g}" if p < P_FLOOR else f"p = {p:.{digits}g}"


def sign_flip_pvalue(diff: ArrayLike, n_random: int = 200_000, seed: int = 0) -> float:
    """One-sided p-value of "mean(diff) > 0" by the sign-flip (Fisher-Pitman) permutation test.

    Under H0 each run's difference is symmetric about zero, so every assignment of signs is equally
    likely; p is the fraction of the 2^n sign patterns whose mean is at least the observed one
    (exact enumeration for n <= 18, else ``n_random`` seeded random patterns).

    Parameters
    ----------
    diff : array_like, shape (n,)
        One difference per run (any unit).
    n_random : int
        Number of random sign patterns when n > 18.
    seed : int
        Seed of those patterns.

    Returns
    -------
    float
        The p-value; 1 for n = 0 or an all-zero ``diff``.
    """
    d = np.asarray(diff, float)
    n = d.size
    if n == 0 or not np.any(d != 0):
        return 1.0
    obs = d.sum()
    if n <= 18:
        signs = 1 - 2 * ((np.arange(2**n)[:, None] >> np.arange(n)) & 1)
    else:
        signs = np.random.default_rng(seed).choice([-1, 1], size=(n_random, n))
    sums = signs @ np.abs(d)
    return float(np.mean(sums >= obs - 1e-12 * np.abs(d).sum()))


def smallest_sign_flip_pvalue(n_runs: int) -> float:
    """The smallest p-value :func:`sign_flip_pvalue` can return for ``n_runs`` differences: 2^-n (every run
    improved; only the all-positive sign pattern reaches the observed sum). 1 for no run."""
    return 0.5 ** int(n_runs) if n_runs > 0 else 1.0


def runs_needed(alpha: float) -> int:
    """The fewest runs with which the one-sided sign-flip test can reach ``p <= alpha`` (7 for alpha = 0.01)."""
    if not 0 < alpha < 1:
        raise ValueError(f"alpha must lie in (0, 1), got {alpha!r}")
    return int(np.ceil(-np.log2(alpha) - 1e-12))


def wilcoxon_greater_pvalue(diff: ArrayLike) -> float:
    """One-sided p-value of the Wilcoxon signed-rank test that ``diff`` lies above zero (zero differences
    split between the signs); 1 for an all-zero ``diff`` or a sample the test cannot rank."""
    from scipy.stats import wilcoxon

    d = np.asarray(diff, float)
    try:
        return float(wilcoxon(d, alternative="greater", zero_method="zsplit").pvalue) if np.any(d != 0) else 1.0
    except ValueError:
        return 1.0
