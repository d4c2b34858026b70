"""Shared fixtures for the fitting tests: the truth model and small synthetic data sets."""
from __future__ import annotations

import numpy as np
import pytest

from fitting.synthetic import SyntheticConfig, generate_runs, paper_reduced_model, write_dataset


@pytest.fixture(scope="session")
def truth():
    return paper_reduced_model()


@pytest.fixture(scope="session")
def small_dataset(tmp_path_factory, truth):
    """Three noisy 2-s runs written as CSV (with a few missing frames)."""
    d = tmp_path_factory.mktemp("small_ds")
    write_dataset(d, truth, SyntheticConfig(n_runs=3, duration=2.0, seed=7))
    return d


@pytest.fixture(scope="session")
def clean_runs(truth):
    """Four noise-free 3-s runs (dicts with t, y, theta, exact state)."""
    return generate_runs(truth, SyntheticConfig(n_runs=4, noise_y=0.0, noise_theta=0.0, missing_frames=0, seed=3))
