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
from typing import TYPE_CHECKING

import numpy as np

from acousim.dynamics.effects import EFFECT_TYPES
from acousim.models import ModelSpec
from cubedimer.config_checks import check_choices, check_fraction, check_positive, check_whole

if TYPE_CHECKING:
    from cubedimer.dataset import Dataset, LoadConfig

from .calibrate.calibration import CALIBRATED_ON
from .calibrate.drift import DriftSettings, detect_pressure_drift
from .calibrate.gap_model import GapFit, fit_gap_model
from .calibrate.metrics import fit_components, fit_gaps, gap_definition, noise_floors, scalar_gap
from .calibrate.model_parameters import calibrate_model_parameters, parameter_record
from .calibrate.orientation import check_y_orientation
from .discover.joint_model import joint_estimates, judge_candidates
from .discover.library_terms import Discovery, discover_terms, discovered_equations
from .identify.elimination import backward_check
from .identify.folded import leave_out_folded_runs
from .identify.identification import PracticalThresholds, identify_effects
from .identify.statistics import format_p, runs_needed, smallest_sign_flip_pvalue
from .prepare.candidate_effects import CANDIDATE_EFFECTS, default_candidates
from .prepare.problem import DiagnosisProblem
from .prepare.runs import prepare_diagnosis_runs
from .summarise.constants import constants_used, data_set_warnings
from .summarise.localization import localize_residuals
from .summarise.long_time import long_time_gaps, mean_long_time_gap
from .summarise.result import Diagnosis, DiagnosisInternals
from .summarise.uncertainty import (CONFIDENCE, METHOD, PRESSURE_MODEL_ERROR, interval_from_error, jackknife_errors,
                                    with_model_error)
from .prepare.cavity_lag import derived_quantities
from .summarise.verdicts import ranked_effects

