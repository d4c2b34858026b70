"""Regression (C0) and long-time refinement on noise-free data from the known model."""
import numpy as np
import pytest

from fitting.derivatives.savitzky_golay import SmoothingConfig, run_derivatives
from fitting.model import TERMS, PolynomialModel
from fitting.refinement.long_time import RefineConfig, refine
from fitting.selection.sparse_regression import (RegressionConfig, dataset_scales, fit_ensemble_regression,
                                                 fit_regression)


@pytest.fixture(scope="module")
def clean_derivs(clean_runs):
    # a narrow window (0.3 period): negligible Savitzky-Golay bias on noise-free data
    d = [run_derivatives(r["t"], r["y"], r["theta"], 22.0, SmoothingConfig(window_periods=0.3)) for r in clean_runs]
    return d, dataset_scales(d, [22.0] * len(d))


def test_regression_recovers_strong_terms(clean_derivs, truth):
    d, sc = clean_derivs
    m = fit_regression(d, sc, RegressionConfig(threshold=0.003, alpha=1e-8))
    for eq, term, tol in [(0, "y", 0.002), (0, "1", 0.02), (1, "theta", 0.005), (1, "y", 0.02)]:
        j = TERMS.index(term)
        # tolerances: SG bias at window 0.3 period is ~0.1 % on yddot; y-dependent terms of theta absorb ~1 %
        np.testing.assert_allclose(m.coef[eq, j], truth.coef[eq, j], rtol=tol)


def test_regression_candidates_restrict_support(clean_derivs):
    d, sc = clean_derivs
    cand = np.zeros((2, 35), bool)
    cand[0, TERMS.index("y")] = cand[1, TERMS.index("theta")] = True
    m = fit_regression(d, sc, candidates=cand)
    assert set(np.flatnonzero(m.support.ravel())) <= set(np.flatnonzero(cand.ravel()))


def test_ensemble_baseline_runs(clean_derivs):
    d, sc = clean_derivs
    m, p = fit_ensemble_regression(d[:2], sc, n_models=10, seed=0)
    assert p.shape == (2, 35) and m.coef[0, TERMS.index("y")] < 0


def test_refinement_removes_coefficient_bias(clean_derivs, truth):
    d, sc = clean_derivs
    c = truth.coef.copy()
    c[0, TERMS.index("y")] *= 0.97  # the kind of bias SG smoothing leaves in C0
    c[1, TERMS.index("theta")] *= 1.05
    res = refine(PolynomialModel(c), d[:2], sc, RefineConfig(max_evals=600))
    assert res.loss_end.total < 0.01 * res.loss_start.total  # measured: 0.585 -> 0.0007
    # the long-time loss pins the stiffnesses: a1 from 3 % off to within 1 %, b1 from 5 % to 1 %
    np.testing.assert_allclose(res.model.coef[0, TERMS.index("y")], truth.coef[0, TERMS.index("y")], rtol=1e-2)
    np.testing.assert_allclose(res.model.coef[1, TERMS.index("theta")], truth.coef[1, TERMS.index("theta")], rtol=1e-2)
    # and the refined model's y frequency matches the truth's to 0.2 % (start: 1.5 %)
    from cubedimer.spectra import dominant_frequency
    t = np.arange(4500) / 1500
    x0 = d[0].state[d[0].trim]
    f = [dominant_frequency(m.simulate(x0, t)[0][:, 0], 1 / 1500) for m in (truth, res.model, PolynomialModel(c))]
    assert abs(f[2] / f[0] - 1) > 0.01
    np.testing.assert_allclose(f[1], f[0], rtol=2e-3)
    assert len(res.history) == res.n_evals <= 600


def test_relative_threshold_keeps_a_small_term_of_the_slow_equation():
    """A theta equation whose scaled coefficients are all ~100x smaller than the y equation's: the absolute STLSQ
    threshold cuts its 0.002 cross term, the per-equation relative threshold keeps it (exact data, so the
    recovered coefficients are exact up to the ridge shrinkage)."""
    from fitting.derivatives.savitzky_golay import Derivatives
    from fitting.model import TERMS, Scales
    from fitting.selection.sparse_regression import RegressionConfig, fit_regression
    from cubedimer.terms import evaluate_library

    rng = np.random.default_rng(0)
    x = rng.uniform(-1, 1, (3000, 4))
    truth = np.zeros((2, len(TERMS)))
    truth[0, TERMS.index("y")], truth[0, TERMS.index("y^2")] = -1.0, 0.5
    truth[1, TERMS.index("theta")], truth[1, TERMS.index("y*theta")] = -0.01, 0.002
    acc = evaluate_library(x) @ truth.T
    d = Derivatives(t=np.arange(3000) * 1e-3, state=x, accel=acc, window=7, trim=0)
    sc = Scales(length_y=1.0, length_theta=1.0, time=1.0)
    all_terms = np.ones((2, len(TERMS)), bool)
    absolute = fit_regression([d], sc, RegressionConfig(matched_filter=False), candidates=all_terms)
    relative = fit_regression([d], sc, RegressionConfig(matched_filter=False, relative_threshold=True), candidates=all_terms)
    j = TERMS.index("y*theta")
    assert absolute.coef[1, j] == 0.0
    np.testing.assert_allclose(relative.coef[1, j], 0.002, rtol=0.05)  # ridge alpha = 0.3 shrinks by < 5 % here
    np.testing.assert_array_equal(relative.support[0], absolute.support[0])  # the y equation is unchanged
