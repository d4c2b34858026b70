"""Writing what the tracking measured: one run's CSV, its RUN.json and example frame, or a data set.

* one recording: ``RUN.csv`` (docs/formats.md: ``t`` from 0 at the first frame, ``y``, ``theta``, a
  ``# units:`` comment line, empty values where the dimer could not be measured), ``RUN.json`` beside it
  (:attr:`tracking.track.TrackResult.info`) and ``RUN.frame.png``, the raw example frame the report
  annotates;
* a folder of recordings: a data set folder with those three files per recording and ``meta.json``
  (``frame_rate_hz`` and a ``tracking`` block: the pooled noise estimates, the fraction measured, the
  pixel size and the skipped recordings), built beside the target and renamed into place.

Every file is written atomically (:mod:`cubedimer.atomic`).
"""
from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np

from cubedimer.atomic import atomic_directory, atomic_save, write_json
from cubedimer.dataset import write_run_csv

from .track import TrackResult

__all__ = ["write_run", "write_dataset", "dataset_tracking_block", "frame_png_name", "pooled_noise"]


def frame_png_name(csv_name: str) -> str:
    """``run01.csv`` -> ``run01.frame.png``."""
    return f"{Path(csv_name).stem}.frame.png"


def write_run(csv_path: str | os.PathLike, result: TrackResult) -> Path:
    """Write ``RUN.csv``, ``RUN.json`` and ``RUN.frame.png`` (module docstring); returns the CSV's path."""
    import imageio.v3 as iio

    csv_path = Path(csv_path)
    info = dict(result.info)
    info["example_frame"] = {**info["example_frame"], "file": frame_png_name(csv_path.name)}
    n_bad = info["frames_not_measured"]
    t, y, theta = result.run_series()
    ph = info.get("phases")
    comments = [f"tracked from {Path(info['source']).name} by python -m tracking: {info['frames_measured']} of "
                f"{info['frames']} frames measured ({n_bad} left empty: see {csv_path.stem}.json)",
                "units: t [s], y [m] (centre-of-mass height above the levitation height, up), theta [-] "
                "((alpha - beta) / pi)"]
    if ph and ph["kept"] == "field-on motion":
        comments.insert(1, f"the field-on motion: frames {ph['field_on_first_frame']}-{info['frames'] - 1} of the "
                           f"recording, t = 0 when the field is back (the rest and the fall before: see "
                           f"{csv_path.stem}.json phases)")
    elif ph:
        comments.insert(1, f"the whole recording: at rest, the field off from t = {ph['drop_time_s']:.6f} s, back on "
                           f"at t = {ph['field_on_time_s']:.6f} s (see {csv_path.stem}.json phases)")
    write_run_csv(csv_path, t, y, theta, comments, t_decimals=9, y_digits=8, theta_decimals=6, missing="")
    write_json(csv_path.with_suffix(".json"), info)
    frame = result.example
    if frame.dtype not in (np.uint8, np.uint16):  # float frames: scaled to 16 bits for the picture
        lo, hi = float(np.nanmin(frame)), float(np.nanmax(frame))
        frame = np.round((frame - lo) / max(hi - lo, 1e-12) * 65535).astype(np.uint16)
    atomic_save(csv_path.parent / frame_png_name(csv_path.name), lambda tmp: iio.imwrite(tmp, frame, extension=".png"))
    return csv_path


def dataset_tracking_block(results: list[TrackResult], skipped: list[dict]) -> dict:
    """meta.json's ``tracking`` block: pooled noise (RMS over runs, weighted by measured frames), fraction
    measured, pixel size, per-run summaries and the skipped recordings."""
    k = np.array([r.n_measured for r in results], float)
    ny = np.array([r.info["noise_estimate"]["y_m"] for r in results])
    nt = np.array([r.info["noise_estimate"]["theta"] for r in results])
    frames = sum(r.info["frames"] for r in results)
    return {
        "noise_y_m": pooled_noise(ny, k),
        "noise_theta": pooled_noise(nt, k),
        "noise_pooling": "the larger of the RMS over runs and the RMS over measured frames (a noisy run is never "
                         "averaged away by the others' frames); each run's own in runs[].noise_y_m, noise_theta",
        "fraction_measured": float(np.sum(k) / frames),
        "frames": int(frames),
        "pixel_size_m": float(np.median([r.info["pixel_size_m"] for r in results])),
        "side_length_m_measured": float(np.median([r.info["calibration"]["side_length_m"] for r in results])),
        "runs": [{"file": f"{r.name}.csv", "source": Path(r.info["source"]).name, "frames": r.info["frames"],
                  "fraction_measured": r.info["fraction_measured"], "noise_y_m": r.info["noise_estimate"]["y_m"],
                  "noise_theta": r.info["noise_estimate"]["theta"], "not_measured": r.info["not_measured"],
                  "noise_estimator": {"y": r.info["noise_estimate"]["estimator_y"],
                                      "theta": r.info["noise_estimate"]["estimator_theta"]},
                  "origin": r.info["y_origin"]["method"], "origin_at_rest": r.info["y_origin"]["at_rest"],
                  "phases": _phases_summary(r.info.get("phases"))}
                 for r in results],
        "skipped": skipped,
        "method": "python -m tracking: y from the silhouette's centre of mass, theta from sub-pixel face fits "
                  "(docs/tracking.md); noise: RMS of the per-frame standard errors, or the correlated estimate "
                  "where the frames' errors are correlated (each run's noise_estimator)",
    }


def pooled_noise(noise: np.ndarray, frames: np.ndarray) -> float:
    """A set's noise from its runs': the larger of the RMS over runs and the RMS over measured frames, so that it is
    never below the runs' RMS (a short noisy run, a compressed or transparent one, counts as a run)."""
    noise, frames = np.asarray(noise, float), np.asarray(frames, float)
    return float(max(math.sqrt(np.mean(noise ** 2)), math.sqrt(np.sum(frames * noise ** 2) / np.sum(frames))))


def _phases_summary(ph: dict | None) -> dict | None:
    """A run's field-drop phases in meta.json: frames, times and what the run keeps (None: no drop found)."""
    if not ph:
        return None
    return {k: ph[k] for k in ("rest_frames", "field_off_frames", "field_on_first_frame", "drop_time_s",
                               "field_on_time_s", "field_on_time_error_s", "fall_acceleration_m_s2", "free_fall",
                               "kept")}


def write_dataset(out_dir: str | os.PathLike, results: list[TrackResult], skipped: list[dict],
                  force: bool = False, max_gap: int | None = None) -> Path:
    """Write a data set of tracked runs (module docstring) into ``out_dir``, built beside it and renamed into
    place; an existing ``out_dir`` is replaced only with ``force``.  ``max_gap`` [frames], when given, is recorded
    as ``tracking.max_gap_frames``: the loader's fill limit for the set (longer gaps split a run)."""
    out = Path(out_dir)
    with atomic_directory(out) as tmp:
        for r in results:
            write_run(tmp / f"{r.name}.csv", r)
        fps = sorted({r.info["frame_rate_hz"] for r in results})
        meta = {"frame_rate_hz": fps[0] if len(fps) == 1 else None,
                "tracking": dataset_tracking_block(results, skipped)}
        if max_gap is not None:
            meta["tracking"]["max_gap_frames"] = int(max_gap)
        if meta["frame_rate_hz"] is None:
            del meta["frame_rate_hz"]
        write_json(tmp / "meta.json", meta)
    return out
