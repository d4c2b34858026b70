"""The integral (position-space) form of a second-order equation of motion.

Why
---
Tracking noise is white in the *positions*.  An acceleration estimated from them (Savitzky-Golay,
:mod:`fitting.derivatives.savitzky_golay`) carries that noise times the filter's second-derivative gain, coloured and
largest near the filter's cut-off; a least-squares fit of such accelerations weighs that noise as if
it were white and wastes most of the information.  On the soft Gor'kov hinge (1.7 Hz) thetaddot is
~95 % derivative noise at 0.005 of theta noise, and weak hinge terms (theta*y^2, velocity coupling)
could not be resolved that way.

Method
------
Integrate the equation twice instead of differentiating the data.  Over a window
``[t_a, t_a + W]`` the equation ``x'' = sum_j c_j f_j(state) + a_known(state)`` is exactly

    x(t) = alpha + beta (t - t_a) + sum_j c_j K[f_j](t) + K[a_known](t),

with ``K[f](t) = int_{t_a}^t int_{t_a}^s f(u) du ds`` and the window's initial position and rate
``alpha, beta`` as nuisance parameters.  Removing each window's straight-line trend from both sides
(projection on the complement of ``[1, t]``) eliminates them, so the regression

    P x_measured - P K[a_known] = sum_j c_j P K[f_j]

is linear in the ``c_j`` and its noise is the tracking noise itself, white with standard deviation
sigma (minus the two projected dimensions per window): ordinary least squares is then the efficient
estimator, and its standard errors are honest.  The ``f_j`` are evaluated on smoothed states; their
own smoothing noise enters through ``K`` and grows like ``(omega W)^2`` on a stiff equation, so the
window must stay below about one period of the coordinate's own oscillation
(:func:`integral_window`: 0.75 of the dominant period, within 30-500 ms).  Measured on twin data
(8-10 runs of 3 s, 2000 fps, theta noise 0.005): the residual standard deviation equals the tracking
noise for these windows and exceeds it (noise accumulation) for windows of 2-4 periods.

What it buys, pooled over runs (a coefficient shared by all runs, each window its own nuisance):
on the soft hinge (8 runs) theta*y^2 = (1.39 +- 0.28) x 10^8 1/(m^2 s^2) against the Gor'kov value
1.3-1.6 x 10^8, where per-run acceleration fits scatter by 4 x 10^9; on a pair-scattering hinge
(kappa = 10^4, 10 runs) the velocity coupling c5 = 5000 1/m is recovered as 5019 +- 30.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Sequence

import numpy as np
from numpy.typing import NDArray

from ..model import TERMS
from ..multiple_testing import holm_all_significant, holm_backward_elimination, holm_z_threshold

if TYPE_CHECKING:
    from cubedimer.dataset import Run
    from .savitzky_golay import Derivatives

__all__ = ["column_states", "integral_form_states", "hinge_smoothing_window", "double_integral", "integral_window", "natural_windows", "window_starts", "detrend_windows",
           "integral_columns",
           "IntegralFit", "fit_integral_form", "IntegralSelection",
           "select_integral_form", "integral_form_selection", "METHOD"]


def double_integral(f: NDArray, dt: float, axis: int = 0) -> NDArray[np.float64]:
    """``K[f]`` along ``axis`` on a uniform grid: the second antiderivative that vanishes with its
    derivative at the first sample (trapezoid rule twice; error (omega dt)^2 / 12 at frequency omega)."""
    f = np.moveaxis(np.asarray(f, float), axis, 0)
    zero = np.zeros((1,) + f.shape[1:])
    c1 = np.concatenate([zero, np.cumsum(0.5 * (f[1:] + f[:-1]), axis=0) * dt])
    c2 = np.concatenate([zero, np.cumsum(0.5 * (c1[1:] + c1[:-1]), axis=0) * dt])
    return np.moveaxis(c2, 0, axis)


def integral_window(dt: float, frequency_hz: float, periods: float = 0.75,
                    bounds_s: tuple[float, float] = (0.03, 0.5), *,
                    bounds_periods: tuple[float, float] | None = None, reference_hz: float | None = None) -> int:
    """Window length [frames] for the integral form: ``periods`` of the coordinate's dominant period,
    clipped to ``bounds_s`` seconds (module docstring: longer windows accumulate the smoothing noise of
    the library columns on a stiff equation; shorter ones throw away the low-frequency information).

    With ``bounds_periods`` the bounds are instead that many periods of ``reference_hz`` (the run's fastest dominant
    frequency), so that the window does not depend on the unit of time the data are written in; a non-positive or
    non-finite ``reference_hz`` leaves the window unbounded."""
    if bounds_periods is not None:
        ref = float(reference_hz) if reference_hz is not None else float("nan")
        bounds_s = ((bounds_periods[0] / ref, bounds_periods[1] / ref) if ref > 0 and np.isfinite(ref)
                    else (0.0, np.inf))
    f = float(frequency_hz)
    w_s = periods / f if f > 0 and np.isfinite(f) else bounds_s[1]
    if not np.isfinite(w_s):  # no oscillation and no reference: 64 frames
        return 64
    w_s = float(np.clip(w_s, *bounds_s))
    return max(8, int(round(w_s / dt)))


#: The stiffness term of each equation (its natural frequency is sqrt(-coefficient) / 2 pi).
_STIFFNESS = (TERMS.index("y"), TERMS.index("theta"))


def natural_windows(coef: NDArray, windows: Sequence[Sequence[int]], dts: Sequence[float],
                    natural_periods: float) -> list[list[int]]:
    """Per equation and run, the window [frames] shortened to at most ``natural_periods`` periods of the
    equation's natural frequency ``sqrt(-coef[stiffness]) / 2 pi``, also below the usual lower bound of
    :func:`integral_window`; unchanged for an equation without a restoring stiffness."""
    out = []
    for q in range(2):
        k = -float(coef[q, _STIFFNESS[q]])
        if not k > 0:
            out.append(list(windows[q]))
            continue
        f_nat = np.sqrt(k) / (2.0 * np.pi)
        cap = [integral_window(dt, f_nat, natural_periods, (dt, np.inf)) for dt in dts]
        out.append([min(int(w), c) for w, c in zip(windows[q], cap)])
    return out


def window_starts(n: int, window: int, trim: int = 0) -> NDArray[np.int64]:
    """First frames of the non-overlapping windows of ``window`` frames within ``[trim, n - trim)``."""
    return np.arange(trim, n - trim - window + 1, window, dtype=np.int64)


def detrend_windows(x: NDArray, starts: NDArray, window: int) -> NDArray[np.float64]:
    """Stack the windows of ``x`` (n, ...) and remove each window's least-squares straight line.

    Returns (len(starts) * window, ...): the projection of every window on the complement of
    ``[1, t]`` (uniform sampling), which eliminates the windows' initial positions and rates."""
    x = np.asarray(x, float)
    idx = np.asarray(starts)[:, None] + np.arange(window)[None, :]
    return _detrend_stacked(x[idx]).reshape((idx.size,) + x.shape[1:])


