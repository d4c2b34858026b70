"""Where the calibrated gap's small common bias comes from: the hinge states at which the model is evaluated.

The gap profile compares the measured theta with the double integral of the model's hinge acceleration,
evaluated at theta and thetadot smoothed over half a hinge period (Savitzky-Golay, order 5;
fitting.integral_form.column_states).  This script calibrates the gap of one full-wave twin case with the
state smoother replaced, on noise-free data at a high frame rate (where the double integral's trapezoid
error and the tracking noise vanish) and on data with the study's tracking noise:

* ``sg5``: the diagnosis as it is;
* ``sg7``: order 7 on the same window (less attenuation at the hinge frequency, more noise gain);
* ``short``: order 5 on 0.6 of the window;
* ``exact``: the raw theta and its fourth-order central difference (only meaningful on noise-free data).

    python docs/scripts/gap_bias_states.py --seed 51 --side 450e-6 --gap-ratio 0.0409

Prints one row per (data, smoother): the gap's and the pressure's relative errors and the gap's standard
error.  docs/fullwave.md quotes its output.
"""
from __future__ import annotations

import argparse
import contextlib
import tempfile
from pathlib import Path

import numpy as np

import fitting.derivatives as derivatives
from acousim.models import ExperimentConditions, dynamic_model
from validation.blind import TwinLikeConfig, write_twin_like_dataset
from validation.diagnosis import DiagnoseConfig, diagnose_dataset
from acousim.models import ModelSpec

EFFECTS = {"linear_damping": {"gamma_y": 0.5, "gamma_theta": 2.0}}
_SG = derivatives.smooth_long_window


def _exact(x, dt, window, polyorder):
    x = np.asarray(x, float)
    d = np.gradient(x, dt)
    d[2:-2] = (-x[4:] + 8 * x[3:-1] - 8 * x[1:-3] + x[:-4]) / (12 * dt)
    return x, d


SMOOTHERS = {
    "sg5": _SG,
    "sg7": lambda x, dt, window, polyorder: _SG(x, dt, window, 7),
    "short": lambda x, dt, window, polyorder: _SG(x, dt, int(0.6 * window) | 1, polyorder),
    "exact": _exact,
}


@contextlib.contextmanager
def hinge_state_smoother(name: str):
    """Substitute the long-window smoother that column_states uses (it looks it up at every call)."""
    derivatives.smooth_long_window = SMOOTHERS[name]
    try:
        yield
    finally:
        derivatives.smooth_long_window = _SG


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--seed", type=int, default=51)
    p.add_argument("--side", type=float, default=450e-6, help="cube side [m]")
    p.add_argument("--gap-ratio", type=float, default=0.0409, help="true gap / side")
    args = p.parse_args()
    fm = dynamic_model("fullwave", ExperimentConditions(side_length_m=args.side, gap_m=args.gap_ratio * args.side))
    g_true = args.gap_ratio * args.side
    cases = {"noise-free, 8000 fps": dict(noise=(1e-12, 1e-8), fps=8000.0, effects={}),
             "tracking noise 1 um / 0.005, 2000 fps, linear damping": dict(noise=(1e-6, 0.005), fps=2000.0,
                                                                          effects=EFFECTS)}
    print("| data | hinge states | gap error | std | p0 error |")
    print("|---|---|---|---|---|")
    for label, kw in cases.items():
        out = Path(tempfile.mkdtemp())
        truth = write_twin_like_dataset(out, TwinLikeConfig(runs=8, duration=3.0, seed=args.seed, pressure_error=0.05,
                                                            force_model=fm, **kw))
        for smoother in SMOOTHERS:
            if smoother == "exact" and kw["noise"][1] > 1e-6:
                continue
            with hinge_state_smoother(smoother):
                d = diagnose_dataset(out, DiagnoseConfig(long_time=False), progress=False, spec=ModelSpec("fullwave"))
            cal = d.calibration
            print(f"| {label} | {smoother} | {100 * (cal['gap_m'] / g_true - 1):+.3f} % | "
                  f"{100 * cal['gap_std_m'] / g_true:.3f} % | "
                  f"{100 * (cal['pressure_amplitude_pa'] / truth['pressure_amplitude_pa'] - 1):+.3f} % |", flush=True)


if __name__ == "__main__":
    main()
