"""The run's record, RUN.json (docs/formats.md): what the tracking found in one recording and how.

:func:`run_record` writes the document :attr:`tracking.track.TrackResult.info` holds (the sources of the frame rate,
the pixel size and the origin, the calibration, the counts of frames not measured and why, the noise estimates, the
per-frame quality and the example frame); :func:`phases_record` its ``phases`` (a field drop).  The per-recording
steps of :mod:`tracking.recording_steps` add their own entries beside these.
"""
from __future__ import annotations

import logging
import math

import numpy as np
from numpy.typing import NDArray

from cubedimer.drop_phases import DropPhases
from .frame_row import COLUMNS, STATUS_NAMES, STATUS_TEXT
from .recording import Recording
from .tilt import area_factor
from .track_config import TrackConfig

__all__ = ["run_record", "phases_record", "status_counts", "not_measured_hint", "example_frame"]

logger = logging.getLogger("tracking.track")

_C = {name: i for i, name in enumerate(COLUMNS)}


def status_counts(status: NDArray) -> dict[str, int]:
    """Frames per reason they were not measured, by status name, in the order of the codes."""
    return {STATUS_NAMES[c]: int(np.sum(status == c)) for c in sorted(set(status.tolist())) if c != 0}


def not_measured_hint(status: NDArray) -> str:
    """What to try for the commonest reason frames were not measured (the option that bounds that check)."""
    bad = status[status != 0]
    if bad.size == 0:
        return ""
    top = STATUS_NAMES[int(np.bincount(bad).argmax())]
    return {"poor_fit": "; see RUN.json checks, and --max-hinge-gap (hinge corners apart: a hinge line tilted out of "
                        "the camera axis) or --max-squareness",
            "third_particle": "; python -m tracking inspect shows the background: try --roi",
            "occlusion": "; try --area-tolerance or --roi",
            "touching": "; python -m tracking inspect shows the background: try --roi",
            "motion_blur": "; try --max-motion-blur",
            "out_of_view": "; the dimer reaches the border of the frame (or of --roi)"}.get(top, "")


def phases_record(phases: DropPhases, config: TrackConfig, name: str) -> dict:
    """RUN.json's ``phases``: the frames and times of the rest, the fall and the field's return, and what the run
    keeps (a fall whose acceleration is not g is kept whole, with a warning)."""
    out = phases.to_dict()
    cut = phases.free_fall and not config.keep_drop
    out["kept"] = "field-on motion" if cut else "whole recording"
    if not phases.free_fall:
        logger.warning("%s: the recording starts at rest for %d frames and then moves, but not in a free fall "
                       "(acceleration %.3g m/s^2 against g = 9.81, residual RMS %.2g m against a noise of %.2g m): kept "
                       "whole; cut it to the field-on motion before fitting", name, phases.rest_frames,
                       phases.fall_acceleration, phases.fit_scatter, phases.noise)
    else:
        logger.info("%s: at rest for %d frames, the field off for %.2f ms (fall %.3g +- %.2g m/s^2), back at t = "
                    "%.5f s: %s", name, phases.rest_frames, 1e3 * phases.field_off_s, phases.fall_acceleration,
                    phases.fall_acceleration_error, out["field_on_time_s"],
                    "the run is the field-on motion, t = 0 at the field's return" if cut else "kept whole (--keep-drop)")
    return out


def example_frame(ok: np.ndarray, theta: np.ndarray) -> int:
    """The example frame: a measured frame with a clear bend (90th percentile of |theta|)."""
    meas = np.flatnonzero(ok)
    target = np.quantile(np.abs(theta[meas]), 0.9)
    return int(meas[np.argmin(np.abs(np.abs(theta[meas]) - target))])


