"""What the shipped default dimer's table predicts (docs/fullwave.md, "What the full-wave hinge predicts"):
python docs/scripts/default_table_summary.py [TABLE.json]  (a second; no boundary-element solve).

Prints the table's mesh and build, Z_eq, the hinge stiffness, the equilibrium, the small-oscillation frequencies,
the escape height, the Taylor coefficients of thetaddot about (0, 0), kappa of the pair-scattering form, and
where the restoring hinge acceleration at y = 0 peaks and changes sign (the folding barrier).
"""
import sys

import numpy as np

from acousim.fullwave.force_surrogate import DEFAULT_TABLE, FullwaveSurrogate

sur = FullwaveSurrogate.load(sys.argv[1] if len(sys.argv) > 1 else DEFAULT_TABLE)
ba, st = sur.build_accuracy, sur.settings
print(f"table: {int(ba['dofs'])} DOFs, {st['n_half']} solves, h_edge {st.get('h_edge')}, wall {ba.get('wall_s', 0):.0f} s")
th, y = sur.equilibrium()
f_y, f_t = sur.linear_frequencies()
print(f"Z_eq {sur.z_eq * 1e6:.1f} um; hinge stiffness {sur.hinge_stiffness():.4e} N m; equilibrium theta* {th:+.4f}, "
      f"y* {y * 1e6:+.2f} um")
print(f"linear frequencies f_y {f_y:.3f} Hz, f_theta {f_t:.3f} Hz (ratio {f_t / f_y:.3f}); escape height "
      f"{sur.escape_height() * 1e3:.3f} mm")
tc = sur.taylor_coefficients()["thetaddot"]
print("thetaddot Taylor: " + ", ".join(f"{k} {v:+.3e}" for k, v in tc.items()))
kz = sur.two_k * sur.z_eq / 2
print(f"kappa (theta term / cos^2(k Z_eq)): {-tc['theta'] / np.cos(kz) ** 2:.3e} 1/s^2")
for sign in (+1, -1):  # the restoring acceleration is -sign * thetaddot on the side sign * theta > 0
    theta = sign * np.linspace(0.0, sur.theta_max, 901)
    _, qt = sur.generalized_forces(theta, np.zeros_like(theta))
    restoring = -sign * np.asarray(qt) / np.array([float(sur.hinge_inertia(t)) for t in theta])
    i_peak = int(np.argmax(restoring))
    turn = np.abs(theta[1:][(restoring[1:] < 0) & (restoring[:-1] >= 0)])
    print(f"theta {'>' if sign > 0 else '<'} 0: the restoring hinge acceleration at y = 0 peaks at |theta| = "
          f"{abs(theta[i_peak]):.3f} ({restoring[i_peak]:.3g} 1/s^2) and changes sign at |theta| = "
          f"{turn[-1] if turn.size else float('nan'):.3f}")
