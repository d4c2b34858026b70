"""``python -m acousim sweep``: the static force/torque sweep of any registered force model (docs/formats.md)."""
from __future__ import annotations

import argparse
import sys

import numpy as np

from cubedimer.cli import UserInputError, check_limit, prepare_output_dir, prepare_output_file
from cubedimer.meta import (DEFAULT_FREQUENCY_HZ, DEFAULT_PARTICLE_DENSITY, DEFAULT_PRESSURE_AMPLITUDE_PA, DEFAULT_SIDE_LENGTH_M,
                            check_meta_value)

from ..models import force_model_type
from .model_options import add_model_arguments, conditions_from_args, static_model_from_args

__all__ = ["add_parser", "parse_range", "run_sweep", "MAX_AXIS_POINTS", "MAX_GRID_POINTS"]

DEFAULT_THETA = "-0.9:0.9:41"
DEFAULT_Y = "-200e-6:200e-6:41"

#: Most points per grid axis.
MAX_AXIS_POINTS = 100_000
#: Most (theta, y) points of a sweep: about 3 minutes at the default mesh and a 100 MB CSV.
MAX_GRID_POINTS = 1_000_000


def parse_range(text: str, name: str) -> np.ndarray:
    """Parse ``START:STOP:N`` into ``numpy.linspace(START, STOP, N)``; N = 1 needs START == STOP."""
    parts = text.split(":")
    if len(parts) != 3:
        raise UserInputError(f"--{name} {text!r}: expected START:STOP:N")
    try:
        start, stop = float(parts[0]), float(parts[1])
        n = int(parts[2])
    except ValueError:
        raise UserInputError(f"--{name} {text!r}: START and STOP must be numbers and N an integer") from None
    if not (np.isfinite(start) and np.isfinite(stop)):
        raise UserInputError(f"--{name} {text!r}: START and STOP must be finite")
    if start > stop:
        raise UserInputError(f"--{name} {text!r}: START {start:g} is greater than STOP {stop:g}")
    if n < 1 or (n == 1 and start != stop) or (n > 1 and start == stop):
        raise UserInputError(f"--{name} {text!r}: N must be >= 2 for START < STOP (or 1 with START == STOP)")
    if n > MAX_AXIS_POINTS:
        raise UserInputError(f"--{name} {text!r}: N = {n} is too many points (at most {MAX_AXIS_POINTS:,})")
    return np.linspace(start, stop, n)


def _positive(name: str, value: float | None, unit: str) -> None:
    if value is not None and (not np.isfinite(value) or value <= 0):
        raise UserInputError(f"--{name} must be positive, got {value:g} {unit}")


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        "sweep",
        help="static force/torque sweep over (theta, y)",
        description=(
            "Evaluate the Gor'kov volume-integral model of the cube dimer at zero velocity on a (theta, y) "
            "grid and write a CSV with the columns theta, y, potential [J], force_z [N], q_y [N], "
            "q_theta [N m], yddot [m/s^2], thetaddot [1/s^2], z_com [m]. y is the height of the centre "
            "of mass above the simulated equilibrium height Z_eq (docs/conventions.md section 2). Optionally "
            "write the figures (restoring force and torque, thetaddot map), the static coefficients "
            "(least squares on the velocity-free cubic monomials) and a rendering of the posed mesh. "
            "With --model fullwave the full-wave (boundary-element) model is swept instead (docs/fullwave.md): the "
            "direct-solve table of the default dimer, or any dimer of the table family (ks = k x side 0.28-0.65, "
            "--gap 0.01-0.05 x side) scaled exactly in side, frequency and pressure; |theta| <= 0.9, no potential "
            "column, the interpolation accuracy in the CSV header."
        ),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    p.add_argument("--theta", default=DEFAULT_THETA, metavar="START:STOP:N", help="bend grid, inside (-1, 1)")
    p.add_argument("--y", default=DEFAULT_Y, metavar="START:STOP:N", help="height grid [m] relative to Z_eq")
    add_model_arguments(p)
    p.add_argument("--side", type=float, default=DEFAULT_SIDE_LENGTH_M, help="cube side [m]")
    p.add_argument("--side-b", type=float, default=None, help="side of the second cube [m] (default: equal)")
    p.add_argument("--pressure", type=float, default=DEFAULT_PRESSURE_AMPLITUDE_PA, help="pressure amplitude p0 [Pa]")
    p.add_argument("--frequency", type=float, default=DEFAULT_FREQUENCY_HZ, help="drive frequency [Hz]")
    p.add_argument("--density", type=float, default=DEFAULT_PARTICLE_DENSITY, help="particle density [kg/m^3]")
    p.add_argument("--mesh-size", type=float, default=None,
                   help="target tetrahedron edge length [m] (Gor'kov model; default: 0.2 x side)")
    p.add_argument("--quadrature-degree", type=int, default=2, help="quadrature degree per tetrahedron (>= 2)")
    p.add_argument("--out", required=True, help="output CSV file")
    p.add_argument("--plots", default=None, metavar="DIR", help="also write the sweep figures (PNG) into DIR")
    p.add_argument("--coefficients", default=None, metavar="FILE", help="also write the static coefficients (JSON)")
    p.add_argument("--fit-theta-max", type=float, default=0.3, help="fitting box for --coefficients: |theta| <=")
    p.add_argument("--fit-y-max", type=float, default=150e-6, help="fitting box for --coefficients: |y| <= [m]")
    p.add_argument("--render", default=None, metavar="PNG", help="also render the posed mesh coloured by u (PNG)")
    p.add_argument("--render-theta", type=float, default=0.3, help="bend of the rendered pose")
    p.add_argument("--quiet", action="store_true", help="no progress bar or summary")
    p.set_defaults(func=run_sweep)


