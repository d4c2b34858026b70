"""Tracking one recording: calibration, the per-frame measurement in batches, the recording's bounds, y and theta.

:func:`track_recording` turns a :class:`~tracking.recording.Recording` into a :class:`TrackResult`:

1. **Calibration** on up to ``TrackConfig.calibration_frames`` frames spread over the recording: the
   polarity (dark cubes on a bright background or bright on dark: the side of the grey-level histogram
   the far tail lies on, by majority), the background level and its gradient (the border ring), the
   cube/background contrast, then a first measurement of those frames for the dimer's silhouette area
   and the edge blur, which set the edge window ``W = ceil(3.5 blur + 2)`` px and the area check.
2. **Measurement** of every frame (:func:`tracking.measure.measure_frames`, batches of
   ``TrackConfig.batch`` frames), undoing a hinge line's tilt out of the camera axis when the calibration found
   one above :data:`tracking.tilt.TILT_CORRECTION_DEG` (the centre of mass then moved back by the two
   silhouettes' overlap at the hinge, :func:`tracking.tilt.overlap_shift`).
3. **The recording's bounds.**  Measured frames whose edges are wider than the recording's median by more
   than the motion blur of ``max_motion_blur`` px (``width^2 - median^2 > L^2 / 12``), whose edge residual
   exceeds ``max_edge_rms_factor`` x its median (+ 0.05 px), whose hinge corners are not square within
   ``max_squareness`` beyond five standard errors of the check (``|alpha_free + beta_free - pi| - 5 sigma``)
   or lie apart by more than ``max_hinge_gap`` of the side are left unmeasured, with their reason.
4. **y and theta.**  ``y = (origin_row - v_com) x pixel_size`` (image rows count down; ``up="bottom"``
   for an image whose rows count up flips y and theta), the origin row from ``origin_row``, else the one
   the file records, else the median centre-of-mass row of the measured frames among the first
   ``origin_frames``; ``theta = (alpha - beta) / pi`` from the kernel.
5. **Noise.**  Each measured frame's standard errors of y (the image noise of the border ring propagated
   through the centroid) and theta (the edge residuals propagated through the face fits); the
   recording's noise estimates are their RMS.
6. **Per-recording steps.**  Every step registered in :mod:`tracking.recording_steps` reads the tracked recording
   and adds its result to RUN.json under its name.

The settings are :class:`~tracking.track_config.TrackConfig`; the run's record is written by
:mod:`tracking.run_record`.
"""
from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field, replace

import numpy as np
from numpy.typing import NDArray

from cubedimer.drop_phases import DropPhases, find_drop_phases

from .calibration import Calibration, faces_tilt, calibrate
from .measure import COLUMNS, STATUS, measure_frames
from .noise_estimate import noise_estimate
from .origin import find_origin
from .recording import Recording, TrackingError
from .recording_steps import TrackedRecording, run_recording_steps
from .run_record import example_frame, not_measured_hint, phases_record, run_record, status_counts
from .tilt import MAX_TILT_DEG, area_factor, overlap_shift, tilt_from_gap
from .track_config import POLARITIES, UP, TrackConfig

__all__ = ["TrackConfig", "TrackResult", "Calibration", "calibrate", "track_recording", "POLARITIES", "UP"]

logger = logging.getLogger(__name__)

_C = {name: i for i, name in enumerate(COLUMNS)}
#: Estimated tilt of the hinge line [degrees] above which the tracking warns (the estimate's noise is ~0.3).
TILT_WARNING_DEG = 3.0


