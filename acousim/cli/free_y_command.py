"""``python -m acousim free-y-map``: periodic orbits of the dimer and its cavity mode with y free (docs/twin.md,
"The free-y attractor map")."""
from __future__ import annotations

import argparse
import sys

from cubedimer.cli import UserInputError, add_executor_arguments, executor_config, prepare_output_dir
from cubedimer.meta import DEFAULT_FREQUENCY_HZ, DEFAULT_PRESSURE_AMPLITUDE_PA

from .atlas_command import parse_dimers, parse_grid

__all__ = ["add_parser"]

#: The default dimers: the 500 um side at four hinge gaps (r = f_theta / f_y = 0.95, 1.11, 1.20, 1.32 at 3 kPa).
DEFAULT_DIMERS = "500e-6:0.05,500e-6:0.03,500e-6:0.02,500e-6:0.01"


def add_parser(subparsers) -> argparse.ArgumentParser:
    p = subparsers.add_parser(
        "free-y-map",
        help="free-y attractor map: periodic orbits of y, the hinge and the cavity mode, with Floquet multipliers",
        description="For every dimer (full-wave family, the air's computed damping), cavity quality factor Q and "
        "detuning, run the dimer with its cavity mode (y free) from a grid of starts, refine the periodic orbit each "
        "settled run is near by shooting (Newton on x(T) - x(0) with the period unknown, ydot held at y's lowest "
        "point), and give each orbit its Floquet multipliers (the trivial one is a check), its phase class (the "
        "suite's classifier), theta's 2 f_y line and its life in cycles. Writes free_y.csv (one row per cell), "
        "free_y.json (every run and orbit) and free_y_map.png. Resumable: rerun the same command.",
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    p.add_argument("--out", required=True, metavar="DIR", help="output folder (resumed if it holds this map)")
    p.add_argument("--dimers", default=DEFAULT_DIMERS, metavar="SIDE:G/S,...",
                   help="dimers: cube side [m] and hinge gap over side, inside the full-wave family")
    p.add_argument("--qualities", default="200,250,300", metavar="Q,...", help="cavity quality factors Q (> 0)")
    p.add_argument("--detunings", default="-7,-6,-5.5,-5,-4.5,-4", metavar="LIST or MIN:MAX:N",
                   help="detunings x = (f_c - f_d) / (f / 2Q) [half-widths], within +-20 (x < 0: drive above the "
                   "resonance)")
    p.add_argument("--area", type=float, default=3e-5, metavar="M2",
                   help="the cavity's effective cross-section A_cav [m^2], in [1e-5, 1e-2]")
    p.add_argument("--pressure", type=float, default=DEFAULT_PRESSURE_AMPLITUDE_PA, metavar="PA", help="pressure amplitude p0 [Pa]")
    p.add_argument("--amplitudes", default="50e-6,150e-6", metavar="M,...",
                   help="start depths of y below the equilibrium [m]")
    p.add_argument("--theta-starts", default="-0.3,0,0.3", metavar="LIST", help="hinge angles at the start")
    p.add_argument("--settle-time", type=float, default=16.0, metavar="SEC", help="run before the shooting [s]")
    p.add_argument("--frequency", type=float, default=DEFAULT_FREQUENCY_HZ, help="drive frequency [Hz]")
    p.add_argument("--no-figures", action="store_true", help="write the tables only")
    p.add_argument("--force", action="store_true", help="discard a map with other settings in --out")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    add_executor_arguments(p, "One task is one cell (a dimer, a Q and a detuning, every start).")
    p.set_defaults(func=run)
    return p


def run(args: argparse.Namespace) -> int:
    from ..atlas.field_drops import AtlasError
    from ..atlas.free_y import FreeYConfig, run_free_y_map

    try:
        config = FreeYConfig(dimers=parse_dimers(args.dimers), quality_factors=parse_grid(args.qualities, "--qualities"),
                             detunings=parse_grid(args.detunings, "--detunings"), pressure_pa=args.pressure,
                             area_m2=args.area, amplitudes_m=parse_grid(args.amplitudes, "--amplitudes"),
                             theta_starts=parse_grid(args.theta_starts, "--theta-starts"),
                             settle_time=args.settle_time, frequency_hz=args.frequency)
    except AtlasError as exc:
        raise UserInputError(str(exc)) from None
    out = prepare_output_dir(args.out, "--out", create=False)
    try:
        result = run_free_y_map(config, out, executor_config(args), progress=not args.no_progress,
                                figures=not args.no_figures, force=args.force)
    except AtlasError as exc:
        raise UserInputError(str(exc)) from None
    rows = result["summary"]
    total = lambda k: sum(r[k] for r in rows)  # noqa: E731
    print(f"wrote the free-y map of {len(rows)} cells to {args.out}: {total('orbits')} periodic orbits, "
          f"{total('stable')} stable ({total('stable_in_phase')} in phase, {total('stable_anti_phase')} anti-phase, "
          f"{total('stable_other')} other), {total('unstable')} unstable", file=sys.stderr)
    return 0
