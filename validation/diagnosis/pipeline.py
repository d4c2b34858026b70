"""A data set's diagnosis from end to end: :func:`diagnose_dataset` (its files: :func:`validation.report.write_diagnosis`).

Output, ``diagnosis.json`` (docs/formats.md, extended)::

    {"identified": [...], "calibration": {...}, "gap_before": g0, "gap_after": g1, "gap_definition": "...",
     "gap_components": [...], "gap_component_forms": {...}, "gap_per_run": {...}, "noise_floor": ...,
     "effects": [every candidate, ranked], "localization": {"before": ..., "after": ...},
     "long_time": {...}, "remaining_gap": {...}, "identification_rounds": [...], "skipped_files": [...],
     "settings": {...}}
"""
from __future__ import annotations

import logging
from dataclasses import dataclass, field, replace
from functools import partial
from pathlib import Path

import numpy as np

from acousim.dynamics.effects import EFFECT_TYPES

from .calibration import CALIBRATED_ON
from .candidates import CANDIDATE_EFFECTS
from .discovery import Discovery, discover_terms, discovered_equations
from .joint_model import joint_estimates, judge_candidates
from .drift import DriftSettings, detect_pressure_drift
from .gap_model import GapFit, fit_gap_model
from .elimination import backward_check
from .identification import PracticalThresholds, identify_effects
from .localization import localize_residuals
from .long_time import long_time_gaps, mean_long_time_gap
from .metrics import fit_components, fit_gaps, gap_definition, noise_floors, scalar_gap
from .model_parameters import ParameterCalibration, calibrate_model_parameter
from .orientation import check_y_orientation
from .preparation import RunAccelerations, prepare_diagnosis_runs
from .problem import DiagnosisProblem
from .statistics import format_p, runs_needed, smallest_sign_flip_pvalue

__all__ = ["DiagnoseConfig", "DiagnosisInternals", "diagnose_dataset", "EXPLAINED_GAP", "MIN_RUNS", "check_enough_runs"]

logger = logging.getLogger(__name__)

#: The candidate dampings (the air's effects), judged together against discovered terms.
AIR_DAMPINGS = tuple(n for n, t in EFFECT_TYPES.items() if t.acts_without_field and t.candidate)

#: A gap (in excess of the noise floor) below this is "explained within the noise".
EXPLAINED_GAP = 0.01


@dataclass(frozen=True)
class DiagnoseConfig:
    """Settings of a diagnosis.

    Parameters
    ----------
    candidates : names of the candidate effects (default: all of docs/conventions.md section 5)
    alpha : significance level of the one-sided sign-flip permutation test of the held-out improvement
    min_relative_improvement : practical significance, as a fraction of the current gap
    min_absolute_improvement : practical significance, as a fraction of the variance (beyond noise)
    max_frames_per_run : runs are thinned to at most this many frames for the fits (speed)
    max_vertical_gap : no cause is named when the vertical (calibration) equation stays unexplained beyond
        this fraction of its variance (the calibration is then distorted by something else)
    long_time : also compute the long-time (shape, Poincare, frequency) gaps
    long_time_duration : seconds of each run simulated for them [s]; None: the whole run
    drift : settings of the test for a pressure drifting within runs (:mod:`validation.diagnosis.drift`);
        None: the pressure is taken as constant without testing
    discover : regress what remains after the candidates on the cubic library (:mod:`validation.diagnosis.discovery`)
    discovery_min_improvement : a discovered term's median held-out improvement, as a fraction of the variance
    check_orientation : test whether y points down (:mod:`validation.diagnosis.orientation`); if so, warn
        (``data_warnings``, code ``y_inverted``) and diagnose the data with y -> -y
    """

    candidates: tuple[str, ...] = field(default_factory=lambda: tuple(CANDIDATE_EFFECTS))
    alpha: float = 0.01
    min_relative_improvement: float = 0.05
    min_absolute_improvement: float = 5e-6
    max_frames_per_run: int = 1500
    max_vertical_gap: float = 0.05
    long_time: bool = True
    long_time_duration: float | None = 2.0
    drift: DriftSettings | None = DriftSettings()
    discover: bool = True
    discovery_min_improvement: float = 1e-3
    check_orientation: bool = True

    def __post_init__(self):
        unknown = [c for c in self.candidates if c not in CANDIDATE_EFFECTS]
        if unknown:
            raise ValueError(f"unknown effect(s) {', '.join(unknown)}; candidates are {', '.join(CANDIDATE_EFFECTS)}")
        if not 0 < self.alpha < 1:
            raise ValueError(f"alpha must lie in (0, 1), got {self.alpha}")
        if self.max_frames_per_run < 10:
            raise ValueError(f"max_frames_per_run must be at least 10, got {self.max_frames_per_run}")
        if self.long_time_duration is not None and not self.long_time_duration > 0:
            raise ValueError(f"long_time_duration must be positive, got {self.long_time_duration}")
        self.thresholds  # validates the practical thresholds

    @property
    def thresholds(self) -> PracticalThresholds:
        """The practical-significance settings of the identification."""
        return PracticalThresholds(self.min_relative_improvement, self.min_absolute_improvement, self.max_vertical_gap)


