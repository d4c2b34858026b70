"""``python -m acousim simulate``: synthetic field-drop experiments from the digital twin.

Writes a trajectory data set (docs/formats.md: one ``runNN.csv`` per run with ``t, y, theta``, and
``meta.json`` with the nominal settings) plus ``truth.json`` (true pressure amplitude, effects,
seed and every other setting) and ``truth_states.npz`` (exact states), atomically.  See
:mod:`acousim.twin` and ``docs/twin.md``.

Examples
--------
::

    python -m acousim simulate --runs 12 --seed 1 --out data/twin      # the air's computed damping only
    python -m acousim simulate --runs 12 --seed 1 --no-air-damping --out data/inviscid
    python -m acousim simulate --preset paper-like --runs 20 --pressure-error 0.08 --out data/paper_like
    python -m acousim simulate --effect pair_scattering:kappa=12000 \\
        --effect linear_damping:gamma_y=0.3,gamma_theta=0.8 --duration 4 --fps 2000 \\
        --noise-y 1e-6 --noise-theta 0.005 --out data/two_effects
    python -m acousim simulate --preset paper-like --runs 4 --duration 2 --video --out data/video_twin
    python -m acousim simulate --detuning 1 --transducer-q 250 --runs 10 --out data/resonator   # the resonator

Every twin has the air's drag computed from the dimer's geometry (effect ``air_damping``, docs/damping.md) unless
``--no-air-damping`` is given or the preset leaves it out (``paper-like``, whose tuned linear damping is the total);
``truth.json`` records ``"air_damping"`` (true or false) and the computed parameters under ``effects``.

With ``--video`` each run's high-speed camera frames are written as well (``video/runNN.tif``, a
multi-page TIFF that records its frame rate and pixel size, with the true motion in
``video/runNN_truth.csv``); see :mod:`acousim.twin.video` and ``docs/tracking.md``.
"""
from __future__ import annotations

import argparse
import sys

from cubedimer.cli import (UserInputError, add_executor_arguments, check_limit, executor_config,
                           prepare_output_dir)
from cubedimer.meta import DEFAULT_FREQUENCY_HZ, DEFAULT_PRESSURE_AMPLITUDE_PA, DEFAULT_TRACKING_NOISE

__all__ = ["add_parser", "run", "MAX_RUNS", "MAX_FRAMES_PER_RUN", "MAX_FRAMES", "MAX_VIDEO_FRAMES"]

#: Most runs of one data set.
MAX_RUNS = 10_000
#: Most camera frames of one run (1,000 s at 2,000 fps).
MAX_FRAMES_PER_RUN = 2_000_000
#: Most frames of a data set: every run's states are held in memory before writing (~60 bytes a frame).
MAX_FRAMES = 20_000_000
#: Most rendered camera frames of one data set (--video): 50 runs of 4 s at 2,000 fps.
MAX_VIDEO_FRAMES = 400_000


def _range(text: str) -> tuple[float, float]:
    parts = text.split(":")
    try:
        if len(parts) == 1:
            v = float(parts[0])
            return v, v
        if len(parts) == 2:
            return float(parts[0]), float(parts[1])
    except ValueError:
        pass
    raise argparse.ArgumentTypeError(f"expected MIN:MAX (or one value), got {text!r}")


def _frame_size(text: str) -> tuple[int, int]:
    try:
        w, h = (int(x) for x in text.lower().split("x"))
        return w, h
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected WIDTHxHEIGHT in pixels, e.g. 180x150, got {text!r}") from None


