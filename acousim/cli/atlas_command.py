"""``python -m acousim atlas``: where field drops of full-wave dimers settle (docs/twin.md, "The attractor atlas")."""
from __future__ import annotations

import argparse
import sys

import numpy as np

from cubedimer.cli import UserInputError, add_executor_arguments, executor_config, prepare_output_dir
from cubedimer.meta import DEFAULT_FREQUENCY_HZ

__all__ = ["add_parser", "parse_dimers", "parse_grid"]


def parse_grid(text: str, option: str) -> tuple[float, ...]:
    """``MIN:MAX:N`` (N evenly spaced values) or a comma-separated list, as floats; one-line error naming ``option``."""
    try:
        if ":" in text:
            lo, hi, n = text.split(":")
            n = int(n)
            if n < 1:
                raise ValueError
            return tuple(float(v) for v in np.linspace(float(lo), float(hi), n))
        return tuple(float(v) for v in text.split(",") if v.strip())
    except ValueError:
        raise UserInputError(f"{option} {text!r}: expected MIN:MAX:N or comma-separated numbers") from None


def parse_dimers(text: str):
    """``SIDE:GAP_RATIO,...`` (side in metres, gap over side) as :class:`acousim.atlas.field_drops.AtlasDimer` s."""
    from ..atlas.field_drops import AtlasDimer, AtlasError

    out = []
    for item in filter(None, (s.strip() for s in text.split(","))):
        parts = item.split(":")
        try:
            if len(parts) != 2:
                raise ValueError
            out.append(AtlasDimer(float(parts[0]), float(parts[1])))
        except AtlasError as exc:
            raise UserInputError(str(exc)) from None
        except ValueError:
            raise UserInputError(f"--dimers {item!r}: expected SIDE:GAP_RATIO, e.g. 500e-6:0.03") from None
    return tuple(out)


def add_parser(subparsers) -> argparse.ArgumentParser:
    p = subparsers.add_parser(
        "atlas",
        help="attractor atlas: where field drops of full-wave dimers settle",
        description="Drop the field for t_off, with the hinge at theta_drop and the dimer at rest, on the full-wave "
        "model of each dimer (table family) with the air's computed damping, and classify where each run settles "
        "(escaped, folded, locked in phase / anti-phase / quadrature, independent, theta at rest; the hinge's "
        "amplitude class, its 2 f_y line, long-lived or not). Writes atlas.csv, atlas.json, a basin map per dimer "
        "and the phase histogram. Resumable: rerun the same command and finished cells are kept.",
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    p.add_argument("--out", required=True, metavar="DIR", help="output folder (resumed if it holds this atlas)")
    p.add_argument("--dimers", default="500e-6:0.015,500e-6:0.05,700e-6:0.05", metavar="SIDE:G/S,...",
                   help="dimers: cube side [m] and hinge gap over side, inside the full-wave family")
    p.add_argument("--t-off", default="5e-3:20e-3:16", metavar="MIN:MAX:N", help="drop durations [s]")
    p.add_argument("--theta-drop", default="-0.2:0.2:9", metavar="MIN:MAX:N", help="hinge angles at the drop [-]")
    p.add_argument("--pressure", type=float, default=6000.0, help="pressure amplitude p0 [Pa]")
    p.add_argument("--frequency", type=float, default=DEFAULT_FREQUENCY_HZ, help="drive frequency [Hz]")
    p.add_argument("--duration", type=float, default=8.0, help="recorded time after the field is back on [s]; the second half is classified")
    p.add_argument("--sample-rate", type=float, default=1000.0, help="samples per second of the classified motion")
    p.add_argument("--transducer-q", type=float, default=0.0, metavar="Q",
                   help="the transducer's quality factor: the field rings down and up with tau = Q / (pi f) and the "
                   "forces follow p(t)^2 (docs/twin.md); 0 (default): instant switching")
    p.add_argument("--no-figures", action="store_true", help="write the table only")
    p.add_argument("--force", action="store_true", help="discard an atlas with other settings in --out")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    add_executor_arguments(p, "One task is one cell (one drop).")
    p.set_defaults(func=run)
    return p


def run(args: argparse.Namespace) -> int:
    from ..atlas.field_drops import AtlasConfig, AtlasError, run_atlas

    try:
        config = AtlasConfig(dimers=parse_dimers(args.dimers), t_off=parse_grid(args.t_off, "--t-off"),
                             theta_drop=parse_grid(args.theta_drop, "--theta-drop"),
                             pressure_amplitude_pa=args.pressure, frequency_hz=args.frequency,
                             duration=args.duration, sample_rate=args.sample_rate, transducer_q=args.transducer_q)
    except AtlasError as exc:
        raise UserInputError(str(exc)) from None
    out = prepare_output_dir(args.out, "--out", create=False)
    try:
        result = run_atlas(config, out, executor_config(args), progress=not args.no_progress,
                           figures=not args.no_figures, force=args.force)
    except AtlasError as exc:
        raise UserInputError(str(exc)) from None
    for label, d in result["dimers"].items():
        counts = ", ".join(f"{k} {v}" for k, v in d["counts"].items() if v)
        print(f"{label}: {counts}", file=sys.stderr)
    print(f"wrote the atlas of {len(result['cells'])} drops to {out}", file=sys.stderr)
    return 0
