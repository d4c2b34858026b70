"""The diagnosis's last step, summarise: the joint model's parameters, every candidate's verdict, the gaps before and
after, where the rest lies, the long-time errors and the constants used, as one :class:`Diagnosis`,
:func:`summary_step`."""
from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING

from ..calibrate.calibration import CALIBRATED_ON
from ..calibrate.calibration_step import Calibrated
from ..calibrate.gap_model import GapFit
from ..calibrate.metrics import fit_components, fit_gaps, gap_definition, scalar_gap
from ..calibrate.model_parameters import parameter_record
from ..discover.joint_model import joint_estimates
from ..discover.library_terms import Discovery, discovered_equations
from ..identify.identification_step import Identified
from ..identify.statistics import format_p, runs_needed, smallest_sign_flip_pvalue
from ..prepare.cavity_lag import derived_quantities
from ..prepare.problem import DiagnosisProblem
from .constants import constants_used, data_set_warnings
from .localization import localize_residuals
from .long_time import long_time_gaps, mean_long_time_gap
from .result import Diagnosis, DiagnosisInternals
from .uncertainty import (CONFIDENCE, METHOD, energy_balance_pulls, interval_from_error, jackknife_errors,
                          pressure_model_error, with_effect_model_errors, with_model_error)
from .verdicts import ranked_effects

if TYPE_CHECKING:
    from acousim.models import ModelSpec

    from ..steps import DiagnoseConfig

__all__ = ["summary_step", "EXPLAINED_GAP"]

#: A gap (in excess of the noise floor) below this is "explained within the noise".
EXPLAINED_GAP = 0.01


def summary_step(dataset, cal: Calibrated, found: Identified, discovery: Discovery, replaced: dict,
               identified: list[str], final: GapFit, spec: "ModelSpec", config: "DiagnoseConfig", log) -> Diagnosis:
    """The joint model's parameters, every candidate's verdict, the gaps before and after, where the rest lies and
    the long-time errors, as one :class:`Diagnosis`."""
    problem, base, runs = cal.problem, found.base, cal.problem.runs
    # a pair whose kept member the discovered terms replaced is not a verdict any more
    pairs = [pr for pr in found.pairs if pr.kept_in_model in identified]
    in_pair = {e: pr for pr in pairs for e in pr.effects}
    named = [e for e in identified if e not in in_pair]
    per_before, per_after, floor = found.per_before, fit_gaps(runs, final), found.noise_floor
    gap_before, gap_after = scalar_gap(per_before), scalar_gap(per_after)
    # the final model's parameters: the identified effects re-estimated together with the discovered terms
    # (a discovered copy of an effect's own column, the partner a discovered term needed, is folded into the effect)
    found_terms = discovery
    joint_params, discovery, folded = joint_estimates(problem, final, discovery)
    log("standard errors: the final model refitted without each of the %d runs", len(runs))
    errors = jackknife_errors(problem, identified, joint_params, final.calibration,
                              lambda sub, fit: joint_estimates(sub, fit, found_terms)[0], derived=derived_quantities)
    oe = found.output_error
    if oe is not None and oe.significant and "velocity_coupling" in identified:
        # named on the whole trajectories: their estimates and errors (the windows' are 2-4 times wider)
        joint_params = {**joint_params, "velocity_coupling": oe.params}
        trajectory = {k: interval_from_error(v, oe.std_errors[k], len(runs) - 1) for k, v in oe.params.items()}
        errors = replace(errors, effects={**errors.effects, "velocity_coupling": trajectory})
    # every parameter's interval also holds its effect's systematic error (EFFECT_MODEL_ERROR), and beta0 the energy
    # balance's pull on it (ENERGY_BALANCE_PULLED)
    pulls = energy_balance_pulls(problem, identified, final.calibration)
    effects = ranked_effects(problem, config.candidates, found.ident, found.elim, identified, named, in_pair,
                             replaced, joint_params, final, per_before,
                             with_effect_model_errors(errors.effects, absolute=pulls),
                             with_effect_model_errors(errors.derived))
    # an effect whose addition raises the gap by more than two of its paired standard errors is not named (its
    # verdict says why, with both gaps)
    named = [e.name for e in effects if e.status == "named"]
    loc_after = localize_residuals(runs, final.residuals)
    components = fit_components(final)
    p_floor = smallest_sign_flip_pvalue(len(runs))
    settings = {"alpha": config.alpha, "smallest_attainable_p": p_floor,
                "identification_possible": bool(p_floor <= config.alpha), "runs_needed": runs_needed(config.alpha),
                "min_relative_improvement": config.min_relative_improvement,
                "candidates": list(config.candidates), "penalty_for_parameters": "leave-one-run-out held-out gap"}
    calibration = _calibration_record(problem, final, cal, spec, errors)
    return Diagnosis(
        model=spec.name,
        simulation={k: v for k, v in problem.model.record().items() if not isinstance(v, (list, dict))},
        identified=tuple(named), indistinguishable=tuple(pr.to_dict() for pr in pairs),
        model_effects=tuple(identified), dropped_by_backward_check=tuple(found.elim.dropped),
        greedy_identified=tuple(found.ident.identified),
        calibration=calibration,
        gap_before=gap_before, gap_after=gap_after, gap_definition=gap_definition(components),
        gap_components=tuple(c.name for c in components),
        gap_component_forms={c.name: c.form for c in components},
        gap_per_run={"before": per_before.tolist(), "after": per_after.tolist(), "runs": [r.name for r in runs]},
        noise_floor=floor, noise_floor_note="mean floor already subtracted from every gap",
        effects=effects,
        localization={"before": localize_residuals(runs, base.residuals), "after": loc_after},
        long_time=_long_time_record(problem, base, final, bool(identified), config, log),
        remaining_gap=_remaining_gap(found.ident, cal.drift, discovery, replaced, folded, identified, gap_after,
                                     floor, loc_after, settings, len(runs)),
        identification_rounds=tuple(r.to_dict() for r in found.ident.rounds),
        data_warnings=tuple(cal.data_warnings) + tuple(data_set_warnings(dataset, len(runs), settings)),
        skipped_files=tuple(dataset.skipped_files()), glitch_frames_masked=dataset.n_glitches, settings=settings,
        constants=tuple(constants_used(dataset.meta, spec, calibration)),
        data_set={"path": str(Path(dataset.path).resolve()), "meta": dict(dataset.meta),
                  "runs": [r.name for r in dataset.runs], "model_options": dict(spec.options)},
        internals=DiagnosisInternals(problem, base, final))