__all__ = ["DiagnoseConfig", "DiagnosisInternals", "Diagnosis", "diagnose", "diagnose_dataset", "load_for_diagnosis",
           "EXPLAINED_GAP", "MIN_RUNS", "check_enough_runs"]

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
    candidates : names of the candidate effects (default: all of docs/conventions.md section 5; the cavity's lag,
        ``cavity_lag``, only when named here)
    alpha : significance level of the one-sided sign-flip permutation test of the held-out improvement
    min_relative_improvement : practical significance, as a fraction of the current gap
    min_absolute_improvement : practical significance, as a fraction of the variance (beyond noise)
    max_frames_per_run : runs are thinned to at most this many frames for the fits (speed)
    max_vertical_gap : no cause is named when the vertical (calibration) equation stays unexplained beyond
        this fraction of its variance (the calibration is then distorted by something else)
    long_time : also compute the long-time (shape, Poincare, frequency) gaps
    long_time_duration : seconds of each run simulated for them [s]; None: the whole run
    drift : settings of the test for a pressure drifting within runs (:mod:`validation.diagnosis.calibrate.drift`);
        None: the pressure is taken as constant without testing
    discover : regress what remains after the candidates on the cubic library (:mod:`validation.diagnosis.discover.library_terms`)
    discovery_min_improvement : a discovered term's median held-out improvement, as a fraction of the variance
    check_orientation : test whether y points down (:mod:`validation.diagnosis.calibrate.orientation`); if so, warn
        (``data_warnings``, code ``y_inverted``) and diagnose the data with y -> -y
    """

    candidates: tuple[str, ...] = field(default_factory=default_candidates)
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

    def __post_init__(self) -> None:
        check_choices(self, "candidates", CANDIDATE_EFFECTS, what="effect(s)")
        check_fraction(self, "alpha")
        check_whole(self, "max_frames_per_run", minimum=10)
        check_positive(self, "long_time_duration", optional=True)
        self.thresholds  # validates the practical thresholds

    @property
    def thresholds(self) -> PracticalThresholds:
        """The practical-significance settings of the identification."""
        return PracticalThresholds(self.min_relative_improvement, self.min_absolute_improvement, self.max_vertical_gap)


def load_for_diagnosis(data_dir: str | Path, strict: bool = False, progress: bool = True,
                       load: "LoadConfig | None" = None) -> "Dataset":
    """Load ``data_dir`` as :func:`diagnose` reads it: the physics bounds of any levitated dimer, and with a meta.json
    also the Gor'kov estimate of the trap frequency at its nominal pressure
    (:func:`acousim.analytic.nominal_trap_frequency`); skipped files are warned about (``progress``) or logged at
    DEBUG level; runs whose hinge ended folded are left out as skipped files
    (:func:`~validation.diagnosis.identify.folded.leave_out_folded_runs`).  Load the data set once and pass the :class:`~cubedimer.dataset.Dataset` to the fit and the
    diagnosis, so that both see the same runs.  ``load``: the loading rules (default :class:`LoadConfig`'s; the
    report passes the fit's glitch masking and shortest run, ``--no-glitch-mask`` and ``--min-periods``), to which the
    trap-frequency check is added."""
    from acousim.analytic import nominal_trap_frequency
    from cubedimer.dataset import LoadConfig, load_dataset

    skip = logger.warning if progress else logger.debug
    config = replace(load if load is not None else LoadConfig(), trap_frequency=nominal_trap_frequency)
    loaded = load_dataset(data_dir, strict=strict, config=config, report=lambda m: skip("skipping %s", m))
    dataset = leave_out_folded_runs(loaded)
    for s in dataset.skipped[len(loaded.skipped):]:
        skip("skipping %s", s)
    return dataset


def diagnose_dataset(data_dir: str | Path, config: DiagnoseConfig = DiagnoseConfig(), strict: bool = False,
                     progress: bool = True, spec: ModelSpec = ModelSpec()) -> Diagnosis:
    """Load the data set ``data_dir`` (:func:`load_for_diagnosis`) and diagnose it (:func:`diagnose`)."""
    dataset = load_for_diagnosis(data_dir, strict=strict, progress=progress)
    return diagnose(dataset, config, progress=progress, spec=spec)


def diagnose(dataset: "Dataset", config: DiagnoseConfig = DiagnoseConfig(), progress: bool = True,
             spec: ModelSpec = ModelSpec()) -> Diagnosis:
    """Diagnose a loaded data set.

    Parameters
    ----------
    dataset : the data set (:func:`load_for_diagnosis` loads it with the checks a diagnosis needs)
    config : DiagnoseConfig
    progress : log the steps at INFO level (else DEBUG)
    spec : the simulation model and its own options (:class:`acousim.models.ModelSpec`; default: the Gor'kov
        model); every model is calibrated the same way (pressure amplitude and height origin), and a model's own
        parameters that the data may determine (the full-wave hinge gap) are profiled unless the spec sets them
        (:mod:`validation.diagnosis.calibrate.model_parameters`)

    Returns
    -------
    Diagnosis
        The diagnosis (``to_json()``: diagnosis.json, docs/formats.md), with :class:`DiagnosisInternals` for the
        figures in ``internals``.

    Runs with one BLAS thread (:func:`cubedimer.executor.single_blas_thread`): the same numbers wherever it
    runs (here, in an executor task, on a dask worker), and faster for its many small factorisations.
    """
    from cubedimer.executor import single_blas_thread

    with single_blas_thread():
        return _diagnose(dataset, config, progress, spec)


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
    skipped = f" ({n_skipped} file(s) skipped, each with its reason above)" if n_skipped else ""
    raise DatasetError(
        f"{data_dir}: {n_runs} usable run{'' if n_runs == 1 else 's'}{skipped}; the diagnosis needs at least {MIN_RUNS}, "
        f"because it scores every fit on runs held out of it, and at least {runs_needed(alpha)} to name an effect at "
        f"alpha {alpha:g} (the held-out sign-flip test's smallest p with n runs is 2^-n); record more runs")


@dataclass(frozen=True, eq=False)
class _Calibrated:
    """The calibration step's outcome: the problem at the calibrated model, with what it decided."""

    problem: DiagnosisProblem
    conditions: object  #: the experiment conditions with the model's calibrated parameters
    parameters: dict  #: ParameterCalibration by field name
    data_warnings: list
    drift: object  #: DriftTest or None


@dataclass(frozen=True, eq=False)
class _Identified:
    """The identification step's outcome: the greedy rounds, the backward check and the fitted model."""

    ident: object  #: Identification
    elim: object  #: the backward check
    pairs: list
    identified: list[str]
    base: GapFit
    final: GapFit
    per_before: np.ndarray  #: the calibrated simulation's gap per run
    noise_floor: float  #: the mean noise floor


def _diagnose(dataset, config: DiagnoseConfig, progress: bool, spec: ModelSpec) -> Diagnosis:
    """The diagnosis as its named steps: calibrate, identify, discover, the joint model, summarise."""
    from ..simulation import conditions_from_meta

    log = logger.info if progress else logger.debug
    dataset = leave_out_folded_runs(dataset)  # a no-op on a data set that load_for_diagnosis loaded
    conditions = conditions_from_meta(dataset.meta, spec)
    # refuses a model that does not fit the experiment first (a dimer outside the full-wave family): a parameter to
    # be calibrated starts at the value the model takes by default
    start = {n: d for n, (_, _, d) in spec.type.calibration_ranges(conditions).items() if getattr(conditions, n) is None}
    model = spec.static(replace(conditions, **start))
    check_enough_runs(dataset.path, len(dataset.runs), len(dataset.skipped_files()), config.alpha)
    cal = _calibrate(dataset, conditions, model, spec, config, log)
    found = _identify(cal.problem, config, progress, log)
    discovery, replaced, identified, final = _discover(cal.problem, found, config, log)
    return _summarise(dataset, cal, found, discovery, replaced, identified, final, spec, config, log)


def _calibrate(dataset, conditions, model, spec: ModelSpec, config: DiagnoseConfig, log) -> _Calibrated:
    """The calibrated problem: from the starting ``model`` (the spec's at its default parameters), y's orientation,
    the model's own parameters the data may determine, and a pressure drift within runs (followed by the
    simulation)."""
    mtype = spec.type
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
        first = detect_pressure_drift(problem, config.drift)
        first_drift = first.drift if first.detected else None
    conditions, parameters = calibrate_model_parameters(spec, conditions, problem.recorded_runs,
                                                        config.max_frames_per_run, log, drift=first_drift)
    if parameters:
        model = spec.static(conditions)
        problem = DiagnosisProblem.from_recorded(model.interpolated(), problem.recorded_runs,
                                                 config.max_frames_per_run)
    log("%d runs; calibrating pressure and height origin (first: a drift of the pressure within runs?)",
        len(problem.runs))
    drift = detect_pressure_drift(problem, config.drift) if config.drift is not None else None
    if drift is not None and drift.detected:
        log("pressure drift detected (relative amplitude %.3g, time scale %.2g s, p = %.2g): the simulation "
            "follows it", drift.relative_amplitude, drift.time_scale_s, drift.p_value)
        problem = problem.with_drift(drift.drift)
    return _Calibrated(problem, conditions, parameters, data_warnings, drift)


def _identify(problem: DiagnosisProblem, config: DiagnoseConfig, progress: bool, log) -> _Identified:
    """The candidate effects that improve held-out runs (greedy rounds), each still needed given all the others
    (the backward check; pairs that only work as either one are one verdict naming both), and the fitted model."""
    n = len(problem.runs)
    p_floor = smallest_sign_flip_pvalue(n)
    if p_floor > config.alpha:  # logged in quiet mode too: it changes what "identified: none" means
        logger.warning("with %d runs no effect can be identified at --alpha %g (smallest attainable p %.3g of the "
                       "held-out sign-flip test, 2^-%d); record at least %d runs", n, config.alpha, p_floor,
                       n, runs_needed(config.alpha))
    base = fit_gap_model(problem, [])
    per_before, floor = fit_gaps(problem.runs, base), float(np.mean(noise_floors(problem.runs, base)))
    log("gap before = %.3g (noise floor %.3g); identifying effects", scalar_gap(per_before), floor)
    held_out_cache: dict = {}
    ident = identify_effects(problem, config.candidates, alpha=config.alpha, thresholds=config.thresholds,
                             progress=progress, cache=held_out_cache)
    elim = backward_check(problem, ident.identified, alpha=config.alpha, thresholds=config.thresholds, log=log,
                          cache=held_out_cache)
    identified = list(elim.model_effects)  # what the model fits; the named ones are decided in the summary
    return _Identified(ident, elim, list(elim.indistinguishable), identified, base, fit_gap_model(problem, identified),
                       per_before, floor)


def _discover(problem: DiagnosisProblem, found: _Identified, config: DiagnoseConfig, log):
    """The library terms that carry what the identified effects leave, and the identified candidates judged against
    them: ``(discovery, replaced, identified, final)``, where ``replaced`` holds the p-value of every candidate the
    discovered terms replaced."""
    identified, final = found.identified, found.final
    discovery, replaced = Discovery(), {}
    if not config.discover:
        return discovery, replaced, identified, final
    log("regressing the remaining residual on the library (held-out runs)")
    discover = partial(discover_terms, problem, alpha=config.alpha,
                       min_absolute_improvement=config.discovery_min_improvement,
                       min_relative_improvement=config.min_relative_improvement)
    discovery = discover(final)
    # the candidates are judged against the terms found on top of them, and against the dissipative terms
    # found without them: a candidate damping can absorb the energy loss of a dissipation it does not
    # describe, leaving nothing to discover on top of it
    for rivals in (discovery, _dissipation_rivals(problem, found.base, identified, discover) if identified
                   else Discovery()):
        if rivals.empty or not identified:
            continue
        kept, pvals = judge_candidates(problem, identified, rivals, alpha=config.alpha, group=AIR_DAMPINGS)
        if kept != identified:
            replaced.update({c: pvals[c] for c in identified if c not in kept})
            identified = kept
            final = fit_gap_model(problem, identified)
            discovery = discover(final)
    return discovery, replaced, identified, final


def _summarise(dataset, cal: _Calibrated, found: _Identified, discovery: Discovery, replaced: dict,
               identified: list[str], final: GapFit, spec: ModelSpec, config: DiagnoseConfig, log) -> Diagnosis:
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
    effects = ranked_effects(problem, config.candidates, found.ident, found.elim, identified, named, in_pair,
                             replaced, joint_params, final, gap_before, errors.effects, errors.derived)
    # an effect whose addition does not shrink the gap is not named (its verdict says why, with both gaps)
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
                      config: DiagnoseConfig, log) -> dict:
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


def _calibration_record(problem: DiagnosisProblem, final: GapFit, cal: _Calibrated, spec: ModelSpec, errors) -> dict:
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
    # the pressure's interval also holds the calibration's systematic error (PRESSURE_MODEL_ERROR)
    stat = errors.calibration["pressure_amplitude_pa"]
    uncertainty["pressure_amplitude_pa"] = {
        **with_model_error(stat, PRESSURE_MODEL_ERROR * abs(stat.value)).to_dict(),
        "statistical_std_error": stat.std_error, "model_std_error": PRESSURE_MODEL_ERROR * abs(stat.value)}
    for name, pc in cal.parameters.items():  # the model's own parameters: their profile's jackknife error
        if pc is not None and getattr(pc, "calibrated", False):
            uncertainty[name] = interval_from_error(pc.value, pc.std_error, errors.runs - 1).to_dict()
        elif pc is not None:
            uncertainty[name] = {"value": pc.value, "std_error": None, "interval_95": None, "dof": None,
                                 "determined": False, "reason": pc.note}
    calibration["uncertainty"] = uncertainty
    return calibration
