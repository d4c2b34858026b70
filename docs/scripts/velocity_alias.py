"""How far the paper's velocity couplings are from position terms on locked orbits (docs/twin.md, the refit):
python docs/scripts/velocity_alias.py SIDE G/S P0 A     e.g. 500e-6 0.02 3000 100e-6

On the held-y orbits of one map cell (python -m acousim held-y), for every distinct locked orbit: the share of the
columns y*thetadot^2 (b5) and y*ydot*thetadot (b6) that the columns y (b2), y^2*theta (b3) and y*theta^2 explain
(R^2 of the least squares over one settled stretch of four periods of y), and the same with all the paper's other
hinge terms (1, theta, y, y^2*theta, thetadot) plus y*theta^2.  R^2 near 1: a fit can trade the velocity coupling for
position terms at almost no cost in the residual.
"""
import sys

import numpy as np

from acousim.atlas.field_drops import atlas_dynamics, settled_outcome
from acousim.atlas.held_y import held_y_arguments, held_y_orbits

side, gap_ratio, p0, amp = (float(v) for v in sys.argv[1:5])
dyn = atlas_dynamics(side, gap_ratio, p0, 45_650.0)
starts = [(th, 0.0) for th in (-0.4, -0.2, 0.0, 0.15, 0.3, 0.4)]
n_per = 40
t, states, n_valid, status, *_ = held_y_orbits(dyn, amp, starts, 304, n_per)
y_eq = held_y_arguments(dyn)[1][0]


def r_squared(target, columns):
    a = np.column_stack(columns)
    resid = target - a @ np.linalg.lstsq(a, target, rcond=None)[0]
    return 1.0 - (resid @ resid) / (target @ target)


seen = set()
for k in range(len(starts)):
    if status[k]:
        continue
    c = settled_outcome(t[-208 * n_per:], states[k, -208 * n_per:])
    key = (c["outcome"], c["lock_ratio"], round(c["amp_theta"], 2))
    if not c["outcome"].startswith("locked-") or key in seen:
        continue
    seen.add(key)
    y, yd, th, thd = states[k, -4 * n_per:].T
    y = y - y_eq
    three = [y, th * y ** 2, th ** 2 * y]
    paper = [np.ones_like(y), th, y, th * y ** 2, thd, th ** 2 * y]
    for name, col in (("b5 y*thetadot^2", y * thd ** 2), ("b6 y*ydot*thetadot", y * yd * thd)):
        print(f"{side * 1e6:.0f} um, g/s {gap_ratio:g}, {p0 / 1e3:g} kPa, A {amp * 1e6:.0f} um, {c['outcome']} "
              f"{c['lock_ratio']} (amplitude {c['amp_theta']:.3f}): {name}: R^2 {r_squared(col, three):.4f} against "
              f"y, y^2*theta, y*theta^2; {r_squared(col, paper):.4f} against b0-b4 and y*theta^2")
