"""The gap model: the calibrated simulation plus candidate effects, fitted to the runs, and its residuals.

:func:`fit_gap_model` calibrates the simulation (:func:`~validation.diagnosis.calibrate.calibration.calibrate`)
and then fits every parameter of the given effects jointly at the calibrated pressure and origin, on
three equations each weighted by its normalisation, so that the fit minimises the sum of the three
gap components (:mod:`validation.diagnosis.calibrate.metrics`):

* the y equation: Savitzky-Golay yddot against the model's accelerations through the matched filter;
* the theta equation: in its integral form against the measured theta when every run carries integral
  data (:class:`~validation.diagnosis.prepare.runs.PositionIntegrals`), else thetaddot as for y;
* the energy balance: over windows of ``energy_window`` seconds (about ten periods) the change of the
  calibrated mechanical energy ``E = M ydot^2/2 + I(theta) thetadot^2/2 + s U_ac(theta, z0 + y) + M g y``
  must equal the work of the non-conservative effect terms,
  ``integral (M ydot a_y,eff + I thetadot a_theta,eff) dt``, again linear in every effect parameter.
  Weak dissipation is invisible in instantaneous accelerations (gamma ydot is ~1e-2 of the trap
  acceleration) but dominates the energy change.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np
from numpy.typing import NDArray

from acousim.dynamics.resonator import CavityMode
from acousim.medium import Medium

from ..prepare.candidate_effects import CANDIDATE_EFFECTS, parameter_vector
from ..prepare.cavity_lag import CavityGains, mode_from_gains
from ..prepare.problem import DiagnosisProblem
from ..prepare.runs import uses_integral_form
from ..prepare.simulation_terms import SimulationTerms
from .calibration import Calibration, calibrate

__all__ = ["EnergyResidual", "IntegralResidual", "GapFit", "fit_gap_model", "apply_gap_model", "predicted_accelerations",
           "fit_cavity_reference"]


@dataclass(frozen=True, eq=False)
class EnergyResidual:
    """One run's energy balance under a fit."""

    residual: NDArray[np.float64]  #: (n_windows,) dE_data - W_sim per window [J]
    oscillation_energy: NDArray[np.float64]  #: (n_windows,) E - E_rest at each window's start [J]
    noise_variance: float  #: variance of dE over a window due to the velocity noise [J^2]


@dataclass(frozen=True, eq=False)
class IntegralResidual:
    """One run's theta equation in its integral form under a fit."""

    residual: NDArray[np.float64]  #: detrended measured theta minus the detrended double integral of the model
    norm: float  #: sum of the detrended measured theta squared
    floor: float  #: residual sum of squares of a perfect model, (frames - 2 per window) sigma_theta^2


@dataclass(frozen=True, eq=False)
class GapFit:
    """A calibrated simulation (plus effects) fitted to runs, and its residuals."""

    calibration: Calibration
    effects: dict[str, dict[str, float]]
    residuals: list[NDArray[np.float64]]  #: per run (n, 2): a_data - a_sim [m/s^2, 1/s^2]
    predicted: list[NDArray[np.float64]]  #: per run (n, 2): a_sim, filtered as the data
    energy: list[EnergyResidual]  #: per run
    #: per run: the theta equation in its integral form; None: the thetaddot accelerations were used
    integral: list[IntegralResidual] | None = None

    def effect_parameter_vector(self, names: Sequence[str]) -> NDArray:
        """The fitted parameters of ``names``, concatenated in the order of :data:`CANDIDATE_EFFECTS`."""
        return parameter_vector(self.effects, names)


def fit_gap_model(problem: DiagnosisProblem, effects: Sequence[str] = (), z0_window: float = 4e-4,
                  fixed: Calibration | None = None, energy_balance: bool = True) -> GapFit:
    """Fit the calibration (s, z0) and the parameters of ``effects`` to the problem's runs.

    With integral data on every run (:class:`~validation.diagnosis.prepare.runs.PositionIntegrals`, what
    :func:`~validation.diagnosis.prepare.runs.prepare_diagnosis_runs` gives) the calibration (vertical
    equation) and the theta rows of the effect fit use the integral form, against the measured positions;
    the y rows of the effect fit, and everything without integral data, use the Savitzky-Golay
    accelerations (matched kernel).

    Parameters
    ----------
    problem : DiagnosisProblem
    effects : names from CANDIDATE_EFFECTS
    z0_window : float
        z0 is searched within +-z0_window [m] of the nominal Z_eq (kept below the node).
    fixed : Calibration, optional
        Use this calibration instead of fitting one (effects are still fitted).
    energy_balance : bool
        Fit the effects to the energy balance's rows too (the default); False: to the y and theta equations alone
        (what the summarise step compares with,
        :func:`~validation.diagnosis.summarise.uncertainty.energy_balance_pulls`).
    """
    if "cavity_lag" in effects and "cavity_reference" not in problem._shared:
        fit_cavity_reference(problem)
    terms = SimulationTerms(problem)
    runs = terms.runs
    integral = uses_integral_form(runs)
    cal = calibrate(terms, effects, z0_window) if fixed is None else fixed
    params = {n: {p: 0.0 for p in CANDIDATE_EFFECTS[n]} for n in effects}
    n_par = sum(len(CANDIDATE_EFFECTS[n]) for n in effects)
    if n_par:
        sol = _fit_effect_parameters(terms, cal, effects, integral, energy_balance)
        i = 0
        for n in effects:
            for p in CANDIDATE_EFFECTS[n]:
                params[n][p] = float(sol[i])
                i += 1
    return _evaluate(terms, cal, params)


