"""Blind cases of the candidate effects: twin data sets with hidden candidate effects.

Each case draws, from its own seed: the number of effects (0, 1 or 2, probabilities
``N_EFFECT_PROBABILITIES``), which effects, their strengths (log-uniform between the weak and strong
ends of ``STRENGTHS``, random signs where the physics allows both) and a pressure error (uniform
within +-``pressure_error``).  A strength that can close the dimer (the mirror asymmetry's constant torque) is drawn
as a fraction of what the drawn dimer's hinge holds at the case's pressure (``HINGE_FRACTIONS``), so that the hinge
stays open.  With ``BlindConfig(resonator=True)`` (the default) the levitator's resonator is one of the effects a case
can draw (Q and detuning within ``RESONATOR_STRENGTHS``; the twin's ``transducer_q`` and ``cavity_detuning``), scored
as the ``cavity_lag`` candidate on its derived Q and detuning, and the diagnosis tries ``cavity_lag``.  The twin
writes the data set; ``truth.json`` is moved out of the data
directory before :func:`validation.diagnosis.diagnose_dataset` runs, so the diagnosis never sees it.

By default the twin runs with its default physics, the air's computed damping (``BlindConfig(air_damping=True)``),
as every real recording has it: the true candidate set is then the drawn effects plus ``linear_damping``, the
candidate that stands for the air's drag, at the air's rates (plus a drawn linear damping's; :func:`candidate_truth`).
The inviscid study (``BlindConfig(air_damping=False)``, ``python -m validation blind --inviscid``) runs without it:
the drawn effects are the whole truth, a case of no effect is the inviscid dimer, and a drawn ``linear_damping`` is
the only damping (the study documented in docs/diagnosis.md's blind check, docs/blind/*).
"""
from __future__ import annotations

from typing import TYPE_CHECKING

import json
import logging
import os
import shutil
from pathlib import Path

import numpy as np

from cubedimer.atomic import write_json
from cubedimer.meta import META_DEFAULTS

from .config import BlindConfig

if TYPE_CHECKING:
    from ..diagnosis import Diagnosis

__all__ = ["STRENGTHS", "N_EFFECT_PROBABILITIES", "draw_parameters", "draw_from", "draw_case", "generate_twin_case",
           "candidate_truth", "hide_truth", "diagnose_blind",
           "run_case", "score_case", "summarize", "candidates_table", "confusion_figure"]

logger = logging.getLogger(__name__)

#: The pressure amplitude a blind case's meta.json states, and its truth's centre [Pa] (docs/conventions.md).
NOMINAL_PRESSURE_PA = META_DEFAULTS["pressure_amplitude_pa"]

#: Weak and strong ends of each parameter's range (SI); "signed" parameters get a random sign.  The mirror asymmetry's
#: entries are its range on the default dimer at the nominal 3 kPa, for reference: its draws are fractions of the drawn
#: dimer's hinge (:data:`HINGE_FRACTIONS`).
STRENGTHS: dict[str, dict[str, tuple[float, float, bool]]] = {
    "linear_damping": {"gamma_y": (0.2, 3.0, False), "gamma_theta": (0.2, 3.0, False)},
    "quadratic_drag": {"c_y": (20.0, 300.0, False), "c_theta": (0.02, 0.5, False)},
    "pair_scattering": {"kappa": (2.0e3, 3.0e4, False)},
    "mirror_asymmetry": {"beta0": (3.9, 13.1, True), "beta1": (1.0e4, 7.9e4, True)},
    "velocity_coupling": {"c5": (5.0e2, 1.0e4, True), "c6": (1.0e5, 2.0e6, True)},
}
#: Strengths drawn relative to what the drawn dimer's hinge can hold (:func:`hinge_holding_acceleration`, H [1/s^2]
#: at the case's true pressure): a constant torque beta0 beyond H closes the dimer (its hinge folds), so beta0 is
#: ``f H`` with f log-uniform in the range below, and beta1 is ``f H / (100 um)`` (the torque beta1 y at a drop's
#: 100 um of y); the two together stay below 0.8 H, so the hinge is open.  (lo, hi, signed) as in STRENGTHS.
HINGE_FRACTIONS: dict[str, dict[str, tuple[float, float, bool]]] = {
    "mirror_asymmetry": {"beta0": (0.15, 0.5, True), "beta1": (0.04, 0.3, True)},
}
#: The y over which a hinge-relative strength that multiplies y is measured [m] (beta1 y).
HINGE_FRACTION_Y = 100e-6
#: The levitator as a resonator (the twin's ``transducer_q`` and ``cavity_detuning``), scored as ``cavity_lag`` with
#: its derived mode: Q and the drive's detuning above the resonance in half-widths, log-uniform.  Only the damping
#: side (x > 0): on the driving side a cavity that drives the motion by more than the air damps it makes every run
#: grow out of the trap.
RESONATOR_STRENGTHS: dict[str, tuple[float, float, bool]] = {
    "quality_factor": (150.0, 400.0, False), "detuning_half_widths": (0.5, 3.0, False)}
