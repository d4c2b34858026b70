"""The twin camera's imperfections of a real recording (acousim.twin.imperfections): each against its definition."""
from __future__ import annotations

import math

import numpy as np
import pytest

from acousim.twin import TwinError
from acousim.twin.imperfections import (Imperfections, band_coverage, dust_tracks, h264_roundtrip, illumination,
                                        tilted_coverage)
from acousim.twin.video import VideoCamera, dimer_squares, record_video, render_coverage

SIDE = 500e-6


def test_no_imperfection_renders_exactly_the_clean_camera():
    t = np.arange(20) / 2000.0
    y = 50e-6 * np.sin(2 * np.pi * 22 * t)
    th = 0.3 * np.cos(2 * np.pi * 3 * t)
    clean = record_video(t, y, th, SIDE, VideoCamera(), 5)[0]
    same = record_video(t, y, th, SIDE, VideoCamera(imperfections=Imperfections(codec="tiff", rest_frames=0)), 5)[0]
    np.testing.assert_array_equal(clean, same)
    assert "imperfections" not in VideoCamera().to_dict()  # truth.json of a clean camera is unchanged
    assert VideoCamera(imperfections=Imperfections(flicker=0.05)).to_dict()["imperfections"]["flicker"] == 0.05


def test_illumination_gradient_and_flicker():
    imp = Imperfections(gradient=0.3, flicker=0.05, flicker_hz=100.0)
    L = illumination(np.array([0.0, 0.0025]), 101, imp)  # a quarter period of 100 Hz: the flicker's maximum
    np.testing.assert_allclose(L[0, 0, [0, 50, 100]], [0.85, 1.0, 1.15], rtol=1e-6)  # float32
    np.testing.assert_allclose(L[1, 0, [0, 50, 100]], 1.05 * np.array([0.85, 1.0, 1.15]), rtol=1e-6)


def test_static_bands_cover_the_top_and_bottom_rows_only():
    cov = band_coverage(150, 180, 12, 1.0)
    # the edge undulates by 1.5 px about row 12 (at least 10.5 rows covered), blurred by 1 px
    assert np.all(cov[:8] > 0.99) and np.all(cov[-8:] > 0.99)
    assert np.all(cov[20:130] < 1e-6)
    # the bands' area: 2 x 12 rows on average (the undulation averages out over 1.5 periods... to 1.5 px x 180)
    assert abs(cov.sum() / 180 - 24.0) < 1.0


def test_dust_specks_cross_the_frame_in_the_given_frames():
    imp = Imperfections(dust=2, dust_frames=100)
    pos = dust_tracks(500, 180, 150, imp, np.random.default_rng(3))
    for k in range(2):
        in_view = pos[:, k, 0] > -1e3
        assert in_view.sum() == 100
        f = np.flatnonzero(in_view)
        assert np.all(np.diff(f) == 1)
        np.testing.assert_allclose(np.diff(pos[f, k, 0]), (180 + 2 * imp.dust_px) / 100)  # straight, uniform


@pytest.mark.parametrize("tilt_deg", [0.0, 10.0])
def test_a_tilted_hinge_line_gives_the_swept_silhouette_area(tilt_deg):
    cam = VideoCamera()
    centres, angles, half = dimer_squares(np.zeros(1), np.zeros(1), SIDE, cam)
    tau = math.radians(tilt_deg)
    cov = tilted_coverage(centres, angles, half, cam.origin[0], tau, (cam.height, cam.width), 1.0)
    s = 2.0 * half
    # each diamond shortened by cos(tilt) and swept by s sin(tilt) over its height s sqrt(2); the two overlap near
    # the hinge by (s sin)^2 / (2 cos)
    area = 2 * s * s * math.cos(tau) + 2 * math.sqrt(2) * s * s * math.sin(tau) - (s * math.sin(tau)) ** 2 / (2 * math.cos(tau))
    # 4 sub-rows per row: the area is exact to the sub-row sampling of the corners (a few 1e-4)
    np.testing.assert_allclose(cov.sum(), area, rtol=1e-3)
    if tilt_deg == 0:  # the same picture as the analytic renderer (the blur is applied as a filter here)
        ref = render_coverage(centres, angles, half, (cam.height, cam.width), 1.0)
        assert np.max(np.abs(cov - ref)) < 0.03