def apply_gap_model(problem: DiagnosisProblem, calibration: Calibration,
                    effects: dict[str, dict[str, float]]) -> GapFit:
    """The calibrated simulation plus ``effects`` (name -> parameters, SI), fitted elsewhere, on the
    problem's runs: its residuals, without fitting anything."""
    return _evaluate(SimulationTerms(problem), calibration, effects)


def _evaluate(terms: SimulationTerms, cal: Calibration, params: dict) -> GapFit:
    residuals, predicted = _acceleration_residuals(terms, cal, params)
    return GapFit(cal, params, residuals, predicted, _energy_residuals(terms, cal, params),
                  _integral_residuals(terms, cal, params))


def _fit_effect_parameters(terms: SimulationTerms, cal: Calibration, effects: Sequence[str], integral: bool,
                           energy_balance: bool = True) -> NDArray:
    """All effect parameters jointly at the calibrated (s, z0): y and theta equations and the energy
    balance (unless ``energy_balance`` is False), each weighted by its normalisation so that the fit minimises
    R_y + R_theta + R_E."""
    runs = terms.runs
    z0 = cal.z_origin_m
    s_cal = cal.pressure_scale
    rows, rhs = [], []
    forces = terms.forces(z0)
    ay_all = np.concatenate([r.accel[:, 0] for r in runs])
    at_all = np.concatenate([r.accel[:, 1] for r in runs])
    w_y = 1.0 / np.sqrt(max(np.sum((ay_all - ay_all.mean()) ** 2), 1e-300))
    w_t = 1.0 / np.sqrt(max(np.sum((at_all - at_all.mean()) ** 2), 1e-300))
    if integral:  # the theta equation in its integral form, against the measured theta
        known = terms.integral_known(z0, 1)
        cols = terms.integral_effect_columns(z0, effects, cal.equilibrium_height_m, 1)
        w_t = 1.0 / np.sqrt(max(sum(float(np.sum(r.integral.target(1) ** 2)) for r in runs), 1e-300))
    regressors = terms.effect_accelerations(z0, effects, cal.equilibrium_height_m)
    for i, (r, (fz, qt), regs) in enumerate(zip(runs, forces, regressors)):
        rows.append(w_y * regs[:, 0, :])
        rhs.append(w_y * (r.accel[:, 0] - (s_cal * fz - terms.g)))
        if integral:
            rows.append(w_t * cols[i])
            rhs.append(w_t * (r.integral.target(1) - s_cal * known[i][0] - known[i][1]))
        else:
            rows.append(w_t * regs[:, 1, :])
            rhs.append(w_t * (r.accel[:, 1] - (s_cal * qt + terms.centrifugal(r))))
    en = terms.energy_terms(z0, effects, cal.equilibrium_height_m) if energy_balance else []
    if en:
        e_rest = terms.rest_energy(s_cal, z0)
        e_scale = np.concatenate([e["k0"] + s_cal * e["u0"] - e_rest for e in en])
        w_e = 1.0 / np.sqrt(max(np.sum(e_scale**2), 1e-300))
    for e in en:
        rows.append(w_e * e["work"])
        rhs.append(w_e * (e["dk"] + s_cal * e["du"]))
    x, b = np.concatenate(rows), np.concatenate(rhs)
    scale = np.maximum(np.abs(x).max(axis=0), 1e-300)
    return np.linalg.lstsq(x / scale, b, rcond=None)[0] / scale


def _integral_residuals(terms: SimulationTerms, cal: Calibration, params: dict) -> list[IntegralResidual] | None:
    """Per run: the theta equation in its integral form; None without integral data."""
    if not uses_integral_form(terms.runs):
        return None
    names = list(params)
    pv = parameter_vector(params, names)
    known = terms.integral_known(cal.z_origin_m, 1)
    cols = terms.integral_effect_columns(cal.z_origin_m, names, cal.equilibrium_height_m, 1)
    out = []
    for r, kn, c in zip(terms.runs, known, cols):
        target = r.integral.target(1)
        res = target - cal.pressure_scale * kn[0] - kn[1] - (c @ pv if pv.size else 0.0)
        out.append(IntegralResidual(res, float(np.sum(target**2)), r.integral.floor(1)))
    return out