def build_video_camera(args: argparse.Namespace):
    """The :class:`~acousim.twin.video.VideoCamera` of parsed arguments, or None without ``--video``."""
    if not getattr(args, "video", False):
        return None
    from ..twin import TwinError, VideoCamera
    from ..twin.imperfections import Imperfections

    try:
        imp = Imperfections(gradient=args.illumination_gradient, flicker=args.flicker, flicker_hz=args.flicker_hz,
                            bands_px=args.static_bands, dust=args.dust, transparent=args.transparent,
                            tilt_deg=args.tilt, codec=args.codec, crf=args.crf, rest_frames=args.rest_frames,
                            record_origin=not args.no_levitation_row)
        return VideoCamera(pixel_size=args.pixel_size, width=args.frame_size[0], height=args.frame_size[1],
                           psf_sigma=args.psf, noise=args.image_noise, bit_depth=args.bit_depth,
                           polarity=args.polarity, lost_frames=args.lost_frames, imperfections=imp)
    except TwinError as exc:
        raise UserInputError(str(exc)) from None


def _add_imperfection_arguments(p: argparse.ArgumentParser) -> None:
    """The options of a real recording's imperfections (:mod:`acousim.twin.imperfections`; all off by default)."""
    v = p.add_argument_group("imperfections of a real recording (--video)", "All off by default; see docs/tracking.md.")
    v.add_argument("--illumination-gradient", type=float, default=0.0, metavar="FRACTION",
                   help="relative change of the illumination from the left edge to the right one (e.g. 0.3)")
    v.add_argument("--flicker", type=float, default=0.0, metavar="FRACTION",
                   help="relative amplitude of the illumination's flicker (e.g. 0.05)")
    v.add_argument("--flicker-hz", type=float, default=100.0, metavar="HZ", help="flicker frequency (default 100)")
    v.add_argument("--static-bands", type=int, default=0, metavar="PX",
                   help="reflector and transducer edges: static bands of PX rows at the top and bottom, as dark "
                   "(or bright) as the cubes")
    v.add_argument("--dust", type=int, default=0, metavar="N", help="dust specks drifting through each run")
    v.add_argument("--transparent", action="store_true",
                   help="transparent crystals: a dark outline around an interior brighter than the background "
                   "(darker with --polarity bright)")
    v.add_argument("--tilt", type=float, default=0.0, metavar="DEG",
                   help="the hinge line turned out of the camera axis about the vertical [degrees]")
    v.add_argument("--codec", choices=("tiff", "h264"), default="tiff",
                   help="uncompressed multi-page TIFF (default) or H.264 in an mp4, which records neither the "
                   "frame rate nor the pixel size (track then needs --fps and --pixel-size)")
    v.add_argument("--crf", type=int, default=23, metavar="Q", help="H.264 constant rate factor (default 23)")
    v.add_argument("--rest-frames", type=int, default=0, metavar="N",
                   help="frames at rest (y = 0) before the drop (default 0: the video starts at the drop, "
                   "mid-oscillation)")
    v.add_argument("--no-levitation-row", action="store_true",
                   help="do not record the levitation row in the TIFF, as a real camera's file")


