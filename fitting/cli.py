"""Command line: ``python -m fitting fit|compare|synth``.

* ``fit DATA_DIR --out OUT_DIR [--method discovery|paper] [--workers N | --scheduler ADDRESS] [--strict]
  [--no-plots] [--max-evals N] [--heldout-tolerance FRACTION] [--output-error MODE] [--no-glitch-mask]``: steps 1-4; writes ``OUT_DIR/model.json`` (docs/formats.md), per-run caches in ``OUT_DIR/runs/``
  (resume) and plots.
* ``compare DATA_DIR --model OUT_DIR/model.json --out OUT_DIR [--drop eq:term ...]
  [--no-reoptimise]``: step 5; writes ``compare.json`` (per-run shape and Poincare errors,
  Wilcoxon tests).  Without ``--drop`` the variant is the minimal model without its
  cross-coupling terms.
* ``synth OUT_DIR [--runs N] [--seed S] ...``: a synthetic data set from the paper's reduced
  model (``truth.json`` beside the CSVs).

Bad input: one line ``error: <file>: <problem>`` on stderr, exit status 2, nothing written.
"""
from __future__ import annotations

import argparse
import sys
import time
from dataclasses import replace
from pathlib import Path

from cubedimer.cli import (UserInputError, add_executor_arguments, check_limit, command_parser, executor_config,
                           field_default, positive_float, positive_int, prepare_output_dir, run_cli)
from .options import add_fit_options, fit_config_from_args
from .uncertainty.final_checks import NoSaneModelError

__all__ = ["main", "build_parser", "COMMANDS", "add_fit_parser", "add_compare_parser", "add_synth_parser",
           "add_plan_parser", "plan_noise_from_args"]

#: Most runs and frames per run of a synthetic data set (frames are held in memory before writing).
MAX_SYNTH_RUNS = 10_000
MAX_SYNTH_FRAMES_PER_RUN = 2_000_000


