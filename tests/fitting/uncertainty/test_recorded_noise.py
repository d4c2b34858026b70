"""A data set tracked from video records its tracking noise (meta.json ``tracking`` block); the oracle uses it."""
from __future__ import annotations

from dataclasses import replace
from types import SimpleNamespace

import numpy as np
import pytest

from cubedimer.dataset import Dataset
from fitting.config import FitConfig
from fitting.synthetic import SyntheticConfig, generate_runs
from fitting import fit as pipeline
from fitting.uncertainty import final_checks
from fitting.uncertainty.oracle import NoiseLevels, OracleResult, recorded_tracking_noise

TRACKED = {"frame_rate_hz": 2000.0, "tracking": {"noise_y_m": 1.2e-7, "noise_theta": 6.0e-4, "fraction_measured": 1.0}}


def test_recorded_noise_is_read_from_the_tracking_block():
    n = recorded_tracking_noise(TRACKED)
    assert (n.sigma_y, n.sigma_theta) == (1.2e-7, 6.0e-4)
    assert "recorded by the tracking" in n.to_json()["source"]
    for meta in ({}, {"tracking": {}}, {"tracking": {"noise_y_m": 1e-7}}, {"tracking": {"noise_y_m": 0.0, "noise_theta": 1e-3}},
                 {"tracking": "yes"}):
        assert recorded_tracking_noise(meta) is None
    assert "fourth differences" in NoiseLevels(1e-6, 1e-3).to_json()["source"]


def test_the_oracle_takes_the_given_noise_instead_of_estimating_it(monkeypatch):
    seen = {}
    monkeypatch.setattr(final_checks, "estimate_tracking_noise", lambda runs: pytest.fail("estimated although given"))
    monkeypatch.setattr(final_checks, "runs_from_data", lambda derivs: [])

    def fake(model, runs, noise):
        seen["noise"] = noise
        return OracleResult({}, noise, 0, 0, {})

    monkeypatch.setattr(final_checks, "oracle_standard_errors", fake)
    given = recorded_tracking_noise(TRACKED)
    res = final_checks.final_oracle(None, [SimpleNamespace(derivs=None, run=None)], given)
    assert seen["noise"] is given and res.noise is given


def test_fit_dataset_passes_the_recorded_noise_on(monkeypatch, tmp_path):
    class Stop(Exception):
        pass

    runs = (SimpleNamespace(n_glitches=0, frames_averaged=1), SimpleNamespace(n_glitches=0, frames_averaged=1))
    monkeypatch.setattr(pipeline, "load_dataset", lambda *a, **k: Dataset(str(tmp_path), runs, dict(TRACKED)))
    monkeypatch.setattr(pipeline, "prepare_runs", lambda r, c: (list(r), SimpleNamespace(length_y=1, length_theta=1, time=1)))

    def fit_runs(*a, noise=None, **k):
        raise Stop(noise)

    monkeypatch.setattr(pipeline, "fit_runs", fit_runs)
    with pytest.raises(Stop) as info:
        pipeline.fit_dataset(tmp_path)
    assert info.value.args[0] == recorded_tracking_noise(TRACKED)
    # without the block, nothing is passed and the fit estimates the noise itself
    monkeypatch.setattr(pipeline, "load_dataset", lambda *a, **k: Dataset(str(tmp_path), runs, {}))
    with pytest.raises(Stop) as info:
        pipeline.fit_dataset(tmp_path)
    assert info.value.args[0] is None


def test_run_weights_follow_the_recorded_noise():
    from fitting.selection.support_search import run_weights

    w = run_weights([1.0, 2.0, 1.0, 2.0])
    # sigma_ref / sigma with sigma_ref the RMS noise: every weighted run has the noise sqrt(2.5)
    np.testing.assert_allclose(w, np.sqrt(2.5) / np.array([1.0, 2.0, 1.0, 2.0]), rtol=1e-15)
    assert run_weights([1.0, None, 2.0]) is None  # a run without a record: nobody is weighted
    assert run_weights([3.0, 3.0]) is None  # one noise for all: the unweighted fit itself
    assert run_weights([1.0, 0.0]) is None and run_weights([]) is None


@pytest.fixture(scope="module")
def mixed_noise_runs(truth):
    """8 runs of 2 s of the paper's reduced model, every second one with twice the tracking noise (1 and 2 um, 0.005
    and 0.01), as cubedimer Runs with and without each run's recorded noise."""
    from cubedimer.dataset import Run

    cfg = SyntheticConfig(n_runs=8, duration=2.0, missing_frames=0, seed=41)
    rng = np.random.default_rng(42)
    plain, recorded = [], []
    for i, r in enumerate(generate_runs(truth, cfg)):
        k = 2.0 if i % 2 else 1.0
        extra = np.sqrt(k ** 2 - 1.0)
        y = r["y"] + extra * cfg.noise_y * rng.standard_normal(r["t"].size)
        th = r["theta"] + extra * cfg.noise_theta * rng.standard_normal(r["t"].size)
        run = Run(name=f"run{i + 1:02d}.csv", t=r["t"], y=y, theta=th)
        plain.append(run)
        recorded.append(replace(run, noise=(k * cfg.noise_y, k * cfg.noise_theta)))
    return plain, recorded


@pytest.mark.slow
def test_the_discovery_weighs_each_run_by_its_recorded_noise(mixed_noise_runs, truth, without_front):
    """Weighted by its own noise, each run's integral-form residual is that noise: the residual over the noise is 1
    (the efficient estimator).  Unweighted, the residual is the runs' RMS noise, sqrt(2.5) = 1.58 times the quiet
    runs', while the pooled robust estimate of the mixture's noise is 1.37 times it (the MAD of a 50/50 mixture of
    N(0, 1) and N(0, 4)): a ratio of 1.155, read as model error (above the discovery's 1.05)."""
    from fitting.fit import prepare_runs
    from fitting.selection.integral_discovery import discover_model

    ratios = {}
    for label, runs in zip(("plain", "recorded"), mixed_noise_runs):
        prepared, _ = prepare_runs(runs)
        disc = discover_model([p.run for p in prepared], [p.derivs for p in prepared], FitConfig().method.selection)
        ratios[label] = disc.residual_to_noise
        if label == "recorded":
            assert disc.selection_modes == ("significance", "significance")
            found = (disc.coef != 0) == (truth.coef != 0)
            assert found.all(), "the weighted discovery finds the true support"
    # 3 % bounds: the ratio's sampling error over 8 x 4000 frames and the fit's degrees of freedom is below 1 %
    assert all(abs(r - 1.0) < 0.03 for r in ratios["recorded"])
    assert all(abs(r - 1.155) < 0.03 for r in ratios["plain"])
