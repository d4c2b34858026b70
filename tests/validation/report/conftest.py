"""A small report with two figures and a table, written by the HTML writer; the reports, data sets and diagnoses made
again from the stored results (stored/, made by stored/make.py)."""
from pathlib import Path

import numpy as np
import pytest

from validation.report import Figure, Section, Table, write_report


@pytest.fixture
def small_report(tmp_path):
    import matplotlib.pyplot as plt

    figs = []
    for i in range(2):
        fig, ax = plt.subplots(figsize=(3, 2))
        ax.plot(np.arange(5) ** (i + 1))
        ax.set_xlabel("t [s]")
        ax.set_ylabel("y [um]")
        p = tmp_path / f"fig{i}.png"
        fig.savefig(p)
        plt.close(fig)
        figs.append(Figure(p, f"figure {i}"))
    sections = [Section("data", "The data", "What the data show.", figs, [Table("numbers", ["term", "value"], [["theta", 1.5], ["y", float("nan")]])], {"a": 1.0, "b": float("nan")})]
    return write_report(sections, tmp_path / "report", "Test report")


# ---------------------------------------------------------------- reports made again from stored results
#: The stored results' folder (diagnosis.json, fit/model.json, fit/variant.json of each case; made by stored/make.py).
STORED = Path(__file__).resolve().parent / "stored"

#: The stored cases: (runs, duration [s], effects) of the twin data set (seed 4, :func:`stored_twin_config`) whose whole
#: report (``build_report``, max_evals 60, one worker) stored/make.py stored, compact, in ``stored/<case>``
#: (spaces as underscores).
STORED_CASES = {
    # the suite's own 4 runs of 1.5 s without damping: nothing can be identified with 4 runs
    "damping-free": (4, 1.5, {}),
    # 7 runs (the fewest the held-out test can identify with at alpha 0.01) with pair scattering
    "pair scattering": (7, 1.0, {"pair_scattering": {"kappa": 15000.0}}),
    # 8 runs of 3 s whose only effect is viscous damping (nothing acts on theta beyond the Gor'kov model): the
    # numbers of docs/fitting.md come from these data
    "linear damping": (8, 3.0, {"linear_damping": {"gamma_y": 0.5, "gamma_theta": 0.5}}),
}


def stored_twin_config(runs, duration, effects):
    """The twin configuration of a stored case (and of the report tests' data sets)."""
    from acousim.dynamics.effects import EffectSet
    from acousim.twin import DropProtocol, TwinConfig

    # no air damping: the cases' effects are the only ones ("damping-free" is the inviscid dimer)
    return TwinConfig(runs=runs, duration=duration, seed=4, effects=EffectSet.from_dict(effects), air_damping=False,
                      protocol=DropProtocol(theta_drop=(-0.2, 0.2), thetadot_drop=(-2.0, 2.0)))


@pytest.fixture(scope="session")
def stored_cases() -> dict:
    """:data:`STORED_CASES`."""
    return STORED_CASES


@pytest.fixture(scope="session")
def stored_diagnosis():
    """``stored_diagnosis(case)``: the :class:`validation.diagnosis.Diagnosis` read from ``stored/diagnosed/<case>.json``
    (spaces as underscores; test_true_sentences.py ``make_diagnosis``, made by stored/make.py)."""
    import json

    from validation.diagnosis import Diagnosis

    return lambda case: Diagnosis.from_json(json.loads((STORED / "diagnosed" / f"{case.replace(' ', '_')}.json")
                                                      .read_text()))


@pytest.fixture(scope="session")
def stored_case_data(pipeline_cache):
    """``stored_case_data(case)``: the folder ``data/`` of the twin data set of a :data:`STORED_CASES` case in the
    pipeline cache (tests/conftest.py; truth.json beside it): read it, never write into it."""
    return lambda case: pipeline_cache.twin_dataset(stored_twin_config(*STORED_CASES[case]))


@pytest.fixture(scope="session")
def stored_report(pipeline_cache, stored_case_data):
    """``stored_report(case)``: the folder of the report of a :data:`STORED_CASES` case made from its stored results
    (``render_report``: a view of diagnosis.json and model.json, nothing fitted or diagnosed again) with the case's
    twin data set (regenerated from the configuration), once per version of the sources (tests/conftest.py
    PipelineCache): read it, never write into it."""
    import hashlib
    import shutil

    def make(case: str) -> Path:
        from validation.report import render_report

        config = stored_twin_config(*STORED_CASES[case])
        data = stored_case_data(case)
        stored = STORED / case.replace(" ", "_")

        def build(folder):
            shutil.copytree(stored, folder / "report")
            render_report(folder / "report", data_dir=data)

        key = f"{config!r} " + " ".join(f"{p.name}={hashlib.sha1(p.read_bytes()).hexdigest()}"
                                        for p in sorted(stored.rglob("*.json")))  # the stored files are in the key
        return pipeline_cache.folder("stored-report", key, build) / "report"

    return make
