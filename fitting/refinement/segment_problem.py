"""The output error's least-squares problem: the runs cut into segments, the weighted residuals of the segments'
trajectories as functions of (support coefficients, segment start states), and the Levenberg-Marquardt step with the
states eliminated by their Schur complement.

The refinement, its pruning and its additions built on it are :mod:`fitting.refinement.output_error`.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Sequence

import numpy as np
from numpy.typing import NDArray

from ..integrate import integrate_batch
from ..model import EXPONENTS, PolynomialModel
from .model_states import segment_layout

if TYPE_CHECKING:
    from .output_error import OutputErrorConfig

__all__ = ["Segments", "build_segments", "TrajectoryProblem", "lm_step", "fit_segment_states", "eliminate_states",
           "reduced_normal"]

#: trajectories of a chunk's Jacobian integrated per compiled call, in frames (bounds the memory to ~100 MB)
_CHUNK_FRAMES = 3_000_000


@dataclass(frozen=True, eq=False)
class Segments:
    """Segments of all runs: frame interval, length [frames], measured (y, theta) padded with NaN (S, Lmax, 2),
    start states (S, 4) and blow-up bounds (S, 4)."""

    dt: NDArray[np.float64]
    length: NDArray[np.int64]
    data: NDArray[np.float64]
    x0: NDArray[np.float64]
    bound: NDArray[np.float64]

    def subset(self, keep: NDArray) -> "Segments":
        return Segments(self.dt[keep], self.length[keep], self.data[keep], self.x0[keep], self.bound[keep])


def build_segments(dts: Sequence[float], ys: Sequence[NDArray], thetas: Sequence[NDArray], states: Sequence[NDArray],
              slow_freqs: Sequence[float], config: OutputErrorConfig) -> Segments:
    rows = []
    for dt, y, th, st, f in zip(dts, ys, thetas, states, slow_freqs):
        n = len(y)
        length = n if not (np.isfinite(f) and f > 0) else max(8, int(round(config.periods / (f * dt))))
        bound = 10.0 * np.maximum(np.nanmax(np.abs(st), axis=0), 1e-300)
        starts, _, L = segment_layout(n, length)
        for s in starts:
            rows.append((dt, L, np.column_stack([y[s:s + L], th[s:s + L]]), st[s], bound))
    if len(rows) > config.max_segments:
        rows = [rows[i] for i in np.unique(np.linspace(0, len(rows) - 1, config.max_segments).round().astype(int))]
    lmax = max(r[1] for r in rows)
    data = np.full((len(rows), lmax, 2), np.nan)
    for b, r in enumerate(rows):
        data[b, :r[1]] = r[2]
    return Segments(np.array([r[0] for r in rows]), np.array([r[1] for r in rows], dtype=np.int64), data,
                     np.array([r[3] for r in rows], dtype=float), np.array([r[4] for r in rows]))


class TrajectoryProblem:
    """The weighted residuals of the segments' trajectories as functions of (support coefficients, segment states)."""

    def __init__(self, coef: NDArray, segs: Segments, sigma: Sequence[float], h_omega: float,
                 mask: NDArray | None = None):
        self.mask = coef != 0.0 if mask is None else np.asarray(mask, bool)
        self.cols = np.flatnonzero(self.mask.any(axis=0))
        self.exps = np.ascontiguousarray(EXPONENTS[self.cols])
        self.where = np.argwhere(self.mask[:, self.cols])
        self.segs = segs
        self.w = 1.0 / np.maximum(np.asarray(sigma, float), 1e-300)
        self.valid = np.isfinite(segs.data[..., 0])
        self.substeps = max(1, max(PolynomialModel(coef).default_substeps(float(d), h_omega)
                                   for d in np.unique(segs.dt)))

    def parameters(self, coef: NDArray) -> NDArray:
        """The parameter vector of the support's coefficients in ``coef`` (2, 35)."""
        return np.asarray(coef, float)[:, self.cols][self.mask[:, self.cols]]

    def matrix(self, p: NDArray) -> NDArray:
        c = np.zeros((2, self.cols.size))
        c[self.where[:, 0], self.where[:, 1]] = p
        return c

    def residuals(self, coefs: NDArray, x0s: NDArray, idx: NDArray) -> tuple[NDArray, NDArray]:
        """Weighted residuals (B, Lmax, 2), zero on padding, of the trajectories from ``x0s`` (B, 4) with the
        coefficient matrices ``coefs`` (B, 2, n_cols) of segments ``idx`` (B,); and which of them stayed in
        bounds."""
        s = self.segs
        traj, nv = integrate_batch(np.ascontiguousarray(coefs), self.exps, x0s, s.dt[idx], s.length[idx],
                                   self.substeps, s.bound[idx])
        L = traj.shape[1]
        res = np.subtract(traj[..., 0::2], s.data[idx, :L])  # the positions y, theta
        res *= self.w
        np.nan_to_num(res, copy=False)
        res[~self.valid[idx, :L]] = 0.0  # padding and missing frames
        return res, nv >= s.length[idx]

    def cost(self, p: NDArray, x0: NDArray) -> tuple[float, NDArray]:
        """Sum of squared weighted residuals over the segments that stayed in bounds, and which did."""
        seg = self.segment_costs(p, x0)
        ok = np.isfinite(seg)
        return float(np.sum(seg[ok])), ok

    def segment_costs(self, p: NDArray, x0: NDArray) -> NDArray:
        """Per segment the sum of squared weighted residuals (inf where the trajectory left its bounds)."""
        idx = np.arange(x0.shape[0])
        res, ok = self.residuals(np.broadcast_to(self.matrix(p), (idx.size, 2, self.cols.size)), x0, idx)
        return np.where(ok, np.sum(res ** 2, axis=(1, 2)), np.inf)

    def normal_equations(self, p: NDArray, x0: NDArray, states_only: bool = False, dp: NDArray | None = None):
        """(A_cc, A_cx (S, nc, 4), A_xx (S, 4, 4), g_c, g_x (S, 4)) of the forward-difference Jacobian (with respect
        to the segment states alone when ``states_only``: nc = 0); ``dp``: the coefficients' steps (default 1e-6
        of each)."""
        nc, S = (0 if states_only else p.size), x0.shape[0]
        dp = 1e-6 * np.maximum(np.abs(p[:nc]), 1e-300) if dp is None else np.asarray(dp, float)[:nc]
        dx = 1e-6 * np.maximum(self.segs.bound / 10.0, 1e-300)
        base = self.matrix(p)
        pert = np.stack([base] + [self.matrix(p + dp[j] * np.eye(p.size)[j]) for j in range(nc)] + [base] * 4)
        k = pert.shape[0]
        chunk = max(1, _CHUNK_FRAMES // (k * self.segs.data.shape[1]))
        acc = (np.zeros((nc, nc)), np.zeros((S, nc, 4)), np.zeros((S, 4, 4)), np.zeros(nc), np.zeros((S, 4)))
        for lo in range(0, S, chunk):
            idx = np.arange(lo, min(S, lo + chunk))
            b = idx.size
            xs = np.repeat(x0[idx][None], k, axis=0)
            for j in range(4):
                xs[1 + nc + j, :, j] += dx[idx, j]
            res, _ = self.residuals(np.repeat(pert, b, axis=0), xs.reshape(-1, 4), np.tile(idx, k))
            res = res.reshape(k, b, -1)
            jac_c = (res[1:1 + nc] - res[0][None]) / dp[:, None, None]
            jac_x = (res[1 + nc:] - res[0][None]) / dx[idx].T[:, :, None]
            acc[0][...] += np.einsum("ibt,jbt->ij", jac_c, jac_c)
            acc[1][idx] = np.einsum("ibt,jbt->bij", jac_c, jac_x)
            acc[2][idx] = np.einsum("ibt,jbt->bij", jac_x, jac_x)
            acc[3][...] += np.einsum("ibt,bt->i", jac_c, res[0])
            acc[4][idx] = np.einsum("ibt,bt->bi", jac_x, res[0])
        return acc


def lm_step(normal, lam: float) -> tuple[NDArray, NDArray]:
    """Levenberg-Marquardt step (coefficients, segment states) with the states eliminated by their Schur
    complement; Marquardt's scaling by the diagonal."""
    _, a_cx, _, _, g_x = normal
    schur, rhs, inv = eliminate_states(normal, lam)
    # equilibrated: the coefficients' SI units span ten decades, and a least squares on the raw matrix would cut
    # the directions of the large coefficients as round-off (a step that depends on the units)
    d = np.sqrt(np.maximum(np.diag(schur), 1e-300))
    step_c = -np.linalg.lstsq(schur / np.outer(d, d), rhs / d, rcond=None)[0] / d
    step_x = -np.einsum("sij,sj->si", inv, g_x + np.einsum("sij,i->sj", a_cx, step_c))
    return step_c, step_x


def fit_segment_states(problem: TrajectoryProblem, p: NDArray, x0: NDArray, steps: int = 4) -> tuple[NDArray, NDArray]:
    """Gauss-Newton on the segment states alone at fixed coefficients (the start of the refinement); a segment
    keeps its state where a step does not lower its misfit.  Returns the states and every segment's misfit there
    (:meth:`TrajectoryProblem.segment_costs`)."""
    eye4 = np.eye(4)
    seg_cost = problem.segment_costs(p, x0)
    for _ in range(steps):
        _, _, a_xx, _, g_x = problem.normal_equations(p, x0, states_only=True)
        step = -np.linalg.solve(a_xx + 1e-9 * np.einsum("sii->si", a_xx)[:, :, None] * eye4 + 1e-300 * eye4,
                                g_x[..., None])[..., 0]
        trial = problem.segment_costs(p, x0 + step)
        better = trial < seg_cost
        x0 = np.where(better[:, None], x0 + step, x0)
        seg_cost = np.where(better, trial, seg_cost)
    return x0, seg_cost


def eliminate_states(normal, lam: float = 0.0, state_ridge: float = 0.0) -> tuple[NDArray, NDArray, NDArray]:
    """The coefficients' normal matrix and gradient with the segment states eliminated (Schur complement), both
    blocks damped by Marquardt's ``lam`` times their diagonal (the states' by ``lam + state_ridge``); also the
    states' inverted blocks (S, 4, 4)."""
    a_cc, a_cx, a_xx, g_c, g_x = normal
    eye4 = np.eye(4)
    inv = np.linalg.inv(a_xx + (lam + state_ridge) * np.einsum("sii->si", a_xx)[:, :, None] * eye4 + 1e-300 * eye4)
    schur = a_cc + lam * np.diag(np.diag(a_cc)) - np.einsum("sij,sjk,slk->il", a_cx, inv, a_cx)
    return schur, g_c - np.einsum("sij,sjk,sk->i", a_cx, inv, g_x), inv


def reduced_normal(normal) -> tuple[NDArray, NDArray]:
    """The coefficients' normal matrix and gradient with the segment states eliminated (a ridge of 1e-12 on the
    states' blocks)."""
    schur, rhs, _ = eliminate_states(normal, 0.0, 1e-12)
    return schur, rhs