def run_sweep(args: argparse.Namespace) -> int:
    """Validate every argument, then compute and write; nothing is written on a bad argument."""
    theta = parse_range(args.theta, "theta")
    y = parse_range(args.y, "y")
    if np.any(np.abs(theta) >= 1):
        raise UserInputError(f"--theta {args.theta!r}: theta must lie inside (-1, 1)")
    check_limit("--theta N x --y N", theta.size * y.size, MAX_GRID_POINTS, "sweep a coarser grid or split it into parts")
    for name, unit in (("side", "m"), ("side_b", "m"), ("pressure", "Pa"), ("frequency", "Hz"), ("density", "kg/m^3"), ("mesh_size", "m")):
        _positive(name.replace("_", "-"), getattr(args, name), unit)
    for name, key in (("side", "side_length_m"), ("side_b", "side_length_m"), ("pressure", "pressure_amplitude_pa"),
                      ("frequency", "frequency_hz"), ("density", "particle_density_kg_m3")):
        if getattr(args, name) is not None:
            check_meta_value(key, getattr(args, name), "--" + name.replace("_", "-"))
    if args.quadrature_degree < 2:
        raise UserInputError("--quadrature-degree must be at least 2")
    if not -1 < args.render_theta < 1:
        raise UserInputError("--render-theta must lie inside (-1, 1)")
    # every output is checked before the model is built and the grid computed
    for option in ("out", "coefficients", "render"):
        if getattr(args, option):
            prepare_output_file(getattr(args, option), "--" + option)
    if args.plots:
        prepare_output_dir(args.plots, "--plots", create=False)

    from ..statics.sweep import fit_static_coefficients, static_sweep, taylor_coefficients

    if args.render is not None and "render" not in force_model_type(args.model).capabilities:
        raise UserInputError(f"--render draws the Gor'kov volume mesh; it does not apply to --model {args.model}")
    model = static_model_from_args(args, conditions_from_args(
        args, side_b_m=args.side_b, mesh_size_m=args.mesh_size,
        quadrature_degree=args.quadrature_degree if args.quadrature_degree != 2 else None))
    if np.any(np.abs(theta) > model.theta_max):
        raise UserInputError(f"--theta {args.theta!r}: the {args.model} model covers |theta| <= {model.theta_max:g}")
    z_eq = model.equilibrium_height
    record = model.record()
    size_note = (f"{record['n_tetrahedra']} tetrahedra" if "n_tetrahedra" in record
                 else record.get("table_source", "full-wave table"))
    result = static_sweep(model, theta, y, progress=not args.quiet)
    result.to_csv(args.out)
    if not args.quiet:
        print(f"sweep: {len(theta)} x {len(y)} points, {size_note}, Z_eq = {z_eq * 1e6:.1f} um -> {args.out}", file=sys.stderr)
    if args.coefficients:
        coefs = fit_static_coefficients(result, theta_max=args.fit_theta_max, y_max=args.fit_y_max, taylor=taylor_coefficients(model))
        coefs.to_json(args.coefficients)
        if not args.quiet:
            b = coefs.coefficients["thetaddot"]["y^2*theta"]
            e = coefs.std_errors["thetaddot"]["y^2*theta"]
            print(f"static coefficients -> {args.coefficients}; thetaddot y^2*theta = {b:.4g} +- {e:.2g} 1/(m^2 s^2)", file=sys.stderr)
    if args.plots:
        from ..statics.plots import save_sweep_figures

        paths = save_sweep_figures(result, args.plots)
        if not args.quiet:
            print("figures: " + ", ".join(str(p) for p in paths), file=sys.stderr)
    if args.render:
        from ..gorkov.render import render_dimer

        render_dimer(model, args.render_theta, 0.0, args.render)
        if not args.quiet:
            print(f"rendering -> {args.render}", file=sys.stderr)
    return 0
