import numpy as np
import pytest
from scipy.integrate import solve_ivp

from fitting.integrate import integrate, integrate_batch, rhs
from fitting.model import EXPONENTS, PolynomialModel, TERMS


def test_harmonic_oscillator_analytic():
    om = 2 * np.pi * 22
    m = PolynomialModel.from_equations({"yddot": {"y": -om**2}, "thetaddot": {"theta": -(om / 2) ** 2}})
    t = np.arange(3000) / 1000
    s, n = m.simulate([1e-4, 0, 0.1, 0], t, substeps=3)
    assert n == t.size
    # RK4 phase error per step ~ (h omega)^5 / 120 = 1.7e-9 at h*omega = 0.046; x 9000 steps = 1.5e-5
    np.testing.assert_allclose(s[:, 0], 1e-4 * np.cos(om * t), atol=1e-4 * 2e-5)
    np.testing.assert_allclose(s[:, 2], 0.1 * np.cos(om / 2 * t), atol=0.1 * 2e-5 / 32)  # (h omega)^5 is 32x smaller


def test_matches_solve_ivp(truth):
    x0 = np.array([1.2e-4, 0.0, 0.3, 0.0])
    t = np.arange(4500) / 1500
    ref = solve_ivp(lambda _t, x: rhs(truth.coef, EXPONENTS, x[None])[0], (0, t[-1]), x0, t_eval=t,
                    rtol=1e-11, atol=1e-15, method="DOP853").y.T
    s, _ = truth.simulate(x0, t, substeps=2)
    # relative to each component's max: RK4 at h*omega ~ 0.046 is ~1e-5 accurate over 3 s
    np.testing.assert_allclose(s / np.abs(ref).max(0), ref / np.abs(ref).max(0), atol=1e-4)


def test_blow_up_is_reported_not_raised():
    m = PolynomialModel.from_equations({"yddot": {"y^3": 1e12}, "thetaddot": {}})
    s, n = m.simulate([1e-3, 0, 0, 0], np.arange(1000) / 1000, bound=1.0)
    assert n < 1000
    assert np.all(np.isfinite(s[:n])) and np.all(np.isnan(s[n:]))


def test_batch_equals_single(truth):
    x0s = np.array([[1e-4, 0, 0.1, 0], [-8e-5, 1e-3, -0.2, 1.0]])
    tb, nb = integrate_batch(truth.coef, EXPONENTS, x0s, 1e-3, np.array([500, 300]), 2)
    for i, n in enumerate([500, 300]):
        ts, _ = integrate(truth.coef, EXPONENTS, x0s[i], 1e-3, n, 2)
        np.testing.assert_array_equal(tb[i, :n], ts)  # identical arithmetic
    assert list(nb) == [500, 300]


@pytest.mark.slow
def test_compiled_integrators_are_cached_on_disk(tmp_path):
    """Worker processes load the compiled integrator from numba's cache instead of compiling it."""
    from tests.cubedimer.test_rk4 import cache_hits_in_fresh_processes

    code = """
        import numpy as np
        import fitting.integrate as fi
        c = np.array([[-1.0, 0.0], [0.0, -1.0]]); e = np.array([[1, 0, 0, 0], [0, 0, 1, 0]])
        fi.integrate(c, e, np.array([1.0, 0, 0.1, 0]), 0.01, 5, bound=10.0)
        fi.integrate_batch(c, e, np.array([[1.0, 0, 0.1, 0]]), 0.01, 5, bound=10.0)
    """
    first, second = cache_hits_in_fresh_processes(code, "[fi._integrate_one, fi._integrate_many]", tmp_path)
    assert first == 0 and second >= 2
