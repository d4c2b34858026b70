"""
From a lab's CSV files to the sim-to-real diagnosis
===================================================

A lab records runs of the two tracked coordinates, the centre-of-mass height ``y`` and the hinge angle
``theta`` (:doc:`/conventions`), after the levitating field is dropped for a few milliseconds, and writes them
as its own software does: times in milliseconds, heights in micrometres, semicolons and decimal commas. The
loader reads such files by their unit labels (:doc:`/formats`), checks every run against the physics of a
levitated dimer, and the diagnosis tells which unmodelled effects explain the gap between the data and the
Gor'kov simulation.

The "lab" here is the digital twin (8 runs of 2 s at 1000 frames/s) with a hidden linear damping of 0.5 1/s on
both coordinates on top of the air's own damping and an 8 % pressure error, so the answer is known. The command-line form of the last step is
``cubedimer-validation diagnose lab/ --out diag/``.
"""

# %%
# Writing the lab's files
# -----------------------
import json
import shutil
import tempfile
import time
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import validation
from acousim import Camera, EffectSet, TwinConfig, simulate_dataset
from cubedimer import load_dataset

start = time.perf_counter()
work = Path(tempfile.mkdtemp(prefix="lab_diagnosis_"))
twin = TwinConfig(runs=8, duration=2.0, seed=7, pressure_error=0.08, camera=Camera(fps=1000.0),
                  effects=EffectSet.parse(["linear_damping:gamma_y=0.5,gamma_theta=0.5"]))
truth = simulate_dataset(twin, work / "twin", progress=False)

lab = work / "lab"
lab.mkdir()
for run in load_dataset(work / "twin").runs:
    rows = [f"{t * 1e3:.3f};{y * 1e6:.4f};{th:.6f}".replace(".", ",") for t, y, th in zip(run.t, run.y, run.theta)]
    (lab / run.name).write_text("t [ms];y [um];theta\n" + "\n".join(rows) + "\n")
shutil.copy(work / "twin" / "meta.json", lab / "meta.json")  # the experiment's constants (side, pressure, ...)
print("\n".join((lab / "run01.csv").read_text().splitlines()[:3]))

# %%
# Loading: unit labels are converted to SI, and each run is checked (a vertical frequency of 5-200 Hz, an
# amplitude below a quarter wavelength, ``y`` oscillating about 0).
dataset = load_dataset(lab)
print(f"{len(dataset.runs)} runs loaded, {len(dataset.skipped)} skipped")
fig, ax = plt.subplots(2, 1, figsize=(7, 4), sharex=True, layout="constrained")
for run in dataset.runs[:3]:
    ax[0].plot(run.t, run.y * 1e6, lw=0.7, label=run.name)
    ax[1].plot(run.t, run.theta, lw=0.7)
ax[0].set_ylabel("y [um]")
ax[1].set_ylabel("theta [-]")
ax[1].set_xlabel("t [s]")
ax[0].legend(fontsize=8, ncol=3)
ax[0].set_title("three of the lab's runs, as loaded")

# %%
# The diagnosis
# -------------
# The simulation is calibrated on the vertical equation (pressure amplitude and height origin), the gap is
# measured, and candidate effects are added while they improve held-out runs significantly (a sign-flip
# permutation test over runs).
diagnosis = validation.diagnose_dataset(lab, progress=False)
calibration = diagnosis.calibration
print(f"calibrated pressure {calibration['pressure_amplitude_pa']:.0f} Pa "
      f"(nominal {calibration['nominal_pressure_amplitude_pa']:.0f} Pa, true "
      f"{truth['pressure_amplitude_pa']:.0f} Pa)")
print("identified:", ", ".join(diagnosis.identified) or "none")
for name in diagnosis.identified:
    verdict = diagnosis.effect(name)
    print(f"  {name}: " + ", ".join(f"{k} = {v:.3g}" for k, v in verdict.params.items())
          + f" (held-out p = {verdict.p_value:.2g})")
print("true effects:", json.dumps(truth["effects"]))

# %%
# The fitted damping rates hold the air's damping as well as the hidden one: the twin adds the air's computed
# drag to every run (:doc:`/damping`), and the diagnosis's candidate ``linear_damping`` stands for the total.
# The diagnosis states no standard error for an effect's parameters; its accuracy is what the blind check
# measures over many such data sets (:doc:`/diagnosis`;
# :ref:`sphx_glr_auto_examples_plot_04_blind_study.py` shows a small one).
#
# ``write_diagnosis`` writes ``diagnosis.json``, the figures and a self-contained HTML page; here are two of its
# figures: how much of the gap each effect explains, and the residual maps over the state space.
paths = validation.write_diagnosis(diagnosis, work / "diagnosis")
figures = sorted((work / "diagnosis" / "figures").glob("*.png"))
print([p.name for p in paths], [f.name for f in figures])
for figure in figures[:2]:
    fig, ax = plt.subplots(figsize=(8, 5), layout="constrained")
    ax.imshow(plt.imread(figure))
    ax.set_axis_off()
    ax.set_title(figure.name, fontsize=9)
print(f"example ran in {time.perf_counter() - start:.1f} s")
