"""The trajectory test's oracle: the standard errors the velocity coupling's output-error fit reaches on noise-free
runs.

The diagnosis judges the velocity coupling beside a damping on the whole trajectories
(:mod:`validation.diagnosis.identify.output_error`): every run simulated from its initial state with the twin's
equations of motion, the pressure, the damping's two rates, c5, c6 (and the other named effects' parameters) shared,
each run's initial state free, compared with every frame in units of the tracking noise.  Its Gauss-Newton
covariance at the *true* parameters on the twin's *noise-free* runs is this oracle: the fit's own normal equations
(:func:`~validation.diagnosis.identify.output_error.fit_trajectories` with no step taken) on each run alone, the
run's initial state marginalised, give the run's information on the shared parameters (the y offset among them); runs
add it, so random draws of runs pool it as the integral form's (:mod:`validation.planner.candidate_plan`).

It needs the truth in the twin's equations of motion: the air's damping (its law with its computed shape) or linear
damping, and effects of :class:`acousim.dynamics.effects.EffectSet`; a twin with a resonator has none (the
diagnosis does not make the trajectory test beside the cavity's lag either).
"""
from __future__ import annotations

from typing import Sequence

import numpy as np
from numpy.typing import NDArray

from fitting.uncertainty.oracle import NoiseLevels, schur_complement

__all__ = ["trajectory_information", "TRAJECTORY_PREFIX"]

#: The prefix of the trajectory test's parameters among a plan's labels.
TRAJECTORY_PREFIX = "trajectory test: "
_SHAPE = ("sway_ratio", "wedge_ratio", "gap_ratio")


def _law(dynamics) -> tuple[str, dict, dict]:
    """(damping law, its shape, start values of its rates) of the twin's damping."""
    effects = dynamics.effects
    if "air_damping" in effects:
        air = effects["air_damping"].params()
        return "air_damping", {k: air[k] for k in _SHAPE}, {"gamma_y": air["gamma_y"], "gamma_theta": air["gamma_theta"]}
    rates = effects["linear_damping"].params() if "linear_damping" in effects else {"gamma_y": 0.0, "gamma_theta": 0.0}
    return "linear_damping", {}, dict(rates)


def trajectory_information(twin, dynamics, states: Sequence[NDArray], dt: float, noise: NoiseLevels
                           ) -> tuple[tuple[str, ...], NDArray[np.float64], dict[str, float]] | None:
    """Each run's information on the trajectory test's shared parameters (module docstring).

    Parameters
    ----------
    twin : acousim.twin.TwinConfig
    dynamics : acousim.DimerDynamics
        The twin's true dynamics (:func:`acousim.twin.twin_dynamics`).
    states : per run, the exact states (n, 4) at the frames
    dt : frame interval [s]
    noise : the positions' white noise

    Returns
    -------
    (labels, information (R, k, k) in the parameters' SI units, truth by label), the labels prefixed with
    :data:`TRAJECTORY_PREFIX`; None for a twin with a resonator.
    """
    from validation.diagnosis.identify import output_error as oe

    if twin.cavity_mode is not None:
        return None
    law, shape, rates = _law(dynamics)
    others = {e.name: e.params() for e in dynamics.effects
              if e.name not in ("air_damping", "linear_damping", "velocity_coupling") and getattr(e, "candidate", True)}
    coupling = (dynamics.effects["velocity_coupling"].params() if "velocity_coupling" in dynamics.effects
                else {"c5": 0.0, "c6": 0.0})
    start = {"pressure_pa": float(dynamics.force_model.pressure_amplitude_pa), **rates, **coupling}
    # the trajectory test's shared parameters, in its order (fit_trajectories), then the y offset
    names = oe.shared_parameter_names(others, with_coupling=True)
    values = {**{f"{k}.{q}": v for k, p in others.items() for q, v in p.items()}, **start}
    p = np.array([float(values[n]) for n in names])
    steps = oe.first_difference_steps(names, p, None)
    scale = np.array([[noise.sigma_y, noise.sigma_theta]])
    k = len(names)
    info = []
    for st in states:
        st = np.asarray(st, float)
        data = oe.RunTrajectories(float(dt), [st[:, [0, 2]]], scale, st[:1])
        res = oe.TrajectoryResiduals(data, dynamics.force_model, law, shape, others, names, st[None, :, [0, 2]],
                                     scale[:, None, :])
        _, _, at = res.misfit(p, 0.0, st[:1])
        jtj, _ = res.normal_equations(p, st[:1], at, steps)
        # the run's initial state marginalised (the shared parameters and the y offset kept)
        info.append(schur_complement(jtj, range(k + 1), range(k + 1, jtj.shape[0])))
    labels = tuple(TRAJECTORY_PREFIX + n for n in names + ["y_offset"])
    return labels, np.array(info), dict(zip(labels, [*map(float, p), 0.0]))