#: The drawn name of the resonator (the diagnosis's candidate for it).
RESONATOR = "cavity_lag"
N_EFFECT_PROBABILITIES = (0.2, 0.4, 0.4)


def _log_uniform(rng: np.random.Generator, lo: float, hi: float, signed: bool) -> float:
    v = float(np.exp(rng.uniform(np.log(lo), np.log(hi))))
    return -v if signed and rng.random() < 0.5 else v


def draw_parameters(rng: np.random.Generator, name: str) -> dict[str, float]:
    """Parameters of effect ``name``: log-uniform within ``STRENGTHS[name]``, a random sign where allowed; for an
    effect of :data:`HINGE_FRACTIONS`, the fractions of the hinge's hold (turned into strengths by
    :func:`hinge_strengths` once the pressure is known); for the resonator, its Q and detuning."""
    if name == RESONATOR:
        return {p: _log_uniform(rng, *r) for p, r in RESONATOR_STRENGTHS.items()}
    ranges = HINGE_FRACTIONS.get(name, STRENGTHS[name])
    return {p: _log_uniform(rng, *r) for p, r in ranges.items()}


def hinge_holding_acceleration(pressure_pa: float) -> float:
    """H [1/s^2]: the largest restoring acceleration of the twin's default dimer's hinge, ``max -Q_theta / I`` over
    0 < theta < 1 at its equilibrium height, at the pressure amplitude ``pressure_pa`` [Pa] (26.2 1/s^2 at
    theta = 0.40 at 3 kPa, 35.4 at 3.3 kPa: the equilibrium moves with the pressure, so H is not p^2 alone).
    A constant hinge acceleration beyond H closes the dimer."""
    theta = np.linspace(0.005, 0.995, 199)
    sur = _twin_surrogate()
    if pressure_pa != sur.pressure_amplitude_pa:
        sur = sur.with_pressure(float(pressure_pa))
    _, q_t = sur.generalized_forces(theta, np.zeros_like(theta))
    return float(np.max(-q_t / sur.hinge_inertia(theta)))


def _twin_surrogate():
    """The twin's default dynamic force model (cached per process)."""
    global _SURROGATE
    if _SURROGATE is None:
        from acousim.twin import TwinConfig

        twin = TwinConfig()
        _SURROGATE = twin.model_spec.dynamic(twin.conditions)
    return _SURROGATE


_SURROGATE = None


def hinge_strengths(effects: dict, pressure_pa: float) -> dict:
    """``effects`` with the fractions of :data:`HINGE_FRACTIONS` turned into strengths at ``pressure_pa`` [Pa]
    (:func:`hinge_holding_acceleration`); the others unchanged."""
    if not set(effects) & set(HINGE_FRACTIONS):
        return effects
    hold = hinge_holding_acceleration(pressure_pa)
    out = {}
    for name, params in effects.items():
        if name in HINGE_FRACTIONS:
            params = {p: v * hold / (HINGE_FRACTION_Y if p == "beta1" else 1.0) for p, v in params.items()}
        out[name] = params
    return out


