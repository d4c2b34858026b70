"""The paper's hinge equation refitted on the physics (docs/twin.md, "The paper's model refitted on the physics"):
python docs/scripts/paper_model_refit.py DATA_DIR

DATA_DIR is a twin data set (python -m acousim simulate ... --model fullwave): the exact states of truth_states.npz
(after the first 0.1 s, past the field's ring-up) and the exact accelerations of the same full-wave dynamics, so the
least squares show what the paper's terms can and cannot represent, free of tracking noise and differentiation.
Also prints the collinearity of the velocity couplings with the position terms on these states.
"""
import json
import sys

import numpy as np

from acousim.atlas.field_drops import atlas_dynamics

data = sys.argv[1]
truth = json.load(open(f"{data}/truth.json"))
dyn = atlas_dynamics(truth["side_length_m"], truth["gap_m"] / truth["side_length_m"], truth["pressure_amplitude_pa"],
                     truth.get("frequency_hz", 45_650.0))
npz = np.load(f"{data}/truth_states.npz")
t = npz["t"]
states = []
for name in sorted(k for k in npz.files if k != "t"):
    x = npz[name]
    keep = np.all(np.isfinite(x), axis=1) & (t > 0.1)
    if keep.sum() >= 1000:      # folded runs keep their frames before the fold
        states.append(x[keep])
X = np.vstack(states)
ay, at = dyn.accelerations(X)
y, yd, th, thd = X.T
cols = {"1": np.ones_like(y), "theta": th, "y": y, "y^2*theta": th * y ** 2, "thetadot": thd,
        "y*thetadot^2": y * thd ** 2, "y*ydot*thetadot": y * yd * thd, "y*theta": y * th, "y*theta^2": y * th ** 2,
        "theta^3": th ** 3}


def fit(names):
    a = np.column_stack([cols[n] for n in names])
    beta = np.linalg.lstsq(a, at, rcond=None)[0]
    r, dev = at - a @ beta, at - at.mean()
    return dict(zip(names, beta)), float((r @ r) / (dev @ dev))


def show(title, names):
    coef, unexplained = fit(names)
    print(f"{title}: unexplained variance of thetaddot {unexplained:.4f};",
          ", ".join(f"{k} {v:.3g}" for k, v in coef.items()))


paper = ["1", "theta", "y", "y^2*theta", "thetadot", "y*thetadot^2", "y*ydot*thetadot"]
print(f"{X.shape[0]} states of {len(states)} runs; theta {th.min():.2f}..{th.max():.2f}, y {y.min() * 1e6:.0f}.."
      f"{y.max() * 1e6:.0f} um")
show("the paper's hinge equation (b0-b6)", paper)
show("without b5, b6", paper[:5])
show("b0-b4 + y*theta, y*theta^2, theta^3", paper[:5] + ["y*theta", "y*theta^2", "theta^3"])
show("b0-b6 + y*theta, y*theta^2, theta^3", paper + ["y*theta", "y*theta^2", "theta^3"])
tc = dyn.force_model.taylor_coefficients()["thetaddot"]
print("the physics' Taylor coefficients about the equilibrium:",
      ", ".join(f"{k} {tc[k]:.3g}" for k in ("1", "theta", "y", "y^2*theta", "y*theta") if k in tc))
ya = np.linalg.lstsq(np.column_stack([np.ones_like(y), y, y ** 2, yd]), ay, rcond=None)[0]
print("yddot a0-a3 (1, y, y^2, ydot):", ", ".join(f"{v:.4g}" for v in ya))
