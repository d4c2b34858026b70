"""
From a high-speed recording to the report
=========================================

The whole job as a lab runs it: high-speed video of the dimer after a field drop is tracked into runs of
``(t, y, theta)`` (:doc:`/tracking`), and the report fits the runs, compares the fit with the simulation,
diagnoses the gap and writes a self-contained HTML page.

The recordings here come from the digital twin's camera (the paper-like preset, 3 runs of 1.5 s at
1000 frames/s, 180 x 150 pixels of 10 um), so the true motion is known. A real recording enters at the
tracking step, with its frame rate and pixel size (``--fps``, ``--pixel-size``). The command-line form is::

    cubedimer-acousim simulate --preset paper-like --runs 3 --duration 1.5 --fps 1000 --video --out twin
    cubedimer-tracking track twin/video --out tracked
    cubedimer-validation report tracked --out report
"""

# %%
# The recordings
# --------------
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import tracking
import validation
from acousim import PAPER_LIKE, Camera, TwinConfig, simulate_dataset
from acousim.twin import VideoCamera

start = time.perf_counter()
work = Path(tempfile.mkdtemp(prefix="recording_report_"))
config = TwinConfig.from_preset(PAPER_LIKE, runs=3, duration=1.5, seed=3, camera=Camera(fps=1000.0))
simulate_dataset(config, work / "twin", progress=False, video=VideoCamera())
recordings = tracking.find_recordings(work / "twin" / "video")
print([r.name for r in recordings])

recording = tracking.read_recording(recordings[0])
print(f"{recording.name}: {recording.n_frames} frames, {recording.fps:g} frames/s, "
      f"pixel {recording.pixel_size * 1e6:g} um ({recording.format})")
fig, axes = plt.subplots(1, 3, figsize=(9, 2.8), layout="constrained")
for ax, k in zip(axes, (0, recording.n_frames // 2, recording.n_frames - 1)):
    ax.imshow(recording.frames[k], cmap="gray")
    ax.set_title(f"frame {k}", fontsize=9)
    ax.set_axis_off()

# %%
# Tracking one recording
# ----------------------
# :func:`tracking.track_recording` measures every frame: the centre-of-mass height from the silhouette and the
# hinge angle from sub-pixel fits of the cubes' faces. Against the twin's true motion the residuals show the
# tracking's noise (each run's estimate is written with it).
tracked = tracking.track_recording(recording)
true = np.genfromtxt(work / "twin" / "video" / f"{recording.name}_truth.csv", delimiter=",", names=True, skip_header=2)
fig, ax = plt.subplots(2, 1, figsize=(7, 4), sharex=True, layout="constrained")
ax[0].plot(tracked.t, (tracked.y - np.interp(tracked.t, true["t"], true["y"])) * 1e6, ".", ms=1)
ax[1].plot(tracked.t, tracked.theta - np.interp(tracked.t, true["t"], true["theta"]), ".", ms=1, color="C1")
ax[0].set_ylabel("y error [um]")
ax[1].set_ylabel("theta error [-]")
ax[1].set_xlabel("t [s]")
ax[0].set_title(f"{recording.name}: tracked minus true motion ({tracked.n_measured} of {recording.n_frames} "
                "frames measured)")
err_y = np.nanstd(tracked.y - np.interp(tracked.t, true["t"], true["y"]))
print(f"y error std {err_y * 1e6:.2f} um (pixel 10 um)")

# %%
# Tracking the folder
# -------------------
# The command tracks every recording (in parallel with ``--workers``) and writes the data set: one CSV and one
# RUN.json per run, and meta.json with the tracking's noise.
command = [sys.executable, "-m", "tracking", "track", str(work / "twin" / "video"), "--out", str(work / "tracked"),
           "--workers", "2"]
print(subprocess.run(command, capture_output=True, text=True, check=True).stderr.strip().splitlines()[-1])

# %%
# The report
# ----------
# :func:`validation.build_report` fits the runs, compares the fitted coefficients with the simulated sweeps,
# diagnoses the gap and writes ``report.html`` with its figures and ``numbers.json``. Three runs are enough for
# the fit; the diagnosis needs at least 7 runs to name an effect (its held-out sign-flip test at alpha = 0.01)
# and says so.
html = validation.build_report(work / "tracked", work / "report", workers=2, progress=False)
numbers = json.loads((work / "report" / "numbers.json").read_text())
print(html.name, f"{html.stat().st_size / 1e6:.1f} MB;", "numbers.json:", ", ".join(list(numbers)[:12]), "...")
figures = sorted((work / "report" / "figures").glob("*.png"))
print(len(figures), "figures:", ", ".join(f.name for f in figures))
for figure in (work / "report" / "figures" / name for name in ("data_timeseries.png", "coefficients.png")):
    fig, ax = plt.subplots(figsize=(8, 5), layout="constrained")
    ax.imshow(plt.imread(figure))
    ax.set_axis_off()
    ax.set_title(figure.name, fontsize=9)
print(f"example ran in {time.perf_counter() - start:.1f} s")