def draw_from(rng: np.random.Generator, index: int, pressure_error: float = 0.10, resonator: bool = False) -> dict:
    """A hidden candidate case drawn from ``rng`` (see :func:`draw_case`); ``resonator``: the levitator's resonator
    (:data:`RESONATOR`) is one of the effects drawn.  Strengths of :data:`HINGE_FRACTIONS` are set at the case's
    true pressure; the case keeps their fractions under ``hinge_fractions``."""
    n = int(rng.choice(3, p=N_EFFECT_PROBABILITIES))
    pool = list(STRENGTHS) + ([RESONATOR] if resonator else [])
    names = [str(x) for x in rng.choice(pool, size=n, replace=False)] if n else []
    drawn = {name: draw_parameters(rng, name) for name in sorted(names, key=pool.index)}
    error = float(rng.uniform(-pressure_error, pressure_error))
    case = {"index": index, "effects": hinge_strengths(drawn, NOMINAL_PRESSURE_PA * (1 + error)),
            "pressure_error": error, "twin_seed": int(rng.integers(2**31))}
    fractions = {k: v for k, v in drawn.items() if k in HINGE_FRACTIONS}
    if fractions:
        case["hinge_fractions"] = fractions
    return case


def draw_case(seed: int, index: int, pressure_error: float = 0.10, resonator: bool = False) -> dict:
    """The hidden truth of case ``index``: effects with parameters, pressure error, twin seed."""
    return draw_from(np.random.default_rng(np.random.SeedSequence([seed, index])), index, pressure_error, resonator)


def generate_twin_case(case: dict, config: BlindConfig, data: Path, air_damping: bool = False) -> tuple[str | None, int]:
    """Write the twin data set of a drawn case into ``data`` with its truth.json; (error or None, redraws).

    A drawn start can drive a run out of the trap (the twin refuses such runs), and a drawn effect can fold the hinge
    (a drop that throws it over the top of its restoring acceleration, 26 1/s^2 on the default dimer at 3 kPa, with a
    constant torque helping; the torque itself is drawn below it, :data:`HINGE_FRACTIONS`): the diagnosis leaves runs
    that ended folded out (:mod:`validation.diagnosis.identify.folded`), so a data set with
    fewer unfolded runs than an effect needs to be named at the diagnosis's alpha is no case to score.  Either way the
    twin's seed is redrawn (same effects and pressure) up to 5 times; a case that still folds is reported as not
    generated, with the reason.  ``air_damping``: the twin adds the air's computed drag (its default physics); off,
    the drawn effects are the whole truth."""
    from acousim.dynamics.effects import EffectSet
    from acousim.models import ExperimentConditions
    from acousim.twin import TwinConfig, TwinError, simulate_dataset

    if data.exists():
        shutil.rmtree(data)
    generation_error, retries = None, 0
    for retries in range(5):
        # with the air's damping, truth.json lists it among the effects (module docstring)
        effects = {k: v for k, v in case["effects"].items() if k != RESONATOR}
        experiment = ExperimentConditions(pressure_amplitude_pa=NOMINAL_PRESSURE_PA * (1 + case["pressure_error"]))
        twin = TwinConfig(runs=config.runs, duration=config.duration, seed=case["twin_seed"] + retries,
                          pressure_error=0.0, effects=EffectSet.from_dict(effects), experiment=experiment,
                          air_damping=air_damping, **_resonator_settings(case["effects"].get(RESONATOR)))
        try:
            simulate_dataset(twin, data, progress=False, force=True)
        except TwinError as exc:
            generation_error = str(exc)
            continue
        generation_error = _too_many_folded(data, config.runs)
        if generation_error is None:
            return None, retries
    return generation_error, retries


def _resonator_settings(mode: dict | None) -> dict:
    """The twin's settings of a drawn resonator (none without one)."""
    if not mode:
        return {}
    return {"transducer_q": float(mode["quality_factor"]), "cavity_detuning": float(mode["detuning_half_widths"])}


def _too_many_folded(data: Path, runs: int) -> str | None:
    """Why the twin data set in ``data`` cannot be scored: fewer runs than an effect needs at the diagnosis's alpha
    (:func:`validation.diagnosis.identify.statistics.runs_needed`) are usable once those that ended folded are left out (a
    run the twin stopped at the fold may also be too short to load); None if enough are."""
    from cubedimer.dataset import load_dataset
    from cubedimer.errors import DatasetError

    from ..diagnosis.identify.folded import folded_angle
    from ..diagnosis.identify.statistics import runs_needed
    from ..diagnosis.steps import DiagnoseConfig

    try:
        usable = sum(folded_angle(run) is None for run in load_dataset(data, report=lambda message: None).runs)
    except DatasetError:  # no run could be loaded at all (every one stopped at a fold within a few periods)
        usable = 0
    needed = min(runs, runs_needed(DiagnoseConfig().alpha))
    if usable >= needed:
        return None
    return (f"the hinge folded (theta reached or stayed near +-1) in {runs - usable} of {runs} runs, leaving fewer "
            f"than the {needed} unfolded runs an effect needs to be named")