def _long_time_record(problem: DiagnosisProblem, base: GapFit, final: GapFit, any_effect: bool,
                      config: "DiagnoseConfig", log) -> dict:
    """diagnosis.json's ``long_time``: the attractor-shape, Poincare and frequency errors of every run simulated
    from its first state, before and after the effects (empty when the config skips them)."""
    if not config.long_time:
        return {}
    log("long-time gaps (simulating every run from its first state)")
    lt_before = long_time_gaps(problem, base, config.long_time_duration)
    lt_after = long_time_gaps(problem, final, config.long_time_duration) if any_effect else lt_before
    return {"before": {"mean": mean_long_time_gap(lt_before), "per_run": [g.to_dict() for g in lt_before]},
            "after": {"mean": mean_long_time_gap(lt_after), "per_run": [g.to_dict() for g in lt_after]}}


def _remaining_gap(ident, drift, discovery: Discovery, replaced: dict, folded: dict, identified: list[str],
                   gap_after: float, floor: float, loc_after: dict, settings: dict, n_runs: int) -> dict:
    """diagnosis.json's ``remaining_gap``: what is left, whether it is within the noise, and what carries it."""
    # the gap is already in excess of the noise floor: "explained" when under 1 % of the variance
    explained = bool(gap_after <= EXPLAINED_GAP)
    remaining = {
        "gap": gap_after,
        "noise_floor": floor,
        "explained_within_noise": explained,
        "statement": (
            ("the calibrated simulation with the identified effects explains the data within its derivative noise"
             if identified else "the calibrated simulation explains the data within its derivative noise")
            if explained else
            "a gap remains that no candidate effect explains; the localization lists the library terms, "
            "state-space regions and time scales that carry it"
            if settings["identification_possible"] else
            f"a gap remains, and with {n_runs} runs the held-out test "
            f"cannot name any effect (record at least {settings['runs_needed']} runs); the localization lists the "
            "library terms, state-space regions and time scales that carry it"),
        "dominant_terms": {eq: [d["term"] for d in loc_after["terms"][eq][:3]] for eq in ("yddot", "thetaddot")},
        "vertical_gap": ident.vertical_gap,
        "withheld": ident.withheld,
        "discovered_terms": discovery.to_dict(),
        "discovered_equations": discovered_equations(discovery),
        "discovery_selected": discovery.selected,
        "replaced_by_discovered_terms": [{"name": c, "p_value": p} for c, p in replaced.items()],
        "folded_into_effects": {eq: t for eq, t in folded.items() if t},
    }
    if not discovery.empty:
        remaining["statement"] += "; the library terms that carry it: " + "; ".join(discovered_equations(discovery).values())
    if drift is not None and drift.detected:
        remaining["statement"] = (
            f"the pressure drifts within runs (relative amplitude {100 * drift.relative_amplitude:.1f} %, time scale "
            f"{drift.time_scale_s:.2g} s, F-test {format_p(drift.p_value)}); the simulation follows the drift, and on top of it "
            + remaining["statement"])
    if ident.withheld:
        remaining["statement"] += (
            f"; the vertical (calibration) equation itself stays {100 * ident.vertical_gap:.0f} % unexplained, so the "
            f"calibration is distorted by a cause outside the candidates, and {', '.join(ident.withheld)} (which improved "
            "held-out runs on top of that calibration) is not named as a cause")
    return remaining


