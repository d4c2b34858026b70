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