def candidate_truth(effects: dict, resonator: dict | None = None) -> dict:
    """The true effects as the candidates describe them: the twin's ``air_damping`` (its computed drag,
    ``-gamma_y ydot`` and ``-gamma_theta S(theta) thetadot`` with S(0) = 1) is ``linear_damping`` at its rates, added
    to a drawn linear damping's; the twin's ``resonator`` (truth.json) is ``cavity_lag`` with its Q and detuning."""
    from ..diagnosis.prepare.cavity_lag import quasi_static_response

    out = {k: dict(v) for k, v in effects.items() if k != "air_damping"}
    if resonator:  # the twin's resonator (truth.json ``resonator``), as the candidate names its mode
        out[RESONATOR] = {p: float(resonator[p]) for p in RESONATOR_STRENGTHS}
        # the combination of Q and x its quasi-static gain alone gives (the diagnosis's derived quantity)
        out[RESONATOR]["quasi_static_response"] = quasi_static_response(*(out[RESONATOR][p] for p in RESONATOR_STRENGTHS))
    air = effects.get("air_damping")
    if air:
        lin = out.setdefault("linear_damping", {"gamma_y": 0.0, "gamma_theta": 0.0})
        for p in ("gamma_y", "gamma_theta"):
            lin[p] = lin.get(p, 0.0) + float(air[p])
    return out


def hide_truth(data: Path, truth_path: Path) -> dict:
    """Move truth.json out of ``data`` and set meta.json to the nominal 3 kPa the experimenter believes in;
    returns the truth."""
    os.replace(data / "truth.json", truth_path)
    meta = json.loads((data / "meta.json").read_text())
    meta["pressure_amplitude_pa"] = NOMINAL_PRESSURE_PA
    write_json(data / "meta.json", meta)
    return json.loads(truth_path.read_text())


def diagnose_blind(data: Path, config: BlindConfig) -> tuple["Diagnosis | None", str | None]:
    """The diagnosis of ``data`` (long-time errors as configured), or (None, error) if it failed."""
    from ..diagnosis import DiagnoseConfig, diagnose_dataset
    from ..diagnosis.prepare.candidate_effects import default_candidates

    candidates = tuple(dict.fromkeys(default_candidates() + ((RESONATOR,) if config.resonator else ())))
    try:
        diag = diagnose_dataset(data, DiagnoseConfig(long_time=config.long_time, candidates=candidates,
                                                       trajectory_test=config.trajectory_test), progress=False)
        return diag, None
    except Exception as exc:  # a failed diagnosis is a result of the study, not a crash of it
        return None, f"{type(exc).__name__}: {exc}"


def not_generated(case: dict, error: str, retries: int) -> dict:
    """The result of a case the twin could not generate (left out of the scores)."""
    return {"index": case["index"], "true_effects": case["effects"], "true_set": sorted(case["effects"]),
            "identified": [], "exact": False, "n_true": len(case["effects"]), "parameter_relative_error": {},
            "gap_before": None, "gap_after": None, "shrink": None, "pressure_true_pa": None,
            "pressure_calibrated_pa": None, "error": f"generation: {error}", "twin_redraws": retries,
            "scored": False}


