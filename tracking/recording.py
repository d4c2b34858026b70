"""Reading a recording: video files, multi-page TIFF, Phantom .cine and folders of images, as grey frames.

* video files (``.mp4``, ``.avi``, ``.mov``, ``.mkv``, ...): decoded by ffmpeg through ``imageio-ffmpeg``
  as 8-bit grey (16-bit when the stream has more than 8 bits);
* TIFF (``.tif``, ``.tiff``): ``tifffile``; a multi-page file is one recording.  The description a
  ``tifffile`` writer leaves (JSON) may record ``fps``, ``pixel_size_m`` and ``levitation_row_px`` (the
  twin's videos do); ImageJ's ``finterval`` gives the frame rate;
* Phantom ``.cine``: ``pims``; the header records the frame rate;
* a folder of image files (PNG, TIFF, BMP, JPEG) in natural name order (``frame2`` before ``frame10``).

Colour frames become grey (ITU-R 601 luminance).  Nothing here decodes a format itself.  Every problem a
user can fix is a :class:`TrackingError` with a one-line message naming the file.
"""
from __future__ import annotations

import logging
import os
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray


__all__ = ["TrackingError", "Recording", "read_recording", "find_recordings", "VIDEO_SUFFIXES", "IMAGE_SUFFIXES",
           "MAX_BYTES"]

logger = logging.getLogger(__name__)

#: Video containers read through ffmpeg.
VIDEO_SUFFIXES = (".mp4", ".avi", ".mov", ".mkv", ".m4v", ".wmv", ".webm", ".mpg", ".mpeg", ".flv", ".ogv", ".mj2")
#: Single images of a folder recording (a TIFF may also hold a whole recording).
IMAGE_SUFFIXES = (".png", ".tif", ".tiff", ".bmp", ".jpg", ".jpeg")
#: Largest recording held in memory [bytes of grey frames].
MAX_BYTES = 4 * 1024 ** 3


class TrackingError(ValueError):
    """A recording or option the tracking cannot use; ``str(err)`` is one line naming the file (the command line
    reports it as a user error, exit status 2)."""


@dataclass(frozen=True, eq=False)
class Recording:
    """The grey frames of one recording and what the file records about them.

    Attributes
    ----------
    name : str
        Name of the run (the file or folder name without suffix).
    path : str
        Where it was read from.
    format : str
        ``"video"``, ``"tiff"``, ``"cine"`` or ``"images"``.
    frames : ndarray (n, height, width)
        Grey levels (uint8, uint16 or float).
    fps : float or None
        Frame rate the file records [1/s].
    pixel_size : float or None
        Pixel size in the object plane the file records [m].
    levitation_row : float or None
        Image row of the levitation height the file records [px].
    """

    name: str
    path: str
    format: str
    frames: NDArray
    fps: float | None = None
    pixel_size: float | None = None
    levitation_row: float | None = None

    @property
    def n_frames(self) -> int:
        return int(self.frames.shape[0])


def _natural_key(path: Path):
    return [int(t) if t.isdigit() else t.lower() for t in re.split(r"(\d+)", path.name)]


def _grey(a: NDArray, path: Path) -> NDArray:
    """Frames (n, h, w) from (n, h, w), (n, h, w, 3|4), (h, w) or (h, w, 3|4)."""
    a = np.asarray(a)
    if a.ndim == 2:
        a = a[None]
    elif a.ndim == 3 and a.shape[-1] in (3, 4) and a.shape[0] > 4:  # one colour image
        a = a[None]
    if a.ndim == 4 and a.shape[-1] in (3, 4):
        rgb = a[..., :3]
        if np.array_equal(rgb[..., 0], rgb[..., 1]) and np.array_equal(rgb[..., 0], rgb[..., 2]):
            a = rgb[..., 0]
        else:
            a = (rgb @ np.array([0.299, 0.587, 0.114])).astype(np.float32)
    if a.ndim != 3 or min(a.shape) < 1:
        raise TrackingError(f"{path}: frames of shape {a.shape[1:]} are not grey or colour images")
    if not (np.issubdtype(a.dtype, np.integer) or np.issubdtype(a.dtype, np.floating)):
        raise TrackingError(f"{path}: pixels of type {a.dtype} are not grey levels")
    return a


def _check_size(n: int, h: int, w: int, itemsize: int, path: Path) -> None:
    if n * h * w * itemsize > MAX_BYTES:
        raise TrackingError(f"{path}: {n} frames of {w} x {h} px exceed the {MAX_BYTES / 1024 ** 3:.0f} GiB this tracker "
                            f"holds in memory; split the recording")


