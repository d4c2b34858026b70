"""The twin's high-speed camera: the frames a camera looking along the hinge line would record.

Geometry (docs/conventions.md section 2).  The camera looks along the hinge line, so the two cubes appear as two
squares of side ``s`` that share a corner (the hinge).  In the lab frame (X to the right in the image,
Z up) cube B (X > 0) is the diamond rotated clockwise by ``phi = pi theta / 4`` about its own centre, cube
A its mirror image in X = 0; the centres sit at ``X = +-d cos(phi)``, ``Z = Z_com`` and the hinge at
``X = 0``, ``Z = Z_com + d sin(phi)`` with ``d = s / sqrt(2)``.  The projection is orthographic.

Image coordinates.  Pixel centres sit at integer ``(u, v)``: ``u`` the column (to the right) and ``v``
the row, counting *down* (the usual image convention); pixel ``(v, u)`` covers
``[u - 1/2, u + 1/2] x [v - 1/2, v + 1/2]``.  The levitation height (y = 0) is the row
``VideoCamera.levitation_row`` and the hinge line the column ``VideoCamera.hinge_column``, so a dimer at
height y has its centre of mass on the row ``levitation_row - y / pixel_size``.

Rendering (vectorised over frames and pixels, no ray tracing).  A square blurred by an isotropic Gaussian
point-spread function of width ``sigma`` is exactly separable in the square's own axes:
``g(x') g(z')`` with ``g(w) = Phi((w + a) / sigma) - Phi((w - a) / sigma)`` (``a`` half the side, ``Phi``
the normal distribution function).  Each pixel integrates that over its area with ``n x n`` sub-samples,
each standing for its own sub-box (a Gaussian of the box's variance ``1 / (12 n^2)`` added to
``sigma^2``).  The squares of one dimer do not overlap, so their blurred images add; other particles
(tests: a third particle) are added the same way and the sum is clipped at full coverage.  Grey levels are
``background + (object - background) x coverage`` plus white Gaussian noise (a fraction of the contrast),
rounded to 8 or 16 bits; a lost frame is recorded as an all-black frame.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit, prange
from numpy.typing import NDArray

from cubedimer.compile_cache import kernel_array

from .config import TwinError
from .imperfections import Imperfections, band_coverage, dust_tracks, illumination, tilted_coverage

__all__ = ["VideoCamera", "dimer_squares", "render_coverage", "render_frames", "record_video", "write_video_tiff",
           "drop_protocol_motion", "POLARITIES"]

#: Dark cubes on a bright background (shadowgraph) or bright cubes on a dark one.
POLARITIES = ("dark", "bright")

#: Grey levels (background, object) as fractions of full scale, by polarity.
_DEFAULT_LEVELS = {"dark": (0.80, 0.15), "bright": (0.10, 0.80)}


@dataclass(frozen=True)
class VideoCamera:
    """The high-speed camera of the twin (orthographic side view along the hinge line).

    Parameters
    ----------
    pixel_size : float
        Size of one pixel in the object plane [m].
    width, height : int
        Frame size [px].
    psf_sigma : float
        Standard deviation of the Gaussian point-spread function [px].
    noise : float
        Standard deviation of the white Gaussian image noise, as a fraction of the grey-level contrast
        between background and cube.
    bit_depth : {8, 16}
        Grey levels of the recorded frames.
    polarity : {"dark", "bright"}
        Dark cubes on a bright background (shadowgraph) or bright cubes on a dark background.
    background, foreground : float, optional
        Grey levels of background and cube as fractions of full scale (defaults by polarity: 0.80 / 0.15
        dark, 0.10 / 0.80 bright).
    levitation_row : float, optional
        Image row of the levitation height y = 0 [px] (default: the middle row).
    hinge_column : float, optional
        Image column of the hinge line [px] (default: the middle column).
    lost_frames : int
        Frames per run the camera loses (recorded all black), at random interior positions.
    subsamples : int
        Sub-samples per pixel and axis of the area integration.
    imperfections : Imperfections
        What a real recording has beyond the clean camera (:mod:`acousim.twin.imperfections`; none by default).
    """

    pixel_size: float = 10e-6
    width: int = 180
    height: int = 150
    psf_sigma: float = 1.0
    noise: float = 0.02
    bit_depth: int = 8
    polarity: str = "dark"
    background: float | None = None
    foreground: float | None = None
    levitation_row: float | None = None
    hinge_column: float | None = None
    lost_frames: int = 0
    subsamples: int = 2
    imperfections: Imperfections = Imperfections()

    def __post_init__(self) -> None:
        if not (math.isfinite(self.pixel_size) and 1e-8 < self.pixel_size < 1e-3):
            raise TwinError(f"pixel size must lie in (10 nm, 1 mm), got {self.pixel_size!r} m")
        for name in ("width", "height"):
            v = getattr(self, name)
            if int(v) != v or not 16 <= v <= 4096:
                raise TwinError(f"frame {name} must be a whole number of pixels in [16, 4096], got {v!r}")
        if not (math.isfinite(self.psf_sigma) and 0 <= self.psf_sigma <= 20):
            raise TwinError(f"point-spread width must lie in [0, 20] px, got {self.psf_sigma!r}")
        if not (math.isfinite(self.noise) and 0 <= self.noise <= 1):
            raise TwinError(f"image noise must lie in [0, 1] (fraction of the contrast), got {self.noise!r}")
        if self.bit_depth not in (8, 16):
            raise TwinError(f"bit depth must be 8 or 16, got {self.bit_depth!r}")
        if self.polarity not in POLARITIES:
            raise TwinError(f"polarity must be one of {', '.join(POLARITIES)}, got {self.polarity!r}")
        bg, fg = self.levels
        if not (0 <= bg <= 1 and 0 <= fg <= 1) or abs(bg - fg) < 0.05:
            raise TwinError(f"grey levels must lie in [0, 1] and differ by at least 0.05, got {bg!r}, {fg!r}")
        if int(self.lost_frames) != self.lost_frames or self.lost_frames < 0:
            raise TwinError(f"lost frames must be a non-negative whole number, got {self.lost_frames!r}")
        if int(self.subsamples) != self.subsamples or not 1 <= self.subsamples <= 8:
            raise TwinError(f"sub-samples must be a whole number in [1, 8], got {self.subsamples!r}")

    @property
    def levels(self) -> tuple[float, float]:
        """(background, cube) grey levels as fractions of full scale."""
        bg, fg = _DEFAULT_LEVELS[self.polarity]
        return (bg if self.background is None else float(self.background),
                fg if self.foreground is None else float(self.foreground))

    @property
    def origin(self) -> tuple[float, float]:
        """(hinge column, levitation row) [px]: where X = 0 and y = 0 lie in the image."""
        u0 = (self.width - 1) / 2 if self.hinge_column is None else float(self.hinge_column)
        v0 = (self.height - 1) / 2 if self.levitation_row is None else float(self.levitation_row)
        return u0, v0

    def to_dict(self) -> dict:
        """JSON-ready settings (SI units, pixels where named)."""
        u0, v0 = self.origin
        bg, fg = self.levels
        return {"pixel_size_m": float(self.pixel_size), "width_px": int(self.width), "height_px": int(self.height),
                "psf_sigma_px": float(self.psf_sigma), "noise_fraction_of_contrast": float(self.noise),
                "bit_depth": int(self.bit_depth), "polarity": self.polarity, "background_level": bg,
                "cube_level": fg, "levitation_row_px": v0, "hinge_column_px": u0,
                "lost_frames": int(self.lost_frames), "subsamples": int(self.subsamples),
                **({"imperfections": self.imperfections.to_dict()} if self.imperfections.any else {})}


def dimer_squares(y: NDArray, theta: NDArray, side: float, camera: VideoCamera) -> tuple[NDArray, NDArray, float]:
    """The two squares of the dimer in image coordinates (module docstring).

    Parameters
    ----------
    y : ndarray (n,)
        Centre-of-mass height above the levitation height [m].
    theta : ndarray (n,)
        Normalised bending angle [-].
    side : float
        Cube side [m].
    camera : VideoCamera

    Returns
    -------
    centres : ndarray (n, 2, 2)
        ``(u, v)`` of cube A's and cube B's centres [px].
    angles : ndarray (n, 2)
        Direction of one pair of each square's faces, counter-clockwise from +X in the lab frame (Z up)
        [rad]: ``3 pi / 4 + phi`` for cube A and ``pi / 4 - phi`` for cube B.
    half_side : float
        Half the side [px].
    """
    y = np.asarray(y, float)
    phi = np.pi * np.asarray(theta, float) / 4.0
    u0, v0 = camera.origin
    d = side / np.sqrt(2.0) / camera.pixel_size
    v_c = v0 - y / camera.pixel_size
    du = d * np.cos(phi)
    centres = np.stack([np.stack([u0 - du, v_c], -1), np.stack([u0 + du, v_c], -1)], axis=1)
    angles = np.stack([0.75 * np.pi + phi, 0.25 * np.pi - phi], axis=-1)
    return centres, angles, 0.5 * side / camera.pixel_size


def render_coverage(centres: NDArray, angles: NDArray, half_sides, shape: tuple[int, int], sigma: float,
                    subsamples: int = 2) -> NDArray[np.float32]:
    """Fraction of every pixel covered by squares blurred by a Gaussian point-spread function.

    Parameters
    ----------
    centres : ndarray (n, k, 2)
        ``(u, v)`` of the centres of the k squares in each of n frames [px].
    angles : ndarray (n, k)
        Direction of one pair of faces of each square, counter-clockwise from +X with Z up [rad].
    half_sides : float or ndarray (k,)
        Half the side of each square [px].
    shape : (height, width)
        Frame size [px].
    sigma : float
        Point-spread standard deviation [px].
    subsamples : int
        Sub-samples per pixel and axis.

    Returns
    -------
    ndarray (n, height, width) float32 in [0, 1]

    Notes
    -----
    Every pixel within reach of a square (its circumscribed circle plus six blur widths) is evaluated with the
    exact separable form of the module docstring; pixels deeper than six blur widths inside a square are 1 and
    those farther outside 0 (error below 1e-9).  Compiled (numba), parallel over frames.
    """
    centres = np.ascontiguousarray(centres, float)
    angles = np.ascontiguousarray(angles, float)
    n, k = angles.shape
    halves = kernel_array(np.broadcast_to(np.asarray(half_sides, float), (k,)))
    m = int(subsamples)
    s_eff = math.sqrt(sigma ** 2 + 1.0 / (12.0 * m * m))
    out = np.zeros((n, int(shape[0]), int(shape[1])), np.float32)
    _render_kernel(centres, angles, halves, s_eff, m, out)
    return out


@njit(parallel=True, cache=True)
def _render_kernel(centres, angles, halves, s_eff, m, out):  # pragma: no cover - compiled
    n, h, w = out.shape
    k = angles.shape[1]
    inv = 1.0 / (s_eff * math.sqrt(2.0))
    for f in prange(n):
        for j in range(k):
            a = halves[j]
            uc, vc = centres[f, j, 0], centres[f, j, 1]
            c, s = math.cos(angles[f, j]), math.sin(angles[f, j])
            reach = a * math.sqrt(2.0) + 6.0 * s_eff + 1.0
            u0, u1 = max(0, int(math.floor(uc - reach))), min(w - 1, int(math.ceil(uc + reach)))
            v0, v1 = max(0, int(math.floor(vc - reach))), min(h - 1, int(math.ceil(vc + reach)))
            inner, outer = a - 6.0 * s_eff - 1.0, a + 6.0 * s_eff + 1.0
            for v in range(v0, v1 + 1):
                for u in range(u0, u1 + 1):
                    X = u - uc
                    Z = vc - v
                    xl = X * c + Z * s
                    zl = -X * s + Z * c
                    if abs(xl) > outer or abs(zl) > outer:
                        continue
                    if abs(xl) < inner and abs(zl) < inner:
                        out[f, v, u] += 1.0
                        continue
                    acc = 0.0
                    for p in range(m):
                        for q in range(m):
                            Xs = X + (q + 0.5) / m - 0.5
                            Zs = Z - ((p + 0.5) / m - 0.5)
                            xs = Xs * c + Zs * s
                            zs = -Xs * s + Zs * c
                            gx = 0.5 * (math.erf((xs + a) * inv) - math.erf((xs - a) * inv))
                            gz = 0.5 * (math.erf((zs + a) * inv) - math.erf((zs - a) * inv))
                            acc += gx * gz
                    out[f, v, u] += acc / (m * m)
        for v in range(h):
            for u in range(w):
                if out[f, v, u] > 1.0:
                    out[f, v, u] = 1.0


def render_frames(coverage: NDArray, camera: VideoCamera, rng: np.random.Generator,
                  lost: NDArray | None = None) -> NDArray:
    """Grey-level frames of a coverage movie: levels, image noise, quantisation, lost frames.

    Parameters
    ----------
    coverage : ndarray (n, height, width)
        Fraction of each pixel covered by a cube.
    camera : VideoCamera
    rng : numpy Generator
        Draws the image noise.
    lost : ndarray of int, optional
        Indices of lost frames (recorded all black).

    Returns
    -------
    ndarray (n, height, width) of uint8 or uint16
    """
    bg, fg = camera.levels
    full = (1 << camera.bit_depth) - 1
    img = bg + (fg - bg) * coverage.astype(np.float32)
    if camera.noise > 0:
        img += np.float32(camera.noise * abs(fg - bg)) * rng.standard_normal(img.shape, dtype=np.float32)
    out = np.clip(np.rint(img * full), 0, full).astype(np.uint8 if camera.bit_depth == 8 else np.uint16)
    if lost is not None and len(lost):
        out[np.asarray(lost, int)] = 0
    return out


def record_video(t: NDArray, y: NDArray, theta: NDArray, side: float, camera: VideoCamera,
                 seed: np.random.SeedSequence | int) -> tuple[NDArray, NDArray]:
    """The frames the camera records of a dimer moving along (t, y, theta).

    Parameters
    ----------
    t : ndarray (n,)
        Frame times [s] (only their number is used).
    y : ndarray (n,)
        True centre-of-mass height above the levitation height [m].
    theta : ndarray (n,)
        True bending angle [-].
    side : float
        Cube side [m].
    camera : VideoCamera
    seed : SeedSequence or int
        Stream of the image noise and of the lost frames.

    Returns
    -------
    frames : ndarray (n, height, width) uint8 or uint16
    lost : ndarray of int
        Indices of the lost (all-black) frames.
    """
    n = len(t)
    rng = np.random.default_rng(seed)
    k = int(camera.lost_frames)
    if k > max(0, n - 2):
        raise TwinError(f"a run of {n} frames cannot lose {k} frames")
    lost = np.sort(1 + rng.choice(n - 2, size=k, replace=False)) if k else np.zeros(0, int)
    centres, angles, half = dimer_squares(y, theta, side, camera)
    frames = np.empty((n, camera.height, camera.width), np.uint8 if camera.bit_depth == 8 else np.uint16)
    imp = camera.imperfections
    if imp.changes_frames:
        _record_imperfect(np.asarray(t, float), centres, angles, half, camera, rng, frames)
    else:
        for f0 in range(0, n, 512):
            sl = slice(f0, min(n, f0 + 512))
            cov = render_coverage(centres[sl], angles[sl], half, (camera.height, camera.width), camera.psf_sigma,
                                  camera.subsamples)
            frames[sl] = render_frames(cov, camera, rng)
    frames[lost] = 0
    return frames, lost


def _record_imperfect(t, centres, angles, half, camera: VideoCamera, rng, frames) -> None:
    """:func:`record_video` with the camera's imperfections (:mod:`acousim.twin.imperfections`), into ``frames``:
    the opaque coverage (cubes or their outlines, dust, static structures; clipped at 1), a transparent interior,
    the illumination multiplying the scene, then the sensor's noise and quantisation."""
    imp = camera.imperfections
    n = len(t)
    shape = (camera.height, camera.width)
    bg, fg = camera.levels
    interior = min(1.0, max(0.0, bg + 0.1 * (bg - fg)))  # beyond the background, away from the cube's level
    bands = band_coverage(camera.height, camera.width, imp.bands_px, camera.psf_sigma)
    dust = dust_tracks(n, camera.width, camera.height, imp, rng) if imp.dust else None
    full = (1 << camera.bit_depth) - 1
    for f0 in range(0, n, 512):
        sl = slice(f0, min(n, f0 + 512))
        if imp.tilt_deg:
            cov = tilted_coverage(centres[sl], angles[sl], half, camera.origin[0], math.radians(imp.tilt_deg), shape,
                                  camera.psf_sigma)
        else:
            cov = render_coverage(centres[sl], angles[sl], half, shape, camera.psf_sigma, camera.subsamples)
        inner = None
        if imp.transparent:
            inner = render_coverage(centres[sl], angles[sl], half * (1.0 - 2.0 * imp.rim), shape, camera.psf_sigma,
                                    camera.subsamples)
        if dust is not None:
            d = dust[sl]
            cov += render_coverage(d, np.full(d.shape[:2], 0.3), 0.5 * imp.dust_px, shape, camera.psf_sigma,
                                   camera.subsamples)
        cov = np.minimum(cov + bands[None], 1.0)
        img = bg + (fg - bg) * cov
        if inner is not None:
            img += (interior - fg) * inner
        img *= illumination(t[sl], camera.width, imp)
        if camera.noise > 0:
            img += np.float32(camera.noise * abs(fg - bg)) * rng.standard_normal(img.shape, dtype=np.float32)
        frames[sl] = np.clip(np.rint(img * full), 0, full)