def run_case(case: dict, config: BlindConfig, out_dir: Path) -> dict:
    """Generate, diagnose blind, score one case; writes ``result.json`` in ``out_dir``."""
    data = out_dir / "data"
    generation_error, retries = generate_twin_case(case, config, data, air_damping=config.air_damping)
    if generation_error is not None:
        result = not_generated(case, generation_error, retries)
        write_json(out_dir / "result.json", result)
        return result
    truth = hide_truth(data, out_dir / "truth.json")  # hidden from the diagnosis
    diag, error = diagnose_blind(data, config)
    # scored against what the twin simulated (with the air's damping as the linear damping it is)
    true_effects = candidate_truth(truth.get("effects", case["effects"]), truth.get("resonator"))
    result = score_case({**case, "effects": true_effects}, truth, diag, error)
    result["air_damping"] = bool(config.air_damping)
    result["twin_redraws"] = retries
    write_json(out_dir / "result.json", result)
    shutil.rmtree(data, ignore_errors=True)  # keep the study small on disk; truth and result stay
    return result


def score_case(case: dict, truth: dict, diag: "Diagnosis | None", error: str | None) -> dict:
    """Score one case: the diagnosis ``diag`` (None if it failed with ``error``) against the hidden truth."""
    true_set = sorted(case["effects"])
    found = [] if diag is None else list(diag.identified)
    params_err, covers, intervals = {}, {}, {}
    if diag is not None:
        fitted = {e.name: e.params for e in diag.effects}
        for name in set(true_set) & set(found):
            values = fitted[name]
            if name == RESONATOR:  # scored on its mode (the derived Q and detuning; nan where no mode has the gains)
                values = {p: iv.value for p, iv in (diag.effect(name).derived or {}).items()}
            errs = {p: abs(values.get(p, float("nan")) - v) / abs(v)
                    for p, v in case["effects"][name].items() if v != 0}
            params_err[name] = errs
            covers[name] = _interval_covers(diag.effect(name), case["effects"][name])
            intervals[name] = _interval_records(diag.effect(name), case["effects"][name])
    pressure = None if diag is None else diag.calibration_estimate("pressure_amplitude_pa")
    return {
        "index": case["index"],
        "true_effects": case["effects"],
        "true_set": true_set,
        "identified": found,
        "exact": sorted(found) == true_set,
        "n_true": len(true_set),
        "parameter_relative_error": params_err,
        "gap_before": None if diag is None else diag.gap_before,
        "gap_after": None if diag is None else diag.gap_after,
        "shrink": None if diag is None else 1 - diag.gap_after / diag.gap_before,
        "pressure_true_pa": truth["pressure_amplitude_pa"],
        "pressure_calibrated_pa": None if diag is None else diag.calibration["pressure_amplitude_pa"],
        # whether each named true parameter's 95 % interval holds the truth (None: no finite interval)
        "interval_covers": covers,
        "pressure_interval_covers": None if pressure is None or not pressure.determined else bool(
            pressure.covers(truth["pressure_amplitude_pa"])),
        # each named true parameter's estimate, standard error, degrees of freedom and truth (the z-scores and
        # interval widths of docs/diagnosis.md's coverage tables are computed from these)
        "intervals": intervals,
        "pressure_interval": None if pressure is None else _interval_record(pressure, truth["pressure_amplitude_pa"]),
        # every effect of these sets is a candidate: a discovered library term is a false alarm of the discovery
        # effects named alone that the truth does not hold, and pairs named as indistinguishable
        "false_effects": sorted(set(found) - set(true_set)),
        # the greedy rounds' set before the backward check and the judgement against discovered terms
        "false_effects_greedy": None if diag is None else sorted(
            set(diag.greedy_identified) - set(true_set)),
        "indistinguishable": [] if diag is None else [p["effects"] for p in diag.indistinguishable or []],
        "discovered_terms": None if diag is None else {
            eq: [t["term"] for t in terms]
            for eq, terms in diag.remaining_gap.get("discovered_terms", {}).items()},
        "error": error,
        "scored": True,
    }


def _interval_covers(verdict, truth: dict) -> dict:
    """Per true parameter of a named effect: whether its 95 % interval holds the truth (None: not determined)."""
    out = {}
    for p, v in truth.items():
        iv = (verdict.derived or {}).get(p) if p not in verdict.params else verdict.estimate(p)
        if iv is None:
            out[p] = None
            continue
        out[p] = bool(iv.covers(v)) if iv.determined else None
    return out


def _interval_record(iv, truth: float) -> dict:
    """``{"value", "std_error", "dof", "truth", "statistical_std_error"}`` of one interval (std_error None: not
    determined; statistical_std_error: the jackknife's part of std_error)."""
    return {"value": float(iv.value), "std_error": iv.std_error, "dof": iv.dof, "truth": float(truth),
            "statistical_std_error": iv.std_error if iv.model_std_error is None else iv.statistical_std_error}


