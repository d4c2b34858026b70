"""A recording of a whole field drop (at rest, the free fall with the field off, the field back on): the tracker
finds the phases, records them and writes the field-on motion with t = 0 at the field's return; --keep-drop keeps
every frame; the pooled noise of a set is never below its runs' RMS."""
from __future__ import annotations

import json

import numpy as np
import pytest

from acousim.twin.video import VideoCamera
from tracking.cli import main
from tracking.output import pooled_noise

from ..conftest import field_drop_heights
from .conftest import FPS, render

CAM = VideoCamera(noise=0.02)
REST, T_OFF = 59.6, 3.6e-3


@pytest.fixture(scope="module")
def drop_video(tmp_path_factory):
    t, y, on = field_drop_heights(400, FPS, REST, T_OFF, f_y=22.0, decay=0.0)
    theta = 0.3 * np.sin(2 * np.pi * 3.1 * t + 0.4)
    from acousim.twin.video import write_video_tiff

    path = tmp_path_factory.mktemp("drop") / "drop.tif"
    write_video_tiff(path, render(y, theta, CAM, seed=9), FPS, CAM)
    return path, t, y, on


@pytest.mark.parametrize("keep", [False, True])
def test_the_phases_are_found_and_the_run_is_the_field_on_motion(tmp_path, drop_video, keep):
    src, t, y, on = drop_video
    out = tmp_path / "drop.csv"
    assert main(["track", str(src), "--out", str(out)] + (["--keep-drop"] if keep else [])) == 0
    info = json.loads(out.with_suffix(".json").read_text())
    ph = info["phases"]
    # the switching times to a frame (tests/cubedimer/test_drop_phases.py), the fall at g to 4 standard errors
    assert abs(ph["drop_time_s"] * FPS - REST) <= 0.2 and abs(ph["field_on_time_s"] * FPS - on) <= 1.0
    assert abs(ph["fall_acceleration_m_s2"] + 9.80665) <= 4 * ph["fall_acceleration_error_m_s2"] + 0.05
    assert ph["rest_frames"] == [0, 60] and ph["free_fall"]
    rows = np.genfromtxt(out, delimiter=",", skip_header=out.read_text().splitlines().index("t,y,theta") + 1)
    if keep:
        assert ph["kept"] == "whole recording" and rows.shape[0] == 400 and rows[0, 0] == 0.0
        return
    k = ph["field_on_first_frame"]
    assert ph["kept"] == "field-on motion" and rows.shape[0] == 400 - k and on - 1 <= k <= on + 5
    # t = 0 at the field's return: the first row's time is its frame's delay after it
    assert rows[0, 0] == pytest.approx((k - ph["field_on_time_s"] * FPS) / FPS, abs=1e-9)
    # the heights are the field-on motion's, to 5 times the tracking's own noise estimate (Gaussian: 6e-7 chance)
    np.testing.assert_allclose(rows[:, 1], y[k:], atol=5 * info["noise_estimate"]["y_m"])


def test_the_pooled_noise_is_never_below_the_runs_rms():
    # a short noisy run (an H.264 one) among long clean ones: the frame-weighted RMS would average it away
    noise, frames = np.array([1e-3, 1e-3, 1e-3, 4e-3]), np.array([4000, 4000, 4000, 500])
    assert pooled_noise(noise, frames) == pytest.approx(np.sqrt(np.mean(noise ** 2)))
    assert pooled_noise(noise, frames) > np.sqrt(np.sum(frames * noise ** 2) / frames.sum())


def test_overlay_video_and_quality_plot(tmp_path, drop_video):
    import imageio.v3 as iio

    from tracking.measure import STATUS

    src, *_ = drop_video
    out = tmp_path / "drop.csv"
    assert main(["track", str(src), "--out", str(out), "--overlay"]) == 0
    video, plot = tmp_path / "drop.overlay.mp4", tmp_path / "drop.quality.png"
    assert plot.stat().st_size > 10_000
    frames = iio.imread(video)
    # every frame, enlarged twice, in colour; the status bar along the top: grey at rest, blue with the field off,
    # green for the measured field-on frames (H.264 shifts colours by a few levels: a margin of 60)
    assert frames.shape == (400, 2 * CAM.height, 2 * CAM.width, 3)
    info = json.loads(out.with_suffix(".json").read_text())
    assert info["quality"]["status"].count(STATUS["measured"]) == 400
    bar = frames[:, 2, CAM.width].astype(int)
    on = info["phases"]["field_on_first_frame"]
    assert np.all(np.abs(bar[10] - [150, 150, 150]) < 60) and np.all(np.abs(bar[on + 5] - [40, 200, 40]) < 60)
    assert bar[info["phases"]["field_off_frames"][0] + 1, 2] > bar[info["phases"]["field_off_frames"][0] + 1, 1]
    # the fitted squares are drawn in green on the frame
    f = frames[on + 5].astype(int)
    green = (f[..., 1] > f[..., 0] + 60) & (f[..., 1] > f[..., 2] + 60)
    assert green[6:].sum() > 200
