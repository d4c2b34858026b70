"""Command line of tracking: ``python -m tracking {track,inspect} ...`` (docs/formats.md, docs/tracking.md).

``python -m tracking track VIDEO --fps F --pixel-size P --out RUN.csv``: camera frames to a run.  VIDEO is a
video file, a multi-page TIFF, a Phantom ``.cine`` or a folder of images (one recording); with ``--out RUN.csv``
it gives ``RUN.csv`` (``t, y, theta``, empty where the dimer could not be measured),
``RUN.json`` (pixel size, frame rate, y origin, counts of frames measured and not, per-frame quality,
noise estimates) and ``RUN.frame.png`` (the example frame).  A folder of recordings (video files, ``.cine``
files, multi-page TIFFs, sub-folders of images) with ``--out DIR`` gives a data set: those files per
recording plus ``meta.json``; the recordings are tracked through :func:`cubedimer.executor.map_ordered`
(``--workers``, ``--scheduler``).  See ``docs/tracking.md``.

``python -m tracking inspect VIDEO``: what the file records (frames, size, grey levels, frame rate, pixel size,
levitation row) and what the calibration of ``track`` finds in it (polarity, contrast, edge blur, the silhouette's
area and the cube side it implies), without measuring every frame and without writing anything: the check to run
before tracking a new camera's files.

Bad input (not a recording, frames of different sizes, no dimer in any frame, an unknown frame rate or
pixel size) gets a one-line error, exit status 2 and no output.  Each command is an ``add_parser(subparsers)``
function, listed in :data:`COMMANDS`; the runner is :func:`cubedimer.cli.run_cli`.
"""
from __future__ import annotations

import argparse
import logging
import sys
from pathlib import Path

from cubedimer.cli import (UserInputError, add_executor_arguments, command_parser, executor_config, positive_float,
                           positive_int, prepare_output_dir, prepare_output_file, run_cli)

__all__ = ["main", "build_parser", "run", "COMMANDS", "add_track_parser", "add_inspect_parser"]

logger = logging.getLogger("tracking")


def _add_polarity_argument(p: argparse.ArgumentParser) -> None:
    """``--polarity``, the same for every command that calibrates a recording."""
    from .track import POLARITIES

    p.add_argument("--polarity", choices=POLARITIES, default="auto",
                   help="dark cubes on a bright background (shadowgraph), bright on dark, or detect (default)")


def parse_roi(text: str | None) -> tuple[int, int, int, int] | None:
    """``--roi x0:x1,y0:y1`` (columns, then rows; the ends excluded) as four whole numbers (None without it);
    a malformed, empty or inverted region raises :class:`UserInputError` (one line, exit 2)."""
    if text is None:
        return None
    try:
        cols, rows = text.split(",")
        x0, x1 = (int(v) for v in cols.split(":"))
        y0, y1 = (int(v) for v in rows.split(":"))
    except ValueError:
        raise UserInputError(f"--roi {text}: expected x0:x1,y0:y1 in pixels (columns, then rows), e.g. "
                             "0:180,20:130") from None
    if min(x0, x1, y0, y1) < 0 or x1 <= x0 or y1 <= y0:
        raise UserInputError(f"--roi {text}: the region is empty or inverted: give 0 <= x0 < x1 (columns) and "
                             "0 <= y0 < y1 (rows)")
    return x0, x1, y0, y1


def _add_roi_argument(p: argparse.ArgumentParser) -> None:
    p.add_argument("--roi", default=None, metavar="x0:x1,y0:y1",
                   help="measure only columns x0..x1-1 and rows y0..y1-1 (pixels from the top left; e.g. to leave out "
                   "a structure that is neither at the border nor moving); a dimer reaching its border is out of view")


