"""Compiled, allocation-free fixed-step RK4 integration of polynomial models.

A polynomial model is given by an exponent table ``exps`` (n_terms, 4) over the state
[y, ydot, theta, thetadot] and a coefficient matrix ``coef`` (2, n_terms) for the accelerations
[yddot, thetaddot].  The acceleration is evaluated with per-variable power tables (powers up
to 3 for the cubic library), so one evaluation costs ~2 multiplications per term and allocates
nothing.  The integrator is the suite's one compiled RK4, :func:`cubedimer.rk4.rk4`;
:func:`integrate_batch` integrates many (model, initial state) pairs in one compiled call (no
per-trajectory Python overhead).

Accuracy: classical RK4 has a local error O(h^5); with ``h * omega <= 0.05`` (omega the
fastest angular frequency) the phase error is ~(h omega)^5 / 120 per step (checked against the
analytic solution and DOP853 at rtol=1e-11 in the tests and the benchmark).

Blow-up: integration stops as soon as any state leaves ``|x_i| <= bound_i`` or becomes
non-finite; the number of valid output samples is returned (never an exception, NaN or inf in the
valid part).
"""
from __future__ import annotations

import numba as nb
import numpy as np
from numpy.typing import NDArray

from cubedimer.compile_cache import kernel_array
from cubedimer.rk4 import rk4

__all__ = ["integrate", "integrate_batch", "rhs"]

_MAXPOW = 8


@nb.njit(cache=True)
def _polynomial_accel(t, x0, x1, x2, x3, args):
    """(yddot, thetaddot) = coef @ monomials(x) (autonomous: ``t`` unused); ``args = (exps, c0, c1, pw)`` with the
    scratch power table ``pw[var, k] = x_var ** k``."""
    exps, c0, c1, pw = args
    for k in range(1, pw.shape[1]):
        pw[0, k] = pw[0, k - 1] * x0
        pw[1, k] = pw[1, k - 1] * x1
        pw[2, k] = pw[2, k - 1] * x2
        pw[3, k] = pw[3, k - 1] * x3
    a = 0.0
    b = 0.0
    for j in range(exps.shape[0]):
        m = pw[0, exps[j, 0]] * pw[1, exps[j, 1]] * pw[2, exps[j, 2]] * pw[3, exps[j, 3]]
        a += c0[j] * m
        b += c1[j] * m
    return a, b


@nb.njit(cache=True)
def _integrate_one(coef, exps, x0, dt, n_out, substeps, bound, out):
    """Integrate one model with the core RK4 in the box |x_i| <= bound_i; fill ``out[:n_valid]``;
    return n_valid.  The acceleration runs over the monomials with a nonzero coefficient in either equation only
    (in the library's order): a term whose coefficients are both zero adds exactly nothing, so a sparse model's
    trajectory is the same, at the cost of its own terms."""
    n_terms = 0
    for j in range(exps.shape[0]):
        if coef[0, j] != 0.0 or coef[1, j] != 0.0:
            n_terms += 1
    used = np.empty((n_terms, 4), dtype=np.int64)
    c0 = np.empty(n_terms)
    c1 = np.empty(n_terms)
    maxp = 1
    k = 0
    for j in range(exps.shape[0]):
        if coef[0, j] != 0.0 or coef[1, j] != 0.0:
            c0[k] = coef[0, j]
            c1[k] = coef[1, j]
            for i in range(4):
                used[k, i] = exps[j, i]
                if exps[j, i] > maxp:
                    maxp = exps[j, i]
            k += 1
    pw = np.ones((4, maxp + 1))
    n_valid, _ = rk4(_polynomial_accel, (used, c0, c1, pw), x0, dt / substeps, substeps, n_out,
                     -bound, bound, out)
    return n_valid


@nb.njit(cache=True)
def _integrate_many(coefs, exps, x0s, dt, n_outs, substeps, bounds, out, n_valid):
    # serial on purpose: parallelism comes from the process pool (cubedimer.executor), and numba's
    # OpenMP threading layer is not fork-safe
    for b in range(coefs.shape[0]):
        n_valid[b] = _integrate_one(coefs[b], exps, x0s[b], dt[b], n_outs[b], substeps[b], bounds[b], out[b])


def _as_bound(bound, n: int | None = None) -> NDArray[np.float64]:
    if bound is None:
        bound = np.inf
    return kernel_array(np.broadcast_to(np.asarray(bound, dtype=float), (4,) if n is None else (n, 4)))


