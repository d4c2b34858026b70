"""A data set tracked from video records its tracking noise (meta.json ``tracking`` block); the oracle uses it."""
from __future__ import annotations

from types import SimpleNamespace

import pytest

from cubedimer.dataset import Dataset
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
