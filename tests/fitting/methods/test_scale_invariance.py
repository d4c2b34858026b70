"""The discovery does not depend on the units of the data: a data set and its copy with the time divided by 30 and
y multiplied by 1000 (as if written in milliseconds... of a 30-times faster clock, and in millimetres) give the same
support, the same coefficients mapped back, and the same held-out long-time error and front.

Every window, segment and threshold of the discovery is set in periods of the data's own dominant frequencies or in
units of its noise (docs/fitting.md, "Units and time scale"); before that, windows bounded in seconds (25-500 ms)
and segments of 0.1-0.5 s gave another support on the copy (9-13 thetaddot terms against 7, coefficients up to
24 standard errors apart).
"""
from __future__ import annotations

import numpy as np
import pytest

from cubedimer.dataset import Run, fill_gaps
from fitting.config import FitConfig
from fitting.fit import fit_runs, prepare_runs
from fitting.model import PolynomialModel, Scales
from fitting.selection.front import HeldOutRun, long_time_error
from fitting.synthetic import SyntheticConfig, generate_runs

TIME_FACTOR, Y_FACTOR = 30.0, 1000.0


def _runs(gen, time_factor: float, y_factor: float) -> list[Run]:
    out = []
    for i, r in enumerate(gen):
        y, _ = fill_gaps(r["t"], r["y"], 10, "y", "run")
        th, _ = fill_gaps(r["t"], r["theta"], 10, "theta", "run")
        out.append(Run(name=f"run{i + 1:02d}.csv", t=r["t"] / time_factor, y=y * y_factor, theta=th))
    return out


@pytest.fixture(scope="module")
def default_fits(truth):
    """Six fitted runs and a seventh held out, as recorded and as the scaled copy: the whole default fit (discovery and
    long-time polish) of each, with the held-out run."""
    gen = generate_runs(truth, SyntheticConfig(n_runs=7, duration=2.0, seed=5))
    out = []
    for tf, yf in ((1.0, 1.0), (TIME_FACTOR, Y_FACTOR)):
        runs = _runs(gen, tf, yf)
        prep, scales = prepare_runs(runs[:6], FitConfig())
        x0 = gen[6]["x0"] * np.array([yf, yf * tf, 1.0, tf])
        out.append((fit_runs(prep, scales, FitConfig(), progress=False),
                    HeldOutRun(runs[6].dt, runs[6].y, runs[6].theta, x0)))
    return out


@pytest.fixture(scope="module")
def fitted_pair(default_fits):
    """The discovery of each, as the default fit made it (``discover_model`` on the prepared runs: the fit's
    preparation gives the same numbers as the discovery's own, to the bit)."""
    return [(fit.extras.discovery, held) for fit, held in default_fits]


@pytest.fixture(scope="module")
def full_fits(default_fits):
    """The whole default fit of both."""
    return [fit for fit, _ in default_fits]


def test_same_support_and_coefficients(fitted_pair):
    (a, *_), (b, *_) = fitted_pair
    assert np.array_equal(a.mask, b.mask)
    # the copy's coefficients in the copy's units: y' = 1000 y, t' = t / 30 is the scaled variable of
    # Scales(length_y=1 / 1000, length_theta=1, time=30)
    to_copy = Scales(1.0 / Y_FACTOR, 1.0, TIME_FACTOR)
    mapped = to_copy.to_si(b.coef)
    se = a.std_errors
    diff = np.abs(mapped - a.coef)[a.mask] / se[a.mask]
    # 0.1 standard errors is the bound; the method is exactly invariant, so what is left is rounding
    # (measured 6e-10 standard errors)
    assert diff.max() < 0.1
    assert np.allclose(np.abs(to_copy.to_si(b.std_errors))[a.mask], se[a.mask], rtol=1e-3)
    # the windows are the same number of periods: the same frames
    assert np.allclose(b.window_s * TIME_FACTOR, a.window_s, rtol=1e-6)


def test_same_long_time_error_and_front(fitted_pair):
    (a, held_a, *_), (b, held_b, *_) = fitted_pair
    e_a, e_b = long_time_error(a.model, held_a), long_time_error(b.model, held_b)
    assert np.isfinite(e_a) and e_a < 0.2  # the true support at 6 runs follows the held-out run to < 20 %
    # the bound, 2 %; the error is dimensionless and the trajectories the same up to rounding
    assert abs(e_b / e_a - 1.0) < 0.02
    pa, pb = a.front.points, b.front.points
    assert [p.terms for p in pa] == [p.terms for p in pb]
    assert np.allclose([p.error for p in pa if np.isfinite(p.error)], [p.error for p in pb if np.isfinite(p.error)],
                       rtol=0.02)


@pytest.mark.slow
def test_the_polished_model_maps_back_too(fitted_pair, full_fits):
    """The long-time polish starts from the discovered coefficients rounded to 9 significant digits in the data's own
    scaled units; without that its optimiser turned the copy's last-bit differences into 0.2-0.3 standard errors."""
    (a, held_a, *_), _ = fitted_pair
    fa, fb = full_fits
    assert np.array_equal(fa.model.support, fb.model.support)
    mapped = Scales(1.0 / Y_FACTOR, 1.0, TIME_FACTOR).to_si(fb.model.coef)
    # the bound, 0.1 of the discovery's standard errors (measured 3e-8)
    assert (np.abs(mapped - fa.model.coef)[a.mask] / a.std_errors[a.mask]).max() < 0.1
    e_a = long_time_error(fa.model, held_a)
    e_b = long_time_error(PolynomialModel(fb.model.coef), fitted_pair[1][1])
    assert abs(e_b / e_a - 1.0) < 0.02