@dataclass(frozen=True, eq=False)
class DiagnosisInternals:
    """What the figures and the report need beyond diagnosis.json: the problem and the fits before and after."""

    problem: DiagnosisProblem
    base: GapFit  #: the calibrated simulation alone
    final: GapFit  #: with the identified effects

    @property
    def runs(self) -> tuple[RunAccelerations, ...]:
        return self.problem.runs

    @property
    def model(self):
        return self.problem.model


def diagnose_dataset(data_dir: str | Path, config: DiagnoseConfig = DiagnoseConfig(), strict: bool = False,
                     progress: bool = True, mesh_size: float | None = None,
                     model: str = "gorkov", gap: float | None = None,
                     edge_radius: float | None = None) -> tuple[dict, DiagnosisInternals]:
    """Diagnose a data set.

    Parameters
    ----------
    data_dir : path of the data set (CSV runs and meta.json)
    config : DiagnoseConfig
    strict : stop at the first bad file instead of skipping it
    progress : log the steps at INFO level (else DEBUG)
    mesh_size : mesh size of the Gor'kov model [m] (default: the model's)
    model : the simulation model, a name of the registry :mod:`acousim.models` (``"gorkov"``, ``"fullwave"``);
        every model is calibrated the same way (pressure amplitude and height origin), and a model's own
        parameters that the data may determine (the full-wave hinge gap) are profiled unless given
        (:mod:`validation.diagnosis.model_parameters`)
    gap, edge_radius : hinge gap and edge radius of the full-wave model [m]; a given gap is not calibrated

    Returns
    -------
    (diagnosis, internals)
        The diagnosis.json document (docs/formats.md) and :class:`DiagnosisInternals` for figures.

    Runs with one BLAS thread (:func:`cubedimer.executor.single_blas_thread`): the same numbers wherever it
    runs (here, in an executor task, on a dask worker), and faster for its many small factorisations.
    """
    from cubedimer.executor import single_blas_thread

    with single_blas_thread():
        return _diagnose_dataset(data_dir, config, strict, progress, mesh_size, model, gap, edge_radius)


def _label(name: str) -> str:
    """A model parameter's name in prose: the field without its unit (``gap_m`` -> ``gap``)."""
    return name.rsplit("_", 1)[0].replace("_", " ")


def calibrate_model_parameters(model_name: str, conditions, recorded_runs, max_frames_per_run: int,
                               log=logger.info, drift=None) -> tuple[object, dict]:
    """The conditions with every model parameter the data may determine (and the user left unset) calibrated,
    and their :class:`~validation.diagnosis.model_parameters.ParameterCalibration` by field name.

    ``drift`` (a :class:`~validation.diagnosis.drift.PressureDrift`) is followed by every trial model, so that a
    pressure drifting within runs does not bias the hinge profile."""
    from acousim.models import force_model_type, static_model

    mtype = force_model_type(model_name)
    out = {}
    for name, (lo, hi, default) in mtype.calibration_ranges(conditions).items():
        if getattr(conditions, name) is not None:
            continue
        if not hi > lo * (1 + 1e-9):  # the model covers one value only: nothing to profile
            out[name] = ParameterCalibration(name, float(default), float(lo), float("inf"), False,
                                             f"the model's tables cover one {_label(name)} ({lo:.3g}) only: nothing "
                                             f"to profile; the default {default:.3g} is kept", (lo, hi))
            conditions = replace(conditions, **{name: float(default)})
            continue
        log("profiling the %s model's %s over [%.3g, %.3g] on the hinge equation", model_name, name, lo, hi)

        def build(value: float, name=name):
            sim = static_model(model_name, replace(conditions, **{name: value})).interpolated()
            trial = DiagnosisProblem.from_recorded(sim, recorded_runs, max_frames_per_run)
            return trial if drift is None else trial.with_drift(drift)

        pc = calibrate_model_parameter(name, lo, hi, default, build, label=_label(name))
        log("%s", pc.note)
        out[name] = pc
        conditions = replace(conditions, **{name: pc.value})
    return conditions, out