@dataclass(frozen=True, eq=False)
class TrackResult:
    """The tracked run.

    Attributes
    ----------
    name : str
    t, y, theta : ndarray (n,)
        Times from 0 at the first frame [s], height above the levitation height [m] (up), bend [-]; NaN
        in frames not measured.
    status : ndarray (n,) int
        :data:`tracking.measure.STATUS` code per frame.
    rows : ndarray (n, len(COLUMNS))
        The kernel's measurement of every frame (pixel units); with a tilted hinge line undone, ``v_com`` is the
        cubes' centre, moved back by the silhouettes' overlap at the hinge.
    info : dict
        The RUN.json document (:func:`tracking.output.run_json`'s content).
    example : ndarray (height, width)
        The raw grey frame chosen for the annotated figure (``info["example_frame"]``).
    """

    name: str
    t: NDArray[np.float64]
    y: NDArray[np.float64]
    theta: NDArray[np.float64]
    status: NDArray[np.int64]
    rows: NDArray[np.float64]
    info: dict = field(default_factory=dict)
    example: NDArray | None = None

    @property
    def n_measured(self) -> int:
        return int(np.sum(self.status == 0))

    def run_series(self) -> tuple[NDArray, NDArray, NDArray]:
        """(t, y, theta) of the run as written: the field-on motion with t = 0 at the field's return when the
        recording holds a field drop that is cut (``info["phases"]``), else every frame with t from the first."""
        ph = self.info.get("phases")
        if not ph or ph.get("kept") != "field-on motion":
            return self.t, self.y, self.theta
        k = int(ph["field_on_first_frame"])
        return self.t[k:] - ph["field_on_time_s"], self.y[k:], self.theta[k:]


def _flag(status: NDArray, rows: NDArray, config: TrackConfig, tau: float = 0.0) -> dict:
    """Step 3 of the module docstring: the recording's bounds; returns the reference values used.  With a hinge
    line's tilt ``tau`` [rad] undone, the hinge corners are judged in the corrected geometry: the image's squares'
    corners lie ``side sin(tau) / sqrt(area_factor(tau))`` apart there (:mod:`tracking.tilt`), and only the distance
    beyond that counts against ``max_hinge_gap``."""
    ok = status == 0
    if not ok.any():
        return {}
    # a particle stuck to the silhouette moves its centre of mass off the fitted squares' centre (their faces,
    # fitted away from the corners, do not see it): beyond 8 robust standard deviations of the recording (+ 0.05 px)
    dv = rows[:, _C["v_com"]] - 0.5 * (rows[:, _C["v_a"]] + rows[:, _C["v_b"]])
    du = rows[:, _C["u_com"]] - 0.5 * (rows[:, _C["u_a"]] + rows[:, _C["u_b"]])
    off = np.zeros_like(ok)
    for d in (dv, du):
        ref = float(np.median(d[ok]))
        scale = 1.4826 * float(np.median(np.abs(d[ok] - ref)))
        off |= ok & (np.abs(d - ref) > 8.0 * scale + 0.05)
    status[off] = STATUS["touching"]
    ok = status == 0
    width = rows[:, _C["edge_width"]]
    w_ref = float(np.median(width[ok]))
    blur = ok & (width ** 2 - w_ref ** 2 > config.max_motion_blur ** 2 / 12.0)
    status[blur] = STATUS["motion_blur"]
    ok = status == 0
    rms = rows[:, _C["edge_rms"]]
    rms_ref = float(np.median(rms[ok])) if ok.any() else float("nan")
    # the squareness check counts beyond its own noise (short hinge faces at large bends fit loosely)
    square = np.abs(rows[:, _C["alpha_free"]] + rows[:, _C["beta_free"]] - math.pi) - 5.0 * rows[:, _C["squareness_sigma"]]
    side = 2.0 * rows[:, _C["half_side"]]
    gap = np.abs(rows[:, _C["hinge_gap"]] - side * math.sin(tau) / math.sqrt(area_factor(tau)))
    poor = ok & ((rms > config.max_edge_rms_factor * rms_ref + 0.05) | (np.nan_to_num(square) > config.max_squareness)
                 | (gap > config.max_hinge_gap * side))
    status[poor] = STATUS["poor_fit"]
    return {"edge_width_px": w_ref, "edge_rms_px": rms_ref}