def test_transparent_cubes_have_a_bright_interior_inside_a_dark_outline():
    cam = VideoCamera(noise=0.0, imperfections=Imperfections(transparent=True, rim=0.15))
    frames = record_video(np.zeros(1), np.zeros(1), np.zeros(1), SIDE, cam, 0)[0].astype(float) / 255
    u0, v0 = cam.origin
    d = SIDE / math.sqrt(2) / cam.pixel_size
    bg, fg = cam.levels
    centre_b = frames[0, int(round(v0)), int(round(u0 + d))]
    np.testing.assert_allclose(centre_b, bg + 0.1 * (bg - fg), atol=1 / 255)  # brighter than the background
    rim = frames[0, int(round(v0)), int(round(u0 + 2 * d - 3))]  # 3 px inside cube B's outer corner
    assert rim < 0.5 * (bg + fg)


def test_h264_roundtrip_keeps_the_picture_within_a_few_grey_levels(tmp_path):
    cam = VideoCamera()
    t = np.arange(24) / 2000.0
    frames = record_video(t, np.zeros(24), np.zeros(24), SIDE, cam, 1)[0]
    back = h264_roundtrip(frames, 2000.0, 23, tmp_path)
    assert back.shape == frames.shape and back.dtype == np.uint8
    err = back.astype(float) - frames
    assert 0 < np.sqrt(np.mean(err ** 2)) < 8  # lossy, not broken (the image noise alone is 3.3 grey levels)
    assert not list(tmp_path.iterdir())  # the temporary mp4 is gone


@pytest.mark.parametrize("kw", [dict(gradient=1.2), dict(flicker=-0.1), dict(tilt_deg=60), dict(codec="av1"),
                                dict(transparent=True, tilt_deg=5), dict(dust=-1), dict(crf=99)])
def test_bad_imperfection_settings_are_refused(kw):
    with pytest.raises(TwinError):
        Imperfections(**kw)


#: the imperfections whose compiled renderers run frames on numba's threads
THREADED_IMPERFECTIONS = (dict(tilt_deg=10.0), dict(transparent=True, dust=1))


def test_a_recording_is_the_same_on_any_number_of_threads():
    """The compiled renderers run their frames on numba's threads: the frames must not depend on how many there
    are (a scratch array shared between the threads once garbled the tilted silhouettes on two threads).  Each
    imperfection of :data:`THREADED_IMPERFECTIONS` is recorded in each of three processes (one thread, two, two)."""
    import os
    import subprocess
    import sys
    import textwrap
    from pathlib import Path

    code = textwrap.dedent(f"""
        import hashlib, numpy as np
        from acousim.twin.imperfections import Imperfections
        from acousim.twin.video import VideoCamera, record_video
        t = np.arange(96) / 2000.0
        y, theta = 120e-6 * np.sin(2 * np.pi * 22 * t), 0.3 * np.sin(2 * np.pi * 4 * t)
        for imperfection in {THREADED_IMPERFECTIONS!r}:
            cam = VideoCamera(imperfections=Imperfections(**imperfection))
            print(hashlib.sha1(record_video(t, y, theta, 500e-6, cam, 7)[0].tobytes()).hexdigest())
    """)
    root = Path(__file__).resolve().parents[3]
    digests = []
    for threads in ("1", "2", "2"):
        env = dict(os.environ, NUMBA_NUM_THREADS=threads,
                   PYTHONPATH=os.pathsep.join([str(root), os.environ.get("PYTHONPATH", "")]))
        res = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=600)
        assert res.returncode == 0, res.stderr[-2000:]
        digests.append(res.stdout.split()[-len(THREADED_IMPERFECTIONS):])
    # per imperfection: identical frames on one and two threads, and twice on two
    for k, imperfection in enumerate(THREADED_IMPERFECTIONS):
        assert len({d[k] for d in digests}) == 1, imperfection
    assert len({d[0] for d in digests} | {d[1] for d in digests}) == 2  # and the two imperfections differ