def _parameter_record(conditions, calibrated: dict, model_name: str) -> dict:
    """diagnosis.json calibration keys of the model's own parameters: ``gap_m``, ``gap_std_m``,
    ``gap_calibrated`` (and the profile) for every parameter the model type declares calibratable, and
    ``gap_model_error_m`` for a calibrated one whose model states its error (the systematic error the model's own
    stated accuracy implies; None otherwise)."""
    from acousim.models import force_model_type

    mtype = force_model_type(model_name)
    out = {}
    model_errors = None
    for name in mtype.calibration_ranges(conditions):
        base, unit = name.rsplit("_", 1)
        pc = calibrated.get(name)
        out[name] = float(getattr(conditions, name))
        out[f"{base}_std_{unit}"] = None if pc is None or not np.isfinite(pc.std_error) else pc.std_error
        out[f"{base}_calibrated"] = bool(pc is not None and pc.calibrated)
        model_error = None
        if pc is not None and pc.calibrated and mtype.parameter_model_error is not None:
            if model_errors is None:
                model_errors = mtype.parameter_model_error(conditions)
            rel = model_errors.get(name)
            model_error = None if rel is None or not np.isfinite(rel) else float(rel) * out[name]
        out[f"{base}_model_error_{unit}"] = model_error
        out[f"{base}_note"] = pc.note if pc is not None else f"the {_label(name)} given by the user"
        if pc is not None:
            out[f"{base}_profile"] = pc.to_dict()
    return out


def _dissipation_rivals(problem: DiagnosisProblem, base: GapFit, identified: list[str], discover) -> Discovery:
    """The dissipative terms found without the identified candidate dampings: on the calibration alone, and, with
    two or more dampings identified, also beside each of them alone (the other effects kept), united.

    Two candidate dampings together can mimic a dissipation neither describes (linear damping and quadratic drag
    reproduce a loss growing as the amplitude^4); on the calibration alone the search can then find its leading term
    only (measured on the centred y-dependent damping: ``y^2*ydot`` at 23 % under the truth, without the ``y*ydot``
    that its centre off the data's origin adds), and the two dampings still improve every held-out run on top of it.
    Beside one damping, the rest of the dissipation's shape is found (there: ``y*ydot`` and ``y^2*ydot``)."""
    out = discover(base, forms=("energy",))
    dampings = [e for e in identified if e in AIR_DAMPINGS]
    if len(dampings) > 1:
        for d in dampings:
            keep = [e for e in identified if e not in dampings or e == d]
            out = out.union(discover(fit_gap_model(problem, keep), forms=("energy",)))
    return out


