"""Glitch masking is counted per run and can be switched off, and the detector does not flag clean smooth data
filmed at high frame rates."""
import importlib.util
import json
from pathlib import Path

import numpy as np
import pytest

from cubedimer.glitches import find_glitches
from fitting.cli import main
from fitting.synthetic import SyntheticConfig, generate_runs, paper_reduced_model

_spec = importlib.util.spec_from_file_location(
    "_fitting_test_default_fit", Path(__file__).parent / "methods" / "test_default_fit.py")
_default = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(_default)
TRUTH, CFG, _write = _default.TRUTH, _default.CFG, _default._write


@pytest.mark.parametrize("fps", [2000.0, 20000.0, 50000.0])
@pytest.mark.parametrize("quantum", [None, 1e-6])
def test_false_positive_rate_on_clean_smooth_high_rate_data(fps, quantum):
    # the paper's reduced model with 0.1 um / 0.0002 of white noise, optionally quantised like an encoder (1 um,
    # 0.001 of theta): the target is at most 0.1 % of frames flagged; the threshold of 7 robust standard
    # deviations gives ~3e-12 per frame on Gaussian noise, and quantisation leaves residuals within half a step
    runs = generate_runs(paper_reduced_model(), SyntheticConfig(n_runs=3, duration=0.5, fps=fps, noise_y=1e-7,
                                                                 noise_theta=2e-4, missing_frames=0, seed=12))
    flagged = frames = 0
    for r in runs:
        y, th = r["y"], r["theta"]
        if quantum:
            y, th = np.round(y / quantum) * quantum, np.round(th / (1e3 * quantum)) * 1e3 * quantum
        flagged += int((find_glitches(y, fps / 22.0) | find_glitches(th, fps / 9.0)).sum())
        frames += y.size
    assert flagged <= 1e-3 * frames
    assert flagged == 0  # measured: none on every one of these sets


def test_glitches_are_counted_per_run_and_the_switch_keeps_every_frame(tmp_path, without_front):
    # 6 glitches per run of 100 tracking-noise standard deviations (detected with certainty from ~14)
    raw = generate_runs(TRUTH, CFG)
    data = _write(tmp_path / "glitchy", raw, glitches_per_run=6, size=100 * CFG.noise_y, seed=3)
    common = ["--no-plots", "--quiet", "--workers", "1", "--max-evals", "10"]
    assert main(["fit", str(data), "--out", str(tmp_path / "on"), *common]) == 0
    assert main(["fit", str(data), "--out", str(tmp_path / "off"), "--no-glitch-mask", *common]) == 0
    on = json.loads((tmp_path / "on" / "model.json").read_text())
    off = json.loads((tmp_path / "off" / "model.json").read_text())
    assert [p["glitch_frames_masked"] for p in on["per_run"]] == [6] * CFG.n_runs
    assert on["glitch_frames_masked"] == 6 * CFG.n_runs
    assert [p["glitch_frames_masked"] for p in off["per_run"]] == [0] * CFG.n_runs
    assert off["glitch_frames_masked"] == 0 and off["settings"]["load"]["glitches"] is None
    assert on["settings"]["load"]["glitches"]["threshold"] == 7.0
    # the unmasked glitches enter the fit: the y residual grows beyond the tracking noise (6 frames of 100 sigma
    # in 4000 add ~sqrt(6e4 / 4000) ~ 4 sigma of RMS before the double integral's averaging), the masked fit's
    # residual is the noise itself (within 3 %, docs/fitting.md)
    r_on = on["discovery"]["yddot"]["residual_std"]
    r_off = off["discovery"]["yddot"]["residual_std"]
    np.testing.assert_allclose(r_on, CFG.noise_y, rtol=0.03)
    assert r_off > 1.5 * r_on