def add_parser(subparsers) -> argparse.ArgumentParser:
    """Register the ``simulate`` subcommand."""
    from .model_options import add_model_arguments
    from ..twin import PRESETS

    p = subparsers.add_parser(
        "simulate",
        help="synthetic field-drop experiments (digital twin) written as a trajectory data set",
        description="Simulate field-drop experiments of the cube dimer (Gor'kov or full-wave model plus any of the "
        "docs/conventions.md section 5 effects) and write them as a docs/formats.md data set with truth.json. "
        "The air's drag computed from the dimer's geometry (effect air_damping, docs/damping.md) is on by default "
        "(--no-air-damping: off); without --effect (and --preset) it is the only effect. Noise options of 0 give "
        "exact samples.",
    )
    p.add_argument("--out", required=True, metavar="DIR", help="output data set folder (must be empty or absent)")
    p.add_argument("--runs", type=int, default=10, metavar="N", help="number of runs (default 10)")
    p.add_argument("--seed", type=int, default=0, metavar="S", help="master random seed (default 0)")
    p.add_argument("--effect", action="append", default=[], metavar="NAME:param=value,...",
                   help="switch on an effect (repeatable), e.g. pair_scattering:kappa=12000; names and "
                   "parameters of docs/conventions.md section 5; parameters not given are 0")
    p.add_argument("--preset", choices=sorted(PRESETS), default=None,
                   help="start from a documented preset (effects, pressure, drop ranges and, for paper, the dimer and the "
                   "full-wave model; docs/twin.md); options given override it and --effect entries then add to or replace "
                   "its effects. paper-like's tuned linear damping is its total damping: the air's computed drag is off there")
    p.add_argument("--duration", type=float, default=4.0, metavar="SEC", help="recorded time per run [s] (default 4)")
    p.add_argument("--fps", type=float, default=2000.0, help="camera frame rate [1/s] (default 2000)")
    p.add_argument("--noise-y", type=float, default=DEFAULT_TRACKING_NOISE["noise_y_m"], metavar="METRES",
                   help="Gaussian tracking noise on y, standard deviation [m] (default %(default)g)")
    p.add_argument("--noise-theta", type=float, default=DEFAULT_TRACKING_NOISE["noise_theta"], metavar="VALUE",
                   help="Gaussian tracking noise on theta, standard deviation (default %(default)g)")
    p.add_argument("--missing-frames", type=int, default=3, metavar="K", help="missing frames per run (default 3)")
    p.add_argument("--t-off", type=_range, default=None, metavar="MIN:MAX",
                   help="field-off time range [s] (default 0.002:0.004)")
    p.add_argument("--theta-drop", type=_range, default=None, metavar="MIN:MAX",
                   help="hinge angle range when the field drops (default -0.3:0.3)")
    p.add_argument("--thetadot-drop", type=_range, default=None, metavar="MIN:MAX",
                   help="hinge rate range when the field drops [1/s] (default -3:3)")
    p.add_argument("--side", type=float, default=None, help="cube side [m] (default 500e-6 or the preset's)")
    p.add_argument("--frequency", type=float, default=None, metavar="HZ",
                   help=f"drive frequency [Hz] (default {DEFAULT_FREQUENCY_HZ:g} or the preset's; with --side it sets "
                        "ks, which the full-wave family covers from 0.3 to 0.65)")
    p.add_argument("--pressure", type=float, default=None, metavar="PA",
                   help=f"nominal pressure amplitude [Pa] written to meta.json (default "
                        f"{DEFAULT_PRESSURE_AMPLITUDE_PA:g} or the preset's)")
    p.add_argument("--pressure-error", type=float, default=0.0, metavar="FRACTION",
                   help="draw the true pressure amplitude uniformly within +-FRACTION of the nominal one "
                   "(default 0; real data may be off by up to 0.1)")
    add_model_arguments(p, unset_default=True)
    p.add_argument("--no-air-damping", action="store_true",
                   help="leave out the air's drag computed from the dimer's geometry and the air (effect air_damping, "
                   "docs/damping.md), which every twin has by default: the inviscid dimer, damped only by --effect "
                   "(the paper-like preset has it off, its linear damping being the tuned total)")
    p.add_argument("--transducer-q", type=float, default=None, metavar="Q",
                   help="the transducer's quality factor: the field rings down when the drive stops and up when it "
                   "is back, with tau = Q / (pi f), and the acoustic forces follow p(t)^2 / p0^2 (docs/twin.md); "
                   "0: instant switching (default 0, 250 with --detuning, or the preset's; 250 is the value docs/twin.md "
                   "states); with --detuning the cavity mode's Q")
    r = p.add_argument_group("the levitator as a resonator (docs/twin.md)",
                             "The cavity mode's amplitude as a state of every run, detuned by the dimer's position; "
                             "off unless --detuning is given (every output then as without it).")
    r.add_argument("--detuning", type=float, default=None, metavar="HALF_WIDTHS",
                   help="switch the resonator on: the cavity's resonance minus the drive's frequency with the dimer at "
                   "rest, in half-widths f / (2Q) (> 0: drive below the resonance, damps y; < 0: above it, feeds y); "
                   "within +-20; the Q is --transducer-q (default 250 with --detuning); default: off, or the preset's "
                   "(window-resonator: -2.2)")
    r.add_argument("--cavity-area", type=float, default=None, metavar="M2",
                   help="the cavity's effective cross-section [m^2] (the transducer's area; mode volume = area x "
                   "lambda/2), in [1e-5, 1e-2] (default 3.14e-4: a 20 mm transducer, or the preset's)")
    p.add_argument("--mesh-size", type=float, default=None, metavar="M",
                   help="tetrahedron edge of the Gor'kov mesh model [m] (Gor'kov model only; default 0.2 x side)")
    p.add_argument("--max-step", type=float, default=5e-5, metavar="SEC", help="longest internal RK4 step [s]")
    p.add_argument("--force", action="store_true", help="replace a non-empty output folder")
    p.add_argument("--figures", default=None, metavar="DIR",
                   help="also write the twin figures (time series and spectra, phase portraits, Poincare "
                   "map, phase-difference histogram) of this data set to DIR")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    v = p.add_argument_group("video (--video)", "The frames a high-speed camera looking along the hinge line records "
                             "(orthographic side view, Gaussian point-spread function, white image noise), written "
                             "per run to OUT/video/runNN.tif with the true t, y, theta in OUT/video/runNN_truth.csv; "
                             "the frame rate is --fps. Read them back with python -m tracking track.")
    v.add_argument("--video", action="store_true", help="also write every run's camera frames")
    v.add_argument("--pixel-size", type=float, default=10e-6, metavar="M",
                   help="pixel size in the object plane [m] (default 10e-6)")
    v.add_argument("--frame-size", type=_frame_size, default=(180, 150), metavar="WxH",
                   help="frame width x height [px] (default 180x150)")
    v.add_argument("--psf", type=float, default=1.0, metavar="PX",
                   help="standard deviation of the Gaussian point-spread function [px] (default 1)")
    v.add_argument("--image-noise", type=float, default=0.02, metavar="FRACTION",
                   help="white image noise, standard deviation as a fraction of the cube/background contrast "
                   "(default 0.02)")
    v.add_argument("--bit-depth", type=int, choices=(8, 16), default=8, help="grey levels (default 8)")
    v.add_argument("--polarity", choices=("dark", "bright"), default="dark",
                   help="dark cubes on a bright background (shadowgraph, default) or bright on dark")
    v.add_argument("--lost-frames", type=int, default=0, metavar="K",
                   help="frames per run the camera loses, recorded all black (default 0)")
    _add_imperfection_arguments(p)
    add_executor_arguments(p)
    p.set_defaults(func=run)
    return p