def _ranked_effects(problem: DiagnosisProblem, config: DiagnoseConfig, ident, elim, identified: list[str],
                    named: list[str], in_pair: dict, replaced: dict, joint_params: dict, final: GapFit,
                    gap_before: float) -> list[dict]:
    """diagnosis.json's ``effects``: every candidate, the model's effects first (in the order added, with the gap
    after the cumulative fit and their held-out tests), then the others fitted on top of them, by gap."""
    runs = problem.runs
    # every candidate, ranked: identified ones in order with the gap after the cumulative fit;
    # the others fitted on top of the identified set
    effects = []
    last_tests = ident.last_tests()
    for i, name in enumerate(identified):
        fit = fit_gap_model(problem, identified[: i + 1])
        g = scalar_gap(fit_gaps(runs, fit))
        test = ident.rounds[ident.identified.index(name)].candidates[name]
        given = elim.tests.get(name)
        entry = {"name": name, "params": joint_params[name], "gap_after": g, "shrink": 1 - g / gap_before,
                 "significant": True, "p_value": test.p_value, "wilcoxon_p": test.wilcoxon_p,
                 "held_out_improvement_fraction": test.median_improvement_fraction,
                 "added_in_round": ident.identified.index(name) + 1, "named": name in named,
                 "p_value_given_others": given.p_value if given else None,
                 "median_improvement_given_others": given.median_improvement if given else None}
        if name in in_pair:
            entry["indistinguishable_from"] = [e for e in in_pair[name].effects if e != name]
        if joint_params[name] != final.effects[name]:  # fitted beside discovered terms: the effects-only values too
            entry["params_without_discovered_terms"] = final.effects[name]
        effects.append(entry)
    others = []
    for name in config.candidates:
        if name in identified:
            continue
        fit = fit_gap_model(problem, identified + [name])
        g = scalar_gap(fit_gaps(runs, fit))
        test = last_tests.get(name)
        note = "fitted on top of the identified effects; not a significant held-out improvement"
        given = elim.dropped_tests.get(name)
        if name in elim.dropped:
            t = ident.rounds[ident.identified.index(name)].candidates[name]
            note = (f"improved held-out runs when added ({format_p(t.p_value)}), but not given the other effects "
                    f"(backward check{', ' + format_p(given.p_value) if given else ''}): the others explain its share "
                    "of the gap")
        if name in in_pair:
            other = [e for e in in_pair[name].effects if e != name][0]
            note = (f"indistinguishable from {other}: the data cannot tell them apart (see indistinguishable); "
                    f"{other} stands for both in the fitted model")
        if name in replaced:
            note = (f"improved held-out runs, but not once the discovered terms are fitted ({format_p(replaced[name])}): "
                    "the discovered terms explain its share of the gap better")
        others.append({"name": name, "params": fit.effects[name], "gap_after": g, "shrink": 1 - g / gap_before,
                       "significant": False, "p_value": test.p_value if test else None,
                       "wilcoxon_p": test.wilcoxon_p if test else None,
                       "held_out_improvement_fraction": test.median_improvement_fraction if test else None,
                       "note": note, **({"p_value_given_others": given.p_value,
                                         "median_improvement_given_others": given.median_improvement} if given else {})})
    effects += sorted(others, key=lambda e: e["gap_after"])
    return effects


#: The fewest runs a diagnosis takes: every fit is scored on runs held out of it (K-fold over runs), and the
#: calibration's and the effects' held-out comparison needs at least two runs to fit on and one to score.
MIN_RUNS = 3


def check_enough_runs(data_dir, n_runs: int, n_skipped: int, alpha: float) -> None:
    """Refuse a data set with fewer than :data:`MIN_RUNS` usable runs: one line that says how many are needed and why.

    Raises
    ------
    DatasetError
        With fewer than :data:`MIN_RUNS` runs.
    """
    from cubedimer.errors import DatasetError

    if n_runs >= MIN_RUNS:
        return
    skipped = f" ({n_skipped} file(s) skipped)" if n_skipped else ""
    raise DatasetError(
        f"{data_dir}: {n_runs} usable run{'' if n_runs == 1 else 's'}{skipped}; the diagnosis needs at least {MIN_RUNS}, "
        f"because it scores every fit on runs held out of it, and at least {runs_needed(alpha)} to name an effect at "
        f"alpha {alpha:g} (the held-out sign-flip test's smallest p with n runs is 2^-n); record more runs")


