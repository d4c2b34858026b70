"""Long-time errors: the fitted gap model integrated from each run's first state against the run.

The instantaneous gap (:mod:`validation.diagnosis.calibrate.metrics`) says how well the simulation explains the
accelerations at the measured states; these errors say how well it reproduces the motion over seconds:
the fitting package's long-time loss terms (attractor shape, Poincare section, frequency,
:func:`fitting.refinement.losses.loss_terms`), each 0 for a perfect model and about 1 for one that predicts no motion.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

from ..calibrate.gap_model import GapFit
from ..prepare.problem import DiagnosisProblem

__all__ = ["LongTimeGap", "long_time_gaps", "mean_long_time_gap", "simulate_from_first_state"]


@dataclass(frozen=True)
class LongTimeGap:
    """One run's long-time loss terms (dimensionless) and whether the simulation left the trap early."""

    shape: float
    poincare: float
    frequency: float
    total: float
    diverged: bool
    status: str  #: the integrator's message

    def to_dict(self) -> dict:
        """The diagnosis.json form (``long_time.before.per_run[i]``)."""
        return {"shape": self.shape, "poincare": self.poincare, "frequency": self.frequency, "total": self.total,
                "diverged": self.diverged, "status": self.status}


def long_time_gaps(problem: DiagnosisProblem, fit: GapFit, max_duration: float | None = None) -> list[LongTimeGap]:
    """Per recorded run of ``problem``: the long-time loss terms of the simulation started from the run's
    first smoothed state, sampled on the run's own frames (at most ``max_duration`` seconds).

    Integrated with the compiled RK4 of :class:`acousim.dynamics.integrator.DimerDynamics` on the problem's surrogate
    rescaled to the calibrated pressure (its y is measured from the calibrated Z_eq, i.e. the data's y +
    ``calibration.origin_offset_m``), with the fitted effects.
    """
    from fitting.refinement.losses import loss_terms, make_reference

    out = []
    for r in problem.recorded_runs:
        t, sim, m, message = simulate_from_first_state(problem, fit, r, max_duration)
        ref = make_reference(t, r.state[:len(t)])
        lt = loss_terms(sim, int(m), ref)
        out.append(LongTimeGap(lt.shape, lt.poincare, lt.frequency, lt.total, bool(m < len(t)), message))
    return out


def simulate_from_first_state(problem: DiagnosisProblem, fit: GapFit, run, max_duration: float | None = None
                              ) -> tuple[np.ndarray, np.ndarray, int, str]:
    """The calibrated simulation of ``fit`` started from the recorded ``run``'s first smoothed state: ``(t, state,
    m, message)``, with ``t`` [s] from the run's start on its own frames (at most ``max_duration`` seconds),
    ``state`` (n, 4) in the data's y origin (zeros after ``m`` frames when the simulation left the trap early) and
    the integrator's message.

    Integrated with the compiled RK4 of :class:`acousim.dynamics.integrator.DimerDynamics` on the problem's surrogate
    rescaled to the calibrated pressure (its y is measured from the calibrated Z_eq, i.e. the data's y +
    ``calibration.origin_offset_m``), with the fitted effects."""
    from acousim.dynamics.integrator import DimerDynamics
    from acousim.dynamics.effects import EffectSet

    cal = fit.calibration
    surrogate = problem.surrogate().with_pressure(cal.pressure_amplitude_pa)
    dynamics = DimerDynamics(surrogate, EffectSet.from_dict(fit.effects))
    delta = cal.z_origin_m - surrogate.z_eq
    n = len(run.t) if max_duration is None else int(np.searchsorted(run.t - run.t[0], max_duration))
    t = run.t[:n] - run.t[0]
    x0 = run.state[0].copy()
    x0[0] += delta
    x0[2] = float(np.clip(x0[2], -0.999, 0.999))
    dt = float(np.median(np.diff(t)))
    traj = dynamics.integrate(x0, duration=t[-1], dt_out=dt)
    sim = np.zeros((n, 4))
    m = min(n, len(traj.t))
    sim[:m] = traj.state[:m]
    sim[:m, 0] -= delta
    return t, sim, m, traj.message


def mean_long_time_gap(per_run: Sequence[LongTimeGap]) -> dict[str, float]:
    """Mean over runs of each loss term (diagnosis.json ``long_time.before.mean``)."""
    return {k: float(np.mean([getattr(d, k) for d in per_run])) for k in ("shape", "poincare", "frequency", "total")}