def _calibration_record(problem: DiagnosisProblem, final: GapFit, cal: Calibrated, spec: "ModelSpec", errors) -> dict:
    """diagnosis.json's ``calibration``: pressure, height origin (from the nominal and the calibrated Z_eq), the first
    states, the model's calibrated parameters, the pressure drift, and ``uncertainty``: the standard error and 95 %
    interval of the pressure, the origin and every calibrated model parameter
    (:mod:`validation.diagnosis.summarise.uncertainty`)."""
    c, model = final.calibration, problem.model
    calibration = {
        "pressure_amplitude_pa": c.pressure_amplitude_pa,
        "nominal_pressure_amplitude_pa": c.nominal_pressure_pa,
        "pressure_ratio": c.pressure_amplitude_pa / c.nominal_pressure_pa,
        "y_origin_height_m": c.z_origin_m,
        "y_origin_above_nominal_Z_eq_m": c.z_origin_m - model.equilibrium_height,
        "y_origin_above_calibrated_Z_eq_m": c.origin_offset_m,
        "calibrated_Z_eq_m": c.equilibrium_height_m,
        "nominal_Z_eq_m": model.equilibrium_height,
        "initial_states": {r.name: r.state[0].tolist() for r in problem.recorded_runs},
        "calibrated_on": CALIBRATED_ON,
        **parameter_record(cal.conditions, cal.parameters, spec),
    }
    if cal.drift is not None:
        calibration["drift"] = cal.drift.to_dict()
    uncertainty = {"method": METHOD, "confidence": CONFIDENCE, "runs": errors.runs,
                   **{k: iv.to_dict() for k, iv in errors.calibration.items()}}
    # the pressure's interval also holds the calibration's systematic error (PRESSURE_MODEL_ERROR, or its part beside
    # a cavity in the model)
    stat = errors.calibration["pressure_amplitude_pa"]
    systematic = pressure_model_error(errors.effects) * abs(stat.value)
    uncertainty["pressure_amplitude_pa"] = {**with_model_error(stat, systematic).to_dict(),
                                            "statistical_std_error": stat.std_error, "model_std_error": systematic}
    for name, pc in cal.parameters.items():  # the model's own parameters: their profile's jackknife error
        if pc is not None and getattr(pc, "calibrated", False):
            uncertainty[name] = interval_from_error(pc.value, pc.std_error, errors.runs - 1).to_dict()
        elif pc is not None:
            uncertainty[name] = {"value": pc.value, "std_error": None, "interval_95": None, "dof": None,
                                 "determined": False, "reason": pc.note}
    calibration["uncertainty"] = uncertainty
    return calibration
