"""The integral (position-space) form: double integral, detrending, pooled least squares and its selection."""
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from fitting.derivatives.integral_form import (detrend_windows, double_integral, fit_integral_form, integral_window,
                                               select_integral_form, window_starts)
from fitting.multiple_testing import holm_z_threshold

DT = 1.0 / 2000.0  # the twin's camera rate [s]
W0 = 2 * np.pi * 2.0  # hinge-like natural frequency [rad/s]
OMEGA = 2 * np.pi * 20.0  # driving coordinate's frequency [rad/s]
C_TRUE = 1.5e9  # x'' = -W0^2 x + C y^2 x  [1/(m^2 s^2)]: C y^2 is up to 60 1/s^2, 0.4 W0^2
SIGMA = 0.005  # white position noise [rad]


def test_double_integral_of_constant_and_line_is_exact():
    t = np.arange(400) * DT
    np.testing.assert_allclose(double_integral(np.ones_like(t), DT), t**2 / 2, rtol=0, atol=1e-15)
    # the trapezoid rule integrates t^2/2 with the error dt^2 t / 12 (exactly, for a quadratic) ...
    k = double_integral(t, DT)
    np.testing.assert_allclose(k, t**3 / 6 + DT**2 * t / 12, rtol=0, atol=1e-15)
    # ... a straight line, which the window's detrending removes: the design column is exact to round-off
    starts = np.array([0])
    np.testing.assert_allclose(detrend_windows(k, starts, t.size), detrend_windows(t**3 / 6, starts, t.size),
                               rtol=0, atol=1e-15)
    # columns of a 2-D input are integrated independently
    both = double_integral(np.column_stack([np.ones_like(t), t]), DT)
    np.testing.assert_allclose(both[:, 1], k, rtol=0, atol=1e-15)


def test_detrend_removes_lines_exactly(rng):
    n, w = 1000, 90
    starts = window_starts(n, w, trim=7)
    assert starts[0] == 7 and starts[-1] + w <= n - 7 and np.all(np.diff(starts) == w)
    # a different line in every window, for two columns: the detrended stack is zero to round-off
    t = np.arange(n, dtype=float)
    a, b = rng.normal(size=(starts.size, 2)), rng.normal(size=(starts.size, 2))
    x = np.zeros((n, 2))
    for k, s in enumerate(starts):
        x[s:s + w] = a[k] + b[k] * (t[s:s + w, None] - s)
    np.testing.assert_allclose(detrend_windows(x, starts, w), 0.0, rtol=0, atol=1e-12)
    # and a quadratic keeps its component orthogonal to [1, t]: same residual as an explicit lstsq
    q = (t - 300.0) ** 2 / 1e4
    u = np.column_stack([np.ones(w), np.arange(w)])
    seg = q[starts[3]:starts[3] + w]
    expected = seg - u @ np.linalg.lstsq(u, seg, rcond=None)[0]
    np.testing.assert_allclose(detrend_windows(q, starts, w)[3 * w:4 * w], expected, rtol=0, atol=1e-12)


@pytest.fixture(scope="module")
def driven_runs():
    """Four noise-free 3-s runs of x'' = -W0^2 x + C y(t)^2 x with a decaying drive y = a e^(-t/2 s) sin(OMEGA t + phase).

    The drive's mean square differs between runs and in time (a = 50-200 um): with a fixed amplitude C y^2 x would be
    C a^2 / 2 x (collinear with x) plus a 40 Hz part that the double integral suppresses, and C would be unresolved.
    """
    runs = []
    for a, x0, v0, ph in [(0.5e-4, 0.2, 0.0, 0.0), (1e-4, -0.15, 0.5, 1.0), (1.5e-4, 0.1, -0.8, 2.0), (2e-4, 0.25, 0.3, 4.0)]:
        def drive(t, a=a, ph=ph):
            return a * np.exp(-t / 2.0) * np.sin(OMEGA * t + ph)

        def rhs(t, s, drive=drive):
            return [s[1], -W0**2 * s[0] + C_TRUE * drive(t) ** 2 * s[0]]

        t = np.arange(6000) * DT
        sol = solve_ivp(rhs, (0, t[-1]), [x0, v0], t_eval=t, rtol=1e-11, atol=1e-13, method="DOP853")
        y = drive(t)
        runs.append({"x": sol.y[0], "xdot": sol.y[1], "y": y})
    return runs


