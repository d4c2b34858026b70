"""Pair scattering beside the levitator's cavity: named only where it is more than the cavity's own share of the
hinge's stiffness.

The cavity scales every acoustic force by ``s = |a|^2`` (:mod:`validation.diagnosis.prepare.cavity_lag`), the hinge's
acoustic torque included, so over the data it changes the hinge's acoustic stiffness K (``-d(Q_theta / I)/dtheta``
at rest, about 111 1/s^2 on the default dimer at 3 kPa) by up to ``max |s - 1|`` of it: 1-4 % at the drops of the
blind studies (the dimer's shift of the cavity reaches d = delta / Gamma = 3.5 % at 150-200 um).  Its columns hold
that response to the second order of the slow expansion about a fitted reference mode, on the diagnosis's surrogate
of the force model; what they leave of it is a y-theta stiffness of the same order, and pair scattering's column
``-kappa cos^2(k Z_com) theta`` (a hinge stiffness with a y-theta part) takes it up with a significant held-out
improvement: on the blind studies with the resonator, pair scattering was named beside a named cavity with kappa of
about 1 1/s^2 (1 % of K; the drawn kappa are 2,000-30,000 1/s^2, 20-300 times K).

So a named pair scattering beside a named cavity is named only when its hinge stiffness ``kappa cos^2(k Z_eq)`` is
larger than the cavity's own modulation of the hinge's stiffness over the data, ``max |s - 1| K`` (at the calibrated
pressure); below it the data cannot tell it from what the cavity's columns leave of the cavity's response, and it is
rejected with the code ``within_cavity_response`` (it stays in the fitted model, whose gap it is part of).
"""
from __future__ import annotations

from dataclasses import replace
from typing import Sequence

import numpy as np

from ..prepare.cavity_lag import CAVITY_LAG_PARAMETERS, _problem_cavity, problem_columns
from .result import REJECTIONS, EffectVerdict

__all__ = ["cavity_modulation", "hinge_stiffness", "named_only_beyond_cavity"]

#: Half-width of the angles over which the hinge's stiffness at rest is the secant slope [rad].
_STIFFNESS_ANGLE = 0.02


def cavity_modulation(problem, calibration, gains: Sequence[float]) -> float:
    """``max |s - 1|`` over the problem's runs: the cavity's largest fractional change of the acoustic forces, for
    its fitted gains ``(A, B)`` (at nominal pressure, as the columns are), from its y row:
    ``(s - 1) = yddot_cavity M / F_Z,ac(0, Z_com)``."""
    cavity = _problem_cavity(problem)
    fm = cavity.force_model
    out = 0.0
    for run in problem.runs:
        state = np.asarray(run.state, float)
        z_com = calibration.z_origin_m + state[:, 0]
        cols = problem_columns(problem, state, z_com, calibration.equilibrium_height_m)
        accel_y = cols[:, 0, :] @ np.asarray(gains, float)
        out = max(out, float(np.max(np.abs(accel_y * fm.mass / cavity.rest_force(z_com)))))
    return out


def hinge_stiffness(problem, calibration) -> float:
    """K [1/s^2]: the hinge's acoustic stiffness at rest, ``-d(Q_theta / I)/dtheta`` at theta = 0 at the calibrated
    equilibrium and pressure (the surrogate's at nominal pressure times the pressure scale)."""
    fm = _problem_cavity(problem).force_model
    theta = np.array([-_STIFFNESS_ANGLE, _STIFFNESS_ANGLE])
    y = np.full(2, calibration.equilibrium_height_m - fm.z_eq)
    _, q_theta = fm.generalized_forces(theta, y)
    accel = q_theta / np.asarray(fm.hinge_inertia(theta), float)
    return float(-(accel[1] - accel[0]) / (2 * _STIFFNESS_ANGLE) * calibration.pressure_scale)


def named_only_beyond_cavity(effects: Sequence[EffectVerdict], problem, calibration) -> list[EffectVerdict]:
    """``effects`` with a named ``pair_scattering`` rejected (``within_cavity_response``) when a ``cavity_lag`` is
    named beside it and its hinge stiffness is within the cavity's modulation of the hinge's (module docstring)."""
    effects = list(effects)
    names = {e.name: i for i, e in enumerate(effects) if e.status == "named"}
    if "pair_scattering" not in names or "cavity_lag" not in names:
        return effects
    cavity, pair = effects[names["cavity_lag"]], effects[names["pair_scattering"]]
    fm = _problem_cavity(problem).force_model
    k = 0.5 * float(fm.two_k)
    pair_stiffness = float(pair.params["kappa"]) * np.cos(k * calibration.equilibrium_height_m) ** 2
    modulation = cavity_modulation(problem, calibration, [cavity.params[p] for p in CAVITY_LAG_PARAMETERS])
    stiffness = hinge_stiffness(problem, calibration)
    if abs(pair_stiffness) >= modulation * stiffness:
        return effects
    detail = (f"kappa cos^2(k Z_eq) = {pair_stiffness:.3g} 1/s^2 against the cavity's max |s - 1| K = "
              f"{modulation:.3g} x {stiffness:.3g} = {modulation * stiffness:.3g} 1/s^2")
    effects[names["pair_scattering"]] = replace(pair, named=False, status="rejected", rejected_because=(
        {"code": "within_cavity_response", "reason": REJECTIONS["within_cavity_response"] + f" ({detail})"},))
    return effects
