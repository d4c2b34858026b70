"""The fit's command-line options, and the one path from them to a :class:`~fitting.config.FitConfig`.

Every command that fits (``python -m fitting fit``, ``python -m validation report``) adds the same options with
:func:`add_fit_options` and turns them into its configuration with :func:`fit_config_from_args`, so that an option
means the same everywhere (``--max-evals``: the evaluations of the method's own refinement,
``MethodConfig.max_evals_setting``) and a method-specific option acts on the method's own settings
(``FitConfig.method``) and is refused, in one line, by a method whose settings do not accept it
(``MethodConfig.options``).
The defaults the help names are read from the configs themselves.
"""
from __future__ import annotations

import argparse
from dataclasses import replace

from cubedimer.cli import UserInputError, positive_float, positive_int
from cubedimer.dataset import DEFAULT_MAX_GAP, LoadConfig
from .config import OUTPUT_ERROR_MODES, FitConfig
from .method_names import DEFAULT_METHOD, METHOD_OPTIONS, METHODS, methods_help
from .refinement.long_time import JOINT_REFINE
from .selection.rules import SELECTION_RULES

__all__ = ["add_fit_options", "fit_config_from_args", "add_max_gap_option"]


def add_fit_options(parser: argparse.ArgumentParser) -> None:
    """The fit's options: ``--method``, ``--max-evals``, ``--joint-max-evals``, ``--selection``,
    ``--heldout-tolerance``, ``--output-error``, ``--max-terms``, ``--relative-threshold``, ``--no-glitch-mask``, ``--min-periods``,
    ``--max-gap``."""
    parser.add_argument("--method", choices=tuple(METHODS), default=DEFAULT_METHOD, help=methods_help())
    parser.add_argument("--max-evals", type=positive_int, default=None,
                        help="objective evaluations per run refinement (paper) or of the polish (discovery)")
    parser.add_argument("--joint-max-evals", type=positive_int, default=None,
                        help=f"evaluations of the joint re-optimisation (default {JOINT_REFINE.max_evals})")
    parser.add_argument("--selection", choices=tuple(SELECTION_RULES), default=None,
                        help="term selection of the per-run ensemble: " + "; ".join(
                            f"'{r.name}' ({', '.join(r.methods)}): {r.summary}" for r in SELECTION_RULES.values()))
    parser.add_argument(
        "--heldout-tolerance", type=float, default=None, metavar="FRACTION",
        help="discovery: keep the smallest support whose held-out error (5-fold over runs) is within FRACTION "
             "of the best on the elimination path (default 0: the best itself, every term the data resolve). "
             "A practical threshold for data whose truth is not sparse in the library (real dimers): 0.002 "
             "gives the 11-term Gor'kov form on the paper-like twin, but also drops weak true terms near the "
             "information limit; model.json's Pareto front shows the trade-off. In equations under model "
             "error it widens the held-out rule's allowance, and the output error drops a term that raises "
             "the trajectories' RMS misfit by at most FRACTION and adds none that lowers it by less "
             "(0.02-0.05 there: one to three terms fewer per model at long-time errors 0-14 %% higher on average, "
             "up to 2.3 times on single 4-run data sets; docs/fitting.md)")
    parser.add_argument(
        "--output-error", choices=tuple(OUTPUT_ERROR_MODES), default=None,
        help="discovery, for equations whose residual is model error (a truth not sparse in the library): "
             "'select' (default) refines the coefficients so that the model's trajectories follow the runs "
             "over 5-period segments, then drops the terms those trajectories do not need and adds those "
             "they need (a slow nonlinear damping, say); 'refine' only refines; 'off' keeps the integral "
             "form's coefficients and support")
    parser.add_argument("--max-terms", type=positive_int, default=None, metavar="N",
                        help="discovery: at most N terms per equation, the front's point at that size (model.json's "
                             "discovery.front; default: the discovery's own selection)")
    parser.add_argument("--relative-threshold", action="store_true",
                        help="apply the regression threshold to each equation relative to its signal size (for a "
                             "hinge much slower than the vertical oscillation, whose scaled theta coefficients are "
                             "all small)")
    parser.add_argument("--no-glitch-mask", action="store_true",
                        help="keep every recorded frame: no isolated tracking glitch is masked and filled (by default "
                             "the frames masked per run are counted in model.json's per_run entries)")
    parser.add_argument("--min-periods", type=positive_float, default=None, metavar="N",
                        help="oscillation periods (of the dominant frequency of y, or of the first declared "
                             "coordinate) a run must hold to be fitted "
                             f"(default {LoadConfig.__dataclass_fields__['min_periods'].default:g})")
    add_max_gap_option(parser)


def add_max_gap_option(parser: argparse.ArgumentParser) -> None:
    """``--max-gap FRAMES``: the loader's fill limit (:attr:`cubedimer.dataset.LoadConfig.max_gap`), for every command
    that loads a data set; ``args.max_gap`` is None when not given."""
    parser.add_argument("--max-gap", type=positive_int, default=None,
                        metavar="FRAMES",
                        help="longest gap of missing frames (not measured, or masked as tracking glitches) filled by "
                             "interpolation; a run is split into two at a longer gap, and a part too short to fit is "
                             "skipped (default: the data set's meta.json tracking.max_gap_frames, written by tracking "
                             f"track --max-gap, else {DEFAULT_MAX_GAP}); given, it overrides meta.json")


def fit_config_from_args(args: argparse.Namespace) -> FitConfig:
    """The :class:`FitConfig` of the options of :func:`add_fit_options`: the method's default settings
    (``FittingMethod.config_type``) with the options applied to them and to the shared stages;
    :class:`cubedimer.cli.UserInputError` (one line naming the option) for an option the method does not accept
    (``MethodConfig.options``) or a value out of range."""
    if args.selection and args.method not in SELECTION_RULES[args.selection].methods:
        raise UserInputError(f"--selection {args.selection} applies to --method "
                             f"{', '.join(SELECTION_RULES[args.selection].methods)}")
    cfg = FitConfig.for_method(args.method)
    for option in METHOD_OPTIONS:  # the options only some methods accept: the method's settings say which
        value = getattr(args, option, None)
        try:
            cfg = cfg.with_method_option(option, None if value is False else value)
        except ValueError as exc:
            raise UserInputError(f"--{option.replace('_', '-')} {exc}") from None
    settings = cfg.method.with_max_evals(args.max_evals) if args.max_evals else cfg.method
    if args.joint_max_evals:
        settings = settings.with_joint_max_evals(args.joint_max_evals)
    if args.selection:
        settings = replace(settings, selection=replace(settings.selection, rule=args.selection))
    load = cfg.load
    if args.no_glitch_mask:
        load = replace(load, glitches=None)
    if args.min_periods is not None:
        load = replace(load, min_periods=args.min_periods)
    if getattr(args, "max_gap", None) is not None:
        load = replace(load, max_gap=args.max_gap)
    return replace(cfg, load=load, method=settings)