def run_record(rec: Recording, config: TrackConfig, fps: float, pixel: float, cal, rows: np.ndarray,
              status: np.ndarray, refs: dict, origin: dict, tilt_deg: float | None, noise_y: dict, noise_theta: dict,
              ex: int, theta: np.ndarray) -> dict:
    """The run's record, RUN.json (docs/formats.md)."""
    ok = status == 0
    n = len(status)
    sign = 1.0 if config.up == "top" else -1.0
    sigma_y, sigma_theta = noise_y["value"], noise_theta["value"]
    counts = status_counts(status)
    r = rows[ex]
    alpha, beta = (r[_C["alpha"]], r[_C["beta"]]) if sign > 0 else (r[_C["beta"]], r[_C["alpha"]])
    square = rows[ok, _C["alpha_free"]] + rows[ok, _C["beta_free"]] - math.pi
    info = {
        "source": rec.path,
        "format": rec.format,
        "frames": int(n),
        "frame_size_px": [int(rec.frames.shape[2]), int(rec.frames.shape[1])],
        "roi_px": list(config.roi) if config.roi else None,
        "frame_rate_hz": float(fps),
        "frame_rate_from": "option --fps" if config.fps else "recorded in the file",
        "pixel_size_m": float(pixel),
        "pixel_size_from": "option --pixel-size" if config.pixel_size else "recorded in the file",
        "y_origin": {**origin,
                     "convention": "y = (origin row - centre-of-mass row) x pixel size: positive up, image rows "
                                   "counting down" if sign > 0 else
                                   "y = (centre-of-mass row - origin row) x pixel size: the image is upside down "
                                   "(--up bottom), theta's sign flipped with it"},
        "orientation": {"up": config.up, "polarity": cal.polarity, "polarity_from": cal.polarity_from},
        "frames_measured": int(ok.sum()),
        "frames_not_measured": int(n - ok.sum()),
        "fraction_measured": float(ok.mean()),
        "not_measured": counts,
        "noise_estimate": {"y_m": sigma_y, "theta": sigma_theta, "estimator_y": noise_y["estimator"],
                           "estimator_theta": noise_theta["estimator"], "y_details": noise_y,
                           "theta_details": noise_theta,
                           "method": "white: RMS over the measured frames of each frame's standard error (the image "
                                     "noise of the border ring through the centre of mass for y, the edge residuals "
                                     "through the face fits for theta); correlated, when the frames' errors are "
                                     "correlated (lag-1 correlation of the cross-check above 0.3): the fourth "
                                     "differences corrected for that correlation, if larger (docs/tracking.md)"},
        "calibration": {"background_level": cal.background, "contrast": cal.contrast,
                        "background_slope_per_px": [cal.slope_u, cal.slope_v], "edge_blur_px": cal.edge_blur_px,
                        "edge_window_px": cal.edge_window_px, "silhouette_area_px2": cal.area_px2,
                        "side_length_m": math.sqrt(cal.area_px2 / 2.0) * pixel, "frames_used": cal.frames_used,
                        "illumination_change": cal.scene.gradient, "static_structure_px": int(cal.scene.static.sum()),
                        "light_level_range": [float(np.min(rows[ok, _C["background"]]) / cal.background),
                                              float(np.max(rows[ok, _C["background"]]) / cal.background)]
                        if cal.background > 0 else None,
                        "holes_filled": cal.fill_holes, "dark_offset": cal.dark_offset},
        "checks": {"alpha_plus_beta_minus_pi_rad": {"median": float(np.nanmedian(square))
                                                    if np.isfinite(square).any() else None,
                                                    "p95_abs": float(np.nanpercentile(np.abs(square), 95))
                                                    if np.isfinite(square).any() else None,
                                                    "bound": config.max_squareness},
                   "tilt_rad_median": float(np.median(rows[ok, _C["tilt"]])),
                   "hinge_line_tilt_deg": tilt_deg,
                   "side_length_m_tilt_corrected": math.sqrt(cal.area_px2 / 2.0 / area_factor(math.radians(tilt_deg)))
                   * pixel if tilt_deg is not None else None,
                   "edge_rms_px_median": refs.get("edge_rms_px"), "edge_width_px_median": refs.get("edge_width_px")},
        "quality": {"measure": "edge_rms_px: RMS distance [px] of the sub-pixel edge crossings from the fitted faces "
                               "(about the image noise times the window's square root; larger for occlusions, "
                               "bent or blurred edges); null where the frame was not measured",
                    "edge_rms_px": [round(float(v), 4) if s == 0 else None
                                    for v, s in zip(rows[:, _C["edge_rms"]], status)],
                    "status": status.tolist(), "status_codes": dict(STATUS_NAMES),
                    "status_text": STATUS_TEXT},
        "example_frame": {"index": ex, "theta": float(theta[ex]), "alpha_rad": float(alpha), "beta_rad": float(beta),
                          "centre_of_mass_px": [float(r[_C["u_com"]]), float(r[_C["v_com"]])],
                          "half_side_px": float(r[_C["half_side"]]),
                          "squares": [{"cube": "A", "centre_px": [float(r[_C["u_a"]]), float(r[_C["v_a"]])],
                                       "face_direction_rad": float(r[_C["gamma_a"]])},
                                      {"cube": "B", "centre_px": [float(r[_C["u_b"]]), float(r[_C["v_b"]])],
                                       "face_direction_rad": float(r[_C["gamma_b"]])}],
                          "convention": "pixel centres at integer (column, row), rows counting down; face directions "
                                        "counter-clockwise from the +column axis with up = -row"},
        "units": "SI (lengths in pixels where named _px, angles in radians)",
    }
    return info