def track_recording(rec: Recording, config: TrackConfig = TrackConfig()) -> TrackResult:
    """Track one recording (module docstring): the frame rate and pixel size, the frames (in the region of
    interest), the calibration, every frame measured, the hinge line's tilt, the origin, y and theta, their
    noise, and the run's record (RUN.json) with the result of every registered per-recording step
    (:mod:`tracking.recording_steps`) under its name.

    Raises
    ------
    TrackingError
        Unknown frame rate or pixel size, no dimer in any frame, no origin, a step named as an entry of RUN.json.
    """
    fps, pixel = _frame_rate_and_pixel_size(rec, config)
    frames = _frames_in_region(rec, config)
    n = frames.shape[0]
    try:
        cal = calibrate(frames, config)
    except TrackingError as exc:
        raise TrackingError(f"{rec.path}: {exc}") from None
    settings = cal.settings(config)
    tau = settings.hinge_tilt
    rows = np.empty((n, len(COLUMNS)))
    for f0 in range(0, n, config.batch):
        rows[f0:f0 + config.batch] = measure_frames(frames[f0:f0 + config.batch], settings, pinv=cal.pinv)
    status = rows[:, 0].astype(np.int64)
    if tau:
        _correct_centre_of_mass(rows, status, tau, cal)
    refs = _flag(status, rows, config, tau)
    ok = status == 0
    tilt_deg = _hinge_line_tilt(rec, rows, status, config, cal)
    phases = _drop_phases(rows, status, fps, pixel, config)
    origin = _origin(rec, rows, status, replace(config, origin_frames=min(config.origin_frames, phases.rest_frames))
                     if phases is not None and phases.free_fall and phases.rest_frames >= 1 else config)
    sign = 1.0 if config.up == "top" else -1.0
    y0 = config.roi[2] if config.roi else 0
    y = np.where(ok, sign * (origin["row_px"] - y0 - rows[:, _C["v_com"]]) * pixel, np.nan)
    theta = np.where(ok, sign * rows[:, _C["theta"]], np.nan)
    t = np.arange(n) / float(fps)
    noise_y, noise_theta = _noise(rows, ok, y, theta, pixel)
    correction = _tilt_correction(cal, rows, ok, pixel, noise_y, noise_theta) if tau else None
    ex = example_frame(ok, theta)
    info = run_record(rec, config, fps, pixel, cal, rows, status, refs, origin, tilt_deg, noise_y, noise_theta, ex,
                     theta)
    info["tilt_correction"] = correction
    info["phases"] = phases_record(phases, config, rec.name) if phases is not None else None
    info = run_recording_steps(TrackedRecording(rec, config, fps, pixel, t, y, theta, status, rows), info)
    logger.info("%s: %d of %d frames measured (%s); noise y %.3g m, theta %.3g", rec.name, int(ok.sum()), n,
                ", ".join(f"{k} {v}" for k, v in info["not_measured"].items()) or "all", noise_y["value"],
                noise_theta["value"])
    return TrackResult(rec.name, t, y, theta, status, rows, info, np.array(frames[ex]))


def _drop_phases(rows: np.ndarray, status: np.ndarray, fps: float, pixel: float, config: TrackConfig
                 ) -> DropPhases | None:
    """The recording's field-drop phases (:func:`cubedimer.drop_phases.find_drop_phases` on the centre-of-mass
    height, up, with the frames' own noise), or None when it does not start at rest before a fall."""
    ok = status == 0
    if ok.sum() < 50:
        return None
    up = -1.0 if config.up == "top" else 1.0
    height = np.where(ok, up * rows[:, _C["v_com"]] * pixel, np.nan)
    noise = float(np.sqrt(np.median(rows[ok, _C["sigma_v"]] ** 2))) * pixel
    return find_drop_phases(np.arange(len(status)) / fps, height, noise)


def _frame_rate_and_pixel_size(rec: Recording, config: TrackConfig) -> tuple[float, float]:
    """The frame rate [1/s] and pixel size [m]: the options, else the file's; a one-line refusal without either."""
    fps = config.fps or rec.fps
    if fps is None:
        raise TrackingError(f"{rec.path}: unknown frame rate: the file does not record the camera's; give --fps "
                            "(frames per second)")
    pixel = config.pixel_size or rec.pixel_size
    if pixel is None:
        raise TrackingError(f"{rec.path}: unknown pixel size: the file does not record one; give --pixel-size "
                            "(metres per pixel in the object plane)")
    return fps, pixel


