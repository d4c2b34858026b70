"""Which family dimers survive the paper's 13 ms drop (docs/twin.md, the paper preset's table):
python docs/scripts/paper_drop_scan.py (about a minute on one core).

Full-wave model with the air's computed damping; each dimer starts at rest with its hinge at theta* - 0.02,
theta* and theta* + 0.02 (theta* its static equilibrium), falls for 13 ms with a free hinge and is followed for
4 s with the field back on.
"""
import numpy as np

from acousim.atlas.field_drops import atlas_dynamics, drop_and_settle

DIMERS = [(400e-6, 0.03), (500e-6, 0.015), (500e-6, 0.03), (500e-6, 0.05), (600e-6, 0.03), (700e-6, 0.05)]
for p0 in (3000.0, 4000.0, 5000.0, 6000.0, 8000.0):
    for side, gap_ratio in DIMERS:
        dyn = atlas_dynamics(side, gap_ratio, p0, 45_650.0)
        theta_eq, _ = dyn.force_model.equilibrium()
        f_y, f_theta = dyn.force_model.linear_frequencies()
        outcomes = [drop_and_settle(dyn, 13e-3, theta_eq + d, 4.0, 1000.0) for d in (-0.02, 0.0, 0.02)]
        print(f"p0 {p0 / 1e3:g} kPa, {side * 1e6:.0f} um, g/s {gap_ratio:g}: f_y {f_y:.1f} Hz, f_theta {f_theta:.1f} Hz, "
              f"escape height {dyn.force_model.escape_height() * 1e3:.2f} mm: "
              + ", ".join(o["outcome"] + ("" if np.isnan(o.get("t_end_s", np.nan)) or o["t_end_s"] is None
                                          else f" at {o['t_end_s']:.2f} s") for o in outcomes), flush=True)