def _design(runs, names=("x", "y^2*x")):
    cols = {"x": lambda r: r["x"], "y^2*x": lambda r: r["y"] ** 2 * r["x"], "x^3": lambda r: r["x"] ** 3,
            "xdot": lambda r: r["xdot"], "y*x": lambda r: r["y"] * r["x"]}
    return [np.column_stack([cols[n](r) for n in names]) for r in runs]


def _noisy(runs, seed):
    g = np.random.default_rng(seed)
    return [r["x"] + SIGMA * g.standard_normal(r["x"].size) for r in runs]


def test_known_coefficients_recovered_with_white_position_noise(driven_runs):
    # columns at the true (noise-free) states: the method's model, noise only in the measured positions
    w = integral_window(DT, W0 / (2 * np.pi))
    assert w == round(0.75 / (W0 / (2 * np.pi)) / DT)
    n = len(driven_runs)
    fit = fit_integral_form(_noisy(driven_runs, 0), _design(driven_runs), [DT] * n, [w] * n, trim=10)
    truth = np.array([-W0**2, C_TRUE])
    # within 4 standard errors (a 6e-5 chance per coefficient if the errors are honest: next test)
    assert np.all(np.abs(fit.coefficients - truth) <= 4 * fit.std_errors), (fit.coefficients, fit.std_errors)
    assert fit.std_errors[1] < 0.1 * C_TRUE  # and the coupling is resolved (z > 10)
    # residual std is the position noise: its estimate has relative std 1/sqrt(2 dof) ~ 0.5 %, 3 % is > 5 of those
    np.testing.assert_allclose(fit.residual_std, SIGMA, rtol=0.03)
    assert fit.n_windows == n * ((6000 - 20) // w) and fit.dof == n * ((6000 - 20) // w) * (w - 2) - 2


def test_standard_errors_are_honest(driven_runs):
    """Over 30 noise seeds the deviation from the truth in units of the reported SE has std ~1."""
    n = len(driven_runs)
    w = integral_window(DT, W0 / (2 * np.pi))
    cols = _design(driven_runs)
    truth = np.array([-W0**2, C_TRUE])
    z = []
    for seed in range(30):
        fit = fit_integral_form(_noisy(driven_runs, 100 + seed), cols, [DT] * n, [w] * n, trim=10)
        z.append((fit.coefficients - truth) / fit.std_errors)
    z = np.array(z)
    # the std of a 30-sample std of N(0, 1) is 1/sqrt(58) = 0.13: +-0.4 is 3 of those; the mean's std is 0.18
    np.testing.assert_allclose(z.std(axis=0, ddof=1), 1.0, atol=0.4)
    np.testing.assert_allclose(z.mean(axis=0), 0.0, atol=0.6)


def test_selection_drops_a_zero_term_and_keeps_true_ones(driven_runs):
    n = len(driven_runs)
    w = integral_window(DT, W0 / (2 * np.pi))
    names = ("x", "y*x", "y^2*x", "x^3", "xdot")
    sel = select_integral_form(_noisy(driven_runs, 1), _design(driven_runs, names), [DT] * n, [w] * n, names, trim=10)
    assert sel.terms == ("x", "y^2*x")
    assert set(sel.dropped) == {"y*x", "x^3", "xdot"}
    az = np.sort(np.abs(sel.z))[::-1]  # Holm: the k-th most significant needs p <= alpha / (L - k + 1)
    assert np.all(az >= [holm_z_threshold(0.01, len(names), k + 1) for k in range(az.size)])
    assert np.all(np.abs(sel.coefficients - [-W0**2, C_TRUE]) <= 4 * sel.std_errors)
    np.testing.assert_allclose(sel.window_s, w * DT)
    assert sel.get("x^3")[0] != sel.get("x^3")[0]  # NaN for a dropped term
    d = sel.to_json()
    assert set(d["terms"]) == {"x", "y^2*x"} and d["terms"]["y^2*x"]["std_error"] > 0


def test_significance_threshold_is_holm_along_the_path():
    from scipy.stats import norm

    # the most significant of 35: Bonferroni, two-sided p = alpha / 35; the 35th: p = alpha
    np.testing.assert_allclose(2 * norm.sf(holm_z_threshold(0.01, 35, 1)), 0.01 / 35, rtol=1e-10)
    np.testing.assert_allclose(2 * norm.sf(holm_z_threshold(0.01, 35, 35)), 0.01, rtol=1e-10)


@pytest.mark.parametrize("window", [71, 979, 2001])
def test_long_window_savgol_is_exact_for_polynomials(window):
    """A Savitzky-Golay filter of order p reproduces polynomials of degree <= p exactly, edges included;
    scipy's unscaled fit loses that for long windows (0.64 of the amplitude at 979 frames on a sinusoid)."""
    from fitting.derivatives.savitzky_golay import smooth_long_window

    dt = 5e-4
    t = np.arange(6000) * dt
    x = 0.2 - 1.5 * t + 0.7 * t**2 - 0.4 * t**3 + 0.05 * t**5
    dx = -1.5 + 1.4 * t - 1.2 * t**2 + 0.25 * t**4
    s, d = smooth_long_window(x, dt, window, 5)
    # round-off only: the scaled Vandermonde of order 5 is well conditioned at any window
    np.testing.assert_allclose(s, x, atol=1e-9)
    np.testing.assert_allclose(d, dx, atol=1e-6)


def test_long_window_savgol_matches_scipy_on_short_windows():
    from fitting.derivatives.savitzky_golay import differentiate, smooth_long_window

    rng = np.random.default_rng(3)
    x = np.cumsum(rng.normal(size=3000))
    a, b, _ = differentiate(x, 1e-3, 51, 5)
    s, d = smooth_long_window(x, 1e-3, 51, 5)
    # the same least-squares filter; scipy's raw offsets are well conditioned at 51 frames
    np.testing.assert_allclose(s, a, atol=1e-8 * np.abs(x).max())
    np.testing.assert_allclose(d, b, atol=1e-8 * np.abs(b).max())


def test_column_states_use_raw_y_and_a_hinge_period_window():
    from fitting.derivatives.integral_form import column_states

    dt, n = 5e-4, 6000
    t = np.arange(n) * dt
    y = 2e-4 * np.sin(2 * np.pi * 22 * t)
    theta = 0.2 * np.sin(2 * np.pi * 1.7 * t)
    states, edge = column_states(dt, y, theta, np.gradient(y, dt), 22.0, 1.7, trim=30)
    np.testing.assert_array_equal(states[:, 0], y)  # raw y, no smoothing attenuation
    # half a hinge period: 0.5 / 1.7 s = 0.294 s = 588 frames (odd: 589), its half left out at each end
    assert edge == 294
    sl = slice(edge, n - edge)
    # a 5th-order fit over half a period attenuates a sinusoid by ~4e-4 of its amplitude (the Taylor
    # remainder of order 6 over +-pi/2); bound it at 1e-3 of the amplitude, for angle and rate
    np.testing.assert_allclose(states[sl, 2], theta[sl], atol=1e-3 * 0.2)
    np.testing.assert_allclose(states[sl, 3], 0.2 * 2 * np.pi * 1.7 * np.cos(2 * np.pi * 1.7 * t[sl]), atol=1e-3 * 2.14)
