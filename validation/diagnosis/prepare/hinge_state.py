"""The hinge rate of the integral form's columns with its fast response: the slow rate from the data, the fast one
from the simulation.

Why
---
The integral form evaluates its columns at theta and thetadot smoothed over half a hinge period
(:func:`fitting.derivatives.integral_form.column_states`), which removes the derivative noise but also the hinge's
response to the trap's own motion: the Gor'kov torque depends on the height, so y's oscillation at f_y drives theta at
f_y and 2 f_y.  That fast rate is tiny (about 1 % of thetadot), but the velocity coupling's ``c6 thetadot ydot y``
multiplies it by ``y ydot`` (at 2 f_y), and the product has a slow part that the double integral of the integral
form amplifies.  Measured on twin data with the air's damping and a velocity coupling at blind strengths (10 runs of
3 s): the c6 column ``P K[thetadot ydot y]`` at the smoothed states differs from the one at the exact states by 68 %
and 90 % of its rms (regression slope 0.60 and 0.35: a strong errors-in-variables attenuation); with the exact
thetadot alone (y and ydot as measured) by 2.4 % (slope 1.008).  The c5 column ``thetadot^2 y`` is off by 5 %.

Method (a complementary filter)
-------------------------------
``thetadot = D S[theta_data] + u - D S[int u dt]``, ``u(t) = int thetaddot_sim dt``: ``D S`` is the derivative of the
same half-hinge-period smoother the column states use, so the data give the rate below its cut-off and the
simulation's hinge acceleration at the column states (no effects; it holds the trap's y-theta coupling) the rate
above it.  On exact data with an exact model this is the exact rate, whatever the cut-off (``D S`` keeps the straight
line ``theta(0) + thetadot(0) t`` that ``int u`` lacks; tested).  The simulation is the diagnosis's force model at the
pressure whose small-oscillation y frequency is the run's dominant y frequency (the calibration comes later; a
pressure off by a few per cent changes a 1 % correction by a few per cent), with y measured from the levitation
height as docs/formats.md writes it.  What it changes: the c6 column is 16 % off instead of 80 % (slope 0.98) on
the data set of ``docs/scripts/velocity_coupling_columns.py``; docs/diagnosis.md (Known limitations) gives the
diagnosis's verdicts before and after.  The diagnosis does not use it by default: the simulation without the
velocity coupling leaves out the coupling's own fast response, which grows with c5, and strong couplings on the
inviscid twin then got c6 wrong by up to +110 % (-11 % without the completion).
"""
from __future__ import annotations

from dataclasses import replace
from typing import Sequence

import numpy as np
from numpy.typing import NDArray

from .runs import RunAccelerations

__all__ = ["fast_hinge_rate", "pressure_for_frequency", "with_fast_hinge_response"]


def pressure_for_frequency(force_model, f_y: float, iterations: int = 8,
                           bounds: tuple[float, float] = (0.5, 2.0)) -> float:
    """Pressure amplitude [Pa] at which ``force_model``'s small-oscillation y frequency is ``f_y`` [Hz]: secant steps
    on ``ln f(ln p)`` (the trap's stiffness scales as p^2 at fixed height, its equilibrium sags with p), within
    ``bounds`` times the model's pressure; the model's own pressure when ``f_y`` is not a frequency or the search
    leaves the pressures that levitate the dimer."""
    p0 = float(force_model.pressure_amplitude_pa)
    if not (np.isfinite(f_y) and f_y > 0):
        return p0
    lo, hi = np.log(bounds[0] * p0), np.log(bounds[1] * p0)

    def log_frequency(log_p: float) -> float:
        return float(np.log(force_model.with_pressure(float(np.exp(log_p))).linear_frequencies()[0]))

    try:
        x0, x1 = np.log(p0), np.log(p0) + 0.01
        g0, g1 = log_frequency(x0) - np.log(f_y), log_frequency(x1) - np.log(f_y)
        for _ in range(iterations):
            if not (np.isfinite(g1) and np.isfinite(g0)) or g1 == g0 or abs(g1) < 1e-12:
                break
            x0, g0, x1 = x1, g1, float(np.clip(x1 - g1 * (x1 - x0) / (g1 - g0), lo, hi))
            g1 = log_frequency(x1) - np.log(f_y)
    except ValueError:  # a trial pressure that cannot levitate the dimer
        return p0
    return float(np.exp(x1)) if np.isfinite(g1) else p0


