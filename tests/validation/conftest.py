"""Fixtures shared by the validation tests."""
import pytest


@pytest.fixture
def make_diagnosis():
    """A factory of hand-made :class:`validation.diagnosis.Diagnosis` objects for the tests of what reads one.

    ``make_diagnosis(identified, params={name: {...}}, **fields)``: the identified effects named, significant and
    with their ``params`` (default ``{"_": 1.0}``), ``extra_effects`` (EffectVerdicts) after them, and any other
    field of the Diagnosis given by keyword (neutral defaults otherwise)."""
    from validation.diagnosis import Diagnosis, EffectVerdict

    def make(identified=(), params=None, extra_effects=(), **fields):
        effects = tuple(EffectVerdict(n, (params or {}).get(n, {"_": 1.0}), 0.01, 0.9, True, 0.004, None, None,
                                      named=True) for n in identified) + tuple(extra_effects)
        base = dict(model="gorkov", simulation={}, identified=tuple(identified), indistinguishable=(),
                    model_effects=tuple(e.name for e in effects), dropped_by_backward_check=(),
                    greedy_identified=tuple(identified), calibration={"pressure_amplitude_pa": 3000.0},
                    gap_before=0.3, gap_after=0.01, gap_definition="", gap_components=(), gap_component_forms={},
                    gap_per_run={}, noise_floor=0.0, noise_floor_note="", effects=effects, localization={},
                    long_time={}, remaining_gap={"discovered_terms": {"yddot": [], "thetaddot": []}},
                    identification_rounds=())
        return Diagnosis(**{**base, **fields})

    return make


@pytest.fixture
def small_oscillating_dataset(tmp_path, write_csv):
    """A data set of 3 runs of 1.5 s at 2000 frames/s, the fewest a diagnosis takes: a 21.5-Hz y oscillation (the
    Gor'kov trap frequency of the default dimer at the nominal 3000 Pa, which the loading checks) and a 9-Hz hinge,
    with white tracking noise (1 um, 0.001)."""
    import json

    import numpy as np

    rng = np.random.default_rng(5)
    t = np.arange(3000) / 2000.0
    path = tmp_path / "data"
    path.mkdir()
    for k in range(3):
        y = 1e-4 * np.sin(2 * np.pi * 21.5 * t + k) + rng.normal(0, 1e-6, t.size)
        theta = 0.2 * np.sin(2 * np.pi * 9.0 * t + 2 * k) + rng.normal(0, 1e-3, t.size)
        write_csv(path / f"run{k + 1:02d}.csv", t, y, theta)
    (path / "meta.json").write_text(json.dumps({"pressure_amplitude_pa": 3000.0}))
    return path
