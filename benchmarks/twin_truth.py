"""The suite's twin as a benchmark truth: the paper-like dimer's field-on dynamics and their cubic Taylor series.

The truth is :func:`acousim.twin.simulation.twin_dynamics` of :data:`acousim.twin.PAPER_LIKE` at its nominal
pressure (3 kPa, no pressure error): the Gor'kov surrogate of the 1 mm dimer (Chebyshev series in theta times
cos / sin(2 k Z)), the hinge's theta-dependent inertia (its -1/2 I'(theta) thetadot^2 / I(theta)), pair scattering
(-kappa cos^2(k Z) theta), the mirror asymmetry's beta1 y and the tuned linear damping, with the field on.  None of
these forces is a polynomial, so the cubic library holds only its Taylor series.

The Taylor coefficients about rest (y = 0 at Z_eq, theta = 0, both at rest, an equilibrium of the preset) are
the cubic part of a least-squares fit of every monomial up to ``TAYLOR_DEGREE`` in (y, ydot, theta, thetadot) to
the twin's accelerations (:meth:`acousim.dynamics.integrator.DimerDynamics.accelerations`) on a tensor grid of
``TAYLOR_NODES`` Chebyshev nodes per coordinate over ``TAYLOR_BOX`` (the velocities' half-widths are the
positions' times the slower angular frequency).  The degree-4 and 5 monomials absorb the next orders; on the
symmetric grid a degree-7 remainder aliases onto a cubic coefficient at a relative (k y)^4 ~ 1e-6 or theta^4
~ 6e-6, and the accelerations are exactly quadratic in the velocities.  A coefficient whose contribution on the box
is below ``STRUCTURAL_ZERO`` of the equation's largest is a zero of the structure (a symmetry, or a velocity the
equation does not hold), left at rounding by the fit: it is set to 0, so the Taylor support is the structure's.
"""
from __future__ import annotations

from functools import lru_cache

import numpy as np
from numpy.typing import NDArray

#: the Taylor fit's Chebyshev nodes per coordinate and its degree (above the library's 3)
TAYLOR_NODES = 7
TAYLOR_DEGREE = 5
#: half-widths of the Taylor fit's box in y [m] and theta: 2 k y = 0.03 and theta = 0.05, where the quintic
#: remainder is ~1e-6 of the cubic series
TAYLOR_BOX = (20e-6, 0.05)
#: a fitted coefficient whose largest contribution on the box is below this share of the equation's largest
#: contribution is a structural zero (measured: at most 4e-12, the rounding of the least squares; the smallest true
#: term, yddot's theta^2, 5e-7)
STRUCTURAL_ZERO = 1e-9
#: the twin's slower linear frequency [Hz] (the hinge's, tuned by pair scattering just below y's); the test checks
#: it against the Taylor series' linear coefficients
F_SLOW = 20.9


@lru_cache(maxsize=None)
def paper_like_dynamics():
    """The paper-like twin's true dynamics (:class:`acousim.dynamics.integrator.DimerDynamics`) at 3 kPa."""
    from acousim.twin import PAPER_LIKE, TwinConfig
    from acousim.twin.simulation import twin_dynamics

    return twin_dynamics(TwinConfig.from_preset(PAPER_LIKE, seed=0))[0]


def accelerations(state: NDArray) -> NDArray:
    """(yddot [m/s^2], thetaddot [1/s^2]) of the paper-like twin, field on, for states (n, 4) -> (n, 2)."""
    s = np.atleast_2d(np.asarray(state, float))
    ay, at = paper_like_dynamics().accelerations(s)
    return np.column_stack([np.broadcast_to(ay, s.shape[:1]), np.broadcast_to(at, s.shape[:1])])


#: the exact runs' RK4 step [s]: omega h = 7e-4 at 21 Hz, a global error ~1e-12 of the amplitude over a run
EXACT_STEP = 5e-6


def simulate(x0: NDArray, t: NDArray) -> NDArray:
    """Exact trajectory (n, 4) from ``x0`` at the uniform times ``t`` [s] (the twin's compiled RK4,
    :meth:`acousim.dynamics.integrator.DimerDynamics.integrate`, step ``EXACT_STEP``).

    Raises
    ------
    ValueError
        If the run leaves the trap or the hinge reaches face contact (|theta| = 1): its amplitudes are too large.
    """
    dt = float(t[1] - t[0])
    traj = paper_like_dynamics().integrate(x0, dt * (len(t) - 1), dt, max_step=EXACT_STEP)
    if not traj.ok or len(traj.t) < len(t):
        raise ValueError(f"a twin run from {np.asarray(x0).tolist()} stops at t = {traj.t[-1]:.3f} s "
                         f"({traj.message}): use smaller amplitudes")
    return traj.state


def taylor_coefficients(rhs=accelerations, box: tuple[float, float] = TAYLOR_BOX,
                        f_slow: float = F_SLOW) -> NDArray:
    """Cubic Taylor coefficients (2, 35) [SI] of ``rhs`` (states (n, 4) -> accelerations (n, 2)) about rest, in the
    library's canonical order (module docstring)."""
    from cubedimer.terms import evaluate_library

    w = 2 * np.pi * f_slow
    half = np.array([box[0], w * box[0], box[1], w * box[1]])
    nodes = np.cos(np.pi * (np.arange(TAYLOR_NODES) + 0.5) / TAYLOR_NODES)
    grid = np.stack(np.meshgrid(*([nodes] * 4), indexing="ij"), axis=-1).reshape(-1, 4)
    basis = evaluate_library(grid, TAYLOR_DEGREE)  # scaled variables: every column of order 1 on the box
    scale = evaluate_library(half[None, :], TAYLOR_DEGREE)[0]  # a monomial's value at the box's corner
    fitted = np.linalg.lstsq(basis, rhs(grid * half), rcond=None)[0].T  # (2, n) coefficients of scaled monomials
    cubic = fitted[:, :35]
    cubic = np.where(np.abs(cubic) < STRUCTURAL_ZERO * np.abs(cubic).max(axis=1, keepdims=True), 0.0, cubic)
    return cubic / scale[:35]


@lru_cache(maxsize=None)
def compiled():
    """(right-hand side f(state (n, 4)) -> (n, 2), cubic Taylor coefficients (2, 35)): the form of
    :func:`benchmarks.bench_model_error.compiled`."""
    return accelerations, taylor_coefficients()
