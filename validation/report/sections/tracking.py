"""The tracking as a report section, when the data set came from video (``python -m tracking``).

A data set tracked from video holds a ``tracking`` block in ``meta.json`` (pooled noise estimates, fraction of
frames measured) and, beside each run's CSV, its ``RUN.json`` (counts of frames measured and not, with the
reasons, per-frame quality, the example frame's fitted squares and angles) and ``RUN.frame.png`` (that frame).
:func:`tracking_section` turns them into the section: a reading paragraph, a table per run and the example
frame annotated with the fitted faces, the measured alpha and beta and the centre of mass.  Data sets without
them give no section.
"""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from cubedimer.atomic import save_figure

from ..context import ReportContext
from ..html import Figure, Section, Table

__all__ = ["section", "tracking_section", "annotated_frame_figure"]


def _read_json(path: Path) -> dict | None:
    try:
        d = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    return d if isinstance(d, dict) else None


def _run_records(data_dir: Path) -> list[tuple[str, dict]]:
    """(CSV name, RUN.json) of every run that a tracking wrote."""
    out = []
    for csv in sorted(data_dir.glob("*.csv")):
        d = _read_json(csv.with_suffix(".json"))
        if d and "frames_measured" in d and "noise_estimate" in d:
            out.append((csv.name, d))
    return out


def _corners(centre, gamma: float, half: float) -> np.ndarray:
    """Corners (4, 2) of a square in image (column, row) coordinates; ``gamma`` is a face direction
    counter-clockwise from +column with up = -row."""
    e1 = np.array([math.cos(gamma), -math.sin(gamma)])
    e2 = np.array([-math.sin(gamma), -math.cos(gamma)])
    c = np.asarray(centre, float)
    return np.array([c + half * (s1 * e1 + s2 * e2) for s1, s2 in ((1, 1), (-1, 1), (-1, -1), (1, -1))])


def annotated_frame_figure(png: Path, run: dict, out_path: Path) -> Path:
    """The example frame with the fitted squares, the faces that meet at the hinge, the centre of mass and the
    measured alpha (above the hinge) and beta (below it); returns the saved PNG."""
    import imageio.v3 as iio
    import matplotlib.pyplot as plt

    ex = run["example_frame"]
    img = np.asarray(iio.imread(png))
    fig, ax = plt.subplots(figsize=(5.6, 4.6), constrained_layout=True)
    ax.imshow(img, cmap="gray", interpolation="nearest")
    half = ex["half_side_px"]
    hinge = []
    for sq, colour in zip(ex["squares"], ("tab:orange", "tab:cyan")):
        c = _corners(sq["centre_px"], sq["face_direction_rad"], half)
        ax.add_patch(plt.Polygon(c, closed=True, fill=False, ec=colour, lw=1.2, label=f"cube {sq['cube']} (fitted faces)"))
        k = int(np.argmax(c[:, 0]) if sq["cube"] == "A" else np.argmin(c[:, 0]))  # the hinge corner
        hinge.append(c[k])
        for j in (k - 1, (k + 1) % 4):  # the two faces meeting at it
            ax.plot([c[k, 0], c[j, 0]], [c[k, 1], c[j, 1]], color=colour, lw=2.6)
    h = np.mean(hinge, axis=0)
    u, v = ex["centre_of_mass_px"]
    ax.plot(u, v, "+", color="red", ms=12, mew=2, label="centre of mass (y)")
    ax.plot(*h, "o", color="yellow", ms=4, label="hinge")
    box = {"boxstyle": "round,pad=0.2", "fc": "white", "ec": "0.5", "alpha": 0.85}
    ax.annotate(f"alpha = {math.degrees(ex['alpha_rad']):.1f} deg", h, xytext=(h[0], h[1] - 0.9 * half),
                color="black", ha="center", fontsize=9, bbox=box)
    ax.annotate(f"beta = {math.degrees(ex['beta_rad']):.1f} deg", h, xytext=(h[0], h[1] + 1.1 * half),
                color="black", ha="center", fontsize=9, bbox=box)
    ax.set_title(f"{run.get('source_name', '')} frame {ex['index']}: theta = (alpha - beta) / pi = {ex['theta']:.3f}",
                 fontsize=9)
    ax.set_xlabel("image column [px]")
    ax.set_ylabel("image row [px] (counting down)")
    ax.legend(fontsize=7, loc="lower left", framealpha=0.7)
    return save_figure(fig, out_path)


