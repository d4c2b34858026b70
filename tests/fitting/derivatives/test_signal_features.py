"""Derivatives, Poincare section, spectra and attractor classes against analytic signals."""
import numpy as np
import pytest

from cubedimer.attractors import classify_signal
from fitting.derivatives.savitzky_golay import SmoothingConfig, noise_gain, run_derivatives, savgol_window
from cubedimer.poincare import poincare_map, poincare_section
from cubedimer.spectra import dominant_frequency, phase_difference


def test_savgol_derivatives_bias_and_noise():
    fps, f = 1500.0, 22.0
    t = np.arange(4500) / fps
    A, om = 1e-4, 2 * np.pi * f
    y = A * np.cos(om * t)
    d = run_derivatives(t, y, 0.2 * np.cos(2 * np.pi * 9 * t), f)
    assert d.window == 51
    s, a = d.interior()
    sl = slice(d.trim, t.size - d.trim)
    # measured attenuation of yddot at the y frequency for (51, 5): 3.3 % (documented); assert < 4 %
    ratio = np.max(np.abs(a[:, 0])) / (A * om**2)
    assert 0.96 < ratio < 0.975
    np.testing.assert_allclose(s[:, 1], -A * om * np.sin(om * t[sl]), atol=A * om * 0.005)
    # noise: empirical std of the filtered second derivative of white noise equals noise_gain
    rng = np.random.default_rng(1)
    noise = rng.standard_normal(200_000) * 1e-6
    from fitting.derivatives.savitzky_golay import differentiate
    _, _, dd = differentiate(noise, 1 / fps, 51, 5)
    g = noise_gain(51, 5, 2, 1 / fps) * 1e-6
    np.testing.assert_allclose(np.std(dd[100:-100]), g, rtol=0.02)  # 2 %: sampling error of a std over 2e5 samples


def test_window_is_odd_and_bounded():
    assert savgol_window(1e-3, 1 / 22, SmoothingConfig()) % 2 == 1
    assert savgol_window(1e-3, 1e-3, SmoothingConfig()) >= 8


def test_poincare_crossing_times_are_interpolated():
    fps, om = 1000.0, 2 * np.pi * 22.3
    t = np.arange(3000) / fps
    state = np.column_stack([np.cos(om * t), -om * np.sin(om * t), np.sin(om * t), om * np.cos(om * t)])
    sec = poincare_section(t, state)
    k = np.arange(len(sec))
    exact = (np.pi / 2 + 2 * np.pi * k) / om  # cos = 0 going down
    err = np.max(np.abs(sec.times - exact))
    assert err < 2e-6  # linear interpolation near y = 0: O(dt^3 om^2) ~ 1e-6 s; nearest frame would be 5e-4 s
    # theta = sin sits at its peak: linear interpolation error <= (om dt)^2 / 8 = 2.5e-3
    np.testing.assert_allclose(sec.theta, 1.0, atol=(om / fps) ** 2 / 8)
    np.testing.assert_allclose(sec.points[:, 0], -om, rtol=(om / fps) ** 2 / 8)  # ydot at its extremum: same bound
    a, b = poincare_map(sec)
    assert a.shape == (len(sec) - 1, 2) and np.allclose(b / [1, om], a / [1, om], atol=3e-3)  # same bound


@pytest.mark.parametrize("f", [9.0, 21.7, 23.4])
def test_dominant_frequency_subbin_accuracy(f):
    t = np.arange(3000) / 1500
    assert abs(dominant_frequency(np.sin(2 * np.pi * f * t + 0.3), 1 / 1500) - f) < 0.05  # bin is 0.5 Hz


@pytest.mark.parametrize("lag", [0.0, 1.0, np.pi - 0.1, -2.0])
def test_phase_difference(lag):
    t = np.arange(3000) / 1500
    y, th = np.cos(2 * np.pi * 22 * t), np.cos(2 * np.pi * 22 * t + lag)
    assert abs(np.angle(np.exp(1j * (phase_difference(y, th, 1 / 1500) - lag)))) < 0.05


@pytest.mark.parametrize("theta_fn,label", [
    (lambda t: 0.2 * np.cos(2 * np.pi * 22 * t), "locked-in-phase"),
    (lambda t: -0.2 * np.cos(2 * np.pi * 22 * t), "locked-anti-phase"),
    (lambda t: 0.2 * np.sin(2 * np.pi * 22 * t), "locked-quadrature"),
    (lambda t: 0.2 * np.cos(2 * np.pi * 9 * t), "independent"),
    (lambda t: 0.005 * np.cos(2 * np.pi * 9 * t), "theta-at-rest"),
])
def test_attractor_classes(theta_fn, label):
    t = np.arange(4000) / 1000
    assert classify_signal(1e-4 * np.cos(2 * np.pi * 22 * t), theta_fn(t), 1e-3).label == label


@pytest.mark.parametrize("fps,window", [(1500.0, 51), (2000.0, 71)])
def test_acceleration_kernel_matches_the_savgol_second_derivative(fps, window):
    """savgol(x, deriv=2) = K * x'' exactly up to the second-difference error (omega dt)^2 / 12; the smoothing
    filter itself (or nothing) leaves a large attenuation bias at 2.3 f_y."""
    from scipy.signal import savgol_filter

    from fitting.derivatives.savitzky_golay import acceleration_kernel, apply_acceleration_kernel

    dt = 1.0 / fps
    t = np.arange(6000) * dt
    w1, w2 = 2 * np.pi * 22.0, 2 * np.pi * 22.0 * 2.3
    x = np.sin(w1 * t) + 0.3 * np.cos(w2 * t)
    xdd = -w1**2 * np.sin(w1 * t) - 0.3 * w2**2 * np.cos(w2 * t)
    data = savgol_filter(x, window, 5, deriv=2, delta=dt)
    kernel = acceleration_kernel(window, 5, dt)
    np.testing.assert_allclose(kernel.sum(), 1.0, rtol=1e-8)  # the kernel passes constants
    np.testing.assert_allclose(kernel, kernel[::-1], atol=1e-15)
    interior = slice(window, -window)
    scale = np.max(np.abs(data))
    matched = np.max(np.abs(data - apply_acceleration_kernel(xdd, kernel))[interior]) / scale
    smoothed = np.max(np.abs(data - savgol_filter(xdd, window, 5))[interior]) / scale
    # second-difference error at 51 Hz: (w2 dt)^2 / 12 = 0.4 % (1500 fps) of that component (0.3 of the signal);
    # measured 1.0e-3 (1500 fps) and 2.6e-4 (2000 fps)
    assert matched < 3e-3
    # the attenuation bias it removes (measured 9.6 % and 4.7 %) is over an order of magnitude larger
    assert smoothed > 20 * matched
