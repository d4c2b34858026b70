"""The sign-flip permutation test."""
import numpy as np
import pytest

from validation.diagnosis import sign_flip_pvalue


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
