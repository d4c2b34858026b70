"""
The levitator as a resonator
============================

A single-axis levitator is a cavity of finite quality factor Q. The levitated dimer shifts the cavity's resonance
by its acoustic potential energy over the mode's stored energy, ``eps = U_ac / E_mode``, and the mode answers that
shift only after its ring time ``tau = Q / (pi f)``. The force therefore lags the motion: driven below the
resonance (detuning ``x < 0`` in half-widths) the lag feeds y's oscillation, above it (``x > 0``) it damps it
(:doc:`/twin`, "The levitator as a resonator").

This example builds the twin's default dimer (500 um salt cubes, 3 kPa, 45.65 kHz) without the air's damping, so
that the cavity's own gain or loss shows alone (the air takes about 0.6 1/s of y's growth), couples it to a cavity of Q = 250 behind a 100 mm^2 transducer, and compares y's growth rate from the closed-form
linear theory (:class:`acousim.LinearCavityCoupling`, the characteristic quartic of y, ydot and the mode) with
the growth measured on the integrated six-state system (:func:`acousim.integrate_coupled`).
"""

# %%
# The dimer and its cavity
# ------------------------
import time

import matplotlib.pyplot as plt
import numpy as np

from acousim import CavityMode, CoupledCavity, LinearCavityCoupling, Medium, integrate_coupled
from acousim.twin import TwinConfig, twin_dynamics

start = time.perf_counter()
config = TwinConfig(air_damping=False)
dynamics = twin_dynamics(config)[0]
medium = Medium(frequency_hz=config.frequency)
Q, AREA = 250.0, 1e-4  # quality factor [-] and transducer area [m^2]


def cavity(detuning: float) -> CoupledCavity:
    """The dimer in a cavity driven ``detuning`` half-widths f/(2Q) off its empty resonance."""
    return CoupledCavity(dynamics, CavityMode(Q, detuning, AREA), medium)


print(f"ring time tau = {1e3 * Q / (np.pi * medium.frequency_hz):.2f} ms, "
      f"stored energy E_mode = {cavity(-1.0).stored_energy:.3g} J")

# %%
# Growth rate of y against the drive's detuning
# ---------------------------------------------
# The exact rate is the largest real part of the roots of the linearised system's quartic; the first-order formula
# expands it in the coupling.
detunings = np.linspace(-4.0, 4.0, 81)
linear = [LinearCavityCoupling.from_cavity(cavity(x)) for x in detunings]
exact = np.array([lin.growth_rate() for lin in linear])
first_order = np.array([lin.first_order_growth_rate() for lin in linear])

# %%
# The same rate measured on the integrated system, from 1 um of y, at three detunings.
def measured_rate(x: float, duration: float = 1.5) -> float:
    cav = cavity(x)
    traj = integrate_coupled(cav, [1e-6, 0.0, 0.0, 0.0], cav.mode.steady_amplitude(), duration, 2e-4)
    y = traj.state[:, 0]
    peaks = np.flatnonzero((y[1:-1] > y[:-2]) & (y[1:-1] >= y[2:])) + 1
    keep = traj.t[peaks] > 0.1  # after the mode's transient
    return float(np.polyfit(traj.t[peaks][keep], np.log(y[peaks][keep]), 1)[0])


probe = [-2.0, -1.0, 1.0]
measured = [measured_rate(x) for x in probe]
for x, m in zip(probe, measured):
    rate = LinearCavityCoupling.from_cavity(cavity(x)).growth_rate()
    print(f"x = {x:+.1f}: linear theory {rate:+.3f} 1/s, simulation {m:+.3f} 1/s")

fig, ax = plt.subplots(figsize=(6.0, 3.6), constrained_layout=True)
ax.axhline(0.0, color="0.6", lw=0.8)
ax.plot(detunings, exact, label="linear theory (quartic)")
ax.plot(detunings, first_order, "--", label="first order in the coupling")
ax.plot(probe, measured, "o", label="integrated six-state system")
ax.set_xlabel("drive detuning x [half-widths f/(2Q)]")
ax.set_ylabel("growth rate of y [1/s]")
ax.set_title(f"Q = {Q:.0f}, transducer {AREA * 1e6:.0f} mm$^2$: x < 0 feeds y, x > 0 damps it")
ax.legend()
print(f"example took {time.perf_counter() - start:.1f} s")