def _log(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


def _cmd_fit(a: argparse.Namespace) -> int:
    from .fit import fit_dataset
    from .output.model_file import write_fit

    prepare_output_dir(a.out, "--out", create=False)
    cfg = fit_config_from_args(a)
    t0 = time.perf_counter()
    res = fit_dataset(a.data_dir, cfg, executor_config(a), strict=a.strict, progress=not a.no_progress,
                      cache_dir=Path(a.out) / "runs")
    path = write_fit(res, a.out, plots=not a.no_plots)
    _log(f"wrote {path} in {time.perf_counter() - t0:.1f} s")
    for eq, terms in res.model.equations().items():
        name = res.system.rename
        print(f"{name(eq)} = " + " + ".join(f"({v:.6g}) {name(t)}" for t, v in terms.items()))
    return 0


def _cmd_compare(a: argparse.Namespace) -> int:
    from cubedimer.atomic import write_json
    from .compare import compare_models, cross_coupling_mask, drop_terms
    from cubedimer.dataset import load_dataset
    from .fit import prepare_runs
    from .model import Scales
    from .output.model_file import read_model_json

    prepare_output_dir(a.out, "--out", create=False)
    model_file = read_model_json(a.model)
    data, ref = model_file.document, model_file.model
    from .output.model_file import recorded_stages
    try:  # the runs loaded and prepared as the fit loaded and prepared them (generic systems too)
        stages = recorded_stages(data)
    except ValueError as exc:
        raise UserInputError(f"{a.model}: its recorded settings are not valid ({exc}); write it again with "
                             "`python -m fitting fit`") from None
    ds = load_dataset(a.data_dir, strict=a.strict, config=stages.load)
    prepared, scales = prepare_runs(ds.runs, stages)
    system = ds.system
    if "scales" in data:
        s = data["scales"]
        scales = Scales(s["length_y_m"], s["length_theta"], s["time_s"])
    if a.drop:
        try:
            variant = drop_terms(ref, [system.internal(d) for d in a.drop])
        except ValueError as exc:
            raise UserInputError(f"--drop: {exc}") from None
        label = "without " + ", ".join(a.drop)
    else:
        variant = ref.with_mask(ref.support & ~cross_coupling_mask(ref))
        label = "without cross-coupling terms"
    _log(f"comparing the minimal model with the variant {label} on {len(prepared)} runs")
    cmp = compare_models(ref, variant, [p.derivs for p in prepared], scales,
                         names=[p.run.name for p in prepared], reoptimise=not a.no_reoptimise)
    out = {"variant_label": label, **cmp.to_json()}
    write_json(Path(a.out) / "compare.json", system.rename(out))
    for name, t in (("shape", cmp.shape_test), ("Poincare", cmp.poincare_test)):
        print(f"{name}: median(variant - minimal) = {t.median_difference:.4g}, "
              f"Wilcoxon p(variant worse) = {t.p_greater:.3g}, two-sided p = {t.p_two_sided:.3g} (n = {t.n})")
    if not a.no_plots:
        from .output.plots import plot_comparison
        plot_comparison(cmp, Path(a.out))
    return 0


def _cmd_synth(a: argparse.Namespace) -> int:
    from .synthetic import SyntheticConfig, paper_reduced_model, write_dataset, write_generic_example

    if a.system == "generic":
        prepare_output_dir(a.out_dir, "OUT_DIR", create=False)
        cfg = write_generic_example(a.out_dir, seed=a.seed)
        _log(f"wrote {cfg.n_runs} runs of a generic two-coordinate system, meta.json and truth.json to {a.out_dir}")
        return 0
    check_limit("--runs", a.runs, MAX_SYNTH_RUNS)
    check_limit("frames per run (--duration x --fps)", a.duration * a.fps, MAX_SYNTH_FRAMES_PER_RUN)
    prepare_output_dir(a.out_dir, "OUT_DIR", create=False)
    cfg = SyntheticConfig(n_runs=a.runs, duration=a.duration, fps=a.fps, noise_y=a.noise_y,
                          noise_theta=a.noise_theta, seed=a.seed)
    write_dataset(a.out_dir, paper_reduced_model(), cfg)
    _log(f"wrote {a.runs} runs and truth.json to {a.out_dir}")
    return 0


def _cmd_plan(a: argparse.Namespace) -> int:
    from .output.model_file import read_model_json
    from .uncertainty.run_planning import PlanConfig, plan_runs

    model = read_model_json(a.model).model
    noise = plan_noise_from_args(a)
    if a.data is not None:  # say which levels the data set gave
        _log(f"tracking noise: sigma_y = {noise.sigma_y:.3g} m, sigma_theta = {noise.sigma_theta:.3g} ({noise.source})")
    try:
        plan = plan_runs(model, noise, PlanConfig(a.duration, a.fps, a.term, target_z=a.target_z, size=a.size,
                                                  n_reference=a.reference_runs, run_counts=a.runs, seed=a.seed,
                                                  y_amplitude=a.y_amplitude, theta_amplitude=a.theta_amplitude))
    except (ValueError, RuntimeError) as exc:
        raise UserInputError(str(exc)) from None
    print(plan.format_table())
    return 0


def plan_noise_from_args(a: argparse.Namespace):
    """The planner's tracking noise: --noise-y/--noise-theta where given, else the noise the data set of --data
    records in meta.json (:func:`fitting.uncertainty.oracle.recorded_tracking_noise`), else the noise estimated from its runs.
    (The options ``noise_y``, ``noise_theta`` and ``data`` of ``fitting plan``; ``validation plan`` shares it.)"""
    from .uncertainty.oracle import NoiseLevels, estimate_tracking_noise, recorded_tracking_noise

    if a.noise_y is not None and a.noise_theta is not None:
        return NoiseLevels(a.noise_y, a.noise_theta, source="given on the command line")
    if a.data is None:
        raise UserInputError("plan: give --noise-y and --noise-theta, or --data DATA_DIR to read the data set's tracking "
                             "noise")
    from cubedimer.dataset import DatasetError, load_dataset
    from cubedimer.meta import read_meta

    try:
        noise = recorded_tracking_noise(read_meta(a.data))
        if noise is None:
            noise = replace(estimate_tracking_noise(load_dataset(a.data, report=lambda m: None).runs),
                            source=f"estimated from the runs of {a.data} (fourth differences; its meta.json records no "
                                   "tracking noise)")
        else:
            noise = replace(noise, source=f"recorded by the tracking in {Path(a.data) / 'meta.json'}")
    except DatasetError as exc:
        raise UserInputError(str(exc)) from None
    # a level given on the command line overrides the data set's for its coordinate
    return replace(noise, sigma_y=a.noise_y if a.noise_y is not None else noise.sigma_y,
                   sigma_theta=a.noise_theta if a.noise_theta is not None else noise.sigma_theta)


def add_plan_parser(subparsers) -> None:
    """``plan``: how many runs make a term resolvable (the oracle's experiment planner)."""
    p = subparsers.add_parser("plan", help="how many runs make a term resolvable (oracle z of integral-form least squares)")
    p.add_argument("--model", required=True, help="model.json (fit's output or a truth.json)")
    p.add_argument("--term", required=True, help="EQUATION:TERM, e.g. thetaddot:y^2*theta")
    p.add_argument("--size", type=float, default=None, help="the term's coefficient [SI] (default: the model's)")
    p.add_argument("--data", default=None, metavar="DATA_DIR",
                   help="a data set whose tracking noise the plan uses: the noise its meta.json records (written by "
                        "python -m tracking), else the noise estimated from its runs")
    p.add_argument("--noise-y", type=positive_float, default=None,
                   help="tracking noise of y [m] (required without --data; overrides the data set's)")
    p.add_argument("--noise-theta", type=positive_float, default=None,
                   help="tracking noise of theta [-] (required without --data; overrides the data set's)")
    from .synthetic import SyntheticConfig
    from .uncertainty.run_planning import PlanConfig

    p.add_argument("--duration", type=positive_float, default=field_default(SyntheticConfig, "duration"),
                   help="run length [s]")
    p.add_argument("--fps", type=positive_float, default=field_default(SyntheticConfig, "fps"),
                   help="frame rate [1/s]")
    p.add_argument("--target-z", type=positive_float, default=field_default(PlanConfig, "target_z"),
                   help="oracle z that counts as resolvable")
    p.add_argument("--runs", type=positive_int, nargs="+", default=list(field_default(PlanConfig, "run_counts")),
                   help="rows of the table (numbers of runs)")
    p.add_argument("--reference-runs", type=positive_int, default=field_default(PlanConfig, "n_reference"),
                   help="reference runs the per-run information is measured on")
    p.add_argument("--y-amplitude", type=positive_float, nargs=2, default=None, metavar=("LO", "HI"),
                   help="range of initial y amplitudes [m] (default %g %g)" % field_default(SyntheticConfig, "y_amplitude"))
    p.add_argument("--theta-amplitude", type=positive_float, nargs=2, default=None, metavar=("LO", "HI"),
                   help="range of initial theta amplitudes [-] (default %g %g)"
                        % field_default(SyntheticConfig, "theta_amplitude"))
    p.add_argument("--seed", type=int, default=field_default(PlanConfig, "seed"), help="seed of the reference runs")
    p.set_defaults(func=_cmd_plan)


def add_fit_parser(subparsers) -> None:
    """``fit``: discover the minimal model of a data set."""
    f = subparsers.add_parser("fit", help="discover the minimal model of a data set (steps 1-4)")
    f.add_argument("data_dir", help="data set directory: CSV runs (t [s], y [m], theta [-]) and an optional meta.json (docs/formats.md)")
    f.add_argument("--out", required=True, help="output directory (model.json, plots, runs/ cache)")
    f.add_argument("--strict", action="store_true", help="fail on the first bad file instead of skipping it")
    f.add_argument("--no-plots", action="store_true", help="write model.json only, no PNG plots")
    f.add_argument("--quiet", dest="no_progress", action="store_true", help="no progress bar")
    add_fit_options(f)
    add_executor_arguments(f)
    f.set_defaults(func=_cmd_fit)


def add_compare_parser(subparsers) -> None:
    """``compare``: a model variant against the minimal model."""
    c = subparsers.add_parser("compare", help="compare a model variant with the minimal model (step 5)")
    c.add_argument("data_dir", help="data set directory: CSV runs (t [s], y [m], theta [-]) and an optional meta.json (docs/formats.md)")
    c.add_argument("--model", required=True, help="model.json written by `fit`")
    c.add_argument("--out", required=True, help="output directory (compare.json and plots)")
    c.add_argument("--drop", nargs="*", default=None, help="terms to drop, as eq:term (default: cross-coupling terms)")
    c.add_argument("--no-reoptimise", action="store_true", help="compare the variant without re-optimising it")
    c.add_argument("--strict", action="store_true", help="fail on the first bad file instead of skipping it")
    c.add_argument("--no-plots", action="store_true", help="write compare.json only, no PNG plots")
    c.set_defaults(func=_cmd_compare)


def add_synth_parser(subparsers) -> None:
    """``synth``: a synthetic data set from the paper's reduced model."""
    s = subparsers.add_parser("synth", help="write a synthetic data set from the paper's reduced model")
    s.add_argument("out_dir", help="directory to write the run CSVs, meta.json and truth.json into")
    from .synthetic import SyntheticConfig

    def default(name):
        return field_default(SyntheticConfig, name)

    s.add_argument("--runs", type=positive_int, default=default("n_runs"), help="number of runs")
    s.add_argument("--duration", type=positive_float, default=default("duration"), help="length of each run [s]")
    s.add_argument("--fps", type=positive_float, default=default("fps"), help="frame rate [1/s]")
    s.add_argument("--noise-y", type=float, default=default("noise_y"),
                   help="tracking noise of y [m] (standard deviation)")
    s.add_argument("--noise-theta", type=float, default=default("noise_theta"),
                   help="tracking noise of theta [-] (standard deviation)")
    s.add_argument("--seed", type=int, default=default("seed"), help="seed of the initial conditions and the noise")
    s.add_argument("--system", choices=("dimer", "generic"), default="dimer",
                   help="dimer: the paper's reduced model (the options above); generic: the worked example of a "
                        "generic two-coordinate system (docs/fitting.md, 'Any two coordinates'; its own runs and "
                        "noise, only --seed applies)")
    s.set_defaults(func=_cmd_synth)


#: The commands of ``python -m fitting``, in the order of the help.
COMMANDS = (add_fit_parser, add_compare_parser, add_synth_parser, add_plan_parser)


def build_parser() -> argparse.ArgumentParser:
    """The parser of ``python -m fitting`` (one ``add_parser`` function per command)."""
    return command_parser("python -m fitting", "Data-driven model discovery for cube dimers. Data format: "
                          "docs/formats.md; what y and theta are: docs/conventions.md.", COMMANDS)


def main(argv: list[str] | None = None) -> int:
    return run_cli(build_parser(), argv, errors=(NoSaneModelError,))
