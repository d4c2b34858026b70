"""The diagnosis's view of a data set: per run, smoothed states, measured accelerations, noise levels and
the data of the integral form.

:func:`prepare_diagnosis_runs` turns each run of a :class:`cubedimer.dataset.Dataset` into a
:class:`RunAccelerations`: Savitzky-Golay states and second derivatives (:mod:`fitting.derivatives.savitzky_golay`)
at the interior frames, the variances the tracking noise leaves on them, the filter that produced them
(so that the model's accelerations can be filtered the same way, :meth:`RunAccelerations.smooth`) and,
for the integral form of the equations (:mod:`fitting.derivatives.integral_form`), the raw positions and column
states at every frame (:class:`PositionIntegrals`), and the states of the energy balance
(:class:`BalanceStates`).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np
from numpy.typing import NDArray

__all__ = ["BalanceStates", "PositionIntegrals", "RunAccelerations", "BALANCE_POLYORDER", "prepare_diagnosis_runs", "derivative_noise", "thin_runs",
           "uses_integral_form"]


@dataclass(frozen=True, eq=False)
class PositionIntegrals:
    """One run's data for the integral form of both equations (:mod:`fitting.derivatives.integral_form`), at every
    recorded frame (interior frames only, never thinned).

    Each gap component of an equation compares the *measured* coordinate (raw, its tracking noise
    white) with the double integral of the model's accelerations over windows, each window's initial
    position and rate eliminated by removing its straight-line trend.  For a model that explains the
    data the residual is the tracking noise itself, so the noise floor is known:
    ``(frames - 2 per window) sigma^2``.  Coordinate index q: 0 for y, 1 for theta.
    """

    dt: float
    positions: NDArray[np.float64]  # (n, 2) raw measured [y, theta], gaps filled
    state: NDArray[np.float64]  # (n, 4) smoothed states at the same frames
    windows: tuple[int, int]  # frames per window for y and theta (fitting.derivatives.integral_form.integral_window)
    noise_var: tuple[float, float]  # tracking-noise variances of y [m^2] and theta [-]
    t0: float = 0.0  # time of the first frame [s]

    @property
    def times(self) -> NDArray[np.float64]:
        """Times of the frames [s]."""
        return self.t0 + self.dt * np.arange(self.positions.shape[0])

    def starts(self, q: int) -> NDArray[np.int64]:
        """First frames of the non-overlapping windows of coordinate q."""
        from fitting.derivatives.integral_form import window_starts

        return window_starts(self.positions.shape[0], self.windows[q])

    def target(self, q: int) -> NDArray[np.float64]:
        """Detrended measured coordinate q, window by window."""
        from fitting.derivatives.integral_form import detrend_windows

        return detrend_windows(self.positions[:, q], self.starts(q), self.windows[q])

    def columns(self, q: int, accel: NDArray) -> NDArray[np.float64]:
        """Detrended double integrals of accelerations (n, ...) of coordinate q, sampled at every frame."""
        from fitting.derivatives.integral_form import integral_columns

        return integral_columns(accel, self.dt, self.starts(q), self.windows[q])

    def floor(self, q: int) -> float:
        """Expected residual sum of squares of a perfect model: (rows - 2 per window) sigma^2."""
        return float(self.starts(q).size * (self.windows[q] - 2) * self.noise_var[q])

    @property
    def usable(self) -> bool:
        """Both coordinates have at least one whole window."""
        return all(self.starts(q).size > 0 for q in (0, 1))


#: Order of the Savitzky-Golay polynomial of the energy balance's states (same window as the accelerations').
BALANCE_POLYORDER = 7


@dataclass(frozen=True, eq=False)
class BalanceStates:
    """One run's states for the energy balance: a Savitzky-Golay fit of order :data:`BALANCE_POLYORDER` over
    the accelerations' window (0.75 y periods), at the same frames as :attr:`RunAccelerations.state`.

    The energy balance compares the mechanical energy at the ends of each window and integrates the power
    of the effects over it, so its states must keep every harmonic of the motion at its full amplitude.  The
    order-5 window of the accelerations passes the velocity at f_y with a gain of 0.998 but at 2 f_y with
    0.90 (positions 0.83) and at 3 f_y with 0.44; order 7 over the same window passes 0.9999, 0.989 and 0.85,
    at 1.5 times the velocity noise.  On a hinge locked to f_y the 2 f_y harmonics carry a few per cent of
    the kinetic energy, and the order-5 states left the energy balance of exact samples of the paper-like
    twin 23 % short of closing at the true parameters (the linear damping of y then came out 9 % high);
    order 7 closes it to 5 %.  The energy balance is linear in the effects' parameters: its rows carry no
    matched filter, so an attenuated harmonic is a bias, where the acceleration rows' matched kernel
    cancels it.
    """

    state: NDArray[np.float64]  # (n, 4) [y, ydot, theta, thetadot]
    #: variances of ydot and thetadot due to tracking noise (SI^2); None: noise-free data
    velocity_noise: NDArray[np.float64] | None = None

    def subsample(self, step: int) -> "BalanceStates":
        """Every ``step``-th frame."""
        return BalanceStates(self.state[::step], self.velocity_noise)


@dataclass(frozen=True, eq=False)
class RunAccelerations:
    """One run's smoothed states and measured accelerations (interior frames only, SI)."""

    name: str
    t: NDArray[np.float64]
    state: NDArray[np.float64]  # (n, 4) [y, ydot, theta, thetadot]
    accel: NDArray[np.float64]  # (n, 2) [yddot, thetaddot]
    #: derivative-noise variances [yddot, thetaddot, ydot, thetadot] (SI^2); None: noise-free data
    noise: NDArray[np.float64] | None = None
    #: (duration [s], polynomial order) of the Savitzky-Golay window that produced ``accel``; the model's
    #: accelerations are filtered by the matched kernel (:meth:`smooth`) before comparison, so that the
    #: filter's attenuation (strong at 2 f_y for a window of 0.75 y periods) cancels.  None: no filtering.
    smoothing: tuple[float, int] | None = None
    #: frame interval of the recording [s] (``t`` may be thinned); None: ``t``'s own spacing
    frame_dt: float | None = None
    #: positions and states at every frame for the integral form of both equations; None: the gap
    #: components of the equations use the accelerations instead
    integral: PositionIntegrals | None = None
    #: states of the energy balance (:class:`BalanceStates`); not given (None): ``state`` with the velocity noise
    #: of ``noise``
    balance: BalanceStates | None = None

    def __post_init__(self) -> None:
        if self.balance is None:
            object.__setattr__(self, "balance", BalanceStates(self.state, None if self.noise is None else self.noise[2:]))

    def subsample(self, step: int) -> "RunAccelerations":
        """Every ``step``-th frame (the integral data, the noise levels and the filter stay those of the recording)."""
        return RunAccelerations(self.name, self.t[::step], self.state[::step], self.accel[::step], self.noise,
                                self.smoothing, self.frame_dt, self.integral, self.balance.subsample(step))

    def smooth(self, x: NDArray) -> NDArray:
        """Filter a model's accelerations (axis 0 along ``t``) as the data's Savitzky-Golay second derivative
        filtered the true ones: the matched kernel of :func:`fitting.derivatives.savitzky_golay.acceleration_kernel`.

        The kernel is built at the recording's frame rate; on thinned frames (every ``step``-th) it is
        sampled every ``step`` taps, times ``step`` (a Riemann sum of the same smooth kernel), and
        renormalised to sum 1.  Nothing is done without ``smoothing``."""
        if self.smoothing is None or len(self.t) < 3:
            return x
        from fitting.derivatives.savitzky_golay import acceleration_kernel, apply_acceleration_kernel

        duration, order = self.smoothing
        dt = float(np.median(np.diff(self.t)))
        frame_dt = self.frame_dt or dt
        w = int(round(duration / frame_dt))
        w = w if w % 2 else w + 1
        if w <= order + 2:
            return x
        kernel = acceleration_kernel(w, order, frame_dt)
        step = max(1, int(round(dt / frame_dt)))
        if step > 1:
            c = w // 2
            taps = c + step * np.arange(-(c // step), c // step + 1)
            kernel = kernel[taps] / np.sum(kernel[taps])
        return apply_acceleration_kernel(x, kernel)


def prepare_diagnosis_runs(prepared) -> list[RunAccelerations]:
    """The diagnosis's view of a prepared data set: per run, the smoothed states and accelerations (interior frames),
    their derivative-noise variances [yddot, thetaddot, ydot, thetadot] (:attr:`RunAccelerations.noise`) and the
    integral-form data of both coordinates (None for a run too short for the hinge window: its theta component then
    uses the accelerations).

    Every array is read from the one preparation of the data set
    (:func:`fitting.derivatives.preparation.prepare_dataset`), which the fit reads too: the same block-averaged run,
    oscillation frequencies (:func:`fitting.derivatives.preparation.oscillation_frequencies`), Savitzky-Golay states
    and derivatives, column states (raw y, theta smoothed over half a hinge period,
    :func:`fitting.derivatives.integral_form.column_states`), integral windows (0.75 of each coordinate's period) and
    tracking noise.

    Parameters
    ----------
    prepared : fitting.derivatives.preparation.PreparedDataset, or a cubedimer.dataset.Dataset (prepared here with the
        default smoothing)

    Returns
    -------
    list of RunAccelerations, in the data set's order
    """
    from fitting.derivatives.preparation import PreparedDataset, prepare_dataset

    if not isinstance(prepared, PreparedDataset):
        prepared = prepare_dataset(prepared)
    return [_run_accelerations(p) for p in prepared.runs]


def _run_accelerations(p) -> RunAccelerations:
    """:class:`RunAccelerations` of one :class:`fitting.derivatives.preparation.RunPreparation`."""
    run, d = p.run, p.derivs
    sl = slice(d.trim, len(d.t) - d.trim)
    sigma2 = np.asarray(p.noise_var, float)
    nv = derivative_noise(d, sigma2, run.dt)
    integral = None
    if p.columns is not None:
        si = slice(p.column_edge, len(run.t) - p.column_edge)
        integral = PositionIntegrals(float(run.dt), np.column_stack([run.y[si], run.theta[si]]).astype(float),
                                     p.columns[si], p.windows, (float(sigma2[0]), float(sigma2[1])),
                                     float(run.t[p.column_edge]))
    return RunAccelerations(run.name, d.t[sl], d.state[sl], d.accel[sl], nv, (d.window * run.dt, d.polyorder),
                            float(run.dt), integral, _balance_states(run, d.window, sigma2, sl))


def _balance_states(run, window: int, sigma2: NDArray, interior: slice) -> BalanceStates | None:
    """The energy balance's states of ``run`` at its ``interior`` frames (None when the window is too short for
    the order, about 10 frames per y period: the balance then uses the accelerations' states)."""
    from fitting.derivatives.savitzky_golay import differentiate, noise_gain

    if window <= BALANCE_POLYORDER + 1:
        return None
    columns = [c for x in (run.y, run.theta) for c in differentiate(x, run.dt, window, BALANCE_POLYORDER)[:2]]
    noise = np.asarray(sigma2, float) * noise_gain(window, BALANCE_POLYORDER, 1, run.dt) ** 2
    return BalanceStates(np.column_stack(columns)[interior], noise)


def derivative_noise(d, sigma2: NDArray, dt: float) -> NDArray[np.float64]:
    """Variances of the Savitzky-Golay accelerations and velocities due to tracking noise,
    [yddot, thetaddot, ydot, thetadot] (SI^2).

    The tracking noise variances ``sigma2`` of [y, theta] are the run's white-noise estimate
    (:attr:`fitting.derivatives.preparation.RunPreparation.noise_var`: :func:`cubedimer.noise.white_noise_std`, the
    suite's one estimator: the robust scale of the fourth differences, blind to the motion); the k-th derivative's
    noise is then sigma * ||c_k|| (:func:`fitting.derivatives.savitzky_golay.noise_gain`).  (The residual of the
    smoothing itself, raw minus smoothed, would also hold the part of the motion the filter does not follow: on the
    paper-like twin it overstates the y noise by 15-40 %.)

    Parameters
    ----------
    d : fitting.derivatives.savitzky_golay.Derivatives of the run
    sigma2 : (2,) tracking-noise variances of y [m^2] and theta [-]
    dt : frame interval [s]
    """
    from fitting.derivatives.savitzky_golay import noise_gain

    g2, g1 = noise_gain(d.window, d.polyorder, 2, dt) ** 2, noise_gain(d.window, d.polyorder, 1, dt) ** 2
    return np.array([sigma2[0] * g2, sigma2[1] * g2, sigma2[0] * g1, sigma2[1] * g1])


def thin_runs(runs: Sequence[RunAccelerations], max_frames: int) -> list[RunAccelerations]:
    """Every run thinned (every k-th frame) to at most ``max_frames`` frames (the integral data stay whole)."""
    return [r.subsample(max(1, int(np.ceil(len(r.t) / max_frames)))) for r in runs]


def uses_integral_form(runs: Sequence[RunAccelerations]) -> bool:
    """The integral form (calibration and theta equation) is used when every run carries usable integral data."""
    return bool(runs) and all(r.integral is not None and r.integral.usable for r in runs)
