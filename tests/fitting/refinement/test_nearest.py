"""Exact nearest-point distances of the shape loss against scipy's k-d tree."""
import numpy as np
import pytest
from scipy.spatial import cKDTree

from fitting.refinement.nearest import PointGrid


def _trajectory(n, phase=0.0, scale=1.0, noise=0.01, seed=0):
    t = np.arange(n) / 1500.0
    rng = np.random.default_rng(seed)
    x = np.stack([np.cos(2 * np.pi * 22 * t + phase) * np.exp(-0.3 * t), -np.sin(2 * np.pi * 22 * t + phase),
                  np.sin(2 * np.pi * 30 * t + 0.3 * np.sin(2 * np.pi * 22 * t)), np.cos(2 * np.pi * 30 * t)], 1)
    return scale * x + noise * rng.normal(size=x.shape)


CASES = {
    "close trajectory": lambda: (_trajectory(3000), _trajectory(3000, noise=0.012, seed=1)),
    "out of phase": lambda: (_trajectory(3000), _trajectory(3000, phase=1.0, seed=2)),
    "shrunk (far)": lambda: (_trajectory(2000), _trajectory(2000, scale=0.4, seed=3)),
    "outside the grid": lambda: (_trajectory(1000), 3.0 * _trajectory(1500, seed=4)),
    "rest model": lambda: (_trajectory(1000), np.zeros((1000, 4))),
    "gaussian clouds": lambda: (np.random.default_rng(5).normal(size=(700, 3)),
                                np.random.default_rng(6).normal(size=(900, 3)) * 2),
    "one point": lambda: (np.array([[0.3, -0.2]]), np.random.default_rng(7).normal(size=(50, 2))),
    "coincident points": lambda: (np.ones((40, 4)), np.random.default_rng(8).normal(size=(30, 4))),
}


@pytest.mark.parametrize("case", list(CASES))
def test_matches_kdtree_exactly(case):
    points, query = CASES[case]()
    grid = PointGrid.of(points)
    ref, _ = cKDTree(points).query(query)
    got = grid.nearest_squared(query)
    # exact search: only the rounding of the squared distance differs from the tree's sqrt-then-square
    np.testing.assert_allclose(got, ref**2, rtol=1e-12, atol=1e-300)


def test_any_guess_gives_the_same_answer():
    points, query = CASES["close trajectory"]()
    grid = PointGrid.of(points)
    rng = np.random.default_rng(9)
    a = grid.nearest_squared(query)
    b = grid.nearest_squared(query, guess=rng.integers(0, len(points), len(query)))
    np.testing.assert_array_equal(a, b)  # the guess only sets where the search starts


@pytest.mark.parametrize("bad, message", [
    (lambda g: g.nearest_squared(np.zeros((3, 2))), "expected"),
    (lambda g: g.nearest_squared(np.full((2, 4), np.nan)), "finite"),
    (lambda g: g.nearest_squared(np.zeros((2, 4)), guess=[0, 10_000]), "guess"),
    (lambda g: PointGrid.of(np.zeros((0, 4))), "non-empty"),
])
def test_bad_input_is_refused(bad, message):
    grid = PointGrid.of(_trajectory(100))
    with pytest.raises(ValueError, match=message):
        bad(grid)