def build_config(args: argparse.Namespace):
    """The :class:`~acousim.twin.TwinConfig` of parsed arguments (raises UserInputError): the experiment and the model
    through the shared path of every command (:func:`acousim.cli.model_options.experiment_from_args`,
    :func:`acousim.cli.model_options.model_spec_from_args`) over the preset's, the twin's own settings here."""
    from ..dynamics.effects import EffectError, EffectSet
    from ..twin import PRESETS, Camera, DropProtocol, TwinConfig, TwinError
    from .model_options import experiment_from_args, model_spec_from_args

    check_limit("--runs", args.runs, MAX_RUNS)
    if args.duration > 0 and args.fps > 0:
        frames = args.duration * args.fps
        check_limit("frames per run (--duration x --fps)", frames, MAX_FRAMES_PER_RUN)
        if args.runs > 0:
            check_limit("frames in the data set (--runs x --duration x --fps)", args.runs * frames, MAX_FRAMES,
                        "simulate fewer or shorter runs, or several data sets")
    preset = PRESETS[args.preset] if args.preset else None
    dimer = preset.dimer_settings() if preset is not None else {}
    experiment = experiment_from_args(args, dimer.get("experiment"))
    spec = model_spec_from_args(args, dimer.get("model_spec"))
    try:
        effects = EffectSet.parse(args.effect)
        if preset is not None:
            effects = preset.effects.merged(effects)
        proto0 = preset.protocol if preset is not None else DropProtocol()
        protocol = DropProtocol(
            t_off=args.t_off if args.t_off is not None else proto0.t_off,
            theta_drop=args.theta_drop if args.theta_drop is not None else proto0.theta_drop,
            thetadot_drop=args.thetadot_drop if args.thetadot_drop is not None else proto0.thetadot_drop,
        )
        camera = Camera(fps=args.fps, noise_y=args.noise_y, noise_theta=args.noise_theta,
                        missing_frames=args.missing_frames)
        return TwinConfig(
            runs=args.runs, duration=args.duration, seed=args.seed, experiment=experiment, model_spec=spec,
            pressure_error=args.pressure_error, effects=effects, protocol=protocol, camera=camera,
            max_step=args.max_step, preset=args.preset,
            air_damping=not args.no_air_damping and dimer.get("air_damping", True),
            transducer_q=_quality_factor(args, dimer), **_resonator_settings(args, dimer),
        )
    except (EffectError, TwinError) as exc:
        raise UserInputError(str(exc)) from None


