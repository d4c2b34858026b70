"""Periodic orbits of an autonomous flow by shooting, and their Floquet multipliers.

For an autonomous system ``x' = f(x)`` with the flow ``phi(x0, t)``, a periodic orbit of period T through x0 solves
``phi(x0, T) - x0 = 0``.  With one component of x0 pinned (the phase condition: e.g. ydot(0) = 0, the orbit's start on
y's turning point, a Poincare section) the unknowns are the other n - 1 components and T: n equations in n
unknowns, solved by Newton's method with the Jacobian ``[dphi/dx0 - I | f(phi(x0, T))]`` from central differences of
the flow (:func:`shoot_periodic_orbit`; the flow's own steps make the orbit the integrator's, which is what the
simulations follow).  The work is done in scaled coordinates ``z = x / scale`` so that the components are of order 1.

The monodromy matrix ``M = dphi(x0, T) / dx0`` (:func:`monodromy_matrix`, central differences) has the Floquet
multipliers as its eigenvalues.  One of them is exactly 1 with the eigenvector f(x0): a perturbation along the
orbit only shifts its phase.  :func:`floquet_split` picks it by its eigenvector (not by its value: near a
threshold a second multiplier comes close to 1) and returns the others; ``|mu_trivial - 1|`` and ``|M f - f| / |f|``
measure the numerics.  The orbit is stable when every non-trivial |mu| < 1; a perturbation along the largest grows
or decays by e in ``1 / |ln |mu||`` periods (:attr:`PeriodicOrbit.e_fold_periods`).

Checked against the Stuart-Landau oscillator (the Hopf normal form, whose orbit, period and multiplier exp(-2 mu T)
are known in closed form) and a damped linear oscillator (multipliers exp((-gamma/2 +- i w_d) T)) in
tests/acousim/dynamics/test_periodic_orbits.py.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable, Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["Flow", "PeriodicOrbit", "shoot_periodic_orbit", "monodromy_matrix", "floquet_split"]

#: ``flow(x0, t) -> x(t)``: the state after a time t [s] from x0 (NaN entries when the integration failed).
Flow = Callable[[NDArray[np.float64], float], NDArray[np.float64]]


@dataclass(frozen=True, eq=False)
class PeriodicOrbit:
    """A periodic orbit found by :func:`shoot_periodic_orbit`.

    Attributes
    ----------
    x0 : ndarray (n,)
        The state on the orbit at its phase condition.
    period : float
        T [s].
    converged : bool
        The scaled residual |phi(x0, T) - x0| fell below the tolerance.
    residual : float
        The final scaled residual (max norm).
    iterations : int
        Newton steps taken.
    multipliers : ndarray of complex (n - 1,)
        The non-trivial Floquet multipliers, largest |mu| first (empty until computed).
    trivial_multiplier : complex
        The multiplier along the flow (1 exactly in theory).
    flow_invariance : float
        |M f - f| / |f| in scaled coordinates (0 exactly in theory).
    """

    x0: NDArray[np.float64]
    period: float
    converged: bool
    residual: float
    iterations: int
    multipliers: NDArray[np.complex128] = field(default_factory=lambda: np.zeros(0, complex))
    trivial_multiplier: complex = complex("nan")
    flow_invariance: float = float("nan")

    @property
    def max_multiplier(self) -> float:
        """The largest non-trivial |mu| (NaN if not computed)."""
        return float(np.max(np.abs(self.multipliers))) if self.multipliers.size else float("nan")

    @property
    def stable(self) -> bool:
        """Every non-trivial |mu| < 1."""
        return bool(self.max_multiplier < 1.0)

    @property
    def e_fold_periods(self) -> float:
        """Periods over which a perturbation along the largest non-trivial multiplier grows (unstable) or decays
        (stable) by e: 1 / |ln |mu_max|| (inf for |mu_max| = 1)."""
        m = self.max_multiplier
        return float("nan") if not m > 0 else (math.inf if m == 1.0 else 1.0 / abs(math.log(m)))


def _scaled_flow(flow: Flow, scale: NDArray[np.float64]):
    return lambda z, t: np.asarray(flow(z * scale, t), float) / scale


def monodromy_matrix(flow: Flow, x0: ArrayLike, period: float, scale: ArrayLike | None = None,
                     eps: float = 1e-6, components: ArrayLike | None = None) -> NDArray[np.float64]:
    """M[i, j] = d phi_i(x0, T) / d x0_j by central differences, in scaled coordinates ``x / scale``.

    Parameters
    ----------
    flow : Flow
    x0 : array_like (n,)
        A state on the orbit.
    period : float
        T [s].
    scale : array_like (n,), optional
        The size of each component (default 1); the step of component j is ``eps * scale[j]``.
    eps : float
        Relative step: the error is O(eps^2) of the flow's curvature plus roundoff / eps.
    components : array_like of int, optional
        The components perturbed and read (a sub-block of M; default all).

    Returns
    -------
    ndarray (m, m)
        M in scaled coordinates (its eigenvalues are the multipliers, whatever the scale); NaN where a
        perturbed flow failed.
    """
    x0 = np.asarray(x0, float)
    s = np.ones_like(x0) if scale is None else np.asarray(scale, float)
    idx = np.arange(x0.size) if components is None else np.asarray(components, int)
    phi = _scaled_flow(flow, s)
    z0 = x0 / s
    cols = []
    for j in idx:
        dz = np.zeros_like(z0)
        dz[j] = eps
        cols.append((phi(z0 + dz, period)[idx] - phi(z0 - dz, period)[idx]) / (2 * eps))
    return np.column_stack(cols)


def floquet_split(monodromy: NDArray[np.float64], along_flow: NDArray[np.float64]) -> tuple[complex, NDArray[np.complex128], float]:
    """(the trivial multiplier, the others largest |mu| first, |M f - f| / |f|).

    The trivial multiplier is the one whose eigenvector is most nearly parallel to ``along_flow`` (f at the orbit's
    start, in the same scaled coordinates as ``monodromy``)."""
    mu, vec = np.linalg.eig(monodromy)
    f = np.asarray(along_flow, float)
    fn = f / np.linalg.norm(f)
    align = np.abs(vec.conj().T @ fn) / np.linalg.norm(vec, axis=0)
    k = int(np.argmax(align))
    rest = np.delete(mu, k)
    rest = rest[np.argsort(-np.abs(rest), kind="stable")]
    invariance = float(np.linalg.norm(monodromy @ f - f) / np.linalg.norm(f))
    return complex(mu[k]), rest.astype(complex), invariance


def shoot_periodic_orbit(flow: Flow, x0: ArrayLike, period: float, pinned: int | Sequence[int],
                         scale: ArrayLike | None = None, tol: float = 1e-10, max_iter: int = 20, eps: float = 1e-7,
                         max_period_change: float = 0.2, min_motion: float = 1e-6,
                         multipliers: bool = True) -> PeriodicOrbit:
    """Newton's method on ``phi(x0, T) - x0 = 0`` with ``x0[pinned]`` held (the phase condition).

    Parameters
    ----------
    flow : Flow
    x0 : array_like (n,)
        The guess (e.g. a state of a settled run at its section).
    period : float
        The guessed period T [s].
    pinned : int or sequence of int
        The component held at its guessed value (its value must be crossed by the orbit transversally: e.g. a
        velocity held at 0 at a turning point).  More than one (e.g. also an amplitude, for a conservative
        system's family of orbits) makes the system overdetermined: Gauss-Newton (least squares).
    scale : array_like (n,), optional
        Component sizes (module docstring).
    tol : float
        Convergence: max |phi(x0, T) - x0| / scale below ``tol``.
    max_iter : int
        Newton steps at most; a step that does not lower the residual is halved (up to 8 times).
    eps : float
        Relative finite-difference step of the Jacobian.
    max_period_change : float
        A solution whose period moved by more than this fraction of the guess is not the guessed orbit (not
        converged).
    min_motion : float
        A solution that moves less than this (max scaled |phi(x0, T/2) - x0|) is a fixed point, which closes for
        any T, not an orbit (not converged).
    multipliers : bool
        Compute the Floquet multipliers of a converged orbit (:func:`monodromy_matrix`, :func:`floquet_split`).
    """
    x = np.asarray(x0, float).copy()
    n = x.size
    s = np.ones(n) if scale is None else np.asarray(scale, float)
    phi = _scaled_flow(flow, s)
    z, t = x / s, float(period)
    held = {int(pinned)} if np.ndim(pinned) == 0 else {int(j) for j in pinned}
    free = [j for j in range(n) if j not in held]

    def residual(z, t):
        return phi(z, t) - z

    r = residual(z, t)
    norm = float(np.max(np.abs(r))) if np.all(np.isfinite(r)) else math.inf
    it = 0
    while norm > tol and it < max_iter and math.isfinite(norm):
        it += 1
        jac = np.empty((n, len(free) + 1))
        for c, j in enumerate(free):
            dz = np.zeros(n)
            dz[j] = eps
            jac[:, c] = (phi(z + dz, t) - phi(z - dz, t)) / (2 * eps) - dz / eps
        dt = eps * t
        jac[:, -1] = (phi(z, t + dt) - phi(z, t - dt)) / (2 * dt)
        if not np.all(np.isfinite(jac)):
            break
        step = np.linalg.lstsq(jac, -r, rcond=None)[0]
        lam = 1.0
        for _ in range(9):
            z_new, t_new = z.copy(), t + lam * step[-1]
            z_new[free] += lam * step[:-1]
            r_new = residual(z_new, t_new) if t_new > 0 else np.full(n, np.nan)
            n_new = float(np.max(np.abs(r_new))) if np.all(np.isfinite(r_new)) else math.inf
            if n_new < norm:
                break
            lam *= 0.5
        else:
            break  # no decrease along the Newton direction: the guess is not near an orbit
        if lam < 0.1 and n_new > 0.9 * norm:
            break  # stalled (e.g. a slow drift along a nearly neutral direction, no orbit nearby)
        z, t, r, norm = z_new, t_new, r_new, n_new
    ok = bool(norm <= tol and abs(t / period - 1.0) <= max_period_change)
    if ok:
        half = phi(z, 0.5 * t) - z
        ok = bool(np.all(np.isfinite(half)) and np.max(np.abs(half)) > min_motion)
    orbit = PeriodicOrbit(x0=z * s, period=float(t), converged=ok, residual=norm, iterations=it)
    if not (ok and multipliers):
        return orbit
    m = monodromy_matrix(flow, z * s, t, s)
    dt = 1e-6 * t  # f(x0) = f(phi(x0, T)) = d phi(x0, T) / dT on the orbit: forward flows only
    f = (phi(z, t + dt) - phi(z, t - dt)) / (2 * dt)
    if not (np.all(np.isfinite(m)) and np.all(np.isfinite(f))):
        return orbit
    trivial, rest, invariance = floquet_split(m, f)
    return PeriodicOrbit(x0=orbit.x0, period=float(t), converged=ok, residual=norm, iterations=it, multipliers=rest,
                         trivial_multiplier=trivial, flow_invariance=invariance)