def _interval_records(verdict, truth: dict) -> dict:
    """Per true parameter of a named effect: :func:`_interval_record` (absent where the effect gives no interval)."""
    out = {}
    for p, v in truth.items():
        iv = (verdict.derived or {}).get(p) if p not in verdict.params else verdict.estimate(p)
        if iv is not None:
            out[p] = _interval_record(iv, v)
    return out


def interval_coverage(results: list[dict]) -> dict:
    """The 95 % intervals' coverage over scored cases: per effect (its parameters pooled) and the pressure, each as
    ``{"covered", "determined", "not_determined", "coverage", "upper_95"/"lower_95"}`` (Clopper-Pearson bounds of
    the coverage)."""
    from scipy import stats

    def record(flags: list) -> dict:
        det = [f for f in flags if f is not None]
        k, n = sum(det), len(det)
        return {"covered": k, "determined": n, "not_determined": len(flags) - n,
                "coverage": k / n if n else None,
                "lower_95": float(stats.beta.ppf(0.025, k, n - k + 1)) if 0 < k else (0.0 if n else None),
                "upper_95": float(stats.beta.ppf(0.975, k + 1, n - k)) if k < n else (1.0 if n else None)}

    per: dict[str, list] = {n: [] for n in [*STRENGTHS, RESONATOR]}
    widths: dict[str, list] = {}
    for r in results:
        for name, flags in (r.get("interval_covers") or {}).items():
            per.setdefault(name, []).extend(flags.values())
        for name, ivs in (r.get("intervals") or {}).items():
            widths.setdefault(name, []).extend(_relative_half_width(d) for d in ivs.values())
        if r.get("pressure_interval"):
            widths.setdefault("pressure_amplitude_pa", []).append(_relative_half_width(r["pressure_interval"]))
    out = {n: record(f) for n, f in per.items() if f}
    out["pressure_amplitude_pa"] = record([r.get("pressure_interval_covers") for r in results
                                           if "pressure_interval_covers" in r])
    for n, c in out.items():  # the median 95 % half-width relative to the estimate (None: no interval recorded)
        w = [x for x in widths.get(n, []) if x is not None]
        c["median_relative_half_width"] = float(np.median(w)) if w else None
    return out


def _relative_half_width(record: dict) -> float | None:
    """A recorded interval's 95 % half-width over |estimate| (None when not determined or at a zero estimate)."""
    from scipy import stats

    if record.get("std_error") is None or not record.get("dof") or record["value"] == 0:
        return None
    return float(stats.t.ppf(0.975, record["dof"]) * record["std_error"] / abs(record["value"]))


def _upper_95(k: int, n: int) -> float:
    """The Clopper-Pearson 95 % upper bound of a rate of k in n (the two-sided interval's upper end)."""
    from scipy import stats

    return 1.0 if k >= n else float(stats.beta.ppf(0.975, k + 1, n - k))


def _finite(x) -> bool:
    """Whether a relative error is a finite number: a parameter not determined has nan in a study's memory and null
    (None) in a result.json read back when a study resumes."""
    return x is not None and bool(np.isfinite(x))


def _median_per_parameter(records: list[dict]) -> dict | None:
    """Per parameter, the median of the relative errors in ``records`` (nan and None entries left out)."""
    keys = sorted({p for r in records for p in r})
    out = {}
    for p in keys:
        v = [r[p] for r in records if _finite(r.get(p))]
        out[p] = float(np.median(v)) if v else None
    return out or None


