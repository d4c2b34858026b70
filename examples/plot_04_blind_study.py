"""
A blind check of the diagnosis
==============================

How often does the diagnosis name the true causes of a sim-to-real gap, and never a false one? The blind
check answers it on twin data sets with hidden causes: each case draws a set of effects at random strengths and
a pressure error, simulates the runs, diagnoses them without knowing the truth, and scores the verdict. A study
is resumable (each finished case is kept) and runs its cases through the executor, on local processes or a dask
cluster (``cubedimer-validation blind --cases 50 --workers 2``).

This example is a very small study (2 cases of 8 runs of 1.5 s, on two local processes) to show the output; the
numbers that characterise the method come from the studies of :doc:`/diagnosis` (hundreds of cases).
"""

# %%
import json
import tempfile
import time
from pathlib import Path

import matplotlib.pyplot as plt

from cubedimer import ExecutorConfig
from validation import BlindConfig, blind_table, run_blind

start = time.perf_counter()
study = Path(tempfile.mkdtemp(prefix="blind_")) / "study"
config = BlindConfig(cases=2, seed=0, runs=8, duration=1.5)
summaries = run_blind(config, study, executor=ExecutorConfig(workers=2), progress=False)

# %%
# Each case keeps its truth and its verdict:
for case in sorted((study / "cases").rglob("result.json")):
    result = json.loads(case.read_text())
    print(f"{case.parent.name}: true {sorted(result['true_set'])}, named {sorted(result['identified'])}, "
          f"exact {result['exact']}, false {result['false_effects']}")
    for effect, errors in (result["parameter_relative_error"] or {}).items():
        print(f"    {effect}: relative parameter errors " + ", ".join(f"{k} {v:.1%}" for k, v in errors.items()))
    print(f"    pressure {result['pressure_calibrated_pa']:.0f} Pa calibrated, {result['pressure_true_pa']:.0f} Pa true")

# %%
# The study's table (``blind_table.md``), beside the targets of the method; with two cases most rows say
# little, which is why the method's numbers come from far larger studies:
print(blind_table(summaries, config))

# %%
# The confusion matrix of the candidate effects (true effect against named effect), as the study writes it:
fig, ax = plt.subplots(figsize=(7, 5.5), layout="constrained")
ax.imshow(plt.imread(study / "confusion_matrix.png"))
ax.set_axis_off()
print(f"example ran in {time.perf_counter() - start:.1f} s")