def add_track_parser(sub) -> None:
    """``track``: see its --help."""
    from .track import UP

    p = sub.add_parser(
        "track",
        help="camera frames to runs of (t, y, theta)",
        description="Measure the dimer's centre-of-mass height y and bending angle theta = (alpha - beta) / pi in every "
        "frame of a high-speed recording (camera looking along the hinge line; docs/tracking.md) and write a "
        "docs/formats.md run (CSV + RUN.json), or a data set from a folder of recordings.",
    )
    p.add_argument("video", metavar="VIDEO", help="video file (mp4, avi, mov, mkv, ...), multi-page TIFF, Phantom "
                   ".cine, a folder of images (one recording), or a folder of recordings (with --out DIR)")
    p.add_argument("--out", required=True, metavar="RUN.csv|DIR",
                   help="the run's CSV (RUN.json and RUN.frame.png are written beside it), or a data-set folder")
    p.add_argument("--fps", type=positive_float, default=None,
                   help="camera frame rate [frames per second]; required unless the file records it (TIFF "
                   "descriptions, .cine headers; a video container's playback rate is not used)")
    p.add_argument("--pixel-size", type=positive_float, default=None, metavar="M",
                   help="pixel size in the object plane [metres per pixel], e.g. 1e-5; required unless the file "
                   "records it")
    p.add_argument("--origin-frames", type=positive_int, default=50, metavar="N",
                   help="y = 0 at the median centre-of-mass height of the measured frames among the first N "
                   "(the levitation before a field drop; default 50)")
    p.add_argument("--origin-row", type=float, default=None, metavar="R",
                   help="the levitation height as an image row [px, rows counted from 0 at the top, pixel centres "
                   "at whole numbers]; overrides --origin-frames and a row the file records")
    _add_polarity_argument(p)
    p.add_argument("--up", choices=UP, default="top",
                   help="the image edge that is up in the lab (default top: rows count down, as cameras store "
                   "them); bottom for an image stored upside down, which flips y and theta")
    p.add_argument("--edge-window", type=positive_int, default=None, metavar="PX",
                   help="half-length of the window across an edge [px] (default from the measured blur)")
    p.add_argument("--max-motion-blur", type=positive_float, default=3.0, metavar="PX",
                   help="frames whose edges show a motion blur longer than this beyond the recording's typical "
                   "blur are left empty (default 3 px)")
    p.add_argument("--max-squareness", type=positive_float, default=0.05, metavar="RAD",
                   help="largest |alpha + beta - pi| of the faces fitted at the hinge (default 0.05 rad)")
    p.add_argument("--area-tolerance", type=positive_float, default=0.06, metavar="FRACTION",
                   help="largest relative deviation of a frame's silhouette area from the recording's (default 0.06)")
    p.add_argument("--max-hinge-gap", type=positive_float, default=0.1, metavar="FRACTION",
                   help="largest distance between the two cubes' fitted hinge corners, as a fraction of the side "
                   "(default 0.1); a hinge line tilted out of the camera axis separates them")
    _add_roi_argument(p)
    p.add_argument("--keep-drop", action="store_true",
                   help="a recording of a field drop (at rest, the free fall with the field off, the field back on) "
                   "is written whole, t from its first frame; by default the run is the field-on motion, t = 0 at the "
                   "field's return (the phases are in RUN.json either way)")
    p.add_argument("--max-gap", type=positive_int, default=None, metavar="FRAMES",
                   help="a folder of recordings: the longest run of unmeasured frames the data set's loader fills "
                   "(meta.json tracking.max_gap_frames; default the loader's 10); a run is split at longer gaps")
    p.add_argument("--overlay", action="store_true",
                   help="also write RUN.overlay.mp4 (the frames with the fitted squares and each frame's status, "
                   "played at 25 frames/s) and RUN.quality.png (each frame's edge residual and why frames were not "
                   "measured): the tracking checked by eye")
    p.add_argument("--strict", action="store_true",
                   help="a folder of recordings: refuse the set on the first bad recording instead of skipping it")
    p.add_argument("--force", action="store_true", help="replace an existing output")
    p.add_argument("--quiet", action="store_true", help="warnings and errors only")
    add_executor_arguments(p, "Each recording of a folder is one task.")
    p.set_defaults(func=run)


def add_inspect_parser(sub) -> None:
    """``inspect``: see its --help."""
    p = sub.add_parser(
        "inspect",
        help="what a recording holds and what the tracking's calibration finds in it (writes nothing)",
        description="Read one recording and report what the file records (frames, frame size, grey levels, frame rate, "
        "pixel size, levitation row) and what the calibration of `track` finds in frames sampled over it: the "
        "polarity, the contrast against the background noise, the edge blur, the silhouette's area and the cube "
        "side it implies. Nothing is measured frame by frame and nothing is written: run it on a new camera's "
        "files before `track`, to see which of --fps and --pixel-size `track` will need.",
    )
    p.add_argument("video", metavar="VIDEO", help="one recording: video file, multi-page TIFF, Phantom .cine or a "
                   "folder of images")
    _add_polarity_argument(p)
    _add_roi_argument(p)
    p.add_argument("--quiet", action="store_true", help="warnings and errors only")
    p.set_defaults(func=inspect)


#: The commands of ``python -m tracking``, in the order of the help.
COMMANDS = (add_track_parser, add_inspect_parser)