def tracking_section(data_dir: str | Path, figs_dir: str | Path, meta: dict | None = None) -> Section | None:
    """The tracking section of a data set tracked from video, or None when nothing says it came from video
    (``meta``: the data set's meta.json as loaded; read from ``data_dir`` when not given)."""
    data_dir = Path(data_dir)
    meta = meta if meta is not None else (_read_json(data_dir / "meta.json") or {})
    block = meta.get("tracking") if isinstance(meta.get("tracking"), dict) else None
    runs = _run_records(data_dir)
    if block is None and not runs:
        return None
    rows = [[name, d["frames"], d["frames_measured"], d["fraction_measured"], d["noise_estimate"]["y_m"] * 1e6,
             d["noise_estimate"]["theta"], ", ".join(f"{k} {v}" for k, v in d.get("not_measured", {}).items()) or None]
            for name, d in runs]
    if block is not None:
        frac, ny, nt = block.get("fraction_measured"), block.get("noise_y_m"), block.get("noise_theta")
    else:
        k = np.array([d["frames_measured"] for _, d in runs], float)
        frac = float(k.sum() / sum(d["frames"] for _, d in runs))
        ny = float(np.sqrt(np.sum(k * np.array([d["noise_estimate"]["y_m"] for _, d in runs]) ** 2) / k.sum()))
        nt = float(np.sqrt(np.sum(k * np.array([d["noise_estimate"]["theta"] for _, d in runs]) ** 2) / k.sum()))
    figures = []
    shown = next(((name, d) for name, d in runs if "example_frame" in d
                  and (data_dir / d["example_frame"].get("file", "")).is_file()), None)
    if shown is not None:
        name, d = shown
        path = annotated_frame_figure(data_dir / d["example_frame"]["file"], {**d, "source_name": name},
                                      Path(figs_dir) / "tracking_frame.png")
        figures.append(Figure(path, f"{name}, frame {d['example_frame']['index']}: the fitted faces of both cubes (the "
                                    "faces meeting at the hinge drawn thick), the centre of mass that gives y, and the "
                                    "opening angles alpha above and beta below the hinge that give theta."))
    pct = "an unknown fraction" if frac is None else f"{100 * frac:.2f} %"
    noise = ("" if ny is None or nt is None else
             f" The tracking's own noise estimates (the image noise propagated through the centre of mass and the face "
             f"fits, frame by frame) are {ny * 1e6:.3g} um in y and {nt:.3g} in theta; the fit's oracle uses them as "
             f"the tracking noise.")
    skipped = (block or {}).get("skipped") or []
    reading = (f"The runs were tracked from high-speed video: y from the silhouette's centre of mass, theta from "
               f"sub-pixel fits of the cubes' faces. {pct} of the frames were measured; the others (out of view, a "
               f"third particle, occlusion, lost or corrupt frames, motion blur) are left empty and filled by the "
               f"loader where short." + noise
               + (f" {len(skipped)} recording(s) could not be tracked: "
                  + "; ".join(f"{s['file']}: {s['reason']}" for s in skipped) + "." if skipped else ""))
    tables = [Table("Tracked runs", ["file", "frames", "measured", "fraction measured", "noise y [um]", "noise theta",
                                     "not measured (reason count)"], rows)] if rows else []
    moving = _origins_not_at_rest(runs, block)
    if moving:
        reading += (f" {len(moving)} of {len(runs) or len((block or {}).get('runs') or [])} recordings did not start "
                    f"at rest ({', '.join(moving)}): their y = 0 is the centre of the late oscillation, not the "
                    "levitation height, so their y carries an offset of its own (the trap's asymmetry shifts an "
                    "oscillation's centre with its amplitude), while the diagnosis calibrates one origin for all runs; "
                    "such an offset shows as a gap in the vertical equation and can bias the damping. Record the "
                    "first frames at rest, or give tracking --origin-row.")
    return Section("tracking", "Tracking: from video to (t, y, theta)", reading, figures, tables,
                   {"fraction_measured": frac, "noise_y_m": ny, "noise_theta": nt, "runs": len(runs),
                    "skipped_recordings": len(skipped), "origin_not_at_rest": moving})


def _origins_not_at_rest(runs: list[tuple[str, dict]], block: dict | None) -> list[str]:
    """The runs whose y origin is the late oscillation's centre because the recording did not start at rest: from
    each run's RUN.json (``y_origin.at_rest``), else from meta.json's tracking block (``runs[i].origin_at_rest``);
    a run whose origin was given (option or file) is never listed."""
    if runs:
        return [name for name, d in runs if (d.get("y_origin") or {}).get("at_rest") is False]
    return [r.get("file", "?") for r in (block or {}).get("runs") or [] if r.get("origin_at_rest") is False]


def section(context: ReportContext) -> Section | None:
    """:func:`tracking_section` of the report's data set (None: not tracked from video)."""
    return tracking_section(context.data_dir, context.figs_dir, context.meta)
