"""Model-based state estimates: each stretch of a run replaced by the model's own trajectory.

Why
---
The integral form (:mod:`fitting.derivatives.integral_form`) evaluates its library columns at estimated states.
Columns at noisy or smoothed states are biased (errors in the variables): a smoother attenuates the
fast components, a differentiator adds coloured noise that products with y and ydot demodulate to
low frequencies, and weak velocity terms are lost or biased.  A trajectory of a model that is
already close to the truth is noise-free and unattenuated; fitted to the data over a short stretch,
it is the best available estimate of the states there.

Method
------
Each run is cut into overlapping segments (length :attr:`SegmentConfig.periods` of the slower
dominant period, within :attr:`SegmentConfig.bounds_periods`; hop half a segment).  Per segment the
initial state ``x0`` (4 numbers) is fitted by Gauss-Newton so that the model's simulation from
``x0`` matches the measured y and theta, weighted by their noise levels; the Jacobian is a forward
difference, and all segments of all runs (with their four perturbed copies) are integrated in one
compiled call (:func:`fitting.integrate.integrate_batch`).  Every frame takes its state from the
segment whose centre is nearest, i.e. from the middle half of a segment.  With four parameters per
segment of N frames the estimate's noise is ~ sigma sqrt(4 / N), smooth, and free of smoothing
bias; its remaining error is the model's error over half a segment, which vanishes as the model
converges (:mod:`fitting.selection.integral_discovery` iterates).  Segments whose simulation leaves the data's range
keep the given fallback states.
"""
from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import Sequence

import numpy as np
from numpy.typing import NDArray

from cubedimer.config_checks import check_above, check_bounds, check_positive, check_whole
from ..integrate import integrate_batch
from ..model import EXPONENTS, PolynomialModel

__all__ = ["SegmentConfig", "StateEstimate", "segment_length", "segment_layout", "model_states"]

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class SegmentConfig:
    """Settings of the per-segment state estimate.

    Parameters
    ----------
    periods : float
        Segment length in periods of the slower of the two dominant frequencies.
    bounds_periods : (float, float)
        Minimum and maximum segment length in periods of the first coordinate's (y's) dominant frequency (the other's
        when y does not oscillate): 2.2 and 11, 0.1 and 0.5 s at 22 Hz; in periods, so that the segments are the
        same whatever unit of time the data are written in.
    gauss_newton_steps : int
        Gauss-Newton steps per call from the fallback states (each: one batched integration of 5
        trajectories per segment).
    warm_steps : int
        Gauss-Newton steps per call from a warm start (the previous call's initial states).
    h_omega : float
        RK4 step times the model's fastest linear angular frequency.  A segment spans a few periods, so
        the phase error of RK4, ~(h omega)^5 / 120 per step, stays below 1e-4 rad even at 0.15.
    blowup_factor : float
        A simulation leaving ``blowup_factor`` times the run's max |state| counts as failed.
    """

    periods: float = 2.0
    bounds_periods: tuple[float, float] = (2.2, 11.0)
    gauss_newton_steps: int = 3
    warm_steps: int = 1
    h_omega: float = 0.15
    blowup_factor: float = 10.0

    def __post_init__(self) -> None:
        check_positive(self, "periods")
        check_bounds(self, "bounds_periods")
        check_whole(self, "gauss_newton_steps")
        check_whole(self, "warm_steps")
        check_positive(self, "h_omega")
        check_above(self, "blowup_factor", 1.0)


@dataclass(frozen=True, eq=False)
class StateEstimate:
    """Model-based states of every run.

    Attributes
    ----------
    states : list of ndarray (n_i, 4)
        [y, ydot, theta, thetadot] [m, m/s, -, 1/s] per frame.
    x0 : list of ndarray (n_segments_i, 4)
        Fitted initial state of every segment (a warm start for the next call).
    failed : list of ndarray of bool (n_i,)
        Frames that kept the fallback states (their segment's simulation failed).
    rms : ndarray (2,)
        Root-mean-square misfit of the simulations to y and theta over all frames [m, -].
    """

    states: list[NDArray[np.float64]]
    x0: list[NDArray[np.float64]]
    failed: list[NDArray[np.bool_]]
    rms: NDArray[np.float64]

    @property
    def n_failed(self) -> int:
        """Frames that kept the fallback states."""
        return int(sum(int(f.sum()) for f in self.failed))


def segment_length(dt: float, f_y: float, f_theta: float, config: SegmentConfig = SegmentConfig()) -> int:
    """Segment length [frames] for a run with frame interval ``dt`` [s] and dominant frequencies [Hz]:
    ``config.periods`` of the slower one within ``config.bounds_periods`` of y's (of the other's when y does not
    oscillate); 16 frames at least, 64 for a run that does not oscillate."""
    freqs = [f for f in (f_y, f_theta) if np.isfinite(f) and f > 0]
    if not freqs:
        return 64
    lo, hi = (b / freqs[0] for b in config.bounds_periods)
    return max(16, int(round(float(np.clip(config.periods / min(freqs), lo, hi)) / dt)))


