"""
Full-wave forces of a custom dimer
==================================

The full-wave model solves the scattering of the standing wave by both cubes (boundary elements). Rigid cubes in
inviscid air depend only on ``ks`` (wavenumber times side) and ``g/s`` (hinge gap over side), and forces scale
exactly as ``p0^2 s^2 / (rho0 c0^2)``, so the shipped table family gives the model of any lab dimer inside its
range without a new solve (:doc:`/fullwave`).

Here: a dimer of 600 um cubes in a 42 kHz levitator with a 12 um hinge gap, swept over the hinge angle ``theta``
and the height ``y``, beside the Gor'kov volume model of the same dimer. The command-line form is
``cubedimer-acousim sweep --model fullwave --side 600e-6 --frequency 42000 --gap 12e-6 ...``.
"""

# %%
# The two models of one experiment
# --------------------------------
import dataclasses
import time

import matplotlib.pyplot as plt
import numpy as np

from acousim import ExperimentConditions, fit_static_coefficients, static_model, static_sweep

start = time.perf_counter()
conditions = ExperimentConditions(side_length_m=600e-6, frequency_hz=42_000.0, gap_m=12e-6)
ks = 2 * np.pi * conditions.frequency_hz / conditions.sound_speed_m_s * conditions.side_length_m
print(f"ks = {ks:.3f}, g/s = {conditions.gap_m / conditions.side_length_m:.3f}")

fullwave = static_model("fullwave", conditions)
# the hinge gap belongs to the full-wave model only: the Gor'kov model of the same dimer refuses it
gorkov = static_model("gorkov", dataclasses.replace(conditions, gap_m=None))

theta = np.linspace(-0.3, 0.3, 13)
y = np.linspace(-150e-6, 150e-6, 13)
sweeps = {"full wave": static_sweep(fullwave, theta, y), "Gor'kov": static_sweep(gorkov, theta, y)}

# %%
# The hinge's generalised force
# -----------------------------
# ``thetaddot`` (the hinge's acceleration, [1/s^2]) against theta at three heights. The two models differ by two
# orders of magnitude in the hinge's stiffness: the Gor'kov volume integral leaves out the scattering between the
# two cubes, and a cube's second moment is isotropic, so its hinge is very soft (:doc:`/conventions`,
# :doc:`/fullwave`).
fig, axes = plt.subplots(1, 2, figsize=(9, 3.6), layout="constrained")
for ax, (label, sweep) in zip(axes, sweeps.items()):
    for j in (0, 6, 12):
        ax.plot(sweep.theta_grid, sweep["thetaddot"][:, j], "o-", ms=3, label=f"y = {sweep.y_grid[j] * 1e6:+.0f} um")
    ax.set_title(label)
    ax.set_xlabel("theta [-]")
    ax.axhline(0, color="0.7", lw=0.6)
axes[0].set_ylabel("thetaddot [1/s^2]")
axes[1].legend(fontsize=8)

# %%
# The Gor'kov hinge force vanishes at theta = 0 at every height. The full-wave one does not: it carries the
# ``1`` and ``y`` terms that :doc:`/fullwave` tabulates, and its hinge comes to rest at a small positive angle.
for label, sweep in sweeps.items():
    at_rest = sweep["thetaddot"][:, 6]  # y = 0
    print(f"{label}: thetaddot(theta=0, y=0) = {at_rest[6]:+.4g} 1/s^2, rest angle at y = 0: "
          f"theta = {np.interp(0.0, -at_rest, sweep.theta_grid):+.3f}")

# %%
# Static coefficients
# -------------------
# A cubic least-squares fit of each sweep gives the equations' coefficients with their standard errors (from
# the fit's residual over the box ``|theta| <= 0.3``, ``|y| <= 150 um``). The theta*y^2 coupling is the paper's key
# term.
for label, sweep in sweeps.items():
    coefficients = fit_static_coefficients(sweep, theta_max=0.3, y_max=150e-6)
    print(label)
    for term in ("theta", "y*theta", "y^2*theta"):
        value = coefficients.coefficients["thetaddot"][term]
        error = coefficients.std_errors["thetaddot"][term]
        print(f"  thetaddot[{term:10s}] = {value:+.4g} +- {error:.2g}")
    print(f"  yddot[y] = {coefficients.coefficients['yddot']['y']:+.4g} +- "
          f"{coefficients.std_errors['yddot']['y']:.2g} 1/s^2 "
          f"(f_y = {np.sqrt(-coefficients.coefficients['yddot']['y']) / (2 * np.pi):.2f} Hz)")

# %%
# The vertical force
# ------------------
# Both models trap the dimer at nearly the same height; the full-wave trap is the stiffer one.
fig, ax = plt.subplots(figsize=(5, 3.4), layout="constrained")
for label, sweep in sweeps.items():
    ax.plot(sweep.y_grid * 1e6, sweep["yddot"][6, :], "o-", ms=3, label=label)
ax.set_xlabel("y [um]")
ax.set_ylabel("yddot at theta = 0 [m/s^2]")
ax.legend()
print(f"example ran in {time.perf_counter() - start:.1f} s")
