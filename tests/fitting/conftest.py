"""Shared fixtures for the fitting tests: the truth model, small synthetic data sets, and discoveries without their
held-out front for the tests that do not read it."""
from __future__ import annotations

from contextlib import contextmanager

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


@contextmanager
def front_left_out():
    """Within the block, :func:`fitting.selection.integral_discovery.discover_model` leaves out its held-out long-time
    front (``DiscoveryResult.front`` is None): about half of a sparse discovery's time, for a record that no selection,
    coefficient, standard error or refinement depends on (it goes only into model.json's ``discovery.front`` and its
    figure; ``--max-terms``, which below the selection's size takes the front's point, then reads the selection
    passes' own paths).  For the tests that assert on the selection and the
    coefficients only; test_discovery.py shows that the results are identical without it, test_front.py and
    test_scale_invariance.py test the front itself."""
    from fitting.selection import integral_discovery

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(integral_discovery, "long_time_front", lambda *args, **kwargs: None)
        yield


@pytest.fixture
def without_front():
    """:func:`front_left_out` for one test."""
    with front_left_out():
        yield


@pytest.fixture(scope="session")
def leave_out_front():
    """:func:`front_left_out` itself (a context manager), for module-scoped fixtures that discover."""
    return front_left_out
