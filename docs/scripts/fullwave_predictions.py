"""What the full wave predicts for the paper's dimers: f_theta / f_y and the theta*y^2 coefficient against side and gap."""
import numpy as np
from acousim.models import ExperimentConditions, dynamic_model
from acousim.fullwave.family import shipped_family
fam = shipped_family()
(k0, k1), (g0, g1) = fam.ranges()
gaps = [g for g in (0.01, 0.015, 0.02, 0.03, 0.04, 0.05) if g0 - 1e-9 <= g <= g1 + 1e-9]
print("| side [um] | ks | g / s | f_y [Hz] | f_theta [Hz] | f_theta / f_y | thetaddot `theta` [1/s^2] | `y^2*theta` [1/(m^2 s^2)] |")
print("|---|---|---|---|---|---|---|---|")
for side in (400e-6, 500e-6, 600e-6, 700e-6):
    for g in gaps:
        c = ExperimentConditions(side_length_m=side, gap_m=g * side)
        sur = dynamic_model("fullwave", c)
        fy, ft = sur.linear_frequencies()
        tc = sur.taylor_coefficients()["thetaddot"]
        print(f"| {side*1e6:.0f} | {c.ks:.3f} | {g:.3f} | {fy:.2f} | {ft:.2f} | {ft/fy:.3f} | {tc['theta']:.3g} | {tc['y^2*theta']:+.3g} |")
