"""Frames the dimer cannot be measured in are left empty and counted with their reason; the good ones are kept."""
from __future__ import annotations

import numpy as np

from acousim.twin.video import VideoCamera
from tracking.measure import STATUS
from tracking.recording import Recording
from tracking.track import TrackConfig, track_recording

from .conftest import FPS, motion, render

CAM = VideoCamera(noise=0.02)


def _track(frames, camera=CAM, **kw):
    return track_recording(Recording("case", "memory", "tiff", frames, FPS, camera.pixel_size, camera.origin[1]),
                           TrackConfig(**kw))


def _good(res, y, theta, ok):
    assert np.sqrt(np.mean((res.y[ok] - y[ok]) ** 2)) < 1e-6
    assert np.sqrt(np.mean((res.theta[ok] - theta[ok]) ** 2)) < 0.005


def test_lost_frames_are_left_empty_and_counted():
    _, y, theta = motion(200, seed=31)
    lost = [17, 18, 90, 151]
    res = _track(render(y, theta, CAM, seed=31, lost=lost))
    assert np.flatnonzero(res.status != 0).tolist() == lost
    assert np.all(np.isnan(res.y[lost])) and np.all(np.isnan(res.theta[lost]))
    assert res.info["not_measured"] == {"corrupt": 4} and res.info["frames_measured"] == 196
    _good(res, y, theta, res.status == 0)


def test_a_particle_costs_only_the_frames_where_it_comes_within_reach_of_the_dimer():
    from acousim.twin.video import dimer_squares, render_coverage

    n = 200
    _, y, theta = motion(n, seed=32)
    # a 300 um particle comes down from above the view towards cube A
    v = -25.0 + 0.25 * np.arange(n)
    centres = np.stack([np.full(n, CAM.origin[0] - 50.0), v], axis=1)
    half = 0.5 * 300e-6 / CAM.pixel_size
    res = _track(render(y, theta, CAM, seed=32, extra=(centres, 0.3, half)))
    # the silhouettes (coverage > 1/2) of each alone: how far the particle's is from the dimer's bounding box
    shape = (CAM.height, CAM.width)
    c2, a2, h2 = dimer_squares(y, theta, 500e-6, CAM)
    dim = render_coverage(c2, a2, h2, shape, CAM.psf_sigma) > 0.5
    par = render_coverage(centres[:, None, :], np.full((n, 1), 0.3), half, shape, CAM.psf_sigma) > 0.5
    rows = np.arange(CAM.height)[None, :]
    top = np.min(np.where(dim.any(axis=2), rows, 10 ** 6), axis=1)
    bottom = np.max(np.where(par.any(axis=2), rows, -10 ** 6), axis=1)
    sep = top - bottom  # rows between them (the particle lies over the dimer's columns)
    window = res.info["calibration"]["edge_window_px"] + 2
    reach = int(np.ceil(2.5 * res.info["calibration"]["edge_blur_px"]))  # a blurred edge's reach (tracking.measure)
    in_view = par.sum(axis=(1, 2)) > 0.02 * dim.sum(axis=(1, 2))
    close = in_view & (sep >= 2) & (sep < 2 * reach - 1)  # the blurred edges within reach of each other
    masked = in_view & (sep >= 2 * reach) & (sep <= window)  # in the dimer's window, clear: masked and measured
    far = in_view & (sep > window + 1)
    assert close.sum() > 10 and np.all(res.status[close] == STATUS["third_particle"])
    assert masked.sum() >= 2 and np.all(res.status[masked] == 0)
    assert far.sum() > 80 and np.all(res.status[far] == 0)  # in view, farther than the dimer's window: measured
    assert np.all(res.status[~in_view] == 0)
    _good(res, y, theta, res.status == 0)


def test_dust_far_from_the_dimer_costs_no_frame():
    n = 120
    _, y, theta = motion(n, seed=37)
    # a 100 um speck crosses the whole view 60 px above the levitation height (the dimer reaches 44 px up)
    u = -10.0 + 1.6 * np.arange(n)
    centres = np.stack([u, np.full(n, CAM.origin[1] - 60.0)], axis=1)
    res = _track(render(y, theta, CAM, seed=37, extra=(centres, 0.2, 0.5 * 100e-6 / CAM.pixel_size)))
    assert np.all(res.status == 0)
    _good(res, y, theta, res.status == 0)


def test_a_cube_leaving_the_frame_for_a_while_keeps_the_good_frames():
    n = 240
    _, y, theta = motion(n, seed=33)
    # the dimer drifts sideways: between frames 80 and 160 cube B is partly outside the right edge
    shift = np.where((np.arange(n) >= 80) & (np.arange(n) < 160), 60.0, 0.0)
    res = _track(render(y, theta, CAM, seed=33, shift_u=shift))
    out = shift > 0
    assert np.all(res.status[out] == STATUS["out_of_view"])
    assert np.all(res.status[~out] == 0)
    assert res.info["not_measured"] == {"out_of_view": 80}
    _good(res, y, theta, ~out)


def test_motion_blur_beyond_the_bound_is_not_measured():
    n = 150
    _, y, theta = motion(n, seed=34)
    frames = render(y, theta, CAM, seed=34)
    frames[60:70] = render(y[60:70], theta[60:70], CAM, seed=35, blur_px=6.0)  # 6 px of vertical motion in the exposure
    res = _track(frames)
    assert np.all(res.status[60:70] == STATUS["motion_blur"])
    assert (res.status[np.r_[0:60, 70:n]] == 0).mean() >= 0.99
    # a looser bound keeps them
    assert np.all(_track(frames, max_motion_blur=10.0).status[60:70] == 0)


def test_a_particle_touching_the_dimer_is_an_occlusion():
    n = 60
    _, y, theta = motion(n, theta_amp=0.0, y_amp=0.0, seed=36)
    u0, v0 = CAM.origin
    half = 0.5 * 200e-6 / CAM.pixel_size
    # a 200 um particle resting on cube B's outer upper face from frame 30 on, else far outside the view
    d = 500e-6 / np.sqrt(2) / CAM.pixel_size
    on = np.arange(n) >= 30
    centres = np.stack([np.where(on, u0 + 1.5 * d, -500.0), np.full(n, v0 - d)], axis=1)
    res = _track(render(y, theta, CAM, seed=36, extra=(centres, 0.0, half)))
    assert np.all(res.status[~on] == 0)
    assert np.all(res.status[on] != 0)
    assert set(res.info["not_measured"]) <= {"occlusion", "poor_fit", "third_particle", "touching"}