def _energy_residuals(terms: SimulationTerms, cal: Calibration, params: dict) -> list[EnergyResidual]:
    names = list(params)
    pv = parameter_vector(params, names)
    out = []
    e_rest = terms.rest_energy(cal.pressure_scale, cal.z_origin_m)
    d = terms.model.dimer
    for r, e in zip(terms.runs, terms.energy_terms(cal.z_origin_m, names, cal.equilibrium_height_m)):
        res = e["dk"] + cal.pressure_scale * e["du"] - (e["work"] @ pv if pv.size else 0.0)
        # noise of dE over a window: two independent endpoint energies, each with velocity noise
        # through the kinetic energy (M ydot sigma_vy)^2 + (I thetadot sigma_vtheta)^2
        b = r.balance
        if b.velocity_noise is not None:
            st, nv = b.state, b.velocity_noise
            ke_var = (terms.mass * st[:, 1]) ** 2 * nv[0] + (d.hinge_inertia(st[:, 2]) * st[:, 3]) ** 2 * nv[1]
            floor_var = 2.0 * float(np.mean(ke_var))
        else:
            floor_var = 0.0
        out.append(EnergyResidual(res, e["k0"] + cal.pressure_scale * e["u0"] - e_rest, floor_var))
    return out


def _acceleration_residuals(terms: SimulationTerms, cal: Calibration, params: dict) -> tuple[list, list]:
    """Per run: the acceleration residuals a_data - a_sim (n, 2) and the model's accelerations a_sim, the
    calibrated simulation plus the effects ``params`` filtered as the data."""
    forces = terms.forces(cal.z_origin_m)
    names = list(params)
    pv = parameter_vector(params, names)
    regressors = terms.effect_accelerations(cal.z_origin_m, names, cal.equilibrium_height_m)
    res, pred = [], []
    for r, (fz, qt), regs in zip(terms.runs, forces, regressors):
        a_y = cal.pressure_scale * fz - terms.g
        a_t = cal.pressure_scale * qt + terms.centrifugal(r)
        a = np.column_stack([a_y, a_t])
        if pv.size:
            a = a + regs @ pv
        pred.append(a)
        res.append(r.accel - a)
    return res, pred


def predicted_accelerations(problem: DiagnosisProblem, calibration: Calibration,
                            effects: dict[str, dict[str, float]]) -> list[NDArray[np.float64]]:
    """Per run (n, 2): the accelerations [yddot, thetaddot] of the calibrated simulation plus ``effects``
    (name -> parameters, SI) at the run's states, filtered as the data's (:meth:`RunAccelerations.smooth`)."""
    return apply_gap_model(problem, calibration, effects).predicted


#: Iterations of the reference mode's fit (:func:`fit_cavity_reference`): measured on acousim's simulated mode
#: (Q 150-300, x 1-2.5), the second iteration changes Q and x by under 0.3 %.
REFERENCE_ITERATIONS = 3
#: The reference mode's accepted range: the slow expansion holds for w_y / Gamma below about 0.35 (Q up to ~300 at the
#: default dimer's 25 Hz); beyond it, or without a mode, the columns stay first order.
REFERENCE_QUALITY_RANGE = (20.0, 600.0)
REFERENCE_DETUNING_RANGE = (0.2, 10.0)


def fit_cavity_reference(problem) -> CavityMode | None:
    """The cavity mode whose second-order terms complete the candidate's columns on ``problem``'s data set
    (:func:`~validation.diagnosis.prepare.cavity_lag.second_order_ratios`): the mode of the candidate fitted alone on
    every run of the data set (the problem's shared runs, so that every fold and jackknife refit uses the same
    columns), refitted with its own terms
    (:data:`REFERENCE_ITERATIONS`); None (first-order columns) when the fit has no mode (A and B of one sign: no
    cavity in the data) or one outside the accepted range.  Computed once per data set."""
    shared = problem._shared
    if "cavity_reference" in shared:
        return shared["cavity_reference"]
    shared["cavity_reference"] = None  # first-order columns while the reference is fitted
    whole = DiagnosisProblem(problem.model, shared.get("runs", problem.runs), drift=problem.drift, _shared=shared)
    frequency = Medium().frequency_hz
    for _ in range(REFERENCE_ITERATIONS):
        fit = fit_gap_model(whole, ["cavity_lag"])
        s = fit.calibration.pressure_scale
        try:
            mode = mode_from_gains(CavityGains(fit.effects["cavity_lag"]["static_gain"] / s,
                                               fit.effects["cavity_lag"]["lag_gain"] / s), frequency)
        except ValueError:
            mode = None
        if mode is None or not (REFERENCE_QUALITY_RANGE[0] <= mode.quality_factor <= REFERENCE_QUALITY_RANGE[1]
                                and REFERENCE_DETUNING_RANGE[0] <= mode.detuning <= REFERENCE_DETUNING_RANGE[1]):
            shared["cavity_reference"] = None
            break
        shared["cavity_reference"] = mode
    return shared["cavity_reference"]
