"""Holm's step-down rule (fitting.multiple_testing) on hand-worked cases and its family-wise error."""
import numpy as np
import pytest
from scipy.stats import norm

from fitting.multiple_testing import holm_level, holm_reject, holm_z_threshold


def test_hand_worked_example():
    # m = 4, alpha = 0.05: levels 0.0125, 0.01667, 0.025, 0.05 for the sorted p-values
    p = np.array([0.01, 0.04, 0.03, 0.005])
    # sorted: 0.005 <= 0.0125 yes, 0.01 <= 0.01667 yes, 0.03 <= 0.025 no -> stop
    np.testing.assert_array_equal(holm_reject(p, 0.05), [True, False, False, True])


def test_removed_hypotheses_count_as_least_significant():
    # alone, 0.011 passes the second level alpha / 1 = 0.05; in a family of 6 the levels are
    # alpha / 6 = 0.0083 (0.005 passes) and alpha / 5 = 0.01 (0.011 fails)
    np.testing.assert_array_equal(holm_reject([0.005, 0.011], 0.05), [True, True])
    np.testing.assert_array_equal(holm_reject([0.005, 0.011], 0.05, n_hypotheses=6), [True, False])
    with pytest.raises(ValueError):
        holm_reject([0.1, 0.2, 0.3], 0.05, n_hypotheses=2)


def test_nan_is_never_rejected_and_shape_is_kept():
    r = holm_reject(np.array([[np.nan, 1e-9], [0.5, 1e-8]]), 0.01)
    np.testing.assert_array_equal(r, [[False, True], [False, True]])


@pytest.mark.parametrize("rank", [1, 7, 35])
def test_z_threshold_matches_the_level(rank):
    z = holm_z_threshold(0.01, 35, rank)
    np.testing.assert_allclose(2 * norm.sf(z), holm_level(0.01, 35, rank), rtol=1e-10)  # round-off only


def test_family_wise_error_under_the_global_null():
    # 2000 families of 20 true nulls: P(any rejection) <= alpha (binomial SE ~ 0.005 at alpha = 0.05)
    rng = np.random.default_rng(0)
    hits = sum(holm_reject(rng.uniform(size=20), 0.05).any() for _ in range(2000))
    assert hits / 2000 <= 0.05 + 3 * np.sqrt(0.05 * 0.95 / 2000)


def test_holm_all_significant_is_holm_reject_on_two_sided_normal_p_values():
    from scipy.special import ndtr

    from fitting.multiple_testing import holm_all_significant

    rng = np.random.default_rng(5)
    for _ in range(200):
        z = np.abs(rng.normal(0, 4, size=rng.integers(1, 8)))
        n = int(z.size + rng.integers(0, 30))
        assert holm_all_significant(z, 0.01, n) == bool(holm_reject(2 * ndtr(-z), 0.01, n).all())
    assert holm_all_significant(np.zeros(0), 0.01, 35) and holm_all_significant([0.1], 0.01, 0)
    assert not holm_all_significant([np.nan], 0.01, 1)  # NaN counts as z = 0


def test_backward_elimination_drops_weak_velocity_terms_first_and_keeps_forced_ones():
    from fitting.multiple_testing import holm_backward_elimination

    # columns: 0 y (z 10), 1 ydot (velocity, z 2), 2 y^2 (z 1), 3 forced damping ydot (velocity, z 0.5)
    z = np.array([10.0, 2.0, 1.0, 0.5])
    velocity = np.array([False, True, False, True])
    removable = np.array([True, True, True, False])
    path = [k for k, _, _ in holm_backward_elimination(lambda k: (z[k], None), [0, 1, 2, 3], velocity, removable, 3.0)]
    # ydot goes before the less significant y^2 (a velocity term below the Bonferroni z = 3); the forced one stays
    assert path == [[0, 1, 2, 3], [0, 2, 3], [0, 3], [3]]
    path = [k for k, _, _ in holm_backward_elimination(lambda k: (z[k], None), [0, 1, 2, 3], velocity, removable, -np.inf)]
    assert path[1] == [0, 1, 3]  # without the velocity preference the smallest |z| goes
