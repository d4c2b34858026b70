"""Shared fixtures of the tracking tests: frames rendered by the twin's camera (acousim.twin.video) from a known
motion, so every measured number is compared with the truth that drew it."""
from __future__ import annotations

import numpy as np
import pytest

from acousim.twin.video import VideoCamera, dimer_squares, render_coverage, render_frames, write_video_tiff

SIDE = 500e-6  #: cube side [m]
FPS = 2000.0


def motion(n: int, y_amp: float = 80e-6, theta_amp: float = 0.6, theta_mean: float = 0.0, seed: int = 0):
    """A smooth test motion: y oscillating at 22 Hz (the trap), theta at 3.1 Hz with a random phase, n frames."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) / FPS
    y = y_amp * np.cos(2 * np.pi * 22.0 * t + rng.uniform(0, 2 * np.pi))
    theta = theta_mean + theta_amp * np.sin(2 * np.pi * 3.1 * t + rng.uniform(0, 2 * np.pi))
    return t, y, theta


def render(y, theta, camera: VideoCamera, seed: int = 0, extra=None, blur_px: float = 0.0, lost=(), shift_u=None):
    """Frames of the dimer at (y, theta) seen by ``camera``.

    extra : (centres (n, 2) [px], angle [rad], half side [px]) of a third particle, or None
    blur_px : vertical motion during the exposure [px]: the coverage is averaged over 9 positions along it
    lost : indices of frames recorded black
    shift_u : per-frame sideways displacement of the dimer [px], or None
    """
    centres, angles, half = dimer_squares(y, theta, SIDE, camera)
    if shift_u is not None:
        centres = centres + np.stack([np.asarray(shift_u, float), np.zeros(len(y))], axis=1)[:, None, :]
    shape = (camera.height, camera.width)
    if blur_px:
        offs = np.linspace(-0.5, 0.5, 9) * blur_px
        cov = np.mean([render_coverage(centres + np.array([0.0, o]), angles, half, shape, camera.psf_sigma,
                                       camera.subsamples) for o in offs], axis=0)
    else:
        cov = render_coverage(centres, angles, half, shape, camera.psf_sigma, camera.subsamples)
    if extra is not None:
        c3, a3, h3 = extra
        cov3 = render_coverage(np.asarray(c3, float)[:, None, :], np.full((len(y), 1), a3), h3, shape, camera.psf_sigma,
                               camera.subsamples)
        cov = np.clip(cov + cov3, 0.0, 1.0)
    return render_frames(cov, camera, np.random.default_rng(seed), np.asarray(lost, int))


def truth_row(y, camera: VideoCamera):
    """Image row of the centre of mass of a dimer at height y [m]."""
    return camera.origin[1] - np.asarray(y) / camera.pixel_size


@pytest.fixture
def write_tiff(tmp_path):
    """write_tiff(name, frames, camera, record=True) -> path of a multi-page TIFF in tmp_path; with ``record`` the
    file records its frame rate, pixel size and levitation row, as the twin's videos do."""
    def _write(name, frames, camera, record=True):
        path = tmp_path / name
        if record:
            write_video_tiff(path, frames, FPS, camera)
        else:
            import tifffile

            tifffile.imwrite(path, frames)
        return path

    return _write
