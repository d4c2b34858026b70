"""A new per-recording step, added the documented way (docs/architecture.md, "A new tracking step"): one
:func:`tracking.register_recording_step` call, no other change, and a rendered recording tracked through it carries
the step's result in TrackResult.info and in the RUN.json the command writes."""
from __future__ import annotations

import json
from dataclasses import dataclass

import numpy as np
import pytest

from acousim.twin.video import VideoCamera
from tracking import TrackedRecording, TrackingError, register_recording_step
from tracking.cli import main
from tracking.recording import Recording
from tracking.recording_steps import RECORDING_STEPS
from tracking.track import TrackConfig, track_recording

from .conftest import FPS, motion, render

CAM = VideoCamera(noise=0.02)
N = 160


@dataclass(frozen=True)
class HeightSpan:
    """A dummy step with a setting of its own: the span of the measured heights between two quantiles [m], and the
    number of frames it spans."""

    name: str = "height_span"
    quantile: float = 0.0  # 0: the full span, min to max

    def run(self, tracked: TrackedRecording) -> dict:
        y = tracked.y[tracked.measured]
        lo, hi = np.quantile(y, [self.quantile, 1.0 - self.quantile])
        return {"span_m": float(hi - lo), "frames": int(y.size), "quantile": self.quantile,
                "side_px": float(2.0 * np.median(tracked.column("half_side")[tracked.measured]))}


@pytest.fixture
def height_span():
    step = register_recording_step(HeightSpan())
    yield step
    del RECORDING_STEPS[step.name]  # registered for this test only


def _truth_span(y, status):
    return float(np.ptp(y[status == 0]))


def test_a_registered_step_s_result_reaches_the_track_result(height_span):
    _, y, theta = motion(N, seed=43)
    rec = Recording("span", "memory", "tiff", render(y, theta, CAM, seed=43), FPS, CAM.pixel_size, CAM.origin[1])
    res = track_recording(rec, TrackConfig())
    span = res.info["height_span"]
    assert span["frames"] == res.n_measured == N and span["quantile"] == 0.0
    # the measured heights' span against the truth's: each extreme is one frame's error, about 0.1 um RMS
    # (docs/tracking.md); 1 um is the tracking's accuracy target, and the span itself is about 160 um
    assert span["span_m"] == pytest.approx(_truth_span(y, res.status), abs=1e-6)
    # the step reads the kernel's rows too: the cube's side [px] is the rendered one (half-pixel edges: 2 %)
    assert span["side_px"] == pytest.approx(500e-6 / CAM.pixel_size, rel=0.02)


def test_the_command_writes_a_registered_step_s_result_into_run_json(height_span, tmp_path, write_tiff):
    _, y, theta = motion(N, seed=44)
    src = write_tiff("run09.tif", render(y, theta, CAM, seed=44), CAM)
    out = tmp_path / "out" / "run09.csv"
    assert main(["track", str(src), "--out", str(out)]) == 0
    run = json.loads(out.with_suffix(".json").read_text())
    assert run["height_span"]["frames"] == run["frames_measured"] == N
    assert run["height_span"]["span_m"] == pytest.approx(_truth_span(y, np.zeros(N, int)), abs=1e-6)


def test_without_the_step_run_json_has_no_entry_of_it(tmp_path, write_tiff):
    _, y, theta = motion(N, seed=45)
    rec = Recording("plain", "memory", "tiff", render(y, theta, CAM, seed=45), FPS, CAM.pixel_size, CAM.origin[1])
    assert "height_span" not in track_recording(rec, TrackConfig()).info


def test_a_step_named_as_an_entry_of_run_json_is_refused_in_one_line():
    step = register_recording_step(HeightSpan(name="noise_estimate"))
    try:
        _, y, theta = motion(N, seed=46)
        rec = Recording("clash", "memory", "tiff", render(y, theta, CAM, seed=46), FPS, CAM.pixel_size,
                        CAM.origin[1])
        with pytest.raises(TrackingError, match=r"^memory: the recording step 'noise_estimate' would replace "
                                                r"RUN.json's own 'noise_estimate'; register it under another name$"):
            track_recording(rec, TrackConfig())
    finally:
        del RECORDING_STEPS[step.name]
    with pytest.raises(TypeError, match="not a RecordingStep"):
        register_recording_step(object())
