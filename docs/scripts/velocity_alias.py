"""How far the paper's velocity couplings are from position terms on locked orbits (docs/twin.md, the refit):
python docs/scripts/velocity_alias.py SIDE G/S P0 A     e.g. 500e-6 0.02 3000 100e-6

On the held-y orbits of one map cell (python -m acousim held-y), for every distinct locked orbit: the share of the
columns y*thetadot^2 (b5) and y*ydot*thetadot (b6) that the columns y (b2), y^2*theta (b3) and y*theta^2 explain
(R^2 of the least squares over one settled stretch of four periods of y), and the same with all the paper's other
hinge terms (1, theta, y, y^2*theta, thetadot) plus y*theta^2.  R^2 near 1: a fit can trade the velocity coupling for
position terms at almost no cost in the residual.

Then the oracle alias z of b5 and b6 (fitting.uncertainty.oracle.oracle_aliases: sqrt of the noise-free residual sum of squares
left when the term is replaced by its best one-for-one rival in the cubic library, the other terms refitted, over
the tracking noise), with what the default fit would use: the integral form's windows of 0.75 periods of theta's
dominant frequency, and the tracking noise the twin's camera adds (sigma_y = 1 um, sigma_theta = 0.005 at 2000 fps;
the fit estimates it from such data by fourth differences, as their meta.json records no tracking block).  The run is the locked orbit itself, 4 s at 2000 fps (the
length of the window data set's runs); the support is the paper's hinge equation (b0-b6) plus y*theta^2, with the
coefficients of its least squares on the orbit's exact thetaddot ("fitted") or with b5, b6 at the paper's scale
(fitting.synthetic.paper_reduced_model: 5e3 1/m and 8e6 1/m^2).  The alias z of a term is proportional to its own
coefficient, and does not depend on the other terms' coefficients.
"""
import math
import sys

import numpy as np

from acousim.atlas.field_drops import atlas_dynamics, settled_outcome
from acousim.atlas.held_y import HINGE_BOX, integrate_held, held_y_acceleration, held_y_arguments, held_y_orbits
from fitting.model import PolynomialModel
from fitting.uncertainty.oracle import NoiseLevels, OracleRun, oracle_aliases

FPS, DURATION, NOISE = 2000.0, 4.0, NoiseLevels(1e-6, 0.005, source="the twin camera's defaults")
SUPPORT = ("1", "theta", "y", "y^2*theta", "thetadot", "y*thetadot^2", "y*ydot*thetadot", "y*theta^2")
PAPER_SCALE = {"y*thetadot^2": 5.0e3, "y*ydot*thetadot": 8.0e6}

side, gap_ratio, p0, amp = (float(v) for v in sys.argv[1:5])
dyn = atlas_dynamics(side, gap_ratio, p0, 45_650.0)
starts = [(th, 0.0) for th in (-0.4, -0.2, 0.0, 0.15, 0.3, 0.4)]
n_per = 40
t, states, n_valid, status, _, args, _ = held_y_orbits(dyn, amp, starts, 304, n_per)
y_eq = held_y_arguments(dyn)[1][0]


def r_squared(target, columns):
    a = np.column_stack(columns)
    resid = target - a @ np.linalg.lstsq(a, target, rcond=None)[0]
    return 1.0 - (resid @ resid) / (target @ target)


def locked_orbits():
    """(start index, settled outcome) of each distinct locked orbit the hinge starts reached."""
    seen = set()
    for k in range(len(starts)):
        if status[k]:
            continue
        c = settled_outcome(t[-208 * n_per:], states[k, -208 * n_per:])
        key = (c["outcome"], c["lock_ratio"], round(c["amp_theta"], 2))
        if c["outcome"].startswith("locked-") and key not in seen:
            seen.add(key)
            yield k, c


for k, c in locked_orbits():
    y, yd, th, thd = states[k, -4 * n_per:].T
    y = y - y_eq
    three = [y, th * y ** 2, th ** 2 * y]
    paper = [np.ones_like(y), th, y, th * y ** 2, thd, th ** 2 * y]
    for name, col in (("b5 y*thetadot^2", y * thd ** 2), ("b6 y*ydot*thetadot", y * yd * thd)):
        print(f"{side * 1e6:.0f} um, g/s {gap_ratio:g}, {p0 / 1e3:g} kPa, A {amp * 1e6:.0f} um, {c['outcome']} "
              f"{c['lock_ratio']} (amplitude {c['amp_theta']:.3f}): {name}: R^2 {r_squared(col, three):.4f} against "
              f"y, y^2*theta, y*theta^2; {r_squared(col, paper):.4f} against b0-b4 and y*theta^2")


def oracle_alias_z(x_end):
    """(alias term, alias z) of b5 and b6 on the orbit through ``x_end``, fitted and at the paper's scale."""
    n = int(DURATION * FPS) + 1
    substeps = int(math.ceil(1.0 / FPS / 1e-4))
    out = np.empty((n, 4))
    m, _ = integrate_held(args, x_end, 1.0 / FPS / substeps, substeps, n, *HINGE_BOX, out)
    traj = out[:m].copy()
    acc = np.array([held_y_acceleration(0.0, *x, args)[1] for x in traj])
    traj[:, 0] -= y_eq
    y, yd, th, thd = traj.T
    cols = {"1": np.ones_like(y), "theta": th, "y": y, "y^2*theta": y ** 2 * th, "thetadot": thd,
            "y*thetadot^2": y * thd ** 2, "y*ydot*thetadot": y * yd * thd, "y*theta^2": y * th ** 2}
    coef = np.linalg.lstsq(np.column_stack([cols[k] for k in SUPPORT]), acc, rcond=None)[0]
    fitted = dict(zip(SUPPORT, coef))
    result = {}
    for label, eqs in (("fitted", fitted), ("paper scale", {**fitted, **PAPER_SCALE})):
        model = PolynomialModel.from_equations({"thetaddot": eqs})
        al = oracle_aliases(model, [OracleRun(traj[0], m, 1.0 / FPS)], NOISE, 0.75, [traj])["thetaddot"]
        result[label] = {k: (eqs[k], *al[k]) for k in PAPER_SCALE}
    return result


for k, c in locked_orbits():
    for label, terms in oracle_alias_z(states[k, -1]).items():
        print(f"{side * 1e6:.0f} um, g/s {gap_ratio:g}, {p0 / 1e3:g} kPa, A {amp * 1e6:.0f} um, {c['outcome']} "
              f"{c['lock_ratio']} (amplitude {c['amp_theta']:.3f}), oracle alias z ({label}): " + "; ".join(
                  f"{name} {coef:+.3g}: alias {alias}, z {z:.3g}" for name, (coef, alias, z) in terms.items()))
