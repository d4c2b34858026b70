"""The effect registry keeps its promises across packages: every registered effect is a candidate of the diagnosis
and is drawn by the blind study (a newly registered effect is fitted by the diagnosis without further code:
tests/validation/diagnosis/test_gap_model.py, beside the model fixture it shares)."""
from __future__ import annotations

import pytest

from acousim.dynamics.effects import EFFECT_TYPES


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
    from validation.diagnosis.prepare.candidate_effects import MODEL_CANDIDATES

    # the registered effects, then the candidates that need the force model (the cavity's lag, asked for by name)
    assert list(CANDIDATE_EFFECTS) == _candidates() + list(MODEL_CANDIDATES)
    assert "constant_push" in DiagnoseConfig().candidates
    assert not set(MODEL_CANDIDATES) & set(DiagnoseConfig().candidates)


def test_a_registered_effect_runs_through_the_twin_and_the_diagnosis(registered_push, tmp_path):
    """One class and its registration are all a new effect needs (8 runs: the held-out sign-flip test needs 7): the twin integrates it (through the compiled
    sum's registered kernels), the data set's truth names it, and the diagnosis's candidate fit finds it again."""
    import json

    from acousim.dynamics.effects import EffectSet
    from acousim.twin import DropProtocol, TwinConfig, simulate_dataset
    from cubedimer.executor import ExecutorConfig
    from validation.diagnosis import DiagnoseConfig, diagnose_dataset

    push = 8.0  # [1/s^2]: shifts the rest angle of the soft Gor'kov hinge (omega_theta^2 about 110 1/s^2) by 0.07
    data = tmp_path / "twin"
    # no air damping: the dummy is the only effect beside the inviscid model, so nothing else may be named
    cfg = TwinConfig(runs=8, duration=1.5, seed=5, effects=EffectSet((registered_push(push=push),)), air_damping=False,
                     protocol=DropProtocol(theta_drop=(-0.2, 0.2), thetadot_drop=(-2.0, 2.0)))
    simulate_dataset(cfg, data, ExecutorConfig(workers=1), progress=False)
    assert json.loads((data / "truth.json").read_text())["effects"] == {"constant_push": {"push": push}}
    (data / "truth.json").unlink()  # the diagnosis is blind
    diag = diagnose_dataset(data, DiagnoseConfig(long_time=False, discover=False,
                                                    candidates=("constant_push", "linear_damping")), progress=False)
    assert diag.identified == ("constant_push",)
    fitted = next(e for e in diag.effects if e.name == "constant_push").params["push"]
    # the hinge noise of the twin (tracking 0.004 over 8 x 1.5 s) leaves a standard error of a few 1/s^2; 5 %
    # also covers the Savitzky-Golay bias of the accelerations (about 1 %, docs/diagnosis.md)
    assert fitted == pytest.approx(push, rel=0.05)
