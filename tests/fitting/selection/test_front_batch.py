"""The front's held-out errors integrated in batches (fitting.selection.front.held_out_fold_errors): the same numbers,
bit for bit, as the one-trajectory-at-a-time definitions (long_time_error, long_time_error_along)."""
from __future__ import annotations

import numpy as np
import pytest

from cubedimer.folds import run_folds
from fitting.integrate import integrate, integrate_batch
from fitting.model import EXPONENTS, TERMS, PolynomialModel
from fitting.selection.front import HeldOutRun, held_out_fold_errors, long_time_error, long_time_error_along
from fitting.synthetic import SyntheticConfig, generate_runs


@pytest.fixture(scope="module")
def held_out(truth):
    """Five noisy 1-s runs (no missing frames) as held-out runs; four carry state estimates (the exact states) and a horizon of 60
    frames (not a divisor of the run: the last horizon overlaps), one carries none (its error along is NaN)."""
    runs = generate_runs(truth, SyntheticConfig(n_runs=5, duration=1.0, missing_frames=0, seed=5))
    out = []
    for k, r in enumerate(runs):
        dt = float(r["t"][1] - r["t"][0])
        states = None if k == 2 else r["state"]
        out.append(HeldOutRun(dt, r["y"], r["theta"], r["state"][0], states=states, horizon=0 if k == 2 else 60))
    return out


def test_batched_fold_errors_are_the_one_by_one_errors(truth, held_out):
    folds = run_folds(len(held_out), 3)
    stiff = truth.coef.copy()
    stiff[0, TERMS.index("y")] *= 4.0  # another substep count than the truth's
    blows_up = truth.coef.copy()
    blows_up[1, TERMS.index("theta^3")] = 1e9  # leaves the blow-up bound: an infinite error
    for coefs in ([truth.coef] * 3, [truth.coef * 1.02, stiff, blows_up]):
        models = [PolynomialModel(c) for c in coefs]
        fold_err, fold_along = held_out_fold_errors(models, folds, held_out)
        want = [float(np.mean([long_time_error(m, held_out[r]) for r in test])) for m, (_, test) in zip(models, folds)]
        want_along = [float(np.mean([long_time_error_along(m, held_out[r]) for r in test]))
                      for m, (_, test) in zip(models, folds)]
        # exact equality: the same compiled integration of every trajectory, the same reductions
        assert fold_err == want
        assert np.array_equal(fold_along, want_along, equal_nan=True)
    assert np.isinf(fold_err[2]) and np.isfinite(fold_err[0])


def test_a_batch_with_substeps_per_trajectory_is_each_trajectory_alone(truth):
    rng = np.random.default_rng(3)
    x0s = rng.normal(size=(4, 4)) * [1e-4, 1e-2, 0.1, 5.0]
    coefs = np.stack([truth.coef * f for f in (1.0, 0.9, 1.1, 1.0)])
    steps, dts, ns = np.array([1, 3, 2, 5]), np.array([1e-3, 2e-3, 1e-3, 5e-4]), np.array([300, 120, 250, 400])
    traj, n_valid = integrate_batch(coefs, EXPONENTS, x0s, dts, ns, steps)
    for b in range(4):
        one, nv = integrate(coefs[b], EXPONENTS, x0s[b], dts[b], ns[b], steps[b])
        assert nv == n_valid[b] == ns[b]
        assert np.array_equal(traj[b, :ns[b]], one)  # bit for bit
        assert np.isnan(traj[b, ns[b]:]).all()  # the padding to the longest trajectory
    # a blow-up: the rows from n_valid on are NaN, in a batch and alone
    wild = truth.coef.copy()
    wild[1, TERMS.index("theta^3")] = 1e9
    traj, n_valid = integrate_batch(wild, EXPONENTS, x0s[:1] * 10, 1e-3, 300, 2, bound=[1e-2, np.inf, 2.0, np.inf])
    one, nv = integrate(wild, EXPONENTS, x0s[0] * 10, 1e-3, 300, 2, bound=[1e-2, np.inf, 2.0, np.inf])
    assert nv == n_valid[0] < 300 and np.isnan(one[nv:]).all() and np.array_equal(traj[0], one, equal_nan=True)
