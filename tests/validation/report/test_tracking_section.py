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
    # the TIFF records its levitation row: the origin is the file's, and nothing is said about rest
    assert sec.numbers["origin_not_at_rest"] == [] and "did not start at rest" not in sec.reading


def test_the_report_names_the_recordings_that_did_not_start_at_rest(tmp_path):
    """Without a recorded levitation row the tracking takes y = 0 from the first 50 frames when they are at rest,
    else from the centre of the late oscillation once it has settled; the report names the second kind, as the
    tracking recorded it.  The oscillations ring down in 30 ms, so the last frames of 0.2 s are settled."""
    cam = VideoCamera()
    videos = tmp_path / "videos"
    t = np.arange(400) / 2000.0
    for k, rest_frames in ((1, 60), (2, 0), (3, 0)):
        moving = t >= rest_frames / 2000.0
        ring = np.exp(-(t - rest_frames / 2000.0) / 0.03)
        y = np.where(moving, 60e-6 * ring * np.sin(2 * np.pi * 22 * (t - rest_frames / 2000.0) + 0.5 * k), 0.0)
        theta = np.where(moving, 0.3 * np.sin(2 * np.pi * 3 * (t - rest_frames / 2000.0) + k), 0.0)
        frames, _ = record_video(t, y, theta, 500e-6, cam, k)
        write_video_tiff(videos / f"run{k}.tif", frames, 2000.0, cam, extra={"levitation_row_px": None})
    data = tmp_path / "data"
    assert track(["track", str(videos), "--out", str(data), "--workers", "1"]) == 0
    recorded = {r["file"]: r["origin_at_rest"] for r in json.loads((data / "meta.json").read_text())["tracking"]["runs"]}
    assert recorded == {"run1.csv": True, "run2.csv": False, "run3.csv": False}
    sec = tracking_section(data, tmp_path / "figs")
    assert sec.numbers["origin_not_at_rest"] == ["run2.csv", "run3.csv"]
    assert "2 of 3 recordings did not start at rest (run2.csv, run3.csv)" in sec.reading


def test_a_dataset_not_from_video_gets_no_section(tmp_path):
    (tmp_path / "run01.csv").write_text("t,y,theta\n0,0,0\n")
    (tmp_path / "meta.json").write_text('{"side_length_m": 5e-4}')
    assert tracking_section(tmp_path, tmp_path / "figs") is None