def _detrend_stacked(seg: NDArray) -> NDArray[np.float64]:
    """Remove the straight line along axis 1 of stacked windows (n_win, window, ...)."""
    window = seg.shape[1]
    u = np.arange(window) - 0.5 * (window - 1)
    u = u.reshape((1, window) + (1,) * (seg.ndim - 2))
    seg = seg - seg.mean(axis=1, keepdims=True)
    slope = np.sum(seg * u, axis=1, keepdims=True) / np.sum(u * u)
    return seg - slope * u


def integral_columns(f: NDArray, dt: float, starts: NDArray, window: int) -> NDArray[np.float64]:
    """Detrended ``K[f]`` per window (f: (n, ...) sampled at every frame): the design columns of the
    integral form.  Each window is integrated from its own first frame (trapezoid rule twice)."""
    f = np.asarray(f, float)
    idx = np.asarray(starts)[:, None] + np.arange(window)[None, :]
    return _detrend_stacked(double_integral(f[idx], dt, axis=1)).reshape((idx.size,) + f.shape[1:])


def _z(coefficients: NDArray, std_errors: NDArray) -> NDArray[np.float64]:
    """coefficient / standard error (NaN or inf where the error is 0)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return coefficients / std_errors


@dataclass(frozen=True)
class IntegralFit:
    """Pooled least-squares fit of the integral form.

    Attributes
    ----------
    coefficients : ndarray (P,)
        In the units of the columns' coefficients (SI).
    std_errors : ndarray (P,)
        From the residual variance and (X^T X)^-1 (white noise; module docstring).
    residual_std : float
        Residual standard deviation per frame, in units of x; compare with the tracking noise.
    dof : int
        Frames minus two per window minus P.
    n_windows : int
    window : int
        Frames per window (the largest over runs).
    """

    coefficients: NDArray[np.float64]
    std_errors: NDArray[np.float64]
    residual_std: float
    dof: int
    n_windows: int
    window: int

    @property
    def z(self) -> NDArray[np.float64]:
        """coefficient / standard error."""
        return _z(self.coefficients, self.std_errors)


def _design(positions: Sequence[NDArray], columns: Sequence[NDArray], dts: Sequence[float],
            windows: Sequence[int], known: Sequence[NDArray] | None,
            trim: Sequence[int] | int) -> tuple[NDArray[np.float64], NDArray[np.float64], int]:
    """Stacked detrended design ``X`` (rows, P), target ``b`` (rows,) and the number of windows."""
    trims = [trim] * len(positions) if np.isscalar(trim) else list(trim)
    rows, rhs, n_win = [], [], 0
    for i, (x, f, dt, w) in enumerate(zip(positions, columns, dts, windows)):
        starts = window_starts(len(x), int(w), int(trims[i]))
        if starts.size == 0:
            continue
        target = detrend_windows(x, starts, int(w))
        if known is not None:
            target = target - integral_columns(known[i], dt, starts, int(w))
        rows.append(integral_columns(f, dt, starts, int(w)))
        rhs.append(target)
        n_win += starts.size
    if not rows:
        raise ValueError("no run is long enough for one integral-form window")
    return np.concatenate(rows), np.concatenate(rhs), n_win


def _ols(X: NDArray, b: NDArray, n_win: int, window: int) -> IntegralFit:
    """Column-scaled least squares with white-noise standard errors (dof: rows - 2 per window - P)."""
    p = X.shape[1]
    scale = np.maximum(np.sqrt(np.sum(X * X, axis=0)), 1e-300)
    Xs = X / scale
    coef_s, *_ = np.linalg.lstsq(Xs, b, rcond=None)
    resid = b - Xs @ coef_s
    dof = max(len(b) - 2 * n_win - p, 1)
    s2 = float(resid @ resid) / dof
    cov = np.linalg.pinv(Xs.T @ Xs) * s2
    se = np.sqrt(np.clip(np.diag(cov), 0.0, None)) / scale
    return IntegralFit(coef_s / scale, se, float(np.sqrt(s2)), int(dof), int(n_win), int(window))


def fit_integral_form(positions: Sequence[NDArray], columns: Sequence[NDArray], dts: Sequence[float],
                      windows: Sequence[int], known: Sequence[NDArray] | None = None,
                      trim: Sequence[int] | int = 0) -> IntegralFit:
    """Fit ``x'' = columns @ c + known`` to measured positions of several runs (shared ``c``).

    Parameters
    ----------
    positions : per run (n,) measured coordinate (raw, every frame, gaps filled)
    columns : per run (n, P) library or effect columns at the smoothed states (every frame)
    dts : per run frame interval [s]
    windows : per run window length [frames] (:func:`integral_window`)
    known : per run (n,) accelerations with known coefficients, optional
    trim : frames dropped at each end (the smoothing's edge frames), per run or one for all

    Returns
    -------
    IntegralFit
    """
    X, b, n_win = _design(positions, columns, dts, windows, known, trim)
    return _ols(X, b, n_win, int(max(windows)))


def _is_velocity_term(name: str) -> bool:
    """A library term with a velocity factor (docs/formats.md names); other names: contains "dot"."""
    from cubedimer.terms import is_velocity_free

    try:
        return not is_velocity_free(name)
    except ValueError:
        return "dot" in name


@dataclass(frozen=True)
class IntegralSelection:
    """Sparse pooled fit of the integral form (:func:`select_integral_form`).

    Attributes
    ----------
    terms : tuple of str
        Selected terms, in library order.
    coefficients, std_errors : ndarray (len(terms),)
        Least squares on the selected terms (SI units of the coefficients).
    residual_std : float
        Residual standard deviation per frame (units of the coordinate: m or rad).
    window_s : float
        Median window length over runs [s].
    n_windows, dof : int
    alpha : float
        Family-wise significance level of the rule.
    n_library : int
        Number of candidate terms the rule was applied to.
    dropped : tuple of str
        Terms in the order they were eliminated.
    """

    terms: tuple[str, ...]
    coefficients: NDArray[np.float64]
    std_errors: NDArray[np.float64]
    residual_std: float
    window_s: float
    n_windows: int
    dof: int
    alpha: float
    n_library: int
    dropped: tuple[str, ...]

    @property
    def z(self) -> NDArray[np.float64]:
        """coefficient / standard error."""
        return _z(self.coefficients, self.std_errors)

    def get(self, term: str) -> tuple[float, float]:
        """(value, standard error) of ``term``; (NaN, NaN) if it was not selected."""
        if term in self.terms:
            i = self.terms.index(term)
            return float(self.coefficients[i]), float(self.std_errors[i])
        return float("nan"), float("nan")

    def to_json(self) -> dict:
        """``{"terms": {term: {"value", "std_error", "z"}}, "window_s", "residual_std", ...}``."""
        return {"terms": {t: {"value": float(c), "std_error": float(e), "z": float(z)}
                          for t, c, e, z in zip(self.terms, self.coefficients, self.std_errors, self.z)},
                "window_s": self.window_s, "residual_std": self.residual_std, "n_windows": self.n_windows,
                "alpha": self.alpha, "n_library": self.n_library, "dropped": list(self.dropped)}


def select_integral_form(positions: Sequence[NDArray], columns: Sequence[NDArray], dts: Sequence[float],
                         windows: Sequence[int], term_names: Sequence[str],
                         known: Sequence[NDArray] | None = None, trim: Sequence[int] | int = 0,
                         alpha: float = 0.01) -> IntegralSelection:
    """Backward elimination on the pooled integral form.

    Starting from all ``term_names``, refit (one least squares) and drop the least significant term
    (smallest |z|; velocity-dependent terms first while any of them is not significant at alpha / L)
    while Holm's step-down rule at family-wise ``alpha`` over the ``L = len(term_names)``
    library terms does not declare every remaining term significant: the k-th most significant
    remaining term needs a two-sided normal p <= alpha / (L - k + 1) (:func:`significance_threshold`;
    the dropped terms count as the least significant ones).  The z are those of the current refit, so
    this is Holm read along the backward path (each step's p-values are conditional on the support).

    Parameters
    ----------
    positions, columns, dts, windows, known, trim
        As :func:`fit_integral_form`; ``columns`` (n, len(term_names)) per run.
    term_names : sequence of str
        Names of the columns.
    alpha : float
        Family-wise significance level.

    Returns
    -------
    IntegralSelection
    """
    names = list(term_names)
    X, b, n_win = _design(positions, columns, dts, windows, known, trim)
    if X.shape[1] != len(names):
        raise ValueError(f"{X.shape[1]} columns but {len(names)} term names")
    velocity = np.array([_is_velocity_term(n) for n in names])

    def score(cols: list[int]):
        if not cols:
            return np.zeros(0), None
        fit = _ols(X[:, cols], b, n_win, int(max(windows)))
        return np.abs(np.nan_to_num(fit.z, nan=0.0)), fit

    keep: list[int] = list(range(len(names)))
    dropped: list[str] = []  # in the order of elimination
    fit = None
    for support, absz, fit in holm_backward_elimination(score, keep, velocity, np.ones(len(names), bool),
                                                        holm_z_threshold(alpha, len(names), 1)):
        dropped += [names[k] for k in keep if k not in support]
        keep = support
        if holm_all_significant(absz, alpha, len(names)):  # (vacuously so once every term is gone)
            break
    window_s = float(np.median([w * dt for w, dt in zip(windows, dts)]))
    if not keep:
        dof = max(len(b) - 2 * n_win, 1)
        return IntegralSelection((), np.zeros(0), np.zeros(0), float(np.sqrt(b @ b / dof)), window_s, n_win, dof,
                                 alpha, len(names), tuple(dropped))
    return IntegralSelection(tuple(names[k] for k in keep), fit.coefficients, fit.std_errors, fit.residual_std,
                             window_s, fit.n_windows, fit.dof, alpha, len(names), tuple(dropped))


#: One-line description written next to the result in model.json.
METHOD = ("pooled integral form: measured position minus each window's straight line regressed on the detrended double "
          "integrals of the cubic library at raw y, smoothed ydot and theta smoothed over half a hinge period (windows of 0.75 of the coordinate's dominant "
          "period, 30-500 ms; coefficients shared by all runs); ordinary least squares, backward elimination until "
          "Holm's rule at family-wise alpha over the 35 library terms declares every remaining term significant "
          "(velocity terms dropped first while one is not significant at alpha/35)")


def hinge_smoothing_window(dt: float, f_y: float, f_theta: float, polyorder: int = 5) -> int:
    """Frames of the window over which :func:`column_states` smooths theta: half a period of the dominant theta
    frequency ``f_theta`` (at most 20 periods of ``f_y``) [Hz], odd."""
    from . import SmoothingConfig, savgol_window

    f_hinge = max(float(f_theta), float(f_y) / 20.0) if np.isfinite(f_theta) else float(f_y)
    return savgol_window(dt, 1.0 / f_hinge, SmoothingConfig(window_periods=0.5, polyorder=polyorder))


def column_states(dt: float, y: NDArray, theta: NDArray, ydot: NDArray, f_y: float, f_theta: float,
                  trim: int = 0, polyorder: int = 5) -> tuple[NDArray[np.float64], int]:
    """The states at which the integral form evaluates its library or model columns, and the frames to
    leave out at each end.

    * y is the *raw* measurement: 1 um of tracking noise on ~100 um of motion costs nothing, while a
      Savitzky-Golay window of 0.75 y periods attenuates y by ~0.3 % at f_y (measured: it biased the
      calibrated pressure by +0.16 %); ydot is the given (smoothed) one.
    * theta and thetadot are smoothed over half a period of the dominant theta frequency (at most 20 y
      periods), not 0.75 y periods: the derivative noise of a y-period window sits near f_y - 2 f_y,
      where products with y and ydot (velocity coupling) demodulate it to low frequencies that the
      double integral amplifies (measured on a 1.7-Hz hinge: c5 26 % low and c6 lost; on a 15-Hz hinge
      with short windows, within 1 %).  The long window uses
      :func:`fitting.derivatives.savitzky_golay.smooth_long_window`; its edges (half a window) are left out.

    Parameters
    ----------
    dt : frame interval [s]; y [m], theta [-]: raw, gap-filled, every frame; ydot [m/s] smoothed
    f_y, f_theta : dominant frequencies [Hz]
    trim : frames the caller leaves out anyway (e.g. the y smoothing's edges)

    Returns
    -------
    states (n, 4) [y, ydot, theta, thetadot]; edge: frames to leave out at each end
    """
    # looked up on the package at every call, so that a study can substitute the smoother there
    # (docs/scripts/gap_bias_states.py)
    from . import smooth_long_window

    y, theta = np.asarray(y, float), np.asarray(theta, float)
    n = y.size
    w = hinge_smoothing_window(dt, f_y, f_theta, polyorder)
    edge = max(int(trim), w // 2)
    if w >= n or n - 2 * edge <= 0:
        raise ValueError(f"a run of {n} frames is shorter than the hinge smoothing window ({w} frames)")
    ts, td = smooth_long_window(theta, dt, w, polyorder)
    return np.column_stack([y, np.asarray(ydot, float), ts, td]), edge


def integral_form_states(runs: Sequence["Run"], derivs: Sequence["Derivatives"],
                         prepared: Sequence | None = None
                         ) -> tuple[list[tuple[float, float]], list[NDArray[np.float64]], list[int]]:
    """Per run, the frequencies (f_y, f_theta) [Hz], the integral form's column states and their edge [frames]:
    those of the runs' preparations when given (``prepared``: per run a
    :class:`fitting.derivatives.preparation.RunPreparation`, in the runs' order), else made from ``runs`` and their
    ``derivs`` by the same rules (:func:`fitting.derivatives.frequencies.oscillation_frequencies`,
    :func:`column_states`).

    Raises
    ------
    ValueError
        A run shorter than the hinge's smoothing window.
    """
    if prepared is not None and all(p is not None for p in prepared):
        short = [p.run.name for p in prepared if p.columns is None]
        if short:
            raise ValueError(f"{', '.join(short)}: shorter than the hinge smoothing window")
        return [(p.f_y, p.f_theta) for p in prepared], [p.columns for p in prepared], [p.column_edge for p in prepared]
    from .frequencies import oscillation_frequencies

    freqs = [oscillation_frequencies(r) for r in runs]
    made = [column_states(float(r.dt), r.y, r.theta, d.state[:, 1], f_y, f_theta, int(d.trim), d.polyorder)
            for r, d, (f_y, f_theta) in zip(runs, derivs, freqs)]
    return freqs, [m[0] for m in made], [m[1] for m in made]


def integral_form_selection(runs: Sequence["Run"], derivs: Sequence["Derivatives"], alpha: float = 0.01,
                            periods: float = 0.75, prepared: Sequence | None = None) -> dict[str, IntegralSelection]:
    """:func:`select_integral_form` of both equations on a data set's runs.

    Parameters
    ----------
    runs : per run :class:`cubedimer.dataset.Run` (raw, gap-filled y [m] and theta [-] at every frame)
    derivs : per run :class:`fitting.derivatives.savitzky_golay.Derivatives` of the same run (the smoothed states the
        library is evaluated on; their ``trim`` edge frames are dropped)
    alpha : float
        Family-wise significance level of the selection.
    periods : float
        Window in periods of the coordinate's dominant frequency (:func:`integral_window`).
    prepared : per run :class:`fitting.derivatives.preparation.RunPreparation`, optional: the frequencies and column
        states prepared once (otherwise made here by the same rules,
        :func:`integral_form_states`)

    Returns
    -------
    dict ``{"yddot": IntegralSelection, "thetaddot": IntegralSelection}`` (y windows from the oscillation frequency
    of y, theta windows from that of theta, of each run: :func:`fitting.derivatives.frequencies.oscillation_frequencies`).
    """
    from cubedimer.terms import EQUATION_NAMES, evaluate_library, library_terms

    dts = [float(r.dt) for r in runs]
    freqs, states, trims = integral_form_states(runs, derivs, prepared)
    columns = [evaluate_library(st) for st in states]
    out = {}
    for q, (eq, coord) in enumerate(zip(EQUATION_NAMES, ("y", "theta"))):
        pos = [np.asarray(getattr(r, coord), float) for r in runs]
        windows = [integral_window(dt, f[q], periods) for f, dt in zip(freqs, dts)]
        out[eq] = select_integral_form(pos, columns, dts, windows, library_terms(), trim=trims, alpha=alpha)
    return out
