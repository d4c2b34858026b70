"""Shared fixtures for the whole suite."""
from __future__ import annotations

import os

import numpy as np
import pytest

os.environ.setdefault("MPLBACKEND", "Agg")
os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")

#: Test modules that solve boundary-element problems.  bempp-cl compiles its assembly kernels at first use in
#: every process (about 100 s on one core; they cannot be cached on disk), so ``make test`` (``--dist loadfile``)
#: sends these modules to one pytest-xdist worker as one unit and the compilation happens once per session.
BOUNDARY_ELEMENT_MODULES = frozenset({
    "tests/acousim/test_fullwave_sphere.py", "tests/acousim/test_fullwave_dimer.py",
    "tests/acousim/test_fullwave_flux.py", "tests/acousim/test_fullwave_cli.py",
    "tests/acousim/test_fullwave_surrogate.py", "tests/acousim/test_fullwave_interaction.py",
})


@pytest.hookimpl(optionalhook=True)  # a plain pytest without pytest-xdist ignores it
def pytest_xdist_make_scheduler(config, log):
    """``--dist loadfile``, with the boundary-element modules as one unit (pytest-xdist's ``xdist_group`` marks
    would do this with ``--dist loadgroup``, but that mode silently stops grouping on pytest 9.2)."""
    if config.getoption("dist") != "loadfile":
        return None
    from xdist.scheduler import LoadFileScheduling

    class _BoundaryElementsTogether(LoadFileScheduling):
        def _split_scope(self, nodeid: str) -> str:
            module = super()._split_scope(nodeid)
            return "boundary-elements" if module in BOUNDARY_ELEMENT_MODULES else module

    return _BoundaryElementsTogether(config, log)


@pytest.fixture(scope="session")
def default_wave():
    from acousim.field import StandingWave

    return StandingWave()


@pytest.fixture(scope="session")
def default_model():
    """The Gor'kov dimer at the docs/conventions.md defaults (500 um NaCl, 3 kPa, default mesh)."""
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
    from validation.report.browser_check import find_chromium

    if find_chromium() is None:
        if os.environ.get("CUBEDIMER_REQUIRE_BROWSER") == "1":
            pytest.fail("Chromium is required for this run but was not found")
        pytest.skip("Chromium not installed")


def _write_csv(path, t, y, theta, header="t,y,theta", comment=True):
    lines = (["# test file"] if comment else []) + [header]
    lines += [f"{a:.10g},{b:.10g},{c:.10g}" for a, b, c in zip(t, y, theta)]
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.fixture
def write_csv():
    """Writer of a CSV run: ``write_csv(path, t, y, theta, header=...)``."""
    return _write_csv


@pytest.fixture
def sine_run():
    """A clean 22-Hz y / 9-Hz theta signal, 2 s at 1000 fps."""
    t = np.arange(2000) / 1000.0
    return t, 1e-4 * np.cos(2 * np.pi * 22 * t), 0.2 * np.sin(2 * np.pi * 9 * t)


@pytest.fixture(scope="session")
def process_cluster():
    """A real dask cluster on the loopback for the whole session: a scheduler and two daemonic worker
    processes (as every normal deployment has); yields its address and shuts it down at the end."""
    pytest.importorskip("dask.distributed")
    from cubedimer.executor import loopback_cluster

    with loopback_cluster(2) as address:
        yield address


#: The synthetic family's analytic dependence: the interpolated quantities (dimensionless coefficients, F_Z's over ks)
#: of the default table times (1 + KS_SLOPE (ks - ks0) + KS_CURV (ks - ks0)^2) for every component, and times
#: (1 + GAP_SLOPE L + GAP_CURV L^2), L = log(g / g0), for Q_theta only (the gap sets the hinge stiffness: softer as
#: the gap opens, as in the full wave).  Quadratic in ks and log g: the family's interpolant is exact.
SYNTHETIC_FAMILY = {"ks_slope": 0.8, "ks_curv": -1.5, "gap_slope": -0.3, "gap_curv": 0.02}


def synthetic_reduced(ks: float, gap_ratio: float) -> dict:
    """The synthetic family's dimensionless coefficients at (ks, g/s)."""
    from acousim.fullwave import default_fullwave_surrogate
    from acousim.fullwave.family import dimensionless_coefficients

    sur0 = default_fullwave_surrogate()
    ks0 = sur0.wavenumber * sur0.settings["side_m"]
    base = dimensionless_coefficients(sur0)
    p = SYNTHETIC_FAMILY
    fk = 1 + p["ks_slope"] * (ks - ks0) + p["ks_curv"] * (ks - ks0) ** 2
    lg = np.log(gap_ratio / 0.01)
    fg = 1 + p["gap_slope"] * lg + p["gap_curv"] * lg**2
    return {"fz": base["fz"] / ks0 * ks * fk, "qt": base["qt"] * fk * fg}


def write_synthetic_family(directory, ks_nodes=None, gap_nodes=None) -> list:
    """Node tables of the synthetic family in ``directory`` (the family's node grid by default); no solve."""
    from dataclasses import replace as dc_replace

    from acousim.fullwave.family import (FAMILY_GAP_RATIOS, FAMILY_KS, REFERENCE, FamilyNode, node_path,
                                         scaled_surrogate)

    from acousim.fullwave import default_fullwave_surrogate

    n_half = default_fullwave_surrogate().settings["n_half"]
    paths = []
    for g in gap_nodes or FAMILY_GAP_RATIOS:
        for k in ks_nodes or FAMILY_KS:
            node = FamilyNode(k, g, n_half=n_half, theta_max=0.9)
            s = REFERENCE["side_m"]
            sur = scaled_surrogate(synthetic_reduced(k, g), 0.9, s, g * s, node.medium,
                                   REFERENCE["particle_density_kg_m3"], REFERENCE["pressure_amplitude_pa"])
            sur = dc_replace(sur, settings={**sur.settings, **node.expected_settings()},
                             build_accuracy={"ks": k, "gap_ratio": g, "dofs": 0, "wall_s": 0.0})
            path = node_path(directory, node)
            sur.save(path)
            paths.append(path)
    return paths


@pytest.fixture(scope="session")
def synthetic_family_dir(tmp_path_factory):
    """A complete synthetic table family (no boundary-element solve) with a known dependence on (ks, g/s)."""
    d = tmp_path_factory.mktemp("synthetic_family")
    write_synthetic_family(d)
    return d


@pytest.fixture
def use_synthetic_family(synthetic_family_dir, monkeypatch):
    """Point the full-wave model at the synthetic family for this test."""
    from acousim.fullwave.family import FAMILY_ENV

    monkeypatch.setenv(FAMILY_ENV, str(synthetic_family_dir))
    return synthetic_family_dir
