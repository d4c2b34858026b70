"""The sign-flip permutation test."""
import numpy as np
import pytest

from validation.diagnosis.identify.statistics import sign_flip_pvalue
from validation.diagnosis.identify.statistics import runs_needed, smallest_sign_flip_pvalue


def test_sign_flip_pvalue_exact_cases():
    assert sign_flip_pvalue(np.ones(5)) == pytest.approx(1 / 32)  # only the observed pattern is as large
    assert sign_flip_pvalue(np.zeros(4)) == 1.0
    # one large positive and four tiny negatives: half of the sign patterns have a sum at least as large
    p = sign_flip_pvalue(np.array([1.0, -1e-3, -1e-3, -1e-3, -1e-3]))
    assert 0.5 <= p <= 0.5 + 1 / 32 + 1e-12
    # brute force on a random vector
    d = np.random.default_rng(3).normal(0.3, 1.0, 9)
    signs = np.array([[1 - 2 * ((k >> i) & 1) for i in range(9)] for k in range(2**9)])
    assert sign_flip_pvalue(d) == pytest.approx(np.mean(signs @ np.abs(d) >= d.sum() - 1e-12))


@pytest.mark.parametrize("n_runs", [1, 3, 6, 7, 10])
def test_smallest_attainable_p_is_that_of_all_runs_improved(n_runs):
    """The floor 2^-n is what the test returns when every run improves (and nothing is smaller)."""
    assert smallest_sign_flip_pvalue(n_runs) == sign_flip_pvalue(np.linspace(1.0, 2.0, n_runs))
    d = np.random.default_rng(n_runs).normal(0.0, 1.0, n_runs)
    assert sign_flip_pvalue(d) >= smallest_sign_flip_pvalue(n_runs)


@pytest.mark.parametrize("alpha, runs", [(0.01, 7), (0.05, 5), (0.001, 10), (0.5, 1), (0.25, 2)])
def test_runs_needed_is_the_fewest_that_can_reach_alpha(alpha, runs):
    assert runs_needed(alpha) == runs
    assert smallest_sign_flip_pvalue(runs) <= alpha < smallest_sign_flip_pvalue(runs - 1)
