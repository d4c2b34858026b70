"""The air's damping rates of docs/damping.md: python docs/scripts/air_damping_table.py (a few seconds)."""
from acousim.dynamics.air_damping import air_damping_rates
from acousim.models import ExperimentConditions, dynamic_model

print("| side [um] | g / s | p0 [kPa] | f_y [Hz] | f_theta [Hz] | delta_y [um] | gamma_y [1/s] | gamma_theta(0) [1/s] "
      "| gamma_theta(0.5) | gamma_theta(0.8) |")
print("|---|---|---|---|---|---|---|---|---|---|")
for side, gap_ratio, p0 in [(400e-6, 0.03, 3000), (500e-6, 0.015, 3000), (500e-6, 0.03, 3000), (500e-6, 0.05, 3000),
                            (600e-6, 0.03, 3000), (700e-6, 0.05, 3000), (700e-6, 0.05, 6000)]:
    cond = ExperimentConditions(side_length_m=side, gap_m=gap_ratio * side, pressure_amplitude_pa=p0)
    fm = dynamic_model("fullwave", cond)
    f_y, f_t = fm.linear_frequencies()  # each mode's drag at its own frequency, as acousim.air_damping_for does
    r = air_damping_rates(side, gap_ratio * side, f_y, f_t)
    g05, g08 = r.hinge_rate([0.5, 0.8])
    print(f"| {side * 1e6:.0f} | {gap_ratio:g} | {p0 / 1e3:g} | {f_y:.1f} | {f_t:.1f} | {r.delta_y * 1e6:.0f} | "
          f"{r.gamma_y:.3f} | {r.gamma_theta:.3f} | {g05:.2f} | {g08:.2f} |")