def integrate(
    coef: NDArray[np.float64],
    exps: NDArray[np.int64],
    x0: NDArray[np.float64],
    dt: float,
    n_out: int,
    substeps: int = 1,
    bound: float | NDArray[np.float64] | None = None,
) -> tuple[NDArray[np.float64], int]:
    """Integrate ``xddot = coef @ monomials(x)`` with fixed-step RK4.

    Parameters
    ----------
    coef : ndarray, shape (2, n_terms)
        Coefficients of [yddot, thetaddot] (units consistent with the state's).
    exps : ndarray of int, shape (n_terms, 4)
        Exponents of each monomial over [y, ydot, theta, thetadot].
    x0 : ndarray, shape (4,)
        Initial state.
    dt : float
        Output sample interval (time units of the state); the RK4 step is ``dt / substeps``.
    n_out : int
        Number of output samples including ``x0``.
    substeps : int
        RK4 steps per output interval.
    bound : float or ndarray (4,), optional
        Blow-up bound per state component (default: none, only non-finite values stop).

    Returns
    -------
    traj : ndarray, shape (n_out, 4)
        States at ``t = k dt``; rows from ``n_valid`` on are NaN.
    n_valid : int
        Number of valid rows (``n_out`` unless the model left the bound).
    """
    exps = kernel_array(exps, np.int64)
    if exps.max(initial=0) > _MAXPOW:
        raise ValueError(f"monomial powers above {_MAXPOW} are not supported")
    out = np.full((int(n_out), 4), np.nan)
    nv = _integrate_one(kernel_array(coef), exps, kernel_array(x0), float(dt), int(n_out), int(substeps),
                        _as_bound(bound), out)
    return out, int(nv)


def integrate_batch(
    coefs: NDArray[np.float64],
    exps: NDArray[np.int64],
    x0s: NDArray[np.float64],
    dt: NDArray[np.float64] | float,
    n_out: NDArray[np.int64] | int,
    substeps: NDArray[np.int64] | int = 1,
    bound: NDArray[np.float64] | float | None = None,
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Integrate B (model, initial state) pairs in one compiled call.

    Parameters
    ----------
    coefs : ndarray, shape (B, 2, n_terms) or (2, n_terms)
        One coefficient matrix per trajectory, or one shared by all.
    exps : ndarray of int, shape (n_terms, 4)
    x0s : ndarray, shape (B, 4)
    dt : float or ndarray (B,)
        Output interval per trajectory.
    n_out : int or ndarray of int (B,)
        Output samples per trajectory; the result is padded with NaN to the longest.
    substeps : int or ndarray of int (B,)
        RK4 steps per output interval, shared or per trajectory.
    bound : float, ndarray (4,) or (B, 4), optional

    Returns
    -------
    traj : ndarray, shape (B, max(n_out), 4)
    n_valid : ndarray of int, shape (B,)
    """
    x0s = kernel_array(np.atleast_2d(x0s))
    B = x0s.shape[0]
    coefs = np.asarray(coefs, dtype=float)
    if coefs.ndim == 2:
        coefs = np.broadcast_to(coefs, (B,) + coefs.shape)
    coefs = kernel_array(coefs)
    dts = kernel_array(np.broadcast_to(np.asarray(dt, dtype=float), (B,)))
    n_outs = kernel_array(np.broadcast_to(np.asarray(n_out, dtype=np.int64), (B,)), np.int64)
    out = np.full((B, int(n_outs.max()), 4), np.nan)
    n_valid = np.zeros(B, dtype=np.int64)
    steps = kernel_array(np.broadcast_to(np.asarray(substeps, dtype=np.int64), (B,)), np.int64)
    _integrate_many(coefs, kernel_array(exps, np.int64), x0s, dts, n_outs, steps, _as_bound(bound, B), out, n_valid)
    return out, n_valid


def rhs(coef: NDArray[np.float64], exps: NDArray[np.int64], x: NDArray[np.float64]) -> NDArray[np.float64]:
    """First-order right-hand side [ydot, yddot, thetadot, thetaddot] at states ``x`` (n, 4) (numpy)."""
    x = np.atleast_2d(x)
    mono = np.prod(x[:, None, :] ** exps[None, :, :], axis=2)
    acc = mono @ np.asarray(coef).T
    return np.column_stack([x[:, 1], acc[:, 0], x[:, 3], acc[:, 1]])
