"""Shared fixtures for the whole suite."""
from __future__ import annotations

import os

import numpy as np
import pytest

os.environ.setdefault("MPLBACKEND", "Agg")
os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")


@pytest.fixture(scope="session")
def default_wave():
    from acousim.field import StandingWave

    return StandingWave()


@pytest.fixture(scope="session")
def default_model():
    """The Gor'kov dimer at the PHYSICS.md defaults (500 um NaCl, 3 kPa, default mesh)."""
    from acousim.forces import GorkovDimer

    return GorkovDimer()


@pytest.fixture(scope="session")
def raw_model():
    """The default model without the symmetrised quadrature: the bare mesh."""
    from acousim.forces import GorkovDimer

    return GorkovDimer(symmetrize=False)


@pytest.fixture
def rng():
    return np.random.default_rng(12345)


@pytest.fixture
def chromium_required():
    """Skip when no Chromium is installed, unless the run promised one (make test sets
    CUBEDIMER_REQUIRE_BROWSER=1 after installing it), in which case its absence is a failure."""
    from validation.browser import find_chromium

    if find_chromium() is None:
        if os.environ.get("CUBEDIMER_REQUIRE_BROWSER") == "1":
            pytest.fail("Chromium is required for this run but was not found")
        pytest.skip("Chromium not installed")
