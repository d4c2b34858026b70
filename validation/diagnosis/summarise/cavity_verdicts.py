"""The verdicts beside the levitator's cavity: the cavity named only with gains a cavity mode can have
(:func:`named_only_with_a_mode`), pair scattering named only where it is more than the cavity's own share of the
hinge's stiffness (:func:`named_only_beyond_cavity`), and the cavity's mode given only where the damping of y beside
it is positive (:func:`mode_only_with_a_positive_damping`).

**Pair scattering.**

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

**The mode beside a negative damping of y.**  The cavity's lag damps y at a rate that varies over a cycle as F_Z^2,
and the linear damping beside it at a constant rate: their split, which sets the lag gain B and with it Q and x
(``x = A^2 / B``), rests on the shape of the damping over the amplitudes, where the slow expansion is least exact
(drops of 300-430 um reach |s - 1| = 6-8 %).  Where linear damping's gamma_y comes out negative, the lag has taken
more than the whole damping of y, which no air does: on the forced-resonator blind cases of seed 15001 (10 runs of 3
s, the air's damping) gamma_y = -0.38 and -3.0 1/s (air 0.60, 0.57) went with B 2.1 and 1.7 times its truth and x
59 % and 41 % low, within 4-25 % statistical errors; the same draw on a twin whose air damps the hinge linearly gave
the same split (gamma_y = -3.02), so it is the y equation's shape, not the hinge's drag.  There Q and x are "not
determined", with the reason; the gains and the quasi-static response stay.
"""
from __future__ import annotations

from dataclasses import replace
from typing import Sequence

import numpy as np

from ..prepare.cavity_lag import CAVITY_LAG_PARAMETERS, _problem_cavity, problem_columns
from .result import EffectVerdict, rejection
from .uncertainty import ParameterInterval

__all__ = ["cavity_modulation", "hinge_stiffness", "named_only_beyond_cavity", "named_only_with_a_mode",
           "mode_only_with_a_positive_damping",
           "MODE_QUANTITIES"]

#: The derived quantities of the cavity that rest on its lag gain (not determined beside a negative damping of y).
MODE_QUANTITIES = ("quality_factor", "detuning_half_widths")

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
    effects[names["pair_scattering"]] = replace(pair, named=False, status="rejected",
                                                rejected_because=(rejection("within_cavity_response", detail),))
    return effects


def mode_only_with_a_positive_damping(effects: Sequence[EffectVerdict]) -> list[EffectVerdict]:
    """``effects`` with the cavity's Q and detuning (:data:`MODE_QUANTITIES`) "not determined" where the model's
    linear damping beside it has gamma_y < 0 (module docstring); every other verdict unchanged."""
    effects = list(effects)
    at = {e.name: i for i, e in enumerate(effects) if e.significant}
    if "cavity_lag" not in at or "linear_damping" not in at:
        return effects
    gamma_y = float(effects[at["linear_damping"]].params.get("gamma_y", 0.0))
    cavity = effects[at["cavity_lag"]]
    if gamma_y >= 0 or not cavity.derived:
        return effects
    reason = (f"linear damping beside the cavity has gamma_y = {gamma_y:.3g} 1/s < 0: the cavity's lag took more than "
              "the whole damping of y, so its lag gain is not resolved from the damping beside it")
    derived = {q: (ParameterInterval(iv.value, None, None, iv.dof, reason) if q in MODE_QUANTITIES else iv)
               for q, iv in cavity.derived.items()}
    effects[at["cavity_lag"]] = replace(cavity, derived=derived)
    return effects


def named_only_with_a_mode(effect: EffectVerdict) -> EffectVerdict:
    """A named cavity whose lag gain has, beyond its 95 % interval, the sign no cavity mode has (that of its
    quasi-static gain: :func:`~validation.diagnosis.prepare.cavity_lag.mode_from_gains`) is not named.  A resonator's
    quasi-static and lag gains have opposite signs at every detuning (the ring's decay rate
    ``Gamma = -2 A / (B (1 + x^2))`` is positive), so such a fit stands for something else.  A lag gain whose interval
    holds zero is no evidence against a cavity (beside the air's damping the lag is often not resolved, while the
    quasi-static response is): the cavity stays named, its Q and detuning not determined.  A rejected one stays in the
    fitted model, with the code ``no_cavity_mode``."""
    if effect.name != "cavity_lag" or effect.status != "named":
        return effect
    a, b = float(effect.params["static_gain"]), float(effect.params["lag_gain"])
    lag = (effect.uncertainty or {}).get("lag_gain")
    if a * b < 0 or lag is None or not lag.determined or lag.interval_95[0] * lag.interval_95[1] <= 0:
        return effect
    return replace(effect, named=False, status="rejected", rejected_because=(rejection(
        "no_cavity_mode", f"static_gain = {a:.3g} s/rad, lag_gain = {b:.3g} s^2/rad, its 95 % interval "
                          f"{lag.interval_95[0]:.3g} to {lag.interval_95[1]:.3g}"),))
