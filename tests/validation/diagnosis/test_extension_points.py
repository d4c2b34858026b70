"""The effect registry keeps its promises across packages: every registered effect is a candidate of the diagnosis
and is drawn by the blind study, and a newly registered effect is fitted by the diagnosis without further code."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, ClassVar

import numpy as np
import pytest

from acousim.effects import EFFECT_TYPES, Effect


def _constant_push_columns(y, ydot, theta, thetadot, wavenumber, z_eq):
    """thetaddot += push (a constant torque per inertia); nothing in yddot."""
    return (0.0,), (1.0,)


@dataclass(frozen=True)
class ConstantPush(Effect):
    """A dummy effect: a constant hinge torque, thetaddot += push [1/s^2]."""

    name: ClassVar[str] = "constant_push"
    columns: ClassVar[Callable] = staticmethod(_constant_push_columns)
    push: float = 0.0


@pytest.fixture
def registered_push(monkeypatch):
    monkeypatch.setitem(EFFECT_TYPES, ConstantPush.name, ConstantPush)
    return ConstantPush


def test_the_blind_study_draws_every_registered_effect_with_its_parameters():
    from validation.blind import STRENGTHS

    missing = sorted(set(EFFECT_TYPES) - set(STRENGTHS))
    assert not missing, f"effects without a blind-study range in validation.blind.STRENGTHS: {missing}"
    for name, cls in EFFECT_TYPES.items():
        assert tuple(STRENGTHS[name]) == cls.parameter_names(), name
        for lo, hi, _ in STRENGTHS[name].values():
            assert 0 < lo < hi


def test_the_diagnosis_candidates_are_the_registered_effects(registered_push):
    from validation.diagnosis import CANDIDATE_EFFECTS, DiagnoseConfig

    assert CANDIDATE_EFFECTS["constant_push"] == ("push",)
    assert list(CANDIDATE_EFFECTS) == list(EFFECT_TYPES)
    assert "constant_push" in DiagnoseConfig().candidates


def test_a_registered_effect_is_fitted_by_the_diagnosis(registered_push, fast_model, synthetic_runs):
    """Runs of the calibrated model whose hinge feels the dummy's constant push: the candidate fit finds it."""
    from validation.diagnosis import Calibration, DiagnosisProblem
    from validation.diagnosis.gap_model import fit_gap_model
    from validation.diagnosis.preparation import RunAccelerations

    truth = Calibration.at(fast_model, 1.0, fast_model.equilibrium_height)
    runs = synthetic_runs(fast_model, truth, {}, n_runs=4, duration=0.8)
    push = 40.0  # [1/s^2]: 0.8 times the thetaddot noise (50 1/s^2) on each of the 1600 samples
    pushed = [RunAccelerations(r.name, r.t, r.state, r.accel + np.array([0.0, push])) for r in runs]
    fit = fit_gap_model(DiagnosisProblem(fast_model, pushed), ["constant_push"])
    # standard error of the mean of 1600 samples at noise 50: 1.25 1/s^2; 4 of them
    assert fit.effects["constant_push"]["push"] == pytest.approx(push, abs=5.0)
