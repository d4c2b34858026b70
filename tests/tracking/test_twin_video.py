"""The twin renders video (``python -m acousim simulate --video``) and the tracking reads it back: the chain
twin -> camera frames -> tracking -> run CSV against the true motion written beside the frames."""
from __future__ import annotations

import json

import numpy as np
import pytest

from acousim.cli import main as acousim_main
from cubedimer.dataset import LoadConfig, load_run
from tracking.cli import main as tracking_main


@pytest.mark.slow  # the twin's integration and rendering: about 10 s on an idle core
def test_simulate_video_then_track_recovers_the_true_motion(tmp_path):
    out = tmp_path / "twin"
    assert acousim_main(["simulate", "--runs", "1", "--duration", "0.15", "--seed", "5", "--video", "--lost-frames", "3",
                         "--polarity", "bright", "--bit-depth", "16", "--out", str(out), "--workers", "1",
                         "--no-progress"]) == 0
    truth = json.loads((out / "truth.json").read_text())["video"]
    assert truth["polarity"] == "bright" and truth["bit_depth"] == 16 and truth["fps"] == 2000.0
    lost = truth["lost_frames_per_run"]["run01"]
    assert len(lost) == 3
    tracked = tmp_path / "run01.csv"
    assert tracking_main(["track", str(out / "video" / "run01.tif"), "--out", str(tracked)]) == 0  # the file records fps, pixel size
    info = json.loads(tracked.with_suffix(".json").read_text())
    # a black lost frame on a dark background shows no particle
    assert info["orientation"]["polarity"] == "bright" and info["not_measured"] == {"no_dimer": 3}
    assert np.flatnonzero(np.array(info["quality"]["status"]) != 0).tolist() == lost
    cfg = LoadConfig(min_periods=0, glitches=None, max_gap=10)
    got, true = load_run(tracked, cfg), load_run(out / "video" / "run01_truth.csv", cfg)
    keep = np.setdiff1d(np.arange(got.t.size), lost)  # the loader filled the lost frames
    assert np.sqrt(np.mean((got.y[keep] - true.y[keep]) ** 2)) < 1e-6
    assert np.sqrt(np.mean((got.theta[keep] - true.theta[keep]) ** 2)) < 0.005


@pytest.mark.slow  # the twin's integration, rendering and H.264: about 15 s on an idle core
def test_simulate_video_with_imperfections_then_track(tmp_path):
    out = tmp_path / "twin"
    assert acousim_main(["simulate", "--runs", "1", "--duration", "0.3", "--seed", "6", "--video", "--rest-frames", "60",
                         "--static-bands", "10", "--illumination-gradient", "0.3", "--flicker", "0.05",
                         "--codec", "h264", "--out", str(out), "--workers", "1", "--no-progress"]) == 0
    truth = json.loads((out / "truth.json").read_text())["video"]
    assert truth["files"] == ["video/run01.mp4"] and truth["imperfections"]["bands_px"] == 10
    tracked = tmp_path / "run01.csv"
    # an mp4 records neither the camera's frame rate nor the pixel size; the origin comes from the 60 rest frames
    assert tracking_main(["track", str(out / "video" / "run01.mp4"), "--fps", "2000", "--pixel-size", "1e-5",
                          "--out", str(tracked)]) == 0
    info = json.loads(tracked.with_suffix(".json").read_text())
    assert info["y_origin"]["at_rest"] and info["calibration"]["static_structure_px"] > 0
    cfg = LoadConfig(min_periods=0, glitches=None, max_gap=10)
    got = load_run(tracked, cfg)
    # the run is the field-on motion: the truth (60 rest frames, the fall, 600 frames of motion) from its first frame
    truth = np.genfromtxt(out / "video" / "run01_truth.csv", delimiter=",", skip_header=3)
    first = info["phases"]["field_on_first_frame"]
    assert info["phases"]["rest_frames"] == [0, 60] and got.t.size == truth.shape[0] - first
    true_y, true_theta = truth[first:, 1], truth[first:, 2]
    err = got.y - true_y
    assert abs(np.mean(err)) < 2e-6 and np.std(err) < 1.5e-6  # the targets of docs/tracking.md
    assert np.sqrt(np.mean((got.theta - true_theta) ** 2)) < 0.005