def _diagnose_dataset(data_dir, config: DiagnoseConfig, strict: bool, progress: bool,
                      mesh_size: float | None, model_name: str, gap: float | None,
                      edge_radius: float | None) -> tuple[dict, DiagnosisInternals]:
    from acousim.analytic import nominal_trap_frequency
    from acousim.models import force_model_type, static_model
    from cubedimer.dataset import LoadConfig, load_dataset
    from cubedimer.meta import read_meta

    from ..simulation import conditions_from_meta

    log = logger.info if progress else logger.debug
    skip = logger.warning if progress else logger.debug
    meta = read_meta(data_dir)
    conditions = conditions_from_meta(meta, mesh_size=mesh_size, gap=gap, edge_radius=edge_radius)
    # refuses a misfit first (a gap with Gor'kov, a dimer outside the full-wave family); a parameter to be calibrated
    # starts at the value the model takes by default
    mtype = force_model_type(model_name)
    mtype.check(conditions)
    start = {n: d for n, (_, _, d) in mtype.calibration_ranges(conditions).items() if getattr(conditions, n) is None}
    model = static_model(model_name, replace(conditions, **start))
    # the loader checks the physics bounds of any levitated dimer; with a meta.json also the Gor'kov estimate
    # of the trap frequency at its nominal pressure
    dataset = load_dataset(data_dir, strict=strict, config=LoadConfig(trap_frequency=nominal_trap_frequency),
                           report=lambda m: skip("skipping %s", m))
    check_enough_runs(data_dir, len(dataset.runs), len(dataset.skipped_files()), config.alpha)
    problem = DiagnosisProblem.from_recorded(model.interpolated(), prepare_diagnosis_runs(dataset),
                                             config.max_frames_per_run)
    data_warnings = []
    if config.check_orientation:
        orientation, flipped = check_y_orientation(problem, dataset, config.max_frames_per_run)
        if orientation.inverted:  # a flipped axis is never reported as new physics: the diagnosis uses -y
            warning = orientation.warning()
            logger.warning("%s", warning["message"])
            data_warnings.append(warning)
            problem = flipped
    # the model's own parameters the data may determine (the full-wave hinge gap), unless given; a pressure drift
    # found with the starting model is followed by every trial model (it is detected again below on the final one)
    calibrated_later = {n for n in mtype.calibration_ranges(conditions) if getattr(conditions, n) is None}
    first_drift = None
    if calibrated_later and config.drift is not None:
        found = detect_pressure_drift(problem, config.drift)
        first_drift = found.drift if found.detected else None
    conditions, parameters = calibrate_model_parameters(model_name, conditions, problem.recorded_runs,
                                                        config.max_frames_per_run, log, drift=first_drift)
    if parameters:
        model = static_model(model_name, conditions)
        problem = DiagnosisProblem.from_recorded(model.interpolated(), problem.recorded_runs,
                                                 config.max_frames_per_run)
    model = problem.model
    runs = problem.runs
    log("%d runs; calibrating pressure and height origin (first: a drift of the pressure within runs?)", len(runs))
    p_floor = smallest_sign_flip_pvalue(len(runs))
    identification_possible = p_floor <= config.alpha
    if not identification_possible:  # logged in quiet mode too: it changes what "identified: none" means
        logger.warning("with %d runs no effect can be identified at --alpha %g (smallest attainable p %.3g of the "
                       "held-out sign-flip test, 2^-%d); record at least %d runs", len(runs), config.alpha, p_floor,
                       len(runs), runs_needed(config.alpha))
    drift = detect_pressure_drift(problem, config.drift) if config.drift is not None else None
    if drift is not None and drift.detected:
        log("pressure drift detected (relative amplitude %.3g, time scale %.2g s, p = %.2g): the simulation "
            "follows it", drift.relative_amplitude, drift.time_scale_s, drift.p_value)
        problem = problem.with_drift(drift.drift)
    base = fit_gap_model(problem, [])
    per_before = fit_gaps(runs, base)
    gap_before = scalar_gap(per_before)
    floor = float(np.mean(noise_floors(runs, base)))
    log("gap before = %.3g (noise floor %.3g); identifying effects", gap_before, floor)
    held_out_cache: dict = {}
    ident = identify_effects(problem, config.candidates, alpha=config.alpha, thresholds=config.thresholds,
                             progress=progress, cache=held_out_cache)
    # every effect the greedy rounds chose must still be needed given all the others; pairs that only work as
    # either one are one verdict naming both
    elim = backward_check(problem, ident.identified, alpha=config.alpha, thresholds=config.thresholds, log=log,
                          cache=held_out_cache)
    pairs = list(elim.indistinguishable)
    identified = list(elim.model_effects)  # what the model fits; the named ones are `named` below
    final = fit_gap_model(problem, identified)
    discovery, replaced = Discovery(), {}
    if config.discover:
        log("regressing the remaining residual on the library (held-out runs)")
        discover = partial(discover_terms, problem, alpha=config.alpha,
                           min_absolute_improvement=config.discovery_min_improvement,
                           min_relative_improvement=config.min_relative_improvement)
        discovery = discover(final)
        # the candidates are judged against the terms found on top of them, and against the dissipative terms
        # found without them: a candidate damping can absorb the energy loss of a dissipation it does not
        # describe, leaving nothing to discover on top of it
        for rivals in (discovery, _dissipation_rivals(problem, base, identified, discover) if identified else Discovery()):
            if rivals.empty or not identified:
                continue
            kept, pvals = judge_candidates(problem, identified, rivals, alpha=config.alpha, group=AIR_DAMPINGS)
            if kept != identified:
                replaced.update({c: pvals[c] for c in identified if c not in kept})
                identified = kept
                final = fit_gap_model(problem, identified)
                discovery = discover(final)
    # a pair whose kept member the discovered terms replaced is not a verdict any more
    pairs = [pr for pr in pairs if pr.kept_in_model in identified]
    in_pair = {e: pr for pr in pairs for e in pr.effects}
    named = [e for e in identified if e not in in_pair]
    per_after = fit_gaps(runs, final)
    gap_after = scalar_gap(per_after)
    # the final model's parameters: the identified effects re-estimated together with the discovered terms
    # (a discovered copy of an effect's own column, the partner a discovered term needed, is folded into the effect)
    joint_params, discovery, folded = joint_estimates(problem, final, discovery)
    effects = _ranked_effects(problem, config, ident, elim, identified, named, in_pair, replaced, joint_params, final,
                              gap_before)
    loc_before = localize_residuals(runs, base.residuals)
    loc_after = localize_residuals(runs, final.residuals)
    long_time = {}
    if config.long_time:
        log("long-time gaps (simulating every run from its first state)")
        lt_before = long_time_gaps(problem, base, config.long_time_duration)
        lt_after = long_time_gaps(problem, final, config.long_time_duration) if identified else lt_before
        long_time = {"before": {"mean": mean_long_time_gap(lt_before), "per_run": [g.to_dict() for g in lt_before]},
                     "after": {"mean": mean_long_time_gap(lt_after), "per_run": [g.to_dict() for g in lt_after]}}
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
            "state-space regions and time scales that carry it"),
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
    cal = final.calibration
    components = fit_components(final)
    calibration = {
        "pressure_amplitude_pa": cal.pressure_amplitude_pa,
        "nominal_pressure_amplitude_pa": cal.nominal_pressure_pa,
        "pressure_ratio": cal.pressure_amplitude_pa / cal.nominal_pressure_pa,
        "y_origin_height_m": cal.z_origin_m,
        "y_origin_above_nominal_Z_eq_m": cal.z_origin_m - model.equilibrium_height,
        "y_origin_above_calibrated_Z_eq_m": cal.origin_offset_m,
        "calibrated_Z_eq_m": cal.equilibrium_height_m,
        "nominal_Z_eq_m": model.equilibrium_height,
        "initial_states": {r.name: r.state[0].tolist() for r in problem.recorded_runs},
        "calibrated_on": CALIBRATED_ON,
        **_parameter_record(conditions, parameters, model_name),
    }
    if drift is not None:
        calibration["drift"] = drift.to_dict()
    diagnosis = {
        "model": model_name,
        "simulation": {k: v for k, v in model.record().items() if not isinstance(v, (list, dict))},
        "identified": named,
        "indistinguishable": [pr.to_dict() for pr in pairs],
        "model_effects": identified,
        "dropped_by_backward_check": list(elim.dropped),
        "greedy_identified": list(ident.identified),
        "calibration": calibration,
        "gap_before": gap_before,
        "gap_after": gap_after,
        "gap_definition": gap_definition(components),
        "gap_components": [c.name for c in components],
        "gap_component_forms": {c.name: c.form for c in components},
        "gap_per_run": {"before": per_before.tolist(), "after": per_after.tolist(), "runs": [r.name for r in runs]},
        "noise_floor": floor,
        "noise_floor_note": "mean floor already subtracted from every gap",
        "effects": effects,
        "localization": {"before": loc_before, "after": loc_after},
        "long_time": long_time,
        "remaining_gap": remaining,
        "identification_rounds": [r.to_dict() for r in ident.rounds],
        "data_warnings": data_warnings,
        "skipped_files": dataset.skipped_files(),
        "glitch_frames_masked": dataset.n_glitches,
        "settings": {"alpha": config.alpha, "smallest_attainable_p": p_floor,
                     "identification_possible": bool(identification_possible), "runs_needed": runs_needed(config.alpha),
                     "min_relative_improvement": config.min_relative_improvement,
                     "candidates": list(config.candidates), "penalty_for_parameters": "leave-one-run-out held-out gap"},
    }
    return diagnosis, DiagnosisInternals(problem, base, final)
