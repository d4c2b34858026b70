"""The report's tracking section: shown for a data set tracked from video, absent otherwise."""
from __future__ import annotations

import json

import numpy as np

from acousim.twin.video import VideoCamera, record_video, write_video_tiff
from tracking.cli import main as track
from validation.report.sections.tracking import tracking_section


def test_a_tracked_dataset_gets_the_section_with_an_annotated_frame(tmp_path):
    cam = VideoCamera()
    videos = tmp_path / "videos"
    t = np.arange(80) / 2000.0
    for k in (1, 2):
        frames, _ = record_video(t, 60e-6 * np.cos(2 * np.pi * 22 * t + k), 0.4 * np.sin(2 * np.pi * 3 * t + k), 500e-6, cam, k)
        write_video_tiff(videos / f"run{k}.tif", frames, 2000.0, cam)
    data = tmp_path / "data"
    assert track(["track", str(videos), "--out", str(data), "--workers", "1"]) == 0
    sec = tracking_section(data, tmp_path / "figs")
    meta = json.loads((data / "meta.json").read_text())["tracking"]
    assert sec.id == "tracking"
    assert sec.numbers["fraction_measured"] == meta["fraction_measured"] == 1.0
    assert sec.numbers["noise_y_m"] == meta["noise_y_m"] and sec.numbers["noise_theta"] == meta["noise_theta"]
    assert [r[0] for r in sec.tables[0].rows] == ["run1.csv", "run2.csv"]
    assert len(sec.figures) == 1 and sec.figures[0].path.stat().st_size > 10_000
    assert "alpha" in sec.figures[0].caption and f"{meta['noise_theta']:.3g}" in sec.reading


def test_a_dataset_not_from_video_gets_no_section(tmp_path):
    (tmp_path / "run01.csv").write_text("t,y,theta\n0,0,0\n")
    (tmp_path / "meta.json").write_text('{"side_length_m": 5e-4}')
    assert tracking_section(tmp_path, tmp_path / "figs") is None
