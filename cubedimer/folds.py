"""The one K-fold split over the runs of a data set, for every held-out score of the suite.

Run ``i`` is in fold ``i mod K`` (``K = min(k, n_runs)``): the folds interleave the runs, every run is held out
exactly once, and ``k >= n_runs`` is leave-one-run-out.  Used by the held-out supports of the fit
(:mod:`fitting.selection.support_search`) and the held-out tests of the diagnosis (:mod:`validation.diagnosis`).
"""
from __future__ import annotations

__all__ = ["run_folds"]


def run_folds(n_runs: int, k: int) -> list[tuple[list[int], list[int]]]:
    """The ``min(k, n_runs)`` folds over ``n_runs`` runs, run ``i`` held out in fold ``i mod min(k, n_runs)``.

    Parameters
    ----------
    n_runs : int
        Number of runs (0 gives no fold).
    k : int
        Requested number of folds (>= 1); clamped to ``n_runs``.

    Returns
    -------
    list of (list of int, list of int)
        Per fold, the indices of its training runs and of its held-out runs, both increasing.
    """
    kk = min(k, n_runs)
    return [([i for i in range(n_runs) if i % kk != f], list(range(f, n_runs, kk))) for f in range(kk)]
