"""What a real levitator recording has and the twin's clean camera does not: the imperfections of
:class:`Imperfections`, rendered on top of the dimer's coverage (:mod:`acousim.twin.video`).

Every imperfection is off by default, and the camera then renders exactly as without this module.

* **Illumination.**  The light falling on the sensor is ``L(u, t) = (1 + g (u / (w - 1) - 1/2))
  (1 + f sin(2 pi f_hz t))``: a linear gradient of relative size ``g`` from the left edge to the right one
  and a flicker of relative amplitude ``f`` at ``f_hz`` (mains-driven lamps flicker at 100 or 120 Hz).  It
  multiplies the scene's grey levels (background, cubes, structures); the sensor's white noise is added after.
* **Static structures.**  The reflector at the top and the transducer at the bottom of the view, as dark
  (shadowgraph) or as bright (dark field) as the cubes: bands of ``bands_px`` rows whose edges undulate by
  1.5 px, blurred like everything else.  They never move.
* **Dust.**  ``dust`` specks (squares of ``dust_px`` side at the cubes' grey level) drift straight across
  the frame, each during ``dust_frames`` frames from a random start, at a random height.
* **Transparent crystals.**  A salt crystal passes light through its parallel faces: each cube is a dark
  (or, bright polarity, bright) outline of width ``rim`` x side around an interior beyond the background
  (brighter than it on a bright background, darker on a dark one, by 10 % of the contrast).
* **Tilt.**  The hinge line turned by ``tilt_deg`` about the vertical out of the camera axis: each cube's
  square cross-section is seen shortened by ``cos(tilt)`` across and swept along its depth ``s`` by
  ``s sin(tilt)``, a skewed hexagon.  y and theta (the bend about the hinge line) are unchanged; the
  silhouettes of the two cubes overlap near the hinge.  Rendered row by row with 16 sub-rows per pixel row
  (exact along the rows; the hexagons' horizontal edges, ``s sin(tilt)`` long, are placed to 1/16 px, which moves
  the silhouette's centre of mass by about 0.003 px RMS at 10 degrees, against 0.01 px with 4 sub-rows) and the
  Gaussian point-spread function applied as a filter.
* **H.264.**  :func:`encode_h264` writes an mp4 the way a high-speed camera's software or a phone exports it
  (libx264, 4:2:0, constant rate factor ``crf``), through ``imageio-ffmpeg``; :func:`h264_roundtrip` gives the
  frames a reader decodes from it.
* **Rest frames and the start.**  ``rest_frames`` frames at rest (y = 0, the drop's theta) precede the drop, and
  the free fall with the drive off follows them (:func:`acousim.twin.video.drop_protocol_motion`); ``record_origin = False`` leaves the levitation row out of the file (as a real camera's file).
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np
from numba import njit, prange
from numpy.typing import NDArray

from .config import TwinError

__all__ = ["Imperfections", "illumination", "band_coverage", "dust_tracks", "tilted_coverage", "encode_h264",
           "h264_roundtrip", "CODECS"]

#: File formats of the twin's video: uncompressed multi-page TIFF, or H.264 in an mp4.
CODECS = ("tiff", "h264")


@dataclass(frozen=True)
class Imperfections:
    """The imperfections of a real recording (module docstring); all off by default.

    Parameters
    ----------
    gradient : float
        Relative illumination change from the left edge of the frame to the right one (0.3: 30 %).
    flicker : float
        Relative amplitude of the illumination's flicker.
    flicker_hz : float
        Flicker frequency [Hz].
    bands_px : int
        Height of the static structures at the top and bottom of the frame [px].
    dust : int
        Dust specks drifting through each run.
    dust_frames : int
        Frames one speck takes to cross the frame.
    dust_px : float
        Side of a speck [px].
    transparent : bool
        Transparent crystals: bright interiors inside a dark outline.
    rim : float
        Width of a transparent cube's outline, as a fraction of its side.
    tilt_deg : float
        Angle of the hinge line out of the camera axis, about the vertical [degrees].
    codec : {"tiff", "h264"}
        File format of the video.
    crf : int
        H.264 constant rate factor (0 lossless ... 51; 23 is the encoder's default).
    rest_frames : int
        Frames at rest before the drop.
    record_origin : bool
        Whether the file records the levitation row.
    """

    gradient: float = 0.0
    flicker: float = 0.0
    flicker_hz: float = 100.0
    bands_px: int = 0
    dust: int = 0
    dust_frames: int = 200
    dust_px: float = 10.0
    transparent: bool = False
    rim: float = 0.15
    tilt_deg: float = 0.0
    codec: str = "tiff"
    crf: int = 23
    rest_frames: int = 0
    record_origin: bool = True

    def __post_init__(self) -> None:
        if not (math.isfinite(self.gradient) and 0 <= self.gradient < 1):
            raise TwinError(f"illumination gradient must lie in [0, 1), got {self.gradient!r}")
        if not (math.isfinite(self.flicker) and 0 <= self.flicker < 1):
            raise TwinError(f"flicker must lie in [0, 1), got {self.flicker!r}")
        if not (math.isfinite(self.flicker_hz) and self.flicker_hz > 0):
            raise TwinError(f"flicker frequency must be positive, got {self.flicker_hz!r}")
        for name in ("bands_px", "dust", "rest_frames"):
            v = getattr(self, name)
            if int(v) != v or v < 0:
                raise TwinError(f"{name.replace('_', ' ')} must be a non-negative whole number, got {v!r}")
        if int(self.dust_frames) != self.dust_frames or self.dust_frames < 2:
            raise TwinError(f"dust frames must be a whole number >= 2, got {self.dust_frames!r}")
        if not (math.isfinite(self.dust_px) and 0.5 <= self.dust_px <= 50):
            raise TwinError(f"dust speck size must lie in [0.5, 50] px, got {self.dust_px!r}")
        if not (math.isfinite(self.rim) and 0.02 <= self.rim <= 0.45):
            raise TwinError(f"a transparent cube's rim must lie in [0.02, 0.45] of its side, got {self.rim!r}")
        if not (math.isfinite(self.tilt_deg) and abs(self.tilt_deg) <= 45):
            raise TwinError(f"tilt must lie within +-45 degrees, got {self.tilt_deg!r}")
        if self.transparent and self.tilt_deg:
            raise TwinError("transparent crystals and a tilt cannot be rendered together")
        if self.codec not in CODECS:
            raise TwinError(f"codec must be one of {', '.join(CODECS)}, got {self.codec!r}")
        if int(self.crf) != self.crf or not 0 <= self.crf <= 51:
            raise TwinError(f"H.264 rate factor must be a whole number in [0, 51], got {self.crf!r}")

    @property
    def any(self) -> bool:
        """Whether anything differs from the clean camera."""
        return self != Imperfections()

    @property
    def changes_frames(self) -> bool:
        """Whether the rendered frames differ from the clean camera's (codec and file contents aside)."""
        return bool(self.gradient or self.flicker or self.bands_px or self.dust or self.transparent or self.tilt_deg)

    def to_dict(self) -> dict:
        """JSON-ready settings."""
        return asdict(self)


def illumination(t: NDArray, width: int, imp: Imperfections) -> NDArray[np.float32]:
    """The relative illumination ``L`` (module docstring) at the frame times ``t`` [s], shape (n, 1, width)."""
    u = np.arange(width, dtype=np.float64)
    grad = 1.0 + imp.gradient * (u / max(width - 1, 1) - 0.5)
    t = np.asarray(t, float)
    flick = 1.0 + imp.flicker * np.sin(2.0 * np.pi * imp.flicker_hz * t)
    return (flick[:, None, None] * grad[None, None, :]).astype(np.float32)


def band_coverage(height: int, width: int, bands_px: int, sigma: float) -> NDArray[np.float32]:
    """Coverage (height, width) of the static structures: bands of ``bands_px`` rows at the top and bottom
    whose edges undulate by 1.5 px (module docstring), blurred by the point-spread function."""
    cov = np.zeros((height, width), np.float32)
    if bands_px <= 0:
        return cov
    u = np.arange(width)
    edge = bands_px + 1.5 * np.sin(2.0 * np.pi * u / max(width, 1) * 1.5)  # rows covered from the edge
    v = np.arange(height)[:, None] + 0.5  # the lower edge of row v, counted from the top
    top = np.clip(edge[None, :] - (v - 1.0), 0.0, 1.0)
    bottom = np.clip(edge[None, :] - (height - v), 0.0, 1.0)
    cov[:] = np.maximum(top, bottom)
    if sigma > 0:
        from scipy.ndimage import gaussian_filter

        cov = gaussian_filter(cov, sigma, mode="nearest").astype(np.float32)
    return cov


def dust_tracks(n: int, width: int, height: int, imp: Imperfections, rng: np.random.Generator) -> NDArray:
    """Positions (n, dust, 2) [px] of the dust specks (module docstring); far outside the frame when a speck is
    not in view.  Each speck enters at the left edge and leaves at the right one."""
    out = np.full((n, imp.dust, 2), -1e4)
    for k in range(imp.dust):
        start = int(rng.integers(0, max(1, n - imp.dust_frames)))
        row = rng.uniform(0.15, 0.85) * height
        f = np.arange(start, min(n, start + imp.dust_frames))
        out[f, k, 0] = -imp.dust_px + (f - start) * (width + 2.0 * imp.dust_px) / imp.dust_frames
        out[f, k, 1] = row + 0.05 * (f - start)
    return out


def tilted_coverage(centres: NDArray, angles: NDArray, half_side: float, hinge_u: float, tilt_rad: float,
                    shape: tuple[int, int], sigma: float, subrows: int = 16) -> NDArray[np.float32]:
    """Coverage of a dimer whose hinge line is turned by ``tilt_rad`` out of the camera axis (module
    docstring): each square of ``centres`` / ``angles`` / ``half_side`` (as :func:`acousim.twin.video.dimer_squares`
    gives them) shortened across by cos(tilt) about ``hinge_u`` and swept along the rows by +-side sin(tilt) / 2;
    the union of the two, blurred by a Gaussian of ``sigma`` px."""
    n = centres.shape[0]
    c = np.cos(tilt_rad)
    sweep = half_side * abs(np.sin(tilt_rad))  # half the sweep: (side / 2) sin(tilt)
    corners = np.empty((n, 2, 4, 2))
    for j in range(2):
        g = angles[:, j]
        e1 = np.stack([np.cos(g), -np.sin(g)], -1)  # along a face, in (u, v) with v down
        e2 = np.stack([-np.sin(g), -np.cos(g)], -1)
        for k, (a, b) in enumerate(((1, 1), (-1, 1), (-1, -1), (1, -1))):
            corners[:, j, k] = centres[:, j] + half_side * (a * e1 + b * e2)
    corners[..., 0] = hinge_u + (corners[..., 0] - hinge_u) * c
    out = np.zeros((n, int(shape[0]), int(shape[1])), np.float32)
    _union_rows(corners, sweep, int(subrows), out)
    if sigma > 0:
        from scipy.ndimage import gaussian_filter

        out = gaussian_filter(out, (0.0, sigma, sigma), mode="constant").astype(np.float32)
    return out


@njit(parallel=True, cache=True)
def _union_rows(corners, sweep, m, out):  # pragma: no cover - compiled
    """Area coverage of the union of convex quadrilaterals (``corners`` (n, k, 4, 2), in order around each) each
    widened along the rows by +-``sweep``: exact along the rows, ``m`` sub-rows per pixel row."""
    n, h, w = out.shape
    kq = corners.shape[1]
    for f in prange(n):
        lo = np.empty(kq)  # each thread's own interval ends (shared ones would be overwritten by the other frames)
        hi = np.empty(kq)
        for v in range(h):
            for p in range(m):
                z = v - 0.5 + (p + 0.5) / m
                for j in range(kq):
                    a = 1e30
                    b = -1e30
                    for e in range(4):
                        x0, z0 = corners[f, j, e, 0], corners[f, j, e, 1]
                        x1, z1 = corners[f, j, (e + 1) % 4, 0], corners[f, j, (e + 1) % 4, 1]
                        if (z0 - z) * (z1 - z) <= 0.0 and z0 != z1:
                            x = x0 + (z - z0) * (x1 - x0) / (z1 - z0)
                            a = min(a, x)
                            b = max(b, x)
                    lo[j] = a - sweep
                    hi[j] = b + sweep
                # the union of the (at most two) intervals, then its overlap with each pixel
                for u in range(w):
                    left = u - 0.5
                    right = u + 0.5
                    cov = 0.0
                    for j in range(kq):
                        if hi[j] <= lo[j]:
                            continue
                        cov += max(0.0, min(right, hi[j]) - max(left, lo[j]))
                    if kq == 2 and hi[0] > lo[0] and hi[1] > lo[1]:
                        cov -= max(0.0, min(right, hi[0], hi[1]) - max(left, lo[0], lo[1]))
                    out[f, v, u] += cov / m


def encode_h264(path, frames: NDArray, fps: float, crf: int = 23) -> None:
    """Write 8-bit grey frames as H.264 (libx264, yuv420p, constant rate factor ``crf``) in an mp4 at ``path``
    (not atomically: the caller writes into a temporary place)."""
    import imageio_ffmpeg

    if frames.dtype != np.uint8:
        raise TwinError("H.264 video is written from 8-bit frames: use --bit-depth 8")
    n, h, w = frames.shape
    if h % 2 or w % 2:
        raise TwinError(f"H.264 (4:2:0) needs an even frame size, got {w} x {h}")
    writer = imageio_ffmpeg.write_frames(str(path), (w, h), pix_fmt_in="gray", pix_fmt_out="yuv420p", fps=float(fps),
                                         codec="libx264", quality=None, macro_block_size=1,
                                         output_params=["-crf", str(int(crf)), "-preset", "medium"])
    writer.send(None)
    for f in frames:
        writer.send(np.ascontiguousarray(f))
    writer.close()


def h264_roundtrip(frames: NDArray, fps: float, crf: int = 23, workdir=None) -> NDArray[np.uint8]:
    """The frames a reader decodes from :func:`encode_h264`'s mp4 (a temporary file in ``workdir``)."""
    import tempfile
    from pathlib import Path

    import imageio_ffmpeg

    n, h, w = frames.shape
    with tempfile.TemporaryDirectory(dir=workdir) as tmp:
        path = Path(tmp) / "clip.mp4"
        encode_h264(path, frames, fps, crf)
        reader = imageio_ffmpeg.read_frames(str(path), pix_fmt="gray", bpp=1)
        reader.__next__()  # the stream's metadata
        out = np.stack([np.frombuffer(b, np.uint8).reshape(h, w) for b in reader])
    return out
