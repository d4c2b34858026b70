"""The settings of the tracking of one recording, :class:`TrackConfig` (``python -m tracking track``'s options)."""
from __future__ import annotations

import math
from dataclasses import dataclass, field

from cubedimer.config_checks import (check_choice, check_in_range, check_positive, check_that, check_whole, named,
                                    raising)

from .recording import TrackingError

__all__ = ["TrackConfig", "POLARITIES", "UP"]

#: ``TrackConfig.polarity`` choices.
POLARITIES = ("auto", "dark", "bright")
#: ``TrackConfig.up`` choices: which edge of the image is up in the lab.
UP = ("top", "bottom")


@dataclass(frozen=True)
class TrackConfig:
    """Settings of the tracking.

    Parameters
    ----------
    fps : float, optional
        Frame rate [1/s]; required unless the file records it.
    pixel_size : float, optional
        Pixel size in the object plane [m]; required unless the file records it.
    origin_frames : int
        y = 0 is the median centre-of-mass height of the measured frames among the first ``origin_frames``
        (the levitation before a field drop), unless an origin row is given or recorded.
    origin_row : float, optional
        Image row of the levitation height [px] (pixel centres at integer rows, counted from 0 at the top).
    polarity : {"auto", "dark", "bright"}
        Dark cubes on a bright background (shadowgraph), bright on dark, or detected.
    up : {"top", "bottom"}
        The image edge that is up in the lab: ``"top"`` (default) for images whose rows count down, as
        cameras and image files store them; ``"bottom"`` for an image stored upside down.
    edge_window : int, optional
        Half-length of the window across an edge [px] (default: from the measured edge blur).
    area_tolerance : float
        Largest relative deviation of a frame's silhouette area from the recording's median.
    max_motion_blur : float
        Largest motion-blur length beyond the recording's typical edge blur [px].
    max_edge_rms_factor : float
        Largest edge residual as a multiple of the recording's median (plus 0.05 px).
    max_squareness : float
        Largest ``|alpha_free + beta_free - pi|`` of the faces meeting at the hinge [rad].
    max_hinge_gap : float
        Largest distance between the two cubes' hinge corners, as a fraction of the side.
    calibration_frames : int
        Frames (spread over the recording) used to calibrate.
    batch : int
        Frames measured per batch.
    roi : (x0, x1, y0, y1), optional
        Region of interest: columns ``x0 <= u < x1`` and rows ``y0 <= v < y1`` of the frames [px]; only it is
        measured (a dimer that reaches its border is out of view).
    keep_drop : bool
        A recording of a field drop (rest, free fall, field back on; :mod:`cubedimer.drop_phases`) is written whole,
        with t from its first frame, instead of as the field-on motion with t = 0 at the field's return.
    """

    fps: float | None = field(default=None, metadata=named("--fps"))
    pixel_size: float | None = field(default=None, metadata=named("--pixel-size"))
    origin_frames: int = field(default=50, metadata=named("--origin-frames"))
    origin_row: float | None = field(default=None, metadata=named("--origin-row"))
    polarity: str = field(default="auto", metadata=named("--polarity"))
    up: str = field(default="top", metadata=named("--up"))
    edge_window: int | None = field(default=None, metadata=named("--edge-window"))
    area_tolerance: float = field(default=0.06, metadata=named("--area-tolerance"))
    max_motion_blur: float = field(default=3.0, metadata=named("--max-motion-blur"))
    max_edge_rms_factor: float = 4.0
    max_squareness: float = field(default=0.05, metadata=named("--max-squareness"))
    max_hinge_gap: float = field(default=0.1, metadata=named("--max-hinge-gap"))
    calibration_frames: int = 100
    batch: int = 1024
    roi: tuple[int, int, int, int] | None = field(default=None, metadata=named("--roi"))
    keep_drop: bool = False

    def __post_init__(self) -> None:
        with raising(TrackingError):
            check_positive(self, "fps", optional=True)
            check_positive(self, "pixel_size", optional=True)
            check_that(self, self.pixel_size is None or 1e-9 < self.pixel_size < 1e-2,
                       f"pixel size {self.pixel_size!r} m is implausible: give metres per pixel in the object plane, "
                       "e.g. 1e-5 for 10 um")
            check_whole(self, "origin_frames")
            check_that(self, self.origin_row is None or math.isfinite(self.origin_row),
                       f"--origin-row must be finite, got {self.origin_row!r}")
            check_choice(self, "polarity", POLARITIES)
            check_choice(self, "up", UP)
            check_in_range(self, "edge_window", 2, 50, unit="px", whole=True, optional=True)
            if self.roi is not None:
                x0, x1, y0, y1 = self.roi
                check_that(self, all(int(v) == v for v in self.roi) and min(self.roi) >= 0 and x0 < x1 and y0 < y1,
                           f"region of interest {x0}:{x1},{y0}:{y1} is empty or inverted: give --roi x0:x1,y0:y1 with "
                           "0 <= x0 < x1 (columns) and 0 <= y0 < y1 (rows)")
            for name in ("area_tolerance", "max_motion_blur", "max_edge_rms_factor", "max_squareness", "max_hinge_gap"):
                check_positive(self, name)
