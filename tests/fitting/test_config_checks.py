"""Every config of the fit and the loader refuses a bad value on construction, with one line naming it."""
from __future__ import annotations

import pytest

from cubedimer.dataset import LoadConfig
from fitting.derivatives.savitzky_golay import SmoothingConfig
from fitting.selection.ensemble import EnsembleConfig
from fitting.refinement.losses import LossWeights
from fitting.refinement.long_time import RefineConfig
from fitting.selection.sparse_regression import RegressionConfig
from fitting.selection.rules import SelectionConfig

BAD = [
    (SelectionConfig, {"rule": "lasso"}, "unknown selection rule"),
    (SelectionConfig, {"alpha": 0.0}, "alpha"),
    (SelectionConfig, {"alpha": 1.5}, "alpha"),
    (SelectionConfig, {"n_try": 0}, "n_try"),
    (SelectionConfig, {"max_steps": 2.5}, "max_steps"),
    (RefineConfig, {"algorithm": "LD_LBFGS"}, "algorithm"),
    (RefineConfig, {"max_evals": 0}, "max_evals"),
    (RefineConfig, {"max_evals": True}, "max_evals"),
    (RefineConfig, {"rel_bound": -0.1}, "rel_bound"),
    (RefineConfig, {"abs_bound": float("nan")}, "abs_bound"),
    (RefineConfig, {"h_omega": 0.0}, "h_omega"),
    (RefineConfig, {"xtol_rel": -1e-7}, "xtol_rel"),
    (RefineConfig, {"horizons": ()}, "horizons"),
    (RefineConfig, {"horizons": (1.0, 0.5)}, "horizons"),
    (RefineConfig, {"horizons": (0.5, 1.5)}, "horizons"),
    (RegressionConfig, {"threshold": 0.0}, "threshold"),
    (RegressionConfig, {"alpha": -0.3}, "alpha"),
    (RegressionConfig, {"max_iter": 0}, "max_iter"),
    (EnsembleConfig, {"z_threshold": -3.0}, "z_threshold"),
    (SmoothingConfig, {"polyorder": 2}, "polyorder"),
    (SmoothingConfig, {"window_periods": 0.0}, "window_periods"),
    (SmoothingConfig, {"window": 20}, "odd"),
    (SmoothingConfig, {"window": 5}, "window"),
    (LossWeights, {"shape": -1.0}, "shape"),
    (LossWeights, {"shape": 0.0, "poincare": 0.0, "frequency": 0.0}, "at least one"),
    (LossWeights, {"bound": 0.0}, "bound"),
    (LossWeights, {"penalty": float("inf")}, "penalty"),
    (LoadConfig, {"max_gap": -1}, "max_gap"),
    (LoadConfig, {"max_missing_fraction": 1.5}, "max_missing_fraction"),
    (LoadConfig, {"uniform_tol": 0.0}, "uniform_tol"),
    (LoadConfig, {"min_periods": -5.0}, "min_periods"),
    (LoadConfig, {"trap_frequency": 40.0}, "trap_frequency"),
]


@pytest.mark.parametrize("cls, kwargs, words", BAD, ids=[f"{c.__name__}-{'-'.join(k)}" for c, k, _ in BAD])
def test_bad_value_fails_on_construction_with_one_line(cls, kwargs, words):
    with pytest.raises(ValueError, match=words) as info:
        cls(**kwargs)
    assert "\n" not in str(info.value)


@pytest.mark.parametrize("cls", [SelectionConfig, RefineConfig, RegressionConfig, EnsembleConfig, SmoothingConfig,
                                 LossWeights, LoadConfig])
def test_defaults_are_valid(cls):
    cls()


def test_edge_values_that_the_suite_uses_are_accepted():
    LoadConfig(min_periods=0, glitches=None)  # the tracking's short recordings
    RefineConfig(horizons=(1.0,))
    SmoothingConfig(window=9, polyorder=5)
    LossWeights(poincare=0.0, frequency=0.0)
