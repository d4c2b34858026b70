"""The candidate effects as linear regressors of the accelerations."""
import numpy as np
import pytest

from validation.diagnosis import CANDIDATE_EFFECTS, effect_regressors
from validation.diagnosis.prepare.candidate_effects import default_candidates


@pytest.mark.parametrize("name", default_candidates())  # the cavity's lag: test_cavity_lag.py
def test_regressors_are_linear_in_parameters(name, rng):
    st = rng.normal(size=(20, 4))
    z = rng.uniform(-5e-4, 0, 20)
    reg = effect_regressors(name, st, z, 836.0)
    assert reg.shape == (20, 2, len(CANDIDATE_EFFECTS[name]))
    # docs/conventions.md section 5: which equation each parameter acts in
    acts_in_y = {"gamma_y", "c_y"}
    for j, p in enumerate(CANDIDATE_EFFECTS[name]):
        assert np.any(reg[:, 0, j] != 0) == (p in acts_in_y)