def _read_tiff(path: Path) -> tuple[NDArray, dict]:
    import tifffile

    try:
        with tifffile.TiffFile(path) as tif:
            # tifffile groups consecutive pages of one shape into a series: several series of different frame
            # sizes are frames of different sizes (reading the series, not every page, keeps this fast)
            series = tif.series
            if not series:
                raise TrackingError(f"{path}: the TIFF holds no images")
            sizes = [tuple(s.shape[-2:]) if s.shape[-1] not in (3, 4) else tuple(s.shape[-3:-1]) for s in series]
            if len(set(sizes)) > 1:
                first, other = sizes[0], next(z for z in sizes if z != sizes[0])
                raise TrackingError(f"{path}: frames of different sizes ({first[1]} x {first[0]} px and "
                                    f"{other[1]} x {other[0]} px)")
            n = sum(int(np.prod(s.shape)) for s in series) // int(np.prod(sizes[0]))
            _check_size(n, sizes[0][0], sizes[0][1], np.dtype(series[0].dtype).itemsize, path)
            parts = [np.asarray(s.asarray()) for s in series]
            frames = parts[0] if len(parts) == 1 else np.concatenate(
                [p.reshape((-1,) + p.shape[-3:] if p.shape[-1] in (3, 4) else (-1,) + p.shape[-2:]) for p in parts])
            meta: dict = {}
            for m in (tif.shaped_metadata or ()):
                if isinstance(m, dict):
                    meta.update(m)
            ij = tif.imagej_metadata or {}
            if "finterval" in ij and "fps" not in meta:
                try:
                    meta["fps"] = 1.0 / float(ij["finterval"])
                except (TypeError, ValueError, ZeroDivisionError):
                    pass
    except TrackingError:
        raise
    except Exception as exc:  # tifffile raises many types on a damaged or foreign file
        raise TrackingError(f"{path}: not a readable TIFF ({type(exc).__name__}: {str(exc)[:120]})") from None
    return frames, meta


def _read_video(path: Path) -> tuple[NDArray, dict]:
    import imageio_ffmpeg

    try:
        gen = imageio_ffmpeg.read_frames(str(path), pix_fmt="gray", bpp=1)
        meta = next(gen)
        gen.close()
        deep = any(b in str(meta.get("pix_fmt", "")) for b in ("10", "12", "16"))
        pix, dtype = ("gray16le", np.uint16) if deep else ("gray", np.uint8)
        gen = imageio_ffmpeg.read_frames(str(path), pix_fmt=pix, bpp=np.dtype(dtype).itemsize)
        meta = next(gen)
        w, h = (int(v) for v in meta["size"])
        frames = []
        for k, buf in enumerate(gen):
            if len(frames) * h * w * np.dtype(dtype).itemsize > MAX_BYTES:
                _check_size(len(frames) + 1, h, w, np.dtype(dtype).itemsize, path)
            a = np.frombuffer(buf, dtype=dtype)
            if a.size != h * w:
                raise TrackingError(f"{path}: frame {k} has {a.size} pixels, not {w} x {h}")
            frames.append(a.reshape(h, w))
    except TrackingError:
        raise
    except (OSError, RuntimeError, StopIteration, ValueError, KeyError) as exc:
        raise TrackingError(f"{path}: not a video file ffmpeg can read ({type(exc).__name__}: "
                            f"{str(exc).strip().splitlines()[-1][:120] if str(exc).strip() else 'no frames'})") from None
    if not frames:
        raise TrackingError(f"{path}: the video holds no frames")
    # the container's rate is a playback rate, often not the camera's: it is not taken as the frame rate
    return np.stack(frames), {"container_fps": meta.get("fps")}


def _read_cine(path: Path) -> tuple[NDArray, dict]:
    try:
        import pims

        with pims.Cine(str(path)) as cine:
            n = len(cine)
            h, w = cine.frame_shape[:2]
            _check_size(n, h, w, 2, path)
            frames = np.stack([np.asarray(cine[i]) for i in range(n)])
            meta = {"fps": float(cine.frame_rate)}
    except TrackingError:
        raise
    except Exception as exc:  # pims raises many types on a damaged or foreign file
        raise TrackingError(f"{path}: not a readable Phantom .cine file ({type(exc).__name__}: {str(exc)[:120]})") from None
    return frames, meta