def summarize(results: list[dict]) -> dict:
    """Identification rates, per-effect precision/recall, parameter errors, shrink, false positives."""
    names = list(STRENGTHS) + [RESONATOR]
    out: dict = {"n_cases": len(results), "failed": sum(r["error"] is not None for r in results),
                 "not_generated": sum(not r.get("scored", True) for r in results)}
    results = [r for r in results if r.get("scored", True)]
    for k in (0, 1, 2, 3):  # three: two drawn effects beside the air's damping (linear_damping)
        sub = [r for r in results if r["n_true"] == k]
        out[f"exact_rate_{k}_effects"] = float(np.mean([r["exact"] for r in sub])) if sub else None
        out[f"n_{k}_effects"] = len(sub)
    false_sets = [bool(set(r["identified"]) - set(r["true_set"])) for r in results]
    out["false_effect_rate"] = float(np.mean(false_sets)) if results else None
    out["false_effect_sets"] = int(sum(false_sets))
    out["false_effect_rate_upper_95"] = _upper_95(sum(false_sets), len(false_sets)) if results else None
    greedy = [bool(r["false_effects_greedy"]) for r in results if r.get("false_effects_greedy") is not None]
    out["false_effect_rate_greedy_rounds_alone"] = float(np.mean(greedy)) if greedy else None
    out["cases_with_indistinguishable_pairs"] = int(sum(bool(r.get("indistinguishable")) for r in results))
    within = [_finite(e) and e <= 0.05 for r in results if len(r["true_set"]) == 1 and r["exact"]
              for errs in r["parameter_relative_error"].values() for e in errs.values()]
    out["single_effect_parameters_within_5pct"] = float(np.mean(within)) if within else None
    none_sets = [r for r in results if r["n_true"] == 0]
    out["false_positive_sets_on_no_effect"] = int(sum(bool(r["identified"]) for r in none_sets))
    out["sets_with_discovered_terms"] = int(sum(any((r.get("discovered_terms") or {}).values()) for r in results))
    per = {}
    for n in names:
        tp = sum(n in r["identified"] and n in r["true_set"] for r in results)
        fp = sum(n in r["identified"] and n not in r["true_set"] for r in results)
        fn = sum(n not in r["identified"] and n in r["true_set"] for r in results)
        errs = [max(v) for r in results if n in r["parameter_relative_error"]
                for v in [[x for x in r["parameter_relative_error"][n].values() if _finite(x)]] if v]
        per[n] = {"tp": tp, "fp": fp, "fn": fn,
                  "precision": tp / (tp + fp) if tp + fp else None, "recall": tp / (tp + fn) if tp + fn else None,
                  "median_max_parameter_error": float(np.median(errs)) if errs else None,
                  "median_parameter_error": _median_per_parameter(
                      [r["parameter_relative_error"][n] for r in results if n in r["parameter_relative_error"]]),
                  "fraction_parameters_within_25pct": float(np.mean([e <= 0.25 for e in errs])) if errs else None}
    out["per_effect"] = per
    shr = [r["shrink"] for r in results if r["n_true"] > 0 and r["shrink"] is not None]
    out["median_shrink_with_effect"] = float(np.median(shr)) if shr else None
    pe = [abs(r["pressure_calibrated_pa"] / r["pressure_true_pa"] - 1) for r in results if r["pressure_calibrated_pa"]]
    out["median_pressure_error"] = float(np.median(pe)) if pe else None
    out["interval_coverage"] = interval_coverage(results)
    return out


