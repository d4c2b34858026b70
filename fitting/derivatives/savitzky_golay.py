"""Smoothing and differentiation of noisy trajectories (Savitzky-Golay).

Method
------
A Savitzky-Golay filter fits, in a sliding window of ``w = 2m + 1`` frames, a polynomial of
order ``p`` by least squares and returns its value and derivatives at the window centre.  It is
linear, so white tracking noise of standard deviation ``sigma`` becomes noise of standard
deviation ``sigma * ||c_k|| / dt^k`` on the k-th derivative, where ``c_k`` are the filter
weights (:func:`noise_gain`).  For fixed ``p`` the gain falls like ``m^-(k + 1/2)``, so
second derivatives need wide windows; but a window wider than about half the shortest
oscillation period attenuates the signal (bias) because the polynomial no longer follows it.
The default here, ``p = 5`` over 0.75 of a y period (51 frames at 1500 fps and 22 Hz),
attenuates the second derivative of a sinusoid at the y frequency by 3.3 % (at the theta
frequency 9 Hz by 0.1 %) and gives a yddot noise of ~0.011 m/s^2 per um of tracking noise
(thetaddot: ~11 1/s^2 per 0.001 of theta noise), against 0.029 and 29 for half a period
(0.8 % attenuation).  The regression therefore under-estimates the y stiffness by a few per cent
and its theta equation is noisy: this is the local bias that the long-time refinement has to
remove (see docs/fitting.md).  The paper uses Savitzky-Golay for the same reason: it preserves
peak shapes (and so the Poincare section) better than a moving average at equal noise.

Matched filter (removing the bias exactly)
------------------------------------------
The Savitzky-Golay second-derivative weights ``c2`` annihilate constants and straight lines, so they
are the second difference of a compact kernel ``G`` (the double cumulative sum of ``c2`` times
dt^2, :func:`acceleration_kernel`): ``sum_k c2_k x_{t+k} = sum_k G_k (x_{t+k+1} - 2 x_{t+k} +
x_{t+k-1}) / dt^2``.  The filtered acceleration of the data is therefore ``G`` applied to the true
acceleration, up to the second-difference error (omega dt)^2 / 12 (0.07 % at 22 Hz and 1500 fps).
Comparing it with ``G`` applied to a model's accelerations (``Derivatives.matched``), instead of
with the raw model accelerations, removes the attenuation bias: measured on a 22 Hz + 51 Hz test
signal at the default window (51 frames at 1500 fps), the maximum mismatch is 24 % against the raw
model accelerations, 9.6 % against the same smoothing filter applied to them, and 0.1 % against ``G``
(tests/fitting/derivatives/test_signal_features.py).  The regression uses it (``RegressionConfig.matched_filter``).

Edges are handled with ``mode="interp"`` (polynomial fit to the first/last window); their noise
is larger, so regression drops ``w // 2`` frames at each end (:attr:`Derivatives.trim`).

Long windows
------------
``scipy.signal.savgol_coeffs`` fits powers of the raw frame offset, which is ill-conditioned for long
windows: at order 5 its weights are 1e-8 off (relative) at 201-401 frames, 5e-7 at 701, and at 801 frames and
more they are wrong altogether (the smoothed signal is ~0; measured on a sinusoid at 0.75 periods per window).
Windows longer than :data:`LONG_WINDOW` frames therefore use the same least-squares polynomial with the
offsets scaled to [-1, 1] (:func:`savgol_weights`, :func:`smooth_long_window`), well conditioned for any
window; the fitting pipeline also block-averages data of more than ``SmoothingConfig.max_frames_per_period``
frames per period (:mod:`fitting.derivatives.decimation`), so that its windows stay short.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from numpy.typing import NDArray
from scipy.signal import savgol_coeffs, savgol_filter

from cubedimer.config_checks import check_positive, check_that, check_whole

__all__ = ["SmoothingConfig", "Derivatives", "savgol_window", "savgol_weights", "differentiate", "smooth_long_window",
           "noise_gain", "run_derivatives", "acceleration_kernel", "apply_acceleration_kernel", "LONG_WINDOW",
           "SmoothingFailure"]

#: Longest window [frames] smoothed with scipy's Savitzky-Golay weights (relative error below 1e-8 at order 5);
#: longer windows use the scaled least squares of :func:`savgol_weights` (module docstring, "Long windows").
LONG_WINDOW = 201


class SmoothingFailure(ValueError):
    """The smoothing of a run does not follow its signal (one-line message naming the run and the cause)."""


@dataclass(frozen=True)
class SmoothingConfig:
    """Savitzky-Golay settings.

    Parameters
    ----------
    polyorder : int
        Polynomial order (>= 3 for second derivatives).
    window_periods : float
        Window length as a fraction of the dominant y period (used when ``window`` is None).
    window : int, optional
        Window length in frames (odd); overrides ``window_periods``.
    max_frames_per_period : float or None
        Runs with more frames per period of their fastest dominant coordinate (the larger of the y and theta
        frequencies) are block-averaged by the smallest whole factor that brings them to at most this many
        (:mod:`fitting.derivatives.decimation`; 250: no data at 2000 fps of an oscillation above 8 Hz is touched); None keeps
        every frame.
    """

    polyorder: int = 5
    window_periods: float = 0.75
    window: int | None = None
    max_frames_per_period: float | None = 250.0

    def __post_init__(self) -> None:
        check_whole(self, "polyorder", minimum=3)
        check_positive(self, "window_periods")
        check_that(self, self.max_frames_per_period is None or self.max_frames_per_period >= 20,
                   f"max_frames_per_period must be at least 20 or None, got {self.max_frames_per_period!r}")
        if self.window is not None:
            check_whole(self, "window", minimum=self.polyorder + 2)
            check_that(self, self.window % 2 == 1, f"window must be odd, got {self.window}")


@dataclass(frozen=True, eq=False)
class Derivatives:
    """Smoothed state and accelerations of one run (SI).

    Attributes
    ----------
    t : ndarray (n,) [s]
    state : ndarray (n, 4)
        [y, ydot, theta, thetadot] in [m, m/s, -, 1/s].
    accel : ndarray (n, 2)
        [yddot, thetaddot] in [m/s^2, 1/s^2].
    window : int
        Savitzky-Golay window [frames].
    trim : int
        Frames at each end with edge (larger) noise.
    """

    t: NDArray[np.float64]
    state: NDArray[np.float64]
    accel: NDArray[np.float64]
    window: int
    trim: int
    polyorder: int = 5

    def matched(self, x: NDArray) -> NDArray[np.float64]:
        """``x`` (n, ...) sampled at ``t``, filtered by the kernel that the Savitzky-Golay second
        derivative applies to the true acceleration (:func:`acceleration_kernel`): a model's
        accelerations filtered so that they compare with ``accel`` without attenuation bias."""
        dt = float((self.t[-1] - self.t[0]) / (self.t.size - 1))
        return apply_acceleration_kernel(x, acceleration_kernel(self.window, self.polyorder, dt))

    def interior(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """State and accelerations without the ``trim`` edge frames."""
        s = slice(self.trim, self.state.shape[0] - self.trim)
        return self.state[s], self.accel[s]


def savgol_window(dt: float, period: float, config: SmoothingConfig = SmoothingConfig()) -> int:
    """Odd window length [frames] for frame interval ``dt`` [s] and dominant period [s]."""
    if config.window is not None:
        w = int(config.window)
    else:
        w = int(round(config.window_periods * period / dt))
    w = max(w, config.polyorder + 3)
    return w if w % 2 else w + 1


def acceleration_kernel(window: int, polyorder: int, dt: float) -> NDArray[np.float64]:
    """The kernel ``K`` (length ``window``, centred, sum 1) with ``savgol(x, deriv=2) = K * x''``.

    ``G = cumsum(cumsum(c2)) dt^2`` of the second-derivative weights ``c2`` ends in two zeros (``c2``
    annihilates constants and lines); ``K`` is ``G`` without them, centred (module docstring).
    The kernel is computed once per (window, polyorder, dt) and returned read-only (a diagnosis filters
    thousands of model columns with the same few kernels).
    """
    return _acceleration_kernel(int(window), int(polyorder), float(dt))


@lru_cache(maxsize=64)
def _acceleration_kernel(window: int, polyorder: int, dt: float) -> NDArray[np.float64]:
    c2 = savgol_weights(window, polyorder, 2, dt)[::-1]  # convolution order
    g = np.cumsum(np.cumsum(c2)) * dt * dt
    kernel = np.concatenate([[0.0], g[:-2], [0.0]])
    kernel.flags.writeable = False
    return kernel


def apply_acceleration_kernel(x: NDArray, kernel: NDArray) -> NDArray[np.float64]:
    """Convolve ``x`` (n, ...) with ``kernel`` along axis 0 (edges: nearest value, as trimmed anyway)."""
    from scipy.ndimage import convolve1d

    return convolve1d(np.asarray(x, float), kernel[::-1], axis=0, mode="nearest")


def noise_gain(window: int, polyorder: int, deriv: int, dt: float) -> float:
    """Standard deviation of the k-th derivative estimate per unit white noise [1/s^k]."""
    c = savgol_weights(window, polyorder, deriv, dt)
    return float(np.sqrt(np.sum(c**2)))


def savgol_weights(window: int, polyorder: int, deriv: int, dt: float) -> NDArray[np.float64]:
    """Savitzky-Golay weights of the ``deriv``-th derivative at the window centre, in correlation order
    (``sum_k w_k x_{i+k-m}``) [1/s^deriv]: scipy's up to :data:`LONG_WINDOW` frames, the scaled least squares
    beyond (module docstring, "Long windows")."""
    from math import factorial

    if window <= LONG_WINDOW:
        return savgol_coeffs(window, polyorder, deriv=deriv, delta=dt, use="dot")
    m = window // 2
    pinv = np.linalg.pinv(np.vander(np.arange(-m, m + 1) / m, polyorder + 1, increasing=True))
    return pinv[deriv] * factorial(deriv) / (m * dt) ** deriv


def differentiate(x: NDArray, dt: float, window: int, polyorder: int) -> tuple[NDArray, NDArray, NDArray]:
    """Smoothed signal and its first and second derivatives (units of x per s^k); windows longer than
    :data:`LONG_WINDOW` frames take the well-conditioned path of :func:`smooth_long_window`."""
    if window > LONG_WINDOW:
        s, d1, d2 = _scaled_savgol(np.asarray(x, float), dt, window, polyorder, 2)
        return s, d1, d2
    kw = dict(window_length=window, polyorder=polyorder, delta=dt, mode="interp")
    return (savgol_filter(x, deriv=0, **kw), savgol_filter(x, deriv=1, **kw),
            savgol_filter(x, deriv=2, **kw))


def smooth_long_window(x: NDArray, dt: float, window: int, polyorder: int) -> tuple[NDArray, NDArray]:
    """Savitzky-Golay smoothed signal and first derivative [units of x, per s] for long windows.

    ``scipy.signal.savgol_coeffs`` fits powers of the raw frame offset (up to ``(window/2)^polyorder``), which
    is ill-conditioned for long windows: measured on a pure sinusoid at 0.75 periods per window and order
    5, the smoothed RMS error is 6e-11 for 71 frames but 0.64 of the amplitude for 979 frames.  Here the
    offsets are scaled to [-1, 1] first (the fit is then well conditioned for any window); the edges
    (half a window at each end) use the polynomial fitted to the first and last window, as
    ``mode="interp"`` does.
    """
    s, d1 = _scaled_savgol(np.asarray(x, float), dt, window, polyorder, 1)
    return s, d1


def _scaled_savgol(x: NDArray, dt: float, window: int, polyorder: int, max_deriv: int) -> list[NDArray]:
    """The smoothed signal and its derivatives up to ``max_deriv`` with offsets scaled to [-1, 1] (edges: the
    polynomial of the first and last window)."""
    from math import factorial

    n, m = x.size, window // 2
    if window % 2 == 0 or window > n or window <= polyorder:
        raise ValueError(f"window must be odd, longer than polyorder and at most the signal length, got {window}")
    u = np.arange(-m, m + 1) / m
    pinv = np.linalg.pinv(np.vander(u, polyorder + 1, increasing=True))  # (p+1, window)
    out = []
    for deriv in range(max_deriv + 1):
        w = pinv[deriv] * factorial(deriv) / (m * dt) ** deriv
        y = np.convolve(x, w[::-1], mode="same")
        for seg, pos in ((slice(0, window), np.arange(m)), (slice(n - window, n), np.arange(window - m, window))):
            c = np.polynomial.polynomial.polyder(pinv @ x[seg], deriv) if deriv else pinv @ x[seg]
            y[seg][pos] = np.polynomial.polynomial.polyval(u[pos], c) / (m * dt) ** deriv
        out.append(y)
    return out


def run_derivatives(t: NDArray, y: NDArray, theta: NDArray, f_y: float,
                    config: SmoothingConfig = SmoothingConfig(), velocities: NDArray | None = None) -> Derivatives:
    """Smooth and differentiate one run.

    Parameters
    ----------
    t, y, theta : ndarray
        Uniform times [s], gap-free y [m] and theta [-].
    f_y : float
        Dominant y frequency [Hz], sets the window.
    velocities : ndarray (n, 2), optional
        Measured rates of y and theta [per s] (NaN columns: none); each given one, smoothed by the same filter,
        replaces the Savitzky-Golay derivative of its position in ``state`` (the accelerations stay the second
        derivatives of the positions, which the matched filter assumes).
    """
    dt = float((t[-1] - t[0]) / (t.size - 1))
    w = savgol_window(dt, 1.0 / f_y, config)
    if w >= t.size:
        raise ValueError(f"run of {t.size} frames is shorter than the smoothing window ({w})")
    ys, yd, ydd = differentiate(y, dt, w, config.polyorder)
    ts, td, tdd = differentiate(theta, dt, w, config.polyorder)
    _check_smoothing(y, ys, w, dt, f_y)
    if velocities is not None:
        rates = [yd, td]
        for k in range(2):
            if np.all(np.isfinite(velocities[:, k])):
                rates[k] = differentiate(velocities[:, k], dt, w, config.polyorder)[0]
        yd, td = rates
    return Derivatives(t=t, state=np.column_stack([ys, yd, ts, td]),
                       accel=np.column_stack([ydd, tdd]), window=w, trim=w // 2, polyorder=config.polyorder)


#: Largest share of the signal's RMS (about its mean) that the smoothing may remove from a run's y.
MAX_SMOOTHING_LOSS = 0.5


def _check_smoothing(x: NDArray, smoothed: NDArray, window: int, dt: float, f: float) -> None:
    """Raise :class:`SmoothingFailure` when the smoothed ``x`` does not follow ``x`` (more than
    :data:`MAX_SMOOTHING_LOSS` of its RMS removed): a window far too long for the oscillation, or weights that
    lost the signal.  Every later stage would otherwise fit a model to nothing and report that it blows up."""
    signal = float(np.std(x))
    lost = float(np.sqrt(np.mean((x - smoothed) ** 2)))
    if signal > 0 and lost > MAX_SMOOTHING_LOSS * signal:
        raise SmoothingFailure(
            f"the Savitzky-Golay smoothing over {window} frames ({window * dt * f:.2g} periods of the dominant "
            f"{f:.3g} Hz at {1 / dt:.6g} frames/s) removed {lost / signal:.0%} of the y signal; set a window of "
            f"about 0.75 periods (SmoothingConfig.window_periods) or keep max_frames_per_period")
