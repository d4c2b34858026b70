"""Every point of the front (fitting.selection.front) carries its model: the coefficients of its supports fitted on
all runs, in memory and in model.json's front, so that a user (and the benchmark against pysindy) takes any size
without refitting."""
from __future__ import annotations

import numpy as np

from cubedimer.dataset import Run
from cubedimer.spectra import dominant_frequency
from fitting.derivatives.savitzky_golay import run_derivatives
from fitting.model import TERMS, PolynomialModel
from fitting.selection.integral_discovery import discover_model
from fitting.synthetic import SyntheticConfig, generate_runs

W_Y, W_9 = 2 * np.pi * 22.0, 2 * np.pi * 9.0


def _discovery():
    # the small, low-noise set of the discovery's tests (4 runs of 2 s): every true term has oracle z > 10
    truth = PolynomialModel.from_equations({"yddot": {"y": -W_Y ** 2, "ydot": -0.3, "1": 0.1, "y^2": 9.5e6},
                                            "thetaddot": {"theta": -W_9 ** 2, "thetadot": -0.8, "1": 60.0,
                                                          "y": 1.5e6, "y^2*theta": 2e10, "y*thetadot^2": 5e3,
                                                          "y*ydot*thetadot": 8e6}})
    runs, derivs = [], []
    for i, r in enumerate(generate_runs(truth, SyntheticConfig(n_runs=4, duration=2.0, noise_y=1e-6,
                                                               noise_theta=0.002, missing_frames=0, seed=21))):
        run = Run(name=f"run{i + 1:02d}.csv", t=r["t"], y=r["y"], theta=r["theta"])
        runs.append(run)
        derivs.append(run_derivatives(run.t, run.y, run.theta, dominant_frequency(run.y, run.dt)))
    return truth, discover_model(runs, derivs)


def test_front_points_carry_their_models():
    truth, res = _discovery()
    points = res.front.points
    for p in points:
        # the coefficients live exactly on the point's supports (a zero there would be a term the point lacks)
        for q, eq in enumerate(("yddot", "thetaddot")):
            assert {TERMS[j] for j in np.flatnonzero(p.coef[q])} == set(p.terms[eq])
        doc = p.to_json()["coefficients"]
        assert {eq: set(c) for eq, c in doc.items()} == {eq: set(t) for eq, t in p.terms.items()}
    # the selected point (the true support here; no model error, so no output error) is the discovery's own
    # integral-form fit on all runs: the same least squares, equal to rounding (1e-9 relative)
    selected = res.front.selected
    assert selected is not None and np.array_equal(selected.coef != 0, truth.support)
    np.testing.assert_allclose(selected.coef, res.coef, rtol=1e-9, atol=0.0)