def segment_layout(n: int, length: int) -> tuple[NDArray[np.int64], NDArray[np.int64], int]:
    """Segment starts (hop half a segment, the last one ending at the last frame), the owning segment of
    every frame (nearest centre) and the (possibly shortened) segment length."""
    length = min(int(length), n)
    hop = max(1, length // 2)
    starts = list(range(0, n - length + 1, hop))
    if starts[-1] + length < n:
        starts.append(n - length)
    starts_a = np.asarray(starts, dtype=np.int64)
    centres = starts_a + 0.5 * (length - 1)
    owner = np.abs(np.arange(n)[:, None] - centres[None, :]).argmin(axis=1)
    return starts_a, owner.astype(np.int64), length


@dataclass(frozen=True, eq=False)
class _Segments:
    """Every segment of every run, stacked: its run, start and length [frames], the measured (y, theta) padded to
    the longest segment with NaN, and the runs' layouts (:func:`segment_layout`)."""

    run: NDArray[np.int64]
    start: NDArray[np.int64]
    length: NDArray[np.int64]
    data: NDArray[np.float64]  #: (B, Lmax, 2)
    layouts: list

    @property
    def valid(self) -> NDArray[np.bool_]:
        return np.isfinite(self.data[..., 0])


def _segments(y: Sequence[NDArray], theta: Sequence[NDArray], lengths: Sequence[int]) -> _Segments:
    """The segments of every run (:func:`segment_layout`) with their measured coordinates."""
    seg_run, seg_start, seg_len, layouts = [], [], [], []
    for r, (n_r, L) in enumerate(zip((len(v) for v in y), lengths)):
        starts, owner, L = segment_layout(n_r, L)
        layouts.append((starts, owner, L))
        seg_run += [r] * starts.size
        seg_start += starts.tolist()
        seg_len += [L] * starts.size
    seg_run_a, seg_start_a, seg_len_a = np.array(seg_run), np.array(seg_start), np.array(seg_len, dtype=np.int64)
    data = np.full((seg_run_a.size, int(seg_len_a.max()), 2), np.nan)
    for b, (r, s, L) in enumerate(zip(seg_run_a, seg_start_a, seg_len_a)):
        data[b, :L, 0] = y[r][s:s + L]
        data[b, :L, 1] = theta[r][s:s + L]
    return _Segments(seg_run_a, seg_start_a, seg_len_a, data, layouts)


def model_states(model: PolynomialModel, dts: Sequence[float], y: Sequence[NDArray], theta: Sequence[NDArray],
                 fallback: Sequence[NDArray], lengths: Sequence[int], sigma: tuple[float, float],
                 config: SegmentConfig = SegmentConfig(),
                 x0: Sequence[NDArray] | None = None) -> StateEstimate:
    """Fit the model's trajectory to every segment of every run (module docstring).

    Parameters
    ----------
    model : PolynomialModel
        Current model (SI).
    dts : per run frame interval [s]
    y, theta : per run measured y [m] and theta [-] at every frame (gaps filled)
    fallback : per run (n_i, 4) states used as the Gauss-Newton start and where a simulation fails
    lengths : per run segment length [frames] (:func:`segment_length`)
    sigma : (float, float)
        Noise levels of y [m] and theta [-] (the misfit weights).
    config : SegmentConfig
    x0 : per run (n_segments_i, 4), optional
        Warm start (``StateEstimate.x0`` of a previous call with the same layout).

    Returns
    -------
    StateEstimate
    """
    segs = _segments(y, theta, lengths)
    run_scale = [np.maximum(np.nanmax(np.abs(np.asarray(fb, float)), axis=0), 1e-12) for fb in fallback]
    scale = np.array([run_scale[r] for r in segs.run])  # (B, 4)
    simulate = _segment_simulator(model, dts, segs, config.blowup_factor * scale, sigma, config)
    if x0 is not None:
        start = np.concatenate([np.asarray(v, float) for v in x0])
    else:
        start = np.array([fallback[r][s] for r, s in zip(segs.run, segs.start)])
    steps = config.warm_steps if x0 is not None else config.gauss_newton_steps
    traj, best_x, best_cost = _gauss_newton(simulate, segs, start, 1e-6 * np.maximum(np.abs(start), 0.1 * scale),
                                            np.asarray(sigma, float), steps)
    return _state_estimate(segs, traj, best_x, best_cost, y, theta, fallback)


def _segment_simulator(model: PolynomialModel, dts: Sequence[float], segs: _Segments, bound: NDArray,
                       sigma: tuple[float, float], config: SegmentConfig):
    """``simulate(x) -> (trajectories (k, B, Lmax, 4), costs (k, B))`` of k stacked sets of the segments' initial
    states (k, B, 4): the weighted misfit to the measured coordinates, infinite for a segment that blew up."""
    cols = np.flatnonzero(model.support.any(axis=0))
    if cols.size == 0:
        cols = np.array([0])
    exps = np.ascontiguousarray(EXPONENTS[cols])
    coef = np.ascontiguousarray(model.coef[:, cols])
    w = 1.0 / np.maximum(np.asarray(sigma, float), 1e-300)
    B, Lmax = segs.run.size, segs.data.shape[1]
    dt_seg = np.array([dts[r] for r in segs.run])
    substeps = max(1, max(model.default_substeps(float(d), config.h_omega) for d in dts))
    data, valid, seg_len_a = segs.data, segs.valid, segs.length

    def simulate(x: NDArray) -> tuple[NDArray, NDArray]:
        k = x.shape[0]
        traj, nv = integrate_batch(coef, exps, x.reshape(-1, 4), np.tile(dt_seg, k), np.tile(seg_len_a, k),
                                   substeps, np.tile(bound, (k, 1)))
        traj = traj.reshape(k, B, Lmax, 4)
        res = (traj[..., [0, 2]] - data[None]) * w
        res = np.where(valid[None, ..., None], res, 0.0)
        cost = np.sum(res * res, axis=(2, 3))
        cost = np.where(nv.reshape(k, B) >= np.tile(seg_len_a, (k, 1)), cost, np.inf)
        return traj, cost

    return simulate


def _gauss_newton(simulate, segs: _Segments, start: NDArray, delta: NDArray, sigma: NDArray, steps: int):
    """Gauss-Newton on every segment's initial state at once (forward-difference Jacobians of step ``delta``):
    ``(trajectories (B, Lmax, 4), best initial states (B, 4), best costs (B,))``, the best point of every segment
    over the iterations."""
    w = 1.0 / np.maximum(sigma, 1e-300)
    data, valid = segs.data, segs.valid
    x = start.copy()
    best_x, best_cost = x.copy(), np.full(segs.run.size, np.inf)
    eye = np.eye(4)
    for _ in range(steps):
        pert = np.concatenate([x[None], x[None] + delta[None] * eye[:, None, :]])  # (5, B, 4)
        traj, cost = simulate(pert)
        better = cost[0] < best_cost
        best_x[better], best_cost[better] = x[better], cost[0][better]
        base = traj[0][..., [0, 2]]
        jac = (traj[1:][..., [0, 2]] - base[None]) / delta.T[:, :, None, None] * w  # (4, B, Lmax, 2)
        res = (base - data) * w
        jac = np.where(valid[None, ..., None], np.nan_to_num(jac), 0.0)
        res = np.where(valid[..., None], np.nan_to_num(res), 0.0)
        A = np.einsum("ibtk,jbtk->bij", jac, jac)
        g = np.einsum("ibtk,btk->bi", jac, res)
        A = A + 1e-9 * np.einsum("bii->bi", A)[:, :, None] * eye[None]
        ok = np.isfinite(cost[0]) & np.all(np.isfinite(A), axis=(1, 2))
        step = np.zeros_like(x)
        if ok.any():
            step[ok] = -np.linalg.solve(A[ok] + 1e-300 * eye[None], g[ok][..., None])[..., 0]
        x = np.where(ok[:, None], x + step, best_x)
    traj, cost = simulate(x[None])
    better = cost[0] < best_cost
    best_x[better], best_cost[better] = x[better], cost[0][better]
    if (~better).any():  # the best point was an earlier one: integrate it once more
        traj, _ = simulate(best_x[None])
    return traj[0], best_x, best_cost


def _state_estimate(segs: _Segments, traj: NDArray, best_x: NDArray, best_cost: NDArray, y: Sequence[NDArray],
                    theta: Sequence[NDArray], fallback: Sequence[NDArray]) -> StateEstimate:
    """Every frame's state from its segment's fitted trajectory (the fallback where the segment failed), the warm
    start of the next call and the RMS misfit of y and theta."""
    states, x0_out, failed = [], [], []
    sq, cnt = np.zeros(2), 0
    b0 = 0
    for r, (starts, owner, L) in enumerate(segs.layouts):
        nseg = starts.size
        st = np.array(fallback[r], float, copy=True)
        fail = np.zeros(len(y[r]), bool)
        idx = np.arange(len(y[r]))
        seg = b0 + owner
        local = idx - starts[owner]
        good = np.isfinite(best_cost[seg])
        st[good] = traj[seg[good], local[good]]
        fail[~good] = True
        states.append(st)
        x0_out.append(best_x[b0:b0 + nseg].copy())
        failed.append(fail)
        m = good & np.isfinite(y[r]) & np.isfinite(theta[r])
        sq += [np.sum((st[m, 0] - y[r][m]) ** 2), np.sum((st[m, 2] - theta[r][m]) ** 2)]
        cnt += int(m.sum())
        b0 += nseg
    rms = np.sqrt(sq / max(cnt, 1))
    n_fail = int(np.sum(~np.isfinite(best_cost)))
    if n_fail:
        log.info("model states: %d of %d segments failed (fallback states kept there)", n_fail, segs.run.size)
    return StateEstimate(states=states, x0=x0_out, failed=failed, rms=rms)