def _frames_in_region(rec: Recording, config: TrackConfig) -> np.ndarray:
    """The frames, cut to ``--roi`` when given; refused when the region leaves the frame or is too small."""
    frames = rec.frames
    n, h, w = frames.shape
    if config.roi is not None:
        x0, x1, y0, y1 = config.roi
        if x1 > w or y1 > h:
            raise TrackingError(f"{rec.path}: --roi {x0}:{x1},{y0}:{y1} reaches outside the frames of {w} x {h} px; "
                                f"give columns within 0:{w} and rows within 0:{h}")
        frames = frames[:, y0:y1, x0:x1]
        n, h, w = frames.shape
    if h < 24 or w < 24:
        raise TrackingError(f"{rec.path}: frames of {w} x {h} px" + (" (the --roi)" if config.roi else "")
                            + " are too small to hold a dimer")
    return frames


def _hinge_line_tilt(rec: Recording, rows: np.ndarray, status: np.ndarray, config: TrackConfig,
                     cal: Calibration) -> float | None:
    """The hinge line's tilt out of the camera axis [degrees]: the one undone (the calibration's, from the cubes'
    centres), else from the fitted squares' hinge gap (None when no frame was fitted); a warning above
    :data:`TILT_WARNING_DEG`, a refusal above :data:`MAX_TILT_DEG` or when no frame could be measured (naming the
    counts per reason, and the tilt with the option that measures it)."""
    ok = status == 0
    fitted = (ok | (status == STATUS["poor_fit"])) & np.isfinite(rows[:, _C["hinge_gap"]])
    tilt_deg = tilt_from_gap(float(np.median(rows[fitted, _C["hinge_gap"]] / (2.0 * rows[fitted, _C["half_side"]])))) \
        if fitted.any() else None
    if cal.tilt is not None and tilt_deg is not None:
        tilt_deg = cal.tilt["tilt_deg"]
    elif tilt_deg is not None and tilt_deg > TILT_WARNING_DEG:
        # nothing undone: the faces' reading, which a coverage offset of the background (bright cubes on black under
        # noise: edges read outward) does not enlarge as it does the area's (tracking.tilt.tilt_from_faces)
        tilt_deg = min(tilt_deg, faces_tilt(rows[fitted]) or tilt_deg)
    if tilt_deg is not None and tilt_deg > MAX_TILT_DEG:
        raise TrackingError(f"{rec.path}: the hinge line is tilted about {tilt_deg:.0f} degrees out of the camera axis "
                            f"(the fitted squares' hinge corners lie apart), beyond the {MAX_TILT_DEG:.0f} degrees that "
                            "can be measured; align the camera along the hinge line")
    if tilt_deg is not None and tilt_deg > TILT_WARNING_DEG:
        logger.warning("%s: the hinge line is tilted about %.1f degrees out of the camera axis: y and theta are "
                       "corrected for it, the bias the tilt's error leaves is in the noise estimates (RUN.json "
                       "tilt_correction, docs/tracking.md); frames whose hinge corners lie more than --max-hinge-gap %g "
                       "of the side from where the tilt puts them are not measured", rec.name, tilt_deg,
                       config.max_hinge_gap)
    if not ok.any():
        why = ", ".join(f"{k} in {v}" for k, v in status_counts(status).items())
        tilted = (f"; the hinge line looks tilted about {tilt_deg:.0f} degrees out of the camera axis: "
                  "--max-hinge-gap 0.5 measures it" if tilt_deg is not None and tilt_deg > TILT_WARNING_DEG else "")
        raise TrackingError(f"{rec.path}: no dimer in any frame could be measured ({why}{not_measured_hint(status)}{tilted})")
    return tilt_deg


def _correct_centre_of_mass(rows: np.ndarray, status: np.ndarray, tau: float, cal: Calibration) -> None:
    """The centre of mass of the measured frames moved back to the cubes' centres (``v_com`` in place): under a
    tilt the two cubes' silhouettes overlap at the hinge (:func:`tracking.tilt.overlap_shift`)."""
    ok = status == 0
    side = math.sqrt(cal.area_px2 / 2.0 / area_factor(tau))
    rows[ok, _C["v_com"]] += overlap_shift(rows[ok, _C["theta"]], rows[ok, _C["tilt"]], tau, side, rows[ok, _C["area"]])


