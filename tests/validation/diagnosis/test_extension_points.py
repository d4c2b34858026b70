"""The effect registry keeps its promises across packages: every registered effect is a candidate of the diagnosis
and is drawn by the blind study (a newly registered effect is fitted by the diagnosis without further code:
tests/validation/diagnosis/test_gap_model.py, beside the model fixture it shares)."""
from __future__ import annotations

from acousim.effects import EFFECT_TYPES


def _candidates() -> list[str]:
    """The registered effects the diagnosis fits (an effect computed from physics sets ``candidate = False``)."""
    return [n for n, cls in EFFECT_TYPES.items() if getattr(cls, "candidate", True)]


def test_the_blind_study_draws_every_candidate_effect_with_its_parameters():
    from validation.blind import STRENGTHS

    missing = sorted(set(_candidates()) - set(STRENGTHS))
    assert not missing, f"effects without a blind-study range in validation.blind.STRENGTHS: {missing}"
    for name in _candidates():
        assert tuple(STRENGTHS[name]) == EFFECT_TYPES[name].parameter_names(), name
        for lo, hi, _ in STRENGTHS[name].values():
            assert 0 < lo < hi


def test_the_diagnosis_candidates_are_the_registered_effects(registered_push):
    from validation.diagnosis import CANDIDATE_EFFECTS, DiagnoseConfig

    assert CANDIDATE_EFFECTS["constant_push"] == ("push",)
    assert list(CANDIDATE_EFFECTS) == _candidates()
    assert "constant_push" in DiagnoseConfig().candidates
