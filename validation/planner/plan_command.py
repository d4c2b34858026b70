"""``python -m validation plan``: what runs determine the candidate effects' parameters and tell two candidates apart
(:mod:`validation.planner.candidate_plan`)."""
from __future__ import annotations

import argparse
from dataclasses import replace
from pathlib import Path

from cubedimer.cli import UserInputError, field_default, positive_float, positive_int
from cubedimer.meta import DEFAULT_TRACKING_NOISE

__all__ = ["add_plan_parser", "twin_from_args"]


def _pair(text: str) -> tuple[str, str]:
    true, sep, rival = str(text).partition(":")
    if not sep or not true.strip() or not rival.strip():
        raise argparse.ArgumentTypeError(f"{text!r}: give TRUE:RIVAL, e.g. cavity_lag:linear_damping")
    return true.strip(), rival.strip()


def add_plan_parser(sub) -> None:
    """``plan``: see its --help."""
    from .candidate_plan import CandidatePlanConfig
    from .reference_runs import RunDesign

    p = sub.add_parser(
        "plan", help="what runs determine a candidate effect and tell two candidates apart (oracle of the diagnosis's "
                     "columns on the twin's noise-free runs)",
        description=(
            "For a twin configuration (a preset or the twin's default physics, the true effects and the cavity) and a "
            "run design (duration, fps, drop amplitudes), the oracle standard error of every fitted parameter (the "
            "pressure scale and the candidates' parameters: pooled integral-form least squares at the twin's "
            "noise-free runs with white tracking noise), against the number of runs over random draws of the "
            "reference runs, and the runs for a stated relative error; and for each --pair TRUE:RIVAL the alias z: "
            "how many noise units the true candidate's contribution stands above what the rival's columns (with "
            "the pressure scale and the other fitted candidates) can fit, and the runs for alias z >= the target. "
            "Prints the tables."),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    p.add_argument("--preset", default=None, help="a twin preset as the truth (default: the twin's default physics)")
    p.add_argument("--truth", default=None, metavar="TRUTH_JSON",
                   help="a twin data set's truth.json as the truth (its pressure, effects, cavity, drop protocol); "
                        "its runs, duration, fps and seed are the default design, so that the reference runs are the "
                        "data set's own")
    p.add_argument("--effect", action="append", default=[], metavar="NAME:PARAM=VALUE,...",
                   help="a true effect, e.g. velocity_coupling:c5=2000,c6=5e5 (repeatable; added to the preset's)")
    p.add_argument("--cavity", type=positive_float, nargs=2, default=None, metavar=("Q", "DETUNING"),
                   help="the levitator as a resonator: the cavity's quality factor and the drive's detuning in "
                        "half-widths (the twin's --transducer-q and --detuning)")
    p.add_argument("--no-air-damping", action="store_true", help="leave the air's computed drag out of the truth")
    p.add_argument("--fit", nargs="+", default=None, metavar="CANDIDATE",
                   help="the candidates fitted beside the pressure scale (default: the true candidates and "
                        "linear_damping)")
    p.add_argument("--pair", type=_pair, action="append", default=[], metavar="TRUE:RIVAL",
                   help="a pair whose alias z is measured, e.g. cavity_lag:linear_damping (repeatable)")
    p.add_argument("--duration", type=positive_float, default=None,
                   help=f"run length [s] (default: --truth's, else {field_default(RunDesign, 'duration'):g})")
    p.add_argument("--fps", type=positive_float, default=None,
                   help=f"frame rate [1/s] (default: --truth's, else {field_default(RunDesign, 'fps'):g})")
    p.add_argument("--amplitudes", type=positive_float, nargs="+", default=None, metavar="A",
                   help="the y amplitudes the drops start [m] (each run's field-off time in the twin's linear trap); "
                        "the runs cycle through them (default: the twin's drop protocol)")
    p.add_argument("--theta-drop", type=positive_float, default=None, metavar="MAX",
                   help="the hinge angle at the drop within +-MAX [-] (default: the twin's range)")
    p.add_argument("--reference-runs", type=positive_int, default=None,
                   help="reference runs simulated (the pool of the draws; default: --truth's runs, else "
                        f"{field_default(RunDesign, 'n_reference')})")
    p.add_argument("--runs", type=positive_int, nargs="+", default=list(field_default(CandidatePlanConfig, "run_counts")),
                   help="rows of the tables (numbers of runs)")
    p.add_argument("--relative-error", type=positive_float, default=field_default(CandidatePlanConfig, "relative_error"),
                   help="target: each parameter's interval within +- this fraction of its value")
    p.add_argument("--confidence", type=positive_float, default=field_default(CandidatePlanConfig, "confidence"),
                   help="the interval's confidence")
    p.add_argument("--target-alias-z", type=positive_float, default=field_default(CandidatePlanConfig, "target_alias_z"),
                   help="alias z that counts as told apart")
    p.add_argument("--draws", type=positive_int, default=field_default(CandidatePlanConfig, "n_draws"),
                   help="random draws of runs per row")
    p.add_argument("--data", default=None, metavar="DATA_DIR",
                   help="a data set whose experiment (its meta.json: dimer, frequency, pressure) and tracking noise "
                        "(recorded in its meta.json, else estimated from its runs) the plan uses")
    p.add_argument("--noise-y", type=positive_float, default=None,
                   help=f"tracking noise of y [m] (default: --data's, else {DEFAULT_TRACKING_NOISE['noise_y_m']:g})")
    p.add_argument("--noise-theta", type=positive_float, default=None,
                   help=f"tracking noise of theta [-] (default: --data's, else {DEFAULT_TRACKING_NOISE['noise_theta']:g})")
    p.add_argument("--seed", type=int, default=None,
                   help="seed of the reference runs and the draws (default: --truth's, else 0)")
    p.set_defaults(func=run_plan)


def twin_from_args(a: argparse.Namespace):
    """The twin configuration of the options (the truth of the plan)."""
    from acousim.dynamics.effects import EffectError, EffectSet
    from acousim.twin import PRESETS, TwinConfig, TwinError

    from .reference_runs import twin_from_truth

    try:
        if a.truth is not None:
            if a.preset is not None:
                raise UserInputError("give --preset or --truth, not both")
            twin = twin_from_truth(_read_truth(a.truth))
        elif a.preset is not None:
            if a.preset not in PRESETS:
                raise UserInputError(f"--preset {a.preset!r}: unknown preset (use one of {', '.join(PRESETS)})")
            twin = TwinConfig.from_preset(PRESETS[a.preset])
        else:
            twin = TwinConfig()
        if a.data is not None and a.truth is None:
            twin = replace(twin, experiment=_experiment_of(a.data))
        effects = twin.effects.merged(EffectSet.parse(a.effect)) if a.effect else twin.effects
        cavity = {} if a.cavity is None else {"transducer_q": a.cavity[0], "cavity_detuning": a.cavity[1]}
        twin = replace(twin, effects=effects, air_damping=twin.air_damping and not a.no_air_damping, **cavity)
        twin.cavity_mode  # noqa: B018  (checks the cavity's settings)
    except (EffectError, TwinError) as exc:
        raise UserInputError(f"--effect/--cavity: {exc}") from None
    return twin


def _experiment_of(data: str):
    """The experiment a data set's meta.json states (its dimer, frequency, pressure; the twin's where it states none)."""
    from acousim.models import ExperimentConditions
    from cubedimer.errors import DatasetError
    from cubedimer.meta import read_meta

    if not Path(data, "meta.json").is_file():
        raise UserInputError(f"--data {data}: no meta.json there; give a data set's folder")
    try:
        return ExperimentConditions.from_meta(read_meta(data))
    except (DatasetError, ValueError) as exc:
        raise UserInputError(f"--data {data}: {exc}") from None


def _read_truth(path: str) -> dict:
    """truth.json's content, or a one-line error naming the file."""
    import json

    try:
        truth = json.loads(Path(path).read_text())
    except (OSError, ValueError) as exc:
        raise UserInputError(f"--truth {path}: cannot read it as JSON ({exc}); give a twin data set's truth.json") from None
    if not isinstance(truth, dict):
        raise UserInputError(f"--truth {path}: not a truth.json (a JSON object); give a twin data set's truth.json")
    return truth


def _design(a: argparse.Namespace, twin):
    """The run design of the options; --truth's runs, duration, fps and seed where not given."""
    from .reference_runs import RunDesign

    own = a.truth is not None
    return RunDesign(duration=a.duration or (twin.duration if own else field_default(RunDesign, "duration")),
                     fps=a.fps or (twin.camera.fps if own else field_default(RunDesign, "fps")),
                     n_reference=a.reference_runs or (twin.runs if own else field_default(RunDesign, "n_reference")),
                     amplitudes=None if a.amplitudes is None else tuple(a.amplitudes),
                     theta_drop=None if a.theta_drop is None else (-a.theta_drop, a.theta_drop),
                     seed=a.seed if a.seed is not None else (twin.seed if own else 0))


def _noise(a: argparse.Namespace):
    from fitting.cli import plan_noise_from_args
    from fitting.uncertainty.oracle import NoiseLevels

    if a.data is not None:
        if not Path(a.data, "meta.json").is_file():
            raise UserInputError(f"--data {a.data}: no meta.json there; give a data set's folder")
        return plan_noise_from_args(a)
    return NoiseLevels(a.noise_y or DEFAULT_TRACKING_NOISE["noise_y_m"],
                       a.noise_theta or DEFAULT_TRACKING_NOISE["noise_theta"],
                       source="given on the command line, else the twin camera's default")


def _fitted(a: argparse.Namespace, twin) -> tuple[str, ...]:
    from validation.diagnosis.prepare.candidate_effects import CANDIDATE_EFFECTS

    if a.fit is not None:
        names = tuple(a.fit)
    else:
        names = tuple(e.name for e in twin.effects if e.name in CANDIDATE_EFFECTS) + ("linear_damping",)
        names += ("cavity_lag",) if twin.cavity_mode is not None else ()
    unknown = [n for n in list(names) + [c for p in a.pair for c in p] if n not in CANDIDATE_EFFECTS]
    if unknown:
        raise UserInputError(f"--fit/--pair: unknown candidate {unknown[0]!r} (candidates: "
                             f"{', '.join(CANDIDATE_EFFECTS)})")
    return tuple(dict.fromkeys(names))


def _check_pairs(twin, pairs) -> None:
    """Each pair's true candidate is in the truth (before any run is simulated)."""
    from acousim.twin import twin_dynamics

    from .reference_runs import has_contribution, true_parameters

    truth = true_parameters(twin, twin_dynamics(twin)[0])
    for true, rival in pairs:
        if not has_contribution(truth, true):
            raise UserInputError(f"--pair {true}:{rival}: the twin configuration has no {true} (its contribution is "
                                 "zero); give its strengths with --effect or --cavity")


def run_plan(a: argparse.Namespace) -> int:
    """Run ``plan``."""
    from .candidate_plan import CandidatePlanConfig, plan_candidates
    from acousim.twin import TwinError

    from .reference_runs import reference_runs

    if not 0 < a.relative_error < 1 or not 0 < a.confidence < 1:
        raise UserInputError("--relative-error and --confidence must lie in (0, 1), e.g. 0.2 and 0.95")
    if a.theta_drop is not None and not a.theta_drop < 0.99:
        raise UserInputError(f"--theta-drop {a.theta_drop:g}: the hinge angle at the drop must stay below 0.99 "
                             "(face contact at 1), e.g. 0.3")
    if a.amplitudes is not None and not all(h < 1e-3 for h in a.amplitudes):
        raise UserInputError(f"--amplitudes {' '.join(map(str, a.amplitudes))}: amplitudes are in metres and must be "
                             "below 1 mm, e.g. 20e-6 150e-6")
    twin = twin_from_args(a)
    fitted = _fitted(a, twin)
    noise = _noise(a)
    try:
        _check_pairs(twin, a.pair)
        design = _design(a, twin)
        config = CandidatePlanConfig(fitted, tuple(a.pair), a.relative_error, a.confidence, a.target_alias_z,
                                     tuple(a.runs), a.draws, design.seed)
        names = tuple(dict.fromkeys(fitted + tuple(c for p in a.pair for c in p)))
        plan = plan_candidates(reference_runs(twin, design, names, noise), noise, config)
    except (TwinError, ValueError) as exc:
        raise UserInputError(str(exc)) from None
    print(plan.format_table())
    return 0