def _tilt_correction(cal: Calibration, rows: np.ndarray, ok: np.ndarray, pixel: float, noise_y: dict,
                     noise_theta: dict) -> dict:
    """RUN.json's ``tilt_correction``: the tilt undone and its error, and the bias that error leaves in y (the
    centre-of-mass correction at the tilt plus its error against at the tilt, RMS over the measured frames) and
    theta (the calibration's), added in quadrature to the noise estimates (``value`` of each, in place)."""
    t = cal.tilt
    tau, err = math.radians(t["tilt_deg"]), math.radians(t["error_deg"])
    side = math.sqrt(cal.area_px2 / 2.0 / area_factor(tau))
    args = (rows[ok, _C["theta"]], rows[ok, _C["tilt"]])
    shift = overlap_shift(*args, tau + err, side, rows[ok, _C["area"]]) - overlap_shift(*args, tau, side,
                                                                                       rows[ok, _C["area"]])
    bias_y = float(np.sqrt(np.mean(shift ** 2))) * pixel if ok.any() else 0.0
    bias_theta = t["theta_bias"]
    for noise, bias in ((noise_y, bias_y), (noise_theta, bias_theta)):
        noise["without_tilt_bias"] = noise["value"]
        noise["tilt_bias"] = bias
        noise["value"] = math.hypot(noise["value"], bias)
    return {"applied": True, "tilt_deg": t["tilt_deg"], "error_deg": t["error_deg"],
            "from_hinge_gap_deg": t["from_hinge_gap_deg"], "from_faces_deg": t["from_faces_deg"],
            "frames": t["frames"], "bias_y_m": bias_y,
            "bias_theta": bias_theta,
            "method": "the face fits undo the projection of a hinge line turned by tilt_deg about the vertical (each "
                      "cube's square shortened across by cos(tilt), swept along the rows by side sin(tilt)); the "
                      "centre of mass is moved back by the two silhouettes' overlap at the hinge; the tilt from the "
                      "cubes' centres and the silhouette's area on the calibration frames; the bias its error leaves "
                      "is in noise_estimate (docs/tracking.md)"}


def _origin(rec: Recording, rows: np.ndarray, status: np.ndarray, config: TrackConfig) -> dict:
    """The origin row (of the full frame; the region of interest starts at row y0) and how it was found: the
    option, the file, or the first frames (at rest) or the late oscillation's centre (:func:`find_origin`)."""
    ok = status == 0
    y0 = config.roi[2] if config.roi else 0
    if config.origin_row is not None:
        origin = {"row_px": float(config.origin_row), "from": "option --origin-row", "at_rest": None,
                  "method": "option"}
    elif rec.levitation_row is not None:
        origin = {"row_px": float(rec.levitation_row), "from": "recorded in the file", "at_rest": None,
                  "method": "file"}
    else:
        head = status[: config.origin_frames]
        why = ", ".join(f"{k} in {v}" for k, v in status_counts(head).items())
        origin = find_origin(rows[:, _C["v_com"]] + y0, rows[:, _C["sigma_v"]], ok, config.origin_frames, rec.path,
                             why + not_measured_hint(head))
        if not origin["at_rest"]:
            logger.warning("%s: the recording does not start at rest: y = 0 is the centre of the late oscillation "
                           "(%s); give --origin-row if the levitation row is known", rec.name, origin["from"])
    return origin


def _noise(rows: np.ndarray, ok: np.ndarray, y: np.ndarray, theta: np.ndarray, pixel: float) -> tuple[dict, dict]:
    """The noise estimates of y [m] and theta (:func:`noise_estimate`, with each frame's standard errors and the
    cross-checks of the centre of mass and of the face angles)."""
    check_y = np.where(ok, (rows[:, _C["v_com"]] - 0.5 * (rows[:, _C["v_a"]] + rows[:, _C["v_b"]])) * pixel, np.nan)
    check_theta = np.where(ok, rows[:, _C["theta"]] - (rows[:, _C["alpha_free"]] - rows[:, _C["beta_free"]]) / math.pi,
                           np.nan)
    noise_y = noise_estimate(y, check_y, float(np.sqrt(np.mean(rows[ok, _C["sigma_v"]] ** 2))) * pixel)
    noise_theta = noise_estimate(theta, check_theta, float(np.sqrt(np.mean(rows[ok, _C["sigma_theta"]] ** 2))))
    return noise_y, noise_theta


