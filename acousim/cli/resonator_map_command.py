"""``python -m acousim resonator-map``: y's growth and self-sustained motion over the cavity's (Q, detuning, area)."""
from __future__ import annotations

import argparse
import sys

from cubedimer.cli import UserInputError, add_executor_arguments, executor_config, prepare_output_dir
from cubedimer.meta import DEFAULT_FREQUENCY_HZ

from .atlas_command import parse_grid

__all__ = ["add_parser"]


def add_parser(subparsers) -> argparse.ArgumentParser:
    from ..atlas.resonator_map import DEFAULT_DIMERS

    p = subparsers.add_parser(
        "resonator-map",
        help="the levitator as a resonator: y's growth rate, threshold and self-sustained motion over (Q, detuning, "
        "cavity area)",
        description="For every dimer (the air's computed damping), cavity quality factor Q, cavity area and detuning, "
        "compare y's growth rate from the linear theory (exact quartic root and first-order formula) with the "
        "simulation of the dimer and its cavity mode, and follow a larger start to its fate (decayed, limit cycle, "
        "escaped, folded). Writes resonator_map.csv, resonator_map.json and resonator_map.png (docs/twin.md, "
        "'The levitator as a resonator'). Resumable: rerun the same command.",
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    p.add_argument("--out", required=True, metavar="DIR", help="output folder (resumed if it holds this map)")
    p.add_argument("--dimers", default=",".join(DEFAULT_DIMERS), metavar="SPEC,...",
                   help="dimers: gorkov:SIDE:PRESSURE or fullwave:SIDE:GAP_RATIO:PRESSURE (m, -, Pa; full-wave "
                   "dimers inside the table family)")
    p.add_argument("--qualities", default="100,250,500", metavar="Q,...", help="cavity quality factors Q (> 0)")
    p.add_argument("--areas", default="3e-5,1e-4,3.1416e-4", metavar="M2,...",
                   help="effective cavity cross-sections A_cav [m^2], in [1e-5, 1e-2] (3.14e-4: a 20 mm transducer)")
    p.add_argument("--detunings", default="-4:1:11", metavar="MIN:MAX:N or LIST",
                   help="detunings x = (f_c - f_d) / (f / 2Q) [half-widths], within +-20 (x < 0: drive above the "
                   "resonance)")
    p.add_argument("--duration", type=float, default=40.0, metavar="SEC", help="span of the larger start's run [s]")
    p.add_argument("--start-amplitude", type=float, default=30e-6, metavar="M", help="the larger start's y [m]")
    p.add_argument("--frequency", type=float, default=DEFAULT_FREQUENCY_HZ, metavar="HZ", help="drive frequency [Hz]")
    p.add_argument("--no-figures", action="store_true", help="write the tables only")
    p.add_argument("--force", action="store_true", help="discard a map with other settings in --out")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    add_executor_arguments(p, "One task is one cell (a dimer, a Q and an area, every detuning).")
    p.set_defaults(func=run)
    return p


def run(args: argparse.Namespace) -> int:
    from ..atlas.field_drops import AtlasError
    from ..atlas.resonator_map import ResonatorMapConfig, run_resonator_map

    try:
        config = ResonatorMapConfig(dimers=tuple(s.strip() for s in args.dimers.split(",") if s.strip()),
                                    quality_factors=parse_grid(args.qualities, "--qualities"),
                                    areas_m2=parse_grid(args.areas, "--areas"),
                                    detunings=parse_grid(args.detunings, "--detunings"),
                                    duration=args.duration, start_amplitude=args.start_amplitude,
                                    frequency_hz=args.frequency)
    except AtlasError as exc:
        raise UserInputError(str(exc)) from None
    out = prepare_output_dir(args.out, "--out", create=False)
    try:
        result = run_resonator_map(config, out, executor_config(args), progress=not args.no_progress,
                                   figures=not args.no_figures, force=args.force)
    except AtlasError as exc:
        raise UserInputError(str(exc)) from None
    rows = result["rows"]
    counts = {o: sum(r["outcome"] == o for r in rows) for o in sorted({r["outcome"] for r in rows})}
    print(f"wrote the resonator map of {len(rows)} settings to {args.out}: " +
          ", ".join(f"{k} {v}" for k, v in counts.items()), file=sys.stderr)
    return 0