def build_parser() -> argparse.ArgumentParser:
    """The parser of ``python -m tracking`` (one ``add_parser`` function per command)."""
    return command_parser("python -m tracking",
                          "Camera frames of a levitated cube dimer to runs of (t, y, theta): `track` measures, "
                          "`inspect` shows what a recording holds. Conventions: docs/conventions.md; files: "
                          "docs/formats.md; method and accuracy: docs/tracking.md.", COMMANDS)


def _config(a: argparse.Namespace):
    from .track import TrackConfig

    return TrackConfig(fps=a.fps, pixel_size=a.pixel_size, origin_frames=a.origin_frames, origin_row=a.origin_row,
                       polarity=a.polarity, up=a.up, edge_window=a.edge_window, area_tolerance=a.area_tolerance,
                       max_motion_blur=a.max_motion_blur, max_squareness=a.max_squareness,
                       max_hinge_gap=a.max_hinge_gap, roi=parse_roi(a.roi), keep_drop=a.keep_drop)


def _track_task(item):
    """One recording of a folder (a picklable task): the result, or the one-line reason it failed."""
    from .recording import TrackingError, read_recording
    from .track import track_recording

    path, config = item
    try:
        return track_recording(read_recording(path), config)
    except TrackingError as exc:
        return str(exc)


def inspect(a: argparse.Namespace) -> int:
    """``python -m tracking inspect``: prints the recording's summary to standard output; returns the exit code."""
    import numpy as np

    from .recording import TrackingError, read_recording
    from .track import TrackConfig, calibrate

    src = Path(a.video)
    rec = read_recording(src)  # names a missing or unreadable file
    n, h, w = rec.frames.shape
    frames = rec.frames
    lines = [f"{src}: {rec.format}, {n} frames of {w} x {h} px, {frames.dtype} grey levels "
             f"{float(np.min(frames[0])):g}-{float(np.max(frames[0])):g} in the first frame"]
    lines.append("frame rate: " + (f"{rec.fps:g} frames/s (recorded in the file)" if rec.fps else
                                   "not recorded: give track --fps"))
    lines.append("pixel size: " + (f"{rec.pixel_size:g} m/px (recorded in the file)" if rec.pixel_size else
                                   "not recorded: give track --pixel-size"))
    if rec.levitation_row is not None:
        lines.append(f"levitation row: {rec.levitation_row:g} px (recorded in the file)")
    roi = parse_roi(a.roi)
    if roi is not None:
        x0, x1, y0, y1 = roi
        if x1 > w or y1 > h:
            print("\n".join(lines))
            raise TrackingError(f"{src}: --roi {x0}:{x1},{y0}:{y1} reaches outside the frames of {w} x {h} px")
        frames = frames[:, y0:y1, x0:x1]
        lines.append(f"region of interest: columns {x0}-{x1 - 1}, rows {y0}-{y1 - 1} ({x1 - x0} x {y1 - y0} px)")
    try:
        cal = calibrate(frames, TrackConfig(polarity=a.polarity))
    except TrackingError as exc:
        print("\n".join(lines))  # the file's facts, then the refusal
        raise TrackingError(f"{src}: {exc}") from None
    side_px = float(np.sqrt(cal.area_px2 / 2.0))  # two cubes of side s seen along the hinge: area 2 s^2
    lines.append(f"polarity: {cal.polarity} cubes ({cal.polarity_from}); contrast {cal.contrast:.4g} grey levels "
                 f"over a background of {cal.background:.4g}")
    scene = cal.scene
    rows = scene.static_rows
    lines.append(f"background: illumination changing by {100 * scene.gradient:.0f} % across the frame, light level "
                 f"{scene.levels.min():.3f}-{scene.levels.max():.3f} of its median over the sampled frames; "
                 + (f"static structures on {int(scene.static.sum())} px left out"
                    + (f" (rows {rows[0]}-{rows[-1]} and others)" if rows else "") if scene.static.any()
                    else "no static structure"))
    if cal.fill_holes:
        lines.append("silhouettes with holes (transparent crystals): filled")
    lines.append(f"silhouette: {cal.area_px2:.0f} px^2 in {cal.frames_used} sampled frames, a cube side of "
                 f"{side_px:.1f} px" + (f" = {side_px * rec.pixel_size * 1e6:.0f} um" if rec.pixel_size else ""))
    lines.append(f"edge blur: {cal.edge_blur_px:.2f} px (track's edge window: {cal.edge_window_px} px)")
    if cal.hinge_tilt_deg is not None and cal.hinge_tilt_deg > 3.0:
        from .tilt import area_factor

        tilt = cal.tilt["tilt_deg"] if cal.tilt else cal.hinge_tilt_deg
        how = (f"from the cubes' centres and the area, +- {cal.tilt['error_deg']:.1f}" if cal.tilt else
               "from the squares' hinge corners, which lie apart")
        true_side = side_px / np.sqrt(area_factor(np.radians(tilt)))
        lines.append(f"hinge line: tilted about {tilt:.1f} degrees out of the camera axis ({how}); the side corrected "
                     f"for it is {true_side:.1f} px" + (f" = {true_side * rec.pixel_size * 1e6:.0f} um" if rec.pixel_size
                                                         else "")
                     + ("; track undoes the tilt and judges the hinge corners where the tilt puts them" if cal.tilt
                        else "; track leaves it as it is (the hinge gap over the squares' sides from their faces reads "
                        "3 degrees or less)"))
    print("\n".join(lines))
    return 0


