"""Command line of validation: ``python -m validation compare ...``."""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from acousim.cli.model_options import add_model_arguments, model_spec_from_args
from cubedimer.cli import (UserInputError, add_executor_arguments, check_limit, command_parser, executor_config,
                           field_default, positive_float, positive_int, prepare_output_dir, run_cli)
from cubedimer.load_config import LoadConfig
from fitting.options import add_fit_options, add_load_options, fit_config_from_args, load_config_from_args
from fitting.output.model_file import read_model_json
from fitting.uncertainty.final_checks import NoSaneModelError
from .planner.plan_command import add_plan_parser

__all__ = ["main", "build_parser", "COMMANDS", "add_compare_parser", "add_diagnose_parser", "add_blind_parser",
           "add_report_parser", "add_plan_parser"]

#: Most cases of a blind study, and most simulated frames of one case (runs x duration x 2,000 fps).
MAX_BLIND_CASES = 10_000
MAX_BLIND_FRAMES_PER_CASE = 20_000_000


def add_compare_parser(sub) -> None:
    """``compare``: see its --help."""
    p = sub.add_parser(
        "compare",
        help="fitted coefficients against the simulated static coefficients",
        description=(
            "For every velocity-free library term, the simulated static coefficient (least squares on a Gor'kov "
            "sweep, with its uncertainty) beside the fitted one (ensemble mean, std, z-score across runs), their "
            "ratio, whether the signs agree and whether they agree within the combined uncertainty; velocity terms "
            "are listed as dynamic only. Where model.json carries the pooled integral-form fit (key integral_form) and it "
            "selected a term, the verdict uses that estimate and its standard error instead of the ensemble "
            "(column 'verdict from'). The theta*y^2 term comes first. Simulated coefficients are re-expressed at "
            "the data's y origin (see --origin-offset). Writes comparison.json and comparison.md into --out."
        ),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    p.add_argument("--model", required=True, help="model.json written by `python -m fitting fit`")
    p.add_argument("--sweep", help="sweep CSV written by `python -m acousim sweep`")
    p.add_argument("--data", help="the fitted data set's directory: without --sweep the sweep is computed from its "
                   "meta.json (nominal pressure); with --sweep the sweep's dimer is checked against it (default: "
                   "the data's dimer model.json records, key 'dimer')")
    p.add_argument("--other-dimer", action="store_true",
                   help="compare with a sweep of another dimer (side, frequency, ks, gap) than the data's anyway")
    p.add_argument("--fit-theta-max", type=float, default=None,
                   help="static fitting box |theta| <= (default: the data range model.json records, at most 0.9; "
                        "0.3 for a model.json without one)")
    p.add_argument("--fit-y-max", type=float, default=None,
                   help="static fitting box |y| <= [m] (default: the data range model.json records; 150e-6 for a "
                        "model.json without one)")
    p.add_argument("--origin-offset", default="fitted-equilibrium",
                   help="delta [m] with y_sim = y_data + delta, or 'fitted-equilibrium' (root of the fitted yddot)")
    p.add_argument("--n-sigma", type=float, default=2.0, help="agreement criterion in combined standard deviations")
    p.add_argument("--out", required=True, help="output directory")
    p.set_defaults(func=run_compare)


def _read_model(path: Path) -> dict:
    """The model.json document (:func:`fitting.output.model_file.read_model_json`) of a levitated dimer."""
    model_file = read_model_json(path)
    if model_file.system.generic:
        raise UserInputError(f"{path}: a model of a generic system ({', '.join(model_file.system.equation_names)}); "
                             "compare needs a levitated-dimer model (yddot and thetaddot)")
    return model_file.document


def _check_same_dimer(sweep: str, settings: dict, meta: dict, data: str) -> None:
    """A sweep of another dimer than the data's (side, frequency, ks = 2 pi f s / c, the gap when both state it) is
    refused in one line (0.5 % apart: beyond a record's rounding), naming --other-dimer.  ``meta``: the data's
    meta.json, or model.json's ``dimer`` record; ``data``: where it was read (named in the message)."""
    import math

    from cubedimer.meta import META_DEFAULTS

    facts = {**META_DEFAULTS, **meta}
    side = settings.get("side_a_m", settings.get("side_m"))
    swept = {"side": side, "frequency": settings.get("frequency_hz"),
             "ks": (2 * math.pi * settings["frequency_hz"] * side / settings["sound_speed_m_s"]
                    if side and settings.get("frequency_hz") and settings.get("sound_speed_m_s") else None),
             "gap": settings.get("gap_m")}
    wanted = {"side": facts["side_length_m"], "frequency": facts["frequency_hz"],
              "ks": 2 * math.pi * facts["frequency_hz"] * facts["side_length_m"] / facts["sound_speed_m_s"],
              "gap": meta.get("gap_m")}
    units = {"side": ("um", 1e6), "frequency": ("Hz", 1.0), "ks": ("", 1.0), "gap": ("um", 1e6)}
    off = [k for k in swept if swept[k] is not None and wanted[k] is not None
           and abs(swept[k] / wanted[k] - 1.0) > 0.005]
    if off:
        said = ", ".join(f"{k} {swept[k] * units[k][1]:.4g}{(' ' + units[k][0]) if units[k][0] else ''} against "
                         f"{wanted[k] * units[k][1]:.4g}" for k in off)
        raise UserInputError(f"--sweep {sweep}: a sweep of another dimer than the data's ({data}): {said}; "
                             "sweep the data's dimer (python -m acousim sweep with its side and frequency), or give "
                             "--other-dimer to compare anyway")


def _recorded_dimer(dimer: dict) -> dict:
    """model.json's ``dimer`` record (:func:`fitting.output.model_file.dimer_record`) as meta.json keys: its numbers."""
    from cubedimer.meta import META_DEFAULTS

    return {k: float(v) for k, v in dimer.items()
            if k in META_DEFAULTS and isinstance(v, (int, float)) and not isinstance(v, bool)}


def run_compare(args: argparse.Namespace) -> int:
    from acousim.statics.sweep import read_sweep_csv

    from cubedimer.atomic import atomic_write_text

    from .coefficients import static_comparison
    from cubedimer.atomic import write_json
    from cubedimer.meta import read_meta

    from .simulation import model_from_meta

    if not (args.sweep or args.data):
        raise UserInputError("give --sweep (a sweep CSV) or --data (the fitted data set: its meta.json's dimer)")
    prepare_output_dir(args.out, "--out", create=False)
    model = _read_model(Path(args.model))
    dimer = model.get("dimer")
    rng = model.get("data_range", {})
    theta_max = args.fit_theta_max or min(rng.get("theta_abs_max") or 0.3, 0.9)
    y_max = args.fit_y_max or rng.get("y_abs_max_m") or 150e-6
    if not (0 < theta_max < 1) or not (y_max > 0):
        raise UserInputError("the static fitting box needs 0 < theta_max < 1 and y_max > 0")
    if args.origin_offset != "fitted-equilibrium":
        try:
            offset: float | str = float(args.origin_offset)
        except ValueError:
            raise UserInputError(f"--origin-offset {args.origin_offset!r}: a number in metres or 'fitted-equilibrium'") from None
    else:
        offset = args.origin_offset
    if args.sweep:
        try:
            simulation = read_sweep_csv(args.sweep)
        except ValueError as exc:
            raise UserInputError(str(exc)) from None
        if not args.other_dimer and (args.data or isinstance(dimer, dict)):
            meta, where = ((read_meta(args.data), f"{args.data}/meta.json") if args.data else
                           (_recorded_dimer(dimer), f"{args.model}'s dimer"))
            _check_same_dimer(args.sweep, simulation.settings, meta, where)
    else:
        try:
            simulation = model_from_meta(read_meta(args.data))
        except ValueError as exc:
            raise UserInputError(str(exc)) from None
    static, cmp = static_comparison(model, simulation, theta_max, y_max, origin_offset=offset, n_sigma=args.n_sigma)
    out = Path(args.out)
    d = cmp.to_dict()
    d["static_fit"] = {"relative_residual": static.relative_residual, "y_origin_of_sweep": static.y_origin}
    write_json(out / "comparison.json", d)
    text = f"# Fitted model vs simulated static coefficients\n\n{cmp.origin}.\n\n{cmp.table()}\n"
    atomic_write_text(out / "comparison.md", text)
    print(cmp.table())
    print(f"\n{cmp.origin}\nwritten {out / 'comparison.json'} and {out / 'comparison.md'}", file=sys.stderr)
    return 0


def add_diagnose_parser(sub) -> None:
    """``diagnose``: see its --help."""
    p = sub.add_parser(
        "diagnose",
        help="diagnose the sim-to-real gap of a data set",
        description=(
            "Calibrate the simulation (Gor'kov or full-wave; pressure amplitude and y origin) to a data set, measure the gap "
            "between simulated and measured accelerations (and the long-time attractor, Poincare and frequency "
            "errors), localise it (library terms, state-space regions, time scales), and identify which unmodelled "
            "effects of docs/conventions.md section 5 cause it, adding them greedily while their improvement of held-out runs "
            "(each run held out once, K-fold over runs) is significant (one-sided sign-flip test over runs, --alpha). "
            "Tests whether y points down (data_warnings). Every named effect's parameters, the calibrated pressure, "
            "the y origin and the model's calibrated parameters carry a standard error and a 95 % interval (the "
            "final model refitted without each run in turn: a delete-one-run jackknife, Student t with runs - 1 "
            "degrees of freedom; an effect's parameters and the pressure also carry a systematic part measured on "
            "blind twin studies, docs/diagnosis.md), or 'not determined' with the reason; a candidate tried and rejected is marked so, "
            "with its reasons (not significant, removed by the backward check, a negative damping), and its fit is "
            "no result. Data format and conventions: docs/formats.md, "
            "docs/conventions.md. Writes diagnosis.json, figures and report.html into --out."
        ),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    p.add_argument("data", metavar="DATA_DIR", help="data set directory: CSV runs (t [s], y [m], theta [-]) and an "
                   "optional meta.json (docs/formats.md)")
    p.add_argument("--out", required=True, help="output directory")
    p.add_argument("--alpha", type=float, default=0.01,
                   help="significance level of the one-sided sign-flip test over runs of each effect's improvement of "
                        "held-out runs; with n runs "
                        "its smallest p is 2^-n, so the default 0.01 needs at least 7 runs")
    p.add_argument("--min-improvement", type=float, default=0.05,
                   help="smallest median improvement of held-out runs counted, as a fraction of the current gap")
    p.add_argument("--candidates", default=",".join(_default_candidates()),
                   help="comma-separated candidate effects; also accepted: "
                        + ", ".join(sorted(set(_candidate_names()) - set(_default_candidates())))
                        + " (the levitator's cavity responding with a lag: its gains give Q and the detuning)")
    p.add_argument("--no-long-time", action="store_true", help="skip the long-time (attractor) gaps")
    add_model_arguments(p)
    p.add_argument("--strict", action="store_true", help="stop at the first bad file instead of skipping it")
    add_load_options(p, LoadConfig())
    p.add_argument("--quiet", action="store_true", help="no progress messages")
    add_executor_arguments(p, note="The diagnosis's own steps (calibration, greedy identification, long-time "
                           "errors) run one after another in this process, so these options do not change this "
                           "command; it accepts them so that every command takes the same options.")
    p.set_defaults(func=run_diagnose)


def _default_candidates() -> list[str]:
    from .diagnosis.prepare.candidate_effects import default_candidates

    return list(default_candidates())


def _candidate_names() -> list[str]:
    from .diagnosis import CANDIDATE_EFFECTS

    return list(CANDIDATE_EFFECTS)


def run_diagnose(args: argparse.Namespace) -> int:
    from cubedimer.dataset import DatasetError

    from .diagnosis import DiagnoseConfig, diagnose, load_for_diagnosis
    from .report.sections.gap_diagnosis import write_diagnosis

    cands = tuple(c.strip() for c in args.candidates.split(",") if c.strip())
    unknown = [c for c in cands if c not in _candidate_names()]
    if unknown:
        raise UserInputError(f"unknown effect(s) {', '.join(unknown)}; candidates are {', '.join(_candidate_names())}")
    if not 0 < args.alpha < 1:
        raise UserInputError("--alpha must lie in (0, 1)")
    prepare_output_dir(args.out, "--out", create=False)
    try:
        config = DiagnoseConfig(candidates=cands, alpha=args.alpha, min_relative_improvement=args.min_improvement,
                                long_time=not args.no_long_time)
    except ValueError as exc:
        raise UserInputError(f"{exc} (see --help)") from None
    try:
        dataset = load_for_diagnosis(args.data, strict=args.strict, progress=not args.quiet,
                                     load=load_config_from_args(args, LoadConfig()))
        diagnosis = diagnose(dataset, config, progress=not args.quiet, spec=model_spec_from_args(args))
    except (DatasetError, ValueError) as exc:
        raise UserInputError(str(exc)) from None
    paths = write_diagnosis(diagnosis, args.out)
    if not args.quiet:
        named = "; ".join(str(diagnosis.effect(n)) for n in diagnosis.identified)
        print(f"identified: {named or 'none'}; gap {diagnosis.gap_before:.3g} -> "
              f"{diagnosis.gap_after:.3g}; written {', '.join(str(p) for p in paths)}", file=sys.stderr)
    return 0


def add_blind_parser(sub) -> None:
    """``blind``: see its --help."""
    p = sub.add_parser(
        "blind",
        help="blind check of the diagnosis on twin data sets with hidden effects",
        description=(
            "Generate N data sets per case kind, diagnose each without access to its truth and score it. Candidate "
            "cases: a hidden random choice of no effect, one or two effects (random strengths from weak to strong) "
            "and a random pressure error, on the twin with the air's computed damping (scored as linear_damping at "
            "the air's rates; --inviscid: without it, the drawn effects are the whole truth); scored by identification (exact-set rate by number of effects, per-effect "
            "precision and recall), parameter errors, shrink and false positives. Further kinds: an effect outside "
            "the candidates (not forced onto a candidate, leading discovered term), a drifting pressure (detected), "
            "tracking glitches (against the same case without them) and a file in the wrong units (skipped by name). "
            "Writes summary.json, blind_table.md and confusion_matrix.png; finished cases are kept and not "
            "recomputed on a rerun."
        ),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    from .blind.config import BlindConfig

    def default(name):
        return field_default(BlindConfig, name)

    p.add_argument("--cases", type=positive_int, default=default("cases"), help="number of data sets per case kind")
    p.add_argument("--seed", type=int, default=default("seed"), help="seed of the hidden choices")
    p.add_argument("--runs", type=positive_int, default=default("runs"), help="runs per data set (at least 3)")
    p.add_argument("--duration", type=positive_float, default=default("duration"), help="duration of each run [s]")
    p.add_argument("--kinds", default=",".join(default("kinds")),
                   help="comma-separated case kinds, each with --cases cases and its own rows in the table: candidates "
                   "(hidden candidate effects), out_of_candidate (a cubic hinge term or a y-dependent damping), drift "
                   "(a drifting pressure), glitches (outlier frames, scored against the clean twin), unit_slip (one "
                   "run in micrometres or milliseconds, to be skipped by name); 'all' for every kind. The default keeps the "
                   "study of the identification targets; every further kind costs one diagnosis per case (glitches two)")
    p.add_argument("--inviscid", action="store_true",
                   help="candidate cases without the air's computed damping (the drawn effects are the whole truth; the "
                        "study of docs/diagnosis.md's blind-check table); default: the twin's default physics, whose "
                        "air damping the truth holds as linear_damping at the air's rates")
    p.add_argument("--no-resonator", action="store_true",
                   help="candidate cases never draw the levitator's resonator and the diagnosis does not try the cavity's "
                        "lag (cavity_lag); default: the resonator (Q 150-400, 0.5-3 half-widths above the drive) is one "
                        "of the effects a case can draw, and cavity_lag one of the candidates")
    p.add_argument("--no-trajectory-test", dest="trajectory_test", action="store_false",
                   help="the diagnosis does not judge the velocity coupling on the runs' whole trajectories (the "
                        "output-error fit beside the air's damping, docs/diagnosis.md); default: it does, as the "
                        "diagnosis does")
    p.add_argument("--trajectory-test", dest="trajectory_test", action="store_true",
                   help="judge the velocity coupling on the runs' whole trajectories: the default, named for scripts "
                        "that state it")
    p.set_defaults(trajectory_test=True)
    p.add_argument("--out", required=True, help="output directory (a rerun resumes the study in it, on any executor); "
                   "on a cluster of several machines it must be a folder every worker sees at the same path")
    add_executor_arguments(p, note="One task per case: each case's simulation and diagnosis run serially "
                           "inside its task.")
    p.set_defaults(func=run_blind_cli)


def run_blind_cli(args: argparse.Namespace) -> int:
    from .blind import KINDS, BlindConfig, blind_table, run_blind

    kinds = KINDS if args.kinds.strip() == "all" else tuple(k.strip() for k in args.kinds.split(",") if k.strip())
    unknown = [k for k in kinds if k not in KINDS]
    if unknown or not kinds:
        raise UserInputError(f"--kinds: unknown kind(s) {', '.join(unknown) or '(none)'}; kinds are {', '.join(KINDS)} or all")
    if "unit_slip" in kinds and args.runs < 4:
        raise UserInputError("unit_slip cases need --runs >= 4 (three runs must remain to compare)")
    if args.runs < 3:
        raise UserInputError("need --runs >= 3 (the diagnosis compares held-out runs)")
    check_limit("--cases", args.cases, MAX_BLIND_CASES)
    check_limit("frames per case (--runs x --duration x 2000 fps)", args.runs * args.duration * 2000.0,
                MAX_BLIND_FRAMES_PER_CASE)
    prepare_output_dir(args.out, "--out", create=False)
    config = BlindConfig(cases=args.cases, seed=args.seed, runs=args.runs, duration=args.duration, kinds=kinds,
                         air_damping=not args.inviscid, resonator=not args.no_resonator,
                         trajectory_test=args.trajectory_test)
    summary = run_blind(config, args.out, executor_config(args))
    print(blind_table(summary, config))
    return 0


def add_report_parser(sub) -> None:
    """``report``: see its --help."""
    p = sub.add_parser(
        "report",
        help="the model-vs-simulation report of a data set (HTML with embedded figures)",
        description=(
            "Fit the data (fitting pipeline), compare the minimal model with its variant without cross-coupling terms, "
            "diagnose the sim-to-real gap (calibrating the Gor'kov or the full-wave simulation), put the Gor'kov model, "
            "Gor'kov with fitted pair scattering and the full-wave model side by side, sweep the calibrated simulations, "
            "compare coefficients, and write REPORT_DIR/report.html (self-contained), figures/*.png and numbers.json. "
            "The report is a view of the stored results (diagnosis.json, fit/model.json, fit/variant.json): "
            "--from REPORT_DIR makes it again from them in seconds, without fitting or simulating."
        ),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    p.add_argument("data", metavar="DATA_DIR", nargs="?", default=None,
                   help="data set directory: CSV runs (t [s], y [m], theta [-]) and an optional meta.json "
                        "(docs/formats.md); with --from, where the data set now lies (default: the one diagnosis.json "
                        "records)")
    p.add_argument("--out", default=None, help="report directory (required unless --from)")
    p.add_argument("--from", dest="from_dir", default=None, metavar="REPORT_DIR",
                   help="make the report again from a finished report directory's stored results (diagnosis.json, "
                        "fit/model.json, fit/variant.json), in place")
    fit_options = p.add_argument_group("the fit", "the options of python -m fitting fit, with the same meaning; the "
                                       "minimal model's variant without cross-coupling terms is re-optimised with the "
                                       "fit's joint re-optimisation (--joint-max-evals)")
    add_fit_options(fit_options)
    add_model_arguments(p)
    p.add_argument("--atlas", default=None, metavar="ATLAS_DIR",
                   help="also show an attractor atlas written by python -m acousim atlas (its atlas.json and figures)")
    p.add_argument("--quiet", action="store_true", help="no progress messages")
    add_executor_arguments(p, note="The fit's per-run refinements are the parallel tasks; the diagnosis, sweep "
                           "and figures run in this process.")
    p.set_defaults(func=run_report)


def run_report(args: argparse.Namespace) -> int:
    from acousim.fullwave.family import FamilyRangeError, FamilyTableError
    from acousim.fullwave.statics import TableMismatch
    from acousim.models import ConditionError
    from cubedimer.dataset import DatasetError

    from .report.build import build_report, render_report

    if args.from_dir is None and (args.data is None or args.out is None):
        raise UserInputError("give DATA_DIR and --out REPORT_DIR (or --from REPORT_DIR to make a finished report "
                             "again from its stored results)")
    if args.from_dir is not None and args.out is not None:
        raise UserInputError("--from REPORT_DIR makes the report again in REPORT_DIR; leave out --out")
    if args.atlas is not None:  # before anything runs
        from .report.sections.atlas import AtlasSectionError, atlas_section

        try:
            atlas_section(args.atlas)
        except AtlasSectionError as exc:
            raise UserInputError(str(exc)) from None
    if args.from_dir is not None:
        try:
            render_report(args.from_dir, data_dir=args.data, atlas=args.atlas)
        except DatasetError as exc:
            raise UserInputError(str(exc)) from None
        return 0
    fit_config = fit_config_from_args(args)  # before anything runs
    prepare_output_dir(args.out, "--out", create=False)
    executor = executor_config(args)
    try:
        build_report(args.data, args.out, executor.workers, executor.scheduler, progress=not args.quiet,
                     spec=model_spec_from_args(args), atlas=args.atlas, fit_config=fit_config)
    except (DatasetError, TableMismatch, ConditionError, FamilyRangeError, FamilyTableError) as exc:
        raise UserInputError(str(exc)) from None
    return 0


#: The commands of ``python -m validation``, in the order of the help.
COMMANDS = (add_compare_parser, add_diagnose_parser, add_blind_parser, add_report_parser, add_plan_parser)


def build_parser() -> argparse.ArgumentParser:
    """The parser of ``python -m validation`` (one ``add_parser`` function per command)."""
    return command_parser("python -m validation",
                          "Bridge between fitted models and the simulation: coefficient comparison, sim-to-real gap "
                          "diagnosis, its blind check and the HTML report. Conventions: docs/conventions.md; files: "
                          "docs/formats.md.", COMMANDS)


def main(argv: list[str] | None = None) -> int:
    return run_cli(build_parser(), argv, errors=(NoSaneModelError,))
