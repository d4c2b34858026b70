"""``python -m tracking VIDEO --fps F --pixel-size P --out RUN.csv``: camera frames to a run (docs/formats.md, docs/tracking.md).

VIDEO is a video file, a multi-page TIFF, a Phantom ``.cine`` or a folder of images (one recording); with
``--out RUN.csv`` it gives ``RUN.csv`` (``t, y, theta``, empty where the dimer could not be measured),
``RUN.json`` (pixel size, frame rate, y origin, counts of frames measured and not, per-frame quality,
noise estimates) and ``RUN.frame.png`` (the example frame).  A folder of recordings (video files, ``.cine``
files, multi-page TIFFs, sub-folders of images) with ``--out DIR`` gives a data set: those files per
recording plus ``meta.json``; the recordings are tracked through :func:`cubedimer.executor.map_ordered`
(``--workers``, ``--scheduler``).  See ``docs/tracking.md``.

Bad input (not a recording, frames of different sizes, no dimer in any frame, an unknown frame rate or
pixel size) gets a one-line error, exit status 2 and no output.
"""
from __future__ import annotations

import argparse
import logging
import sys
from pathlib import Path

from cubedimer.cli import (OneLineParser, UserInputError, add_executor_arguments, executor_config, positive_float,
                           positive_int, prepare_output_dir, prepare_output_file, run_cli)

__all__ = ["main", "build_parser", "run"]

logger = logging.getLogger("tracking")


def build_parser() -> argparse.ArgumentParser:
    from .track import POLARITIES, UP

    p = OneLineParser(
        prog="python -m tracking",
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
    p.add_argument("--polarity", choices=POLARITIES, default="auto",
                   help="dark cubes on a bright background (shadowgraph), bright on dark, or detect (default)")
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
    p.add_argument("--strict", action="store_true",
                   help="a folder of recordings: refuse the set on the first bad recording instead of skipping it")
    p.add_argument("--force", action="store_true", help="replace an existing output")
    p.add_argument("--quiet", action="store_true", help="warnings and errors only")
    add_executor_arguments(p, "Each recording of a folder is one task.")
    p.set_defaults(func=run)
    return p


def _config(a: argparse.Namespace):
    from .track import TrackConfig

    return TrackConfig(fps=a.fps, pixel_size=a.pixel_size, origin_frames=a.origin_frames, origin_row=a.origin_row,
                       polarity=a.polarity, up=a.up, edge_window=a.edge_window, area_tolerance=a.area_tolerance,
                       max_motion_blur=a.max_motion_blur, max_squareness=a.max_squareness)


def _track_task(item):
    """One recording of a folder (a picklable task): the result, or the one-line reason it failed."""
    from .recording import TrackingError, read_recording
    from .track import track_recording

    path, config = item
    try:
        return track_recording(read_recording(path), config)
    except TrackingError as exc:
        return str(exc)


def run(a: argparse.Namespace) -> int:
    """Entry point of ``python -m tracking``; returns the exit code."""
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
        result = track_recording(read_recording(src), config)
        write_run(out, result)
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
    write_dataset(out, results, skipped, force=a.force)
    print(f"wrote {len(results)} runs to {out} ({len(skipped)} recordings skipped)", file=sys.stderr)
    return 0


def main(argv: list[str] | None = None) -> int:
    from .recording import TrackingError

    return run_cli(build_parser(), argv, errors=(TrackingError,))