def run(a: argparse.Namespace) -> int:
    """``python -m tracking track``; returns the exit code."""
    from .output import write_dataset, write_run
    from .recording import TrackingError, find_recordings, read_recording
    from .track import track_recording

    config = _config(a)
    src = Path(a.video)
    if not src.exists():
        raise TrackingError(f"{src}: does not exist")
    single_file = str(a.out).lower().endswith(".csv")
    recordings = find_recordings(src) if src.is_dir() else None
    if single_file:
        if recordings is not None:
            raise UserInputError(f"{src}: a folder of {len(recordings)} recordings gives a data set: give --out DIR")
        out = prepare_output_file(a.out)
        existing = [p for p in (out, out.with_suffix(".json")) if p.exists()]
        if existing and not a.force:
            raise UserInputError(f"--out {out}: {existing[0]} exists (use --force to replace it)")
        rec = read_recording(src)
        result = track_recording(rec, config)
        write_run(out, result)
        if a.overlay:
            _write_overlay(out.parent, out.stem, rec.frames, result)
        print(f"wrote {out} ({result.n_measured} of {result.info['frames']} frames measured) and "
              f"{out.with_suffix('.json').name}", file=sys.stderr)
        return 0
    out = prepare_output_dir(a.out, moved_into_place=True)
    if out.exists() and any(out.iterdir()) and not a.force:
        raise UserInputError(f"--out {out}: not empty (use --force to replace it)")
    items = [(p, config) for p in (recordings or [src])]
    names = [Path(p).stem if Path(p).is_file() else Path(p).name for p, _ in items]
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise UserInputError(f"{src}: two recordings would both be written as {dup[0]}.csv; rename one")
    from cubedimer.executor import map_ordered

    outcomes = map_ordered(_track_task, items, executor_config(a), desc="tracking")
    results, skipped = [], []
    for (path, _), res in zip(items, outcomes):
        if isinstance(res, str):
            if a.strict:
                raise TrackingError(res)
            logger.warning("skipping %s", res)
            skipped.append({"file": Path(path).name, "reason": res})
        else:
            results.append(res)
    if not results:
        reasons = {s["reason"].split(": ", 1)[-1] for s in skipped}
        raise TrackingError(f"{src}: no recording could be tracked" + (f" ({reasons.pop()})" if len(reasons) == 1 else
                                                                       f" ({len(skipped)} failed; first: {skipped[0]['reason']})"))
    write_dataset(out, results, skipped, force=a.force, max_gap=a.max_gap)
    if a.overlay:
        for r in results:
            _write_overlay(out, r.name, read_recording(r.info["source"]).frames, r)
    print(f"wrote {len(results)} runs to {out} ({len(skipped)} recordings skipped)", file=sys.stderr)
    return 0


def _write_overlay(directory: Path, stem: str, frames, result) -> None:
    """``STEM.overlay.mp4`` and ``STEM.quality.png`` of one tracked recording (:mod:`tracking.overlay`), the frames
    cut to the region of interest the measurement used."""
    from .overlay import write_overlay, write_quality_plot

    roi = result.info.get("roi_px")
    if roi:
        frames = frames[:, roi[2]:roi[3], roi[0]:roi[1]]
    write_overlay(directory / f"{stem}.overlay.mp4", frames, result.rows, result.status, result.info)
    write_quality_plot(directory / f"{stem}.quality.png", result.status, result.info)


def main(argv: list[str] | None = None) -> int:
    from .recording import TrackingError

    parser = build_parser()
    commands = next(a.choices for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    args = list(sys.argv[1:] if argv is None else argv)
    if args and not args[0].startswith("-") and args[0] not in commands and Path(args[0]).exists():
        # a recording where the command belongs: say which command measures it
        print(f"error: {args[0]} is a recording, not a command: measure it with python -m tracking track "
              f"{args[0]} --out ... (or look at it first with python -m tracking inspect {args[0]})", file=sys.stderr)
        return 2
    return run_cli(parser, args, errors=(TrackingError,))
