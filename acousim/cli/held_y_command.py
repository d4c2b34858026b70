"""``python -m acousim held-y``: the held-y attractor map (docs/twin.md, "The held-y attractor map")."""
from __future__ import annotations

import argparse
import sys

from cubedimer.cli import UserInputError, add_executor_arguments, executor_config, prepare_output_dir
from cubedimer.meta import DEFAULT_FREQUENCY_HZ

from .atlas_command import parse_dimers, parse_grid

__all__ = ["add_parser"]

FAMILY_DIMERS = ",".join(f"{s}e-6:{g}" for s in (400, 500, 600, 700) for g in (0.01, 0.015, 0.02, 0.03, 0.05))


def add_parser(subparsers) -> argparse.ArgumentParser:
    p = subparsers.add_parser(
        "held-y",
        help="held-y attractor map: where the hinge settles with y held on a trap oscillation of amplitude A",
        description="For every dimer (full-wave family, the air's computed damping), pressure p0 and amplitude A, "
        "hold y on the trap's exact oscillation whose lowest point is A below the equilibrium, integrate the hinge "
        "from a grid of starts, classify where each settles (the suite's one classifier) and compute the Floquet "
        "multipliers of the locked orbits. Writes held_y.csv (one row per cell), held_y.json (every run) and the "
        "class map and 2 f_y figures over (f_theta / f_y, A). Resumable: rerun the same command.",
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    p.add_argument("--out", required=True, metavar="DIR", help="output folder (resumed if it holds this map)")
    p.add_argument("--dimers", default=FAMILY_DIMERS, metavar="SIDE:G/S,...",
                   help="dimers: cube side [m] and hinge gap over side, inside the full-wave family")
    p.add_argument("--pressures", default="3000,4500,6000", metavar="PA,...", help="pressure amplitudes p0 [Pa]")
    p.add_argument("--amplitudes", default="50e-6,100e-6,200e-6,300e-6,500e-6", metavar="M,... or MIN:MAX:N",
                   help="depths A of the held y orbit's lowest point below the equilibrium [m], in (0, 1e-3]")
    p.add_argument("--theta-starts", default="-0.4:0.4:5", metavar="MIN:MAX:N", help="hinge angles at the start")
    p.add_argument("--thetadot-starts", default="-30,0,30", metavar="LIST", help="hinge rates at the start [1/s]")
    p.add_argument("--settle-periods", type=int, default=200, help="periods of y before the classified part")
    p.add_argument("--analysed-periods", type=int, default=104, help="periods of y classified")
    p.add_argument("--frequency", type=float, default=DEFAULT_FREQUENCY_HZ, help="drive frequency [Hz]")
    p.add_argument("--no-figures", action="store_true", help="write the tables only")
    p.add_argument("--force", action="store_true", help="discard a map with other settings in --out")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    add_executor_arguments(p, "One task is one cell (a dimer, a pressure and an amplitude, every hinge start).")
    p.set_defaults(func=run)
    return p


def run(args: argparse.Namespace) -> int:
    from ..atlas.field_drops import AtlasError
    from ..atlas.held_y import HeldYConfig, run_held_y_map

    try:
        config = HeldYConfig(dimers=parse_dimers(args.dimers), pressures_pa=parse_grid(args.pressures, "--pressures"),
                             amplitudes_m=parse_grid(args.amplitudes, "--amplitudes"),
                             theta_starts=parse_grid(args.theta_starts, "--theta-starts"),
                             thetadot_starts=parse_grid(args.thetadot_starts, "--thetadot-starts"),
                             frequency_hz=args.frequency, settle_periods=args.settle_periods,
                             analysed_periods=args.analysed_periods)
    except AtlasError as exc:
        raise UserInputError(str(exc)) from None
    out = prepare_output_dir(args.out, "--out", create=False)
    try:
        result = run_held_y_map(config, out, executor_config(args), progress=not args.no_progress,
                                figures=not args.no_figures, force=args.force)
    except AtlasError as exc:
        raise UserInputError(str(exc)) from None
    rows = result["summary"]
    both = [r for r in rows if r["two_phase_classes"]]
    print(f"wrote the held-y map of {len(rows)} cells to {args.out}: both phase classes in {len(both)}, a third "
          f"class in {sum(r['third_class'] for r in rows)}, a 2 f_y line >= 5 % in {sum(r['reaches_2fy'] for r in rows)}",
          file=sys.stderr)
    return 0