def _quality_factor(args: argparse.Namespace, dimer: dict) -> float:
    """--transducer-q, else the preset's, else 250 with the resonator on and 0 (instant switching) without."""
    if args.transducer_q is not None:
        return args.transducer_q
    if "transducer_q" in dimer:
        return dimer["transducer_q"]
    from ..dynamics.switching import DEFAULT_TRANSDUCER_Q

    on = getattr(args, "detuning", None) is not None or dimer.get("cavity_detuning") is not None
    return DEFAULT_TRANSDUCER_Q if on else 0.0


def _resonator_settings(args: argparse.Namespace, dimer: dict) -> dict:
    """The TwinConfig fields of the resonator options (those given or the preset's)."""
    out = {}
    detuning = args.detuning if args.detuning is not None else dimer.get("cavity_detuning")
    if detuning is not None:
        out["cavity_detuning"] = detuning
    area = args.cavity_area if args.cavity_area is not None else dimer.get("cavity_area")
    if area is not None:
        if detuning is None:
            raise UserInputError("--cavity-area needs the resonator: give --detuning too (e.g. --detuning -1)")
        out["cavity_area"] = area
    return out


def run(args: argparse.Namespace) -> int:
    """Entry point of ``python -m acousim simulate``; returns the exit code."""
    from ..dynamics.effects import EffectSet
    from ..twin import TwinError, check_output_dir, simulate_dataset

    config = build_config(args)
    video = build_video_camera(args)
    if video is not None:
        check_limit("video frames (--runs x --duration x --fps)", config.runs * config.n_frames, MAX_VIDEO_FRAMES,
                    "render fewer or shorter runs")
    try:
        check_output_dir(args.out, args.force)
        prepare_output_dir(args.out, "--out", moved_into_place=True)
        if args.figures:
            check_output_dir(args.figures, True)
            prepare_output_dir(args.figures, "--figures", create=False)
        truth = simulate_dataset(config, args.out, executor_config(args), force=args.force,
                                 progress=not args.no_progress, video=video)
    except TwinError as exc:
        raise UserInputError(str(exc)) from None
    print(f"wrote {config.runs} runs to {args.out} (true pressure amplitude {truth['pressure_amplitude_pa']:.1f} Pa, "
          f"effects: {EffectSet.from_dict(truth['effects']).describe()})" + (f"; camera frames in {args.out}/video/" if video else ""),
          file=sys.stderr)
    if truth["folded_runs"]:
        print(f"{truth['folded_runs']} of {config.runs} runs folded (theta reached +-1): recorded up to the fold, "
              "the event in truth.json", file=sys.stderr)
    if truth.get("escaped_runs"):
        print(f"{truth['escaped_runs']} of {config.runs} runs left the trap: recorded up to the escape, the event in "
              "truth.json", file=sys.stderr)
    if args.figures:
        from ..twin import write_twin_figures

        paths = write_twin_figures(args.out, args.figures)
        print(f"wrote {len(paths)} figures to {args.figures}", file=sys.stderr)
    return 0