def fast_hinge_rate(state: NDArray, dt: float, window: int, polyorder: int, hinge_acceleration) -> NDArray[np.float64]:
    """The rate above the smoother's cut-off, ``u - D S[int u dt]`` with ``u = int hinge_acceleration(state) dt``
    [1/s], at every frame (``D S``: the smoother's derivative, as the column states' thetadot is taken).

    Parameters
    ----------
    state : (n, 4) [y, ydot, theta, thetadot] at every frame
    dt : frame interval [s]
    window, polyorder : the smoother ``S`` (:func:`fitting.derivatives.savitzky_golay.smooth_long_window`)
    hinge_acceleration : callable, states (n, 4) -> thetaddot (n,) [1/s^2]
    """
    from fitting.derivatives.savitzky_golay import smooth_long_window

    def integral(f):
        return np.concatenate([[0.0], np.cumsum(0.5 * (f[1:] + f[:-1])) * dt])

    u = integral(np.asarray(hinge_acceleration(state), float))
    # the smoothed rate is the derivative of the smoothed angle, so the complement is taken on the angle too: with
    # U = int u = theta - theta(0) - thetadot(0) t, D S[theta] + u - D S[U] = thetadot (S keeps straight lines)
    return u - smooth_long_window(integral(u), dt, window, polyorder)[1]


def with_fast_hinge_response(runs: Sequence[RunAccelerations], force_model) -> list[RunAccelerations]:
    """``runs`` with the thetadot of their integral-form column states completed by the fast response (module
    docstring); runs without integral data are returned unchanged.

    Parameters
    ----------
    runs : the recorded runs (:func:`validation.diagnosis.prepare.runs.prepare_diagnosis_runs`)
    force_model : the diagnosis's force model at nominal pressure (:meth:`DiagnosisProblem.surrogate`)
    """
    from acousim.dynamics.integrator import DimerDynamics
    from cubedimer.consistency import oscillation_frequency
    from fitting.derivatives.frequencies import THETA_MIN_CYCLES, Y_MIN_CYCLES
    from fitting.derivatives.integral_form import hinge_smoothing_window

    out = []
    for run in runs:
        pi = run.integral
        if pi is None:
            out.append(run)
            continue
        n = pi.positions.shape[0]
        duration = (n - 1) * pi.dt  # the preparation's rule of the frequencies (fitting.derivatives.frequencies)
        f_y, f_theta = (oscillation_frequency(pi.positions[:, i], pi.dt, duration, cycles)
                        for i, cycles in ((0, Y_MIN_CYCLES), (1, THETA_MIN_CYCLES)))
        window = hinge_smoothing_window(pi.dt, f_y, f_theta, run.smoothing[1] if run.smoothing else 5)
        if window >= n:
            out.append(run)
            continue
        dynamics = DimerDynamics(force_model.with_pressure(pressure_for_frequency(force_model, f_y)))
        state = pi.state.copy()
        state[:, 3] += fast_hinge_rate(pi.state, pi.dt, window, run.smoothing[1] if run.smoothing else 5,
                                       lambda s: dynamics.accelerations(s)[1])
        out.append(replace(run, integral=replace(pi, state=state)))
    return out


def prepared_problem(model, dataset, max_frames_per_run: int):
    """The :class:`~validation.diagnosis.prepare.problem.DiagnosisProblem` of ``dataset`` (its runs prepared by
    :func:`~validation.diagnosis.prepare.runs.prepare_diagnosis_runs`, thinned to ``max_frames_per_run``), with the
    hinge rate of the integral form's columns completed by :func:`with_fast_hinge_response` (the force model built
    once and shared)."""
    from .problem import DiagnosisProblem
    from .runs import prepare_diagnosis_runs

    first = DiagnosisProblem.from_recorded(model, prepare_diagnosis_runs(dataset), max_frames_per_run)
    force_model = first.surrogate()
    problem = DiagnosisProblem.from_recorded(model, with_fast_hinge_response(first.recorded_runs, force_model),
                                             max_frames_per_run)
    problem._shared["surrogate"] = force_model  # the same model's force model: not built twice
    return problem
