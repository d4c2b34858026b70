"""Accuracy of the measurement on rendered frames against the truth that drew them.

Targets (docs/tracking.md): at 10 um per pixel, a point-spread width of 1 px and 2 % image noise, y within
1 um RMS and theta within 0.005 RMS, with under 1 % of the frames unmeasured.  Each case is a fresh render
(its own seed) of 300 frames (150 of the four times larger frames at 5 um per pixel); the measured errors are about 0.1 um and 0.0006 (docs/tracking.md), so the
targets leave room for the scatter of 300 frames but not for a bias of a tenth of a pixel or a percent of theta.
"""
from __future__ import annotations

import numpy as np
import pytest

from acousim.twin.video import VideoCamera
from tracking.measure import COLUMNS
from tracking.recording import Recording
from tracking.track import TrackConfig, track_recording

from .conftest import FPS, motion, render

N = 300


def _track(frames, camera, **kw):
    rec = Recording("case", "memory", "tiff", frames, FPS, camera.pixel_size, camera.origin[1])
    return track_recording(rec, TrackConfig(**kw))


def _errors(res, y, theta):
    ok = res.status == 0
    return (float(np.sqrt(np.mean((res.y[ok] - y[ok]) ** 2))), float(np.sqrt(np.mean((res.theta[ok] - theta[ok]) ** 2))),
            float(ok.mean()))


@pytest.mark.parametrize("pixel_size, seed", [(10e-6, 11), (5e-6, 12)])
def test_accuracy_at_two_pixel_sizes_meets_the_targets(pixel_size, seed):
    # 5 um/px: the dimer is twice as many pixels; the frame grows with it (the same field of view)
    scale = 10e-6 / pixel_size
    cam = VideoCamera(pixel_size=pixel_size, width=int(180 * scale), height=int(150 * scale), psf_sigma=1.0, noise=0.02)
    _, y, theta = motion(int(N / scale), seed=seed)
    res = _track(render(y, theta, cam, seed=seed), cam)
    ey, et, frac = _errors(res, y, theta)
    assert frac >= 0.99
    assert ey < 1e-6 and et < 0.005
    # the recording's own noise estimates describe its errors (within the scatter of 300 frames and the bias of
    # propagating pixel noise through the fits)
    assert 0.6 < res.info["noise_estimate"]["y_m"] / ey < 1.6
    assert 0.6 < res.info["noise_estimate"]["theta"] / et < 1.6


def test_noise_free_frames_are_measured_exactly():
    # the edge sums and the centre of mass are unbiased for a symmetric blur: without noise only the 16-bit
    # quantisation (1.5e-5 of the contrast) remains
    cam = VideoCamera(noise=0.0, bit_depth=16)
    _, y, theta = motion(120, theta_amp=0.8, seed=3)
    res = _track(render(y, theta, cam), cam)
    ey, et, frac = _errors(res, y, theta)
    assert frac == 1.0
    assert ey < 0.002 * cam.pixel_size and et < 1e-4


@pytest.mark.parametrize("polarity", ["dark", "bright"])
def test_both_polarities_are_detected_and_measured(polarity):
    cam = VideoCamera(polarity=polarity, noise=0.02)
    _, y, theta = motion(N, seed=21)
    res = _track(render(y, theta, cam, seed=21), cam)
    assert res.info["orientation"] == {"up": "top", "polarity": polarity, "polarity_from": "detected"}
    ey, et, frac = _errors(res, y, theta)
    assert frac >= 0.99 and ey < 1e-6 and et < 0.005


def test_large_bends_keep_their_sign_and_stay_inside_the_open_interval():
    # theta from 0.75 to 0.97 and its mirror: the face orientations alone are ambiguous near +-1 (squares nearly
    # axis-aligned); the hinge's height above or below the centres settles the sign
    cam = VideoCamera(noise=0.02)
    t = np.arange(200) / FPS
    theta = np.concatenate([np.linspace(0.75, 0.97, 100), -np.linspace(0.75, 0.97, 100)])
    y = 20e-6 * np.sin(2 * np.pi * 22 * t)
    res = _track(render(y, theta, cam, seed=5), cam)
    ok = res.status == 0
    assert ok.mean() > 0.95
    assert np.all(np.sign(res.theta[ok]) == np.sign(theta[ok]))
    assert np.max(np.abs(res.theta[ok] - theta[ok])) < 0.02
    assert np.all(np.abs(res.theta[ok]) < 1)


def test_upside_down_image_flips_y_and_theta():
    cam = VideoCamera(noise=0.02)
    _, y, theta = motion(150, seed=8)
    frames = render(y, theta, cam, seed=8)[:, ::-1, :]
    rec = Recording("flip", "memory", "tiff", frames, FPS, cam.pixel_size, None)
    res = track_recording(rec, TrackConfig(up="bottom", origin_row=cam.height - 1 - cam.origin[1]))
    ok = res.status == 0
    assert np.sqrt(np.mean((res.y[ok] - y[ok]) ** 2)) < 1e-6
    assert np.sqrt(np.mean((res.theta[ok] - theta[ok]) ** 2)) < 0.005
    # read with the default (rows count down) the same frames give the mirrored motion: the option matters
    wrong = track_recording(rec, TrackConfig(origin_row=cam.height - 1 - cam.origin[1]))
    assert np.corrcoef(wrong.theta[ok], theta[ok])[0, 1] < -0.99


def test_hinge_corners_are_square_on_a_rendered_dimer():
    cam = VideoCamera(noise=0.02)
    _, y, theta = motion(100, theta_amp=0.5, seed=2)
    res = _track(render(y, theta, cam, seed=2), cam)
    c = {k: i for i, k in enumerate(COLUMNS)}
    s = res.rows[:, c["alpha_free"]] + res.rows[:, c["beta_free"]] - np.pi
    assert np.isfinite(s).mean() > 0.9
    assert np.nanmax(np.abs(s)) < 0.02  # alpha + beta = pi within the face-fit noise (~0.003 rad)
    # and alpha, beta themselves are those of the true bend: alpha = pi/2 (1 + theta)
    ok = res.status == 0
    assert np.allclose(res.rows[ok, c["alpha"]], 0.5 * np.pi * (1 + theta[ok]), atol=0.01)