def drop_protocol_motion(dynamics, run, rest_frames: int, ring_time_s: float = 0.0,
                         max_step: float | None = None) -> tuple[NDArray, NDArray, dict]:
    """The whole field-drop protocol a camera records, frame by frame: ``rest_frames`` frames at rest (y = 0 and the
    hinge at the run's ``theta_drop``), the free fall with the drive off (the frames that fall inside ``t_off``), then
    the run's motion from the field's return (its ring-up included).

    The fall's frames come from the twin's own integration of the drop (:func:`acousim.dynamics.switching.field_drop`,
    with the transducer's ring time): the state ``s`` after the drive stops is the state at the field's return of a
    drop of duration ``s``, so the fall is continuous in height and velocity with the run's first frame.

    Parameters
    ----------
    dynamics : acousim.dynamics.integrator.DimerDynamics
        The run's (true) dynamics.
    run : acousim.twin.simulation.SimulatedRun
        Its ``drop`` (``t_off_s``, ``theta_drop``, ``thetadot_drop``), frame times (0 at the field's return) and
        exact states.
    rest_frames : int
        Frames at rest before the drive stops.
    ring_time_s : float
        The transducer's ring time [s] (0: instant switching).
    max_step : float, optional
        Longest internal step of the integration [s].

    Returns
    -------
    y, theta : ndarray (n,)
        The true motion of every frame [m], [-].
    phases : dict
        ``drop_frame`` (when the drive stops, in frames from the first; fractional), ``field_on_frame`` (the run's
        first frame) and ``fall_frames`` (frames inside the fall).
    """
    from ..dynamics.switching import field_drop

    dt = float(run.t[1] - run.t[0])
    t_off = float(run.drop["t_off_s"])
    x_drop = np.array([0.0, 0.0, run.drop["theta_drop"], run.drop["thetadot_drop"]])
    m = max(0, int(math.ceil(t_off / dt - 1e-9)) - 1)  # frames strictly inside the fall
    fall = [field_drop(dynamics, x_drop, t_off - j * dt, dt, dt, tau=ring_time_s, max_step=max_step).state_at_field_on
            for j in range(m, 0, -1)]
    k = int(rest_frames)
    rest = np.tile(x_drop, (k, 1))
    states = np.concatenate([rest, np.reshape(fall, (m, 4)), run.state])
    phases = {"drop_frame": k + m - t_off / dt, "field_on_frame": k + m, "fall_frames": m, "rest_frames": k}
    return states[:, 0], states[:, 2], phases


def write_video_tiff(path, frames: NDArray, fps: float, camera: VideoCamera, extra: dict | None = None) -> None:
    """Write frames as a multi-page TIFF (uncompressed: image noise hardly compresses, and readers map it
    straight into memory) that records its frame rate, pixel size and levitation row in its description
    (JSON), atomically."""
    import tifffile

    from cubedimer.atomic import atomic_save

    u0, v0 = camera.origin
    meta = {"fps": float(fps), "pixel_size_m": float(camera.pixel_size), "levitation_row_px": float(v0),
            "hinge_column_px": float(u0), "source": "acousim digital twin (synthetic video)"}
    meta.update(extra or {})
    atomic_save(path, lambda tmp: tifffile.imwrite(tmp, frames, metadata=meta))