def _read_image(path: Path) -> NDArray:
    try:
        if path.suffix.lower() in (".tif", ".tiff"):
            import tifffile

            return tifffile.imread(path)
        import imageio.v3 as iio

        return iio.imread(path)
    except Exception as exc:  # imageio/tifffile raise many types on a damaged or foreign file
        raise TrackingError(f"{path}: not a readable image ({type(exc).__name__}: {str(exc)[:120]})") from None


def _image_files(folder: Path) -> list[Path]:
    return sorted((f for f in folder.iterdir() if f.is_file() and f.suffix.lower() in IMAGE_SUFFIXES
                   and not f.name.startswith(".")), key=_natural_key)


def _read_folder(folder: Path) -> tuple[NDArray, dict]:
    files = _image_files(folder)
    if not files:
        raise TrackingError(f"{folder}: no recordings (video files, .cine, multi-page TIFF) and no image files (PNG, "
                            "TIFF, BMP, JPEG) in the folder")
    first = _grey(_read_image(files[0]), files[0])
    if first.shape[0] != 1:
        raise TrackingError(f"{files[0]}: a multi-frame file inside a folder of images; give the file itself")
    _check_size(len(files), first.shape[1], first.shape[2], first.dtype.itemsize, folder)
    frames = np.empty((len(files),) + first.shape[1:], first.dtype)
    frames[0] = first[0]
    for k, f in enumerate(files[1:], 1):
        a = _grey(_read_image(f), f)
        if a.shape[1:] != first.shape[1:]:
            raise TrackingError(f"{f}: frames of different sizes ({a.shape[2]} x {a.shape[1]} px against "
                                f"{first.shape[2]} x {first.shape[1]} px in {files[0].name})")
        frames[k] = a[0]
    return frames, {}


def _positive(meta: dict, *keys: str) -> float | None:
    for k in keys:
        v = meta.get(k)
        if isinstance(v, (int, float)) and not isinstance(v, bool) and np.isfinite(v) and v > 0:
            return float(v)
    return None


def read_recording(path: str | os.PathLike) -> Recording:
    """Read one recording (a video file, a TIFF, a .cine file or a folder of images; module docstring).

    Raises
    ------
    TrackingError
        Missing, unreadable or not a recording; frames of different sizes; too large.
    """
    p = Path(path)
    if not p.exists():
        raise TrackingError(f"{p}: does not exist")
    suffix = p.suffix.lower()
    if p.is_dir():
        frames, meta, fmt = *_read_folder(p), "images"
    elif suffix in (".tif", ".tiff"):
        frames, meta, fmt = *_read_tiff(p), "tiff"
    elif suffix == ".cine":
        frames, meta, fmt = *_read_cine(p), "cine"
    elif suffix in (".png", ".bmp", ".jpg", ".jpeg"):
        frames, meta, fmt = _read_image(p), {}, "images"
    else:
        frames, meta, fmt = *_read_video(p), "video"
    frames = _grey(frames, p)
    levitation_row = meta.get("levitation_row_px")
    return Recording(name=p.stem if p.is_file() else p.name, path=str(p), format=fmt, frames=frames,
                     fps=_positive(meta, "fps", "frame_rate_hz"), pixel_size=_positive(meta, "pixel_size_m"),
                     levitation_row=float(levitation_row) if isinstance(levitation_row, (int, float))
                     and not isinstance(levitation_row, bool) and np.isfinite(levitation_row) else None)


def _is_multipage_tiff(path: Path) -> bool:
    import tifffile

    try:
        with tifffile.TiffFile(path) as tif:
            shape = tif.series[0].shape
            return len(tif.series) > 1 or len(shape) >= 4 or (len(shape) == 3 and shape[-1] not in (3, 4))
    except Exception:  # not a TIFF: let reading it say so
        return False


def find_recordings(folder: str | os.PathLike) -> list[Path] | None:
    """The recordings in ``folder``, in natural name order, or None when the folder is itself one recording
    (a folder of single images).

    Recordings are video files, ``.cine`` files, multi-page TIFFs and sub-folders holding images.
    """
    folder = Path(folder)
    found = []
    for f in sorted(folder.iterdir(), key=_natural_key):
        if f.name.startswith("."):
            continue
        s = f.suffix.lower()
        if f.is_file() and (s in VIDEO_SUFFIXES or s == ".cine" or (s in (".tif", ".tiff") and _is_multipage_tiff(f))):
            found.append(f)
        elif f.is_dir():
            images = _image_files(f)
            # a sub-folder of single images is a recording; one of multi-page TIFFs is a folder of recordings
            # itself, given on its own
            if images and not (images[0].suffix.lower() in (".tif", ".tiff") and _is_multipage_tiff(images[0])):
                found.append(f)
    return found or None