def candidates_table(summary: dict) -> list[str]:
    """The candidate cases' summary as Markdown lines (a table of rates and one per effect), beside the targets."""
    def pct(v):
        return "-" if v is None else f"{100 * v:.0f} %"

    lines = [f"## Candidate effects ({summary['n_cases']} cases)", "", "| quantity | value | target |", "|---|---|---|",
             f"| exact identification, no effect ({summary['n_0_effects']} sets) | {pct(summary['exact_rate_0_effects'])} | no effect named |",
             f"| exact identification, one effect ({summary['n_1_effects']} sets) | {pct(summary['exact_rate_1_effects'])} | >= 90 % |",
             f"| exact identification, two effects ({summary['n_2_effects']} sets) | {pct(summary['exact_rate_2_effects'])} | >= 80 % |",
             *([f"| exact identification, three effects ({summary['n_3_effects']} sets: two drawn beside the air's damping) "
                f"| {pct(summary['exact_rate_3_effects'])} | |"] if summary.get("n_3_effects") else []),
             f"| no-effect sets with an effect named | {summary['false_positive_sets_on_no_effect']} | 0 |",
             f"| sets with a false effect named (alone) | {pct(summary.get('false_effect_rate'))} "
             f"({summary.get('false_effect_sets', '-')}; 95 % upper bound {pct(summary.get('false_effect_rate_upper_95'))}) "
             "| <= 5 % |",
             f"| sets with an indistinguishable pair named | {summary.get('cases_with_indistinguishable_pairs', '-')} | |",
             f"| parameters within 5 %, single effect named exactly | "
             f"{pct(summary.get('single_effect_parameters_within_5pct'))} | 100 % |",
             f"| sets with a library term discovered (every effect is a candidate) | {summary.get('sets_with_discovered_terms', '-')} | 0 |",
             f"| median shrink where an effect is present | {pct(summary['median_shrink_with_effect'])} | >= 70 % |",
             f"| median calibrated-pressure error | {pct(summary['median_pressure_error'])} | |",
             f"| failed cases (of which the twin could not generate) | {summary['failed']} ({summary['not_generated']}) | 0 |", "",
             "| effect | TP | FP | FN | precision | recall | median max parameter error | parameters within 25 % |",
             "|---|---|---|---|---|---|---|---|"]
    for n, d in summary["per_effect"].items():
        lines.append(f"| {n} | {d['tp']} | {d['fp']} | {d['fn']} | {pct(d['precision'])} | {pct(d['recall'])} | "
                     f"{pct(d['median_max_parameter_error'])} | {pct(d['fraction_parameters_within_25pct'])} |")
    lines += ["", "| effect | median error per parameter (named true effects) |", "|---|---|"]
    for n, d in summary["per_effect"].items():
        med = d.get("median_parameter_error") or {}
        if med:
            lines.append(f"| {n} | " + ", ".join(f"{p} {pct(v)}" for p, v in med.items()) + " |")
    coverage = summary.get("interval_coverage") or {}
    if coverage:
        lines += ["", "| named true parameters of | 95 % intervals holding the truth | its 95 % bounds | not determined |"
                  " median half-width / estimate | target |", "|---|---|---|---|---|---|"]
        for n, c in coverage.items():
            bounds = "-" if c["coverage"] is None else f"{pct(c['lower_95'])}-{pct(c['upper_95'])}"
            w = c.get("median_relative_half_width")
            lines.append(f"| {n} | {c['covered']} of {c['determined']} ({pct(c['coverage'])}) | {bounds} | "
                         f"{c['not_determined']} | {'-' if w is None else f'{100 * w:.2g} %'} | 90-98 % |")
    return lines


def confusion_figure(results: list[dict], path: Path) -> Path:
    """Per true effect: identified (diagonal) or missed; false positives in the row of the case's true
    effects (or 'none').  Cases the twin could not generate are left out."""
    import matplotlib.pyplot as plt

    rows = list(STRENGTHS) + [RESONATOR, "none"]
    cols = list(STRENGTHS) + [RESONATOR, "missed", "nothing named"]
    m = np.zeros((len(rows), len(cols)), int)
    for r in results:
        if not r.get("scored", True):
            continue
        trues, found = r["true_set"], r["identified"]
        for t in trues:
            m[rows.index(t), cols.index(t) if t in found else cols.index("missed")] += 1
        for f in found:
            if f not in trues:
                for t in trues or ["none"]:
                    m[rows.index(t), cols.index(f)] += 1  # a false positive, charged to the true effects present
        if not trues and not found:
            m[rows.index("none"), cols.index("nothing named")] += 1
    fig, ax = plt.subplots(figsize=(6.8, 5.4), constrained_layout=True)
    im = ax.imshow(m, cmap="Blues")
    for i in range(len(rows)):
        for j in range(len(cols)):
            if m[i, j]:
                ax.text(j, i, str(m[i, j]), ha="center", va="center", color="white" if m[i, j] > m.max() / 2 else "black")
    ax.set_xticks(range(len(cols)), [c.replace("_", "\n").replace(" ", "\n") for c in cols], fontsize=7)
    ax.set_yticks(range(len(rows)), rows, fontsize=7)
    ax.set_xlabel("identified by the diagnosis (off-diagonal effect columns: false positives)")
    ax.set_ylabel("present in the data (hidden truth)")
    ax.set_title("Blind check: effects present vs identified")
    fig.colorbar(im, ax=ax, label="count")
    from cubedimer.atomic import save_figure

    return save_figure(fig, path)
