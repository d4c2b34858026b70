"""A tracking checked by eye: the recording with the fitted squares drawn on it, and a per-frame quality plot.

* :func:`write_overlay` writes ``RUN.overlay.mp4``: every frame, enlarged twice (nearest pixel), the two fitted
  squares drawn in green where the frame was measured and in orange where it was fitted but left out by a check
  (``poor_fit``, ``touching``, ``motion_blur``), the centre of mass as a cross, and a bar along the top whose colour
  is the frame's status: green measured, red not measured, blue the field off (a field drop's fall, RUN.json
  ``phases``), grey the rest before it.  Played at :data:`PLAYBACK_FPS` frames per second (H.264, 8-bit).
* :func:`write_quality_plot` writes ``RUN.quality.png``: the edge residual of every measured frame against time, the
  frames not measured marked by reason, the phases of a drop shaded.

trackpy's ``annotate`` is the convention this follows: the raw frame, what was found on it, nothing else.
"""
from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from cubedimer.atomic import atomic_save

from .measure import COLUMNS, STATUS

__all__ = ["write_overlay", "write_quality_plot", "overlay_frames", "PLAYBACK_FPS"]

#: Playback rate of the overlay video [frames per second]: a high-speed recording slowed down to be watched.
PLAYBACK_FPS = 25.0
_C = {name: i for i, name in enumerate(COLUMNS)}
_GREEN, _ORANGE, _RED, _BLUE, _GREY = (40, 200, 40), (255, 150, 0), (220, 30, 30), (40, 90, 230), (150, 150, 150)
_FITTED_NOT_KEPT = (STATUS["poor_fit"], STATUS["touching"], STATUS["motion_blur"])
_SCALE = 2


def _grey8(frames: NDArray) -> NDArray[np.uint8]:
    """Frames as 8-bit grey, scaled over the recording's 0.1-99.9 % grey levels."""
    f = np.asarray(frames, np.float32)
    lo, hi = np.percentile(f[:: max(1, len(f) // 50)], [0.1, 99.9])
    return np.clip((f - lo) / max(float(hi - lo), 1e-6) * 255.0, 0, 255).astype(np.uint8)


def _square_points(u: float, v: float, gamma: float, half: float) -> tuple[NDArray, NDArray]:
    """Points along the outline of a square [px]: centre (u, v), faces along ``gamma`` (counter-clockwise from
    +column with up = -row), half side ``half``."""
    e1 = np.array([math.cos(gamma), -math.sin(gamma)])
    e2 = np.array([-math.sin(gamma), -math.cos(gamma)])
    corners = [np.array([u, v]) + half * (a * e1 + b * e2) for a, b in ((1, 1), (-1, 1), (-1, -1), (1, -1), (1, 1))]
    s = np.linspace(0.0, 1.0, max(8, int(8 * half)))[:, None]
    pts = np.concatenate([c0 + s * (c1 - c0) for c0, c1 in zip(corners[:-1], corners[1:])])
    return pts[:, 0], pts[:, 1]


def _phase_of_frames(info: dict, n: int) -> NDArray[np.int8]:
    """0 field on (or no drop), 1 at rest before a drop, 2 the field off."""
    out = np.zeros(n, np.int8)
    ph = info.get("phases")
    if ph:
        out[ph["rest_frames"][0]:ph["rest_frames"][1]] = 1
        out[ph["field_off_frames"][0]:ph["field_off_frames"][1]] = 2
    return out


def overlay_frames(frames: NDArray, rows: NDArray, status: NDArray, info: dict) -> NDArray[np.uint8]:
    """The overlay's RGB frames (module docstring), ``(n, 2 h, 2 w, 3)`` uint8."""
    grey = _grey8(frames)
    n, h, w = grey.shape
    out = np.repeat(np.repeat(grey, _SCALE, axis=1), _SCALE, axis=2)[..., None].repeat(3, axis=3)
    phase = _phase_of_frames(info, n)
    for i in range(n):
        r = rows[i]
        code = int(status[i])
        bar = _GREEN if code == 0 else _RED
        bar = _BLUE if phase[i] == 2 else (_GREY if phase[i] == 1 and code == 0 else bar)
        out[i, :3 * _SCALE, :] = bar
        if code != 0 and code not in _FITTED_NOT_KEPT:
            continue
        colour = _GREEN if code == 0 else _ORANGE
        for cube in ("a", "b"):
            u, v, g = r[_C[f"u_{cube}"]], r[_C[f"v_{cube}"]], r[_C[f"gamma_{cube}"]]
            if not np.isfinite([u, v, g, r[_C["half_side"]]]).all():
                continue
            pu, pv = _square_points(u, v, g, r[_C["half_side"]])
            ui = np.rint((pu + 0.5) * _SCALE - 0.5).astype(int)
            vi = np.rint((pv + 0.5) * _SCALE - 0.5).astype(int)
            keep = (ui >= 0) & (ui < w * _SCALE) & (vi >= 3 * _SCALE) & (vi < h * _SCALE)
            out[i, vi[keep], ui[keep]] = colour
        uc, vc = r[_C["u_com"]], r[_C["v_com"]]
        if np.isfinite(uc) and np.isfinite(vc):
            ui, vi = int(round((uc + 0.5) * _SCALE - 0.5)), int(round((vc + 0.5) * _SCALE - 0.5))
            for d in range(-3, 4):
                if 0 <= vi < h * _SCALE and 0 <= ui + d < w * _SCALE:
                    out[i, vi, ui + d] = colour
                if 0 <= vi + d < h * _SCALE and 0 <= ui < w * _SCALE:
                    out[i, vi + d, ui] = colour
    return out


def write_overlay(path: str | os.PathLike, frames: NDArray, rows: NDArray, status: NDArray, info: dict) -> Path:
    """Write the overlay video (module docstring) at ``path`` (an mp4), atomically; returns the path."""
    import imageio_ffmpeg

    rgb = overlay_frames(frames, rows, status, info)
    n, h, w, _ = rgb.shape

    def _write(tmp) -> None:
        writer = imageio_ffmpeg.write_frames(str(tmp), (w, h), pix_fmt_in="rgb24", pix_fmt_out="yuv420p",
                                             fps=PLAYBACK_FPS, codec="libx264", quality=None, macro_block_size=1,
                                             output_params=["-crf", "18", "-preset", "ultrafast", "-f", "mp4"])
        writer.send(None)
        for f in rgb:
            writer.send(np.ascontiguousarray(f))
        writer.close()

    atomic_save(path, _write)
    return Path(path)


def write_quality_plot(path: str | os.PathLike, status: NDArray, info: dict) -> Path:
    """Write the per-frame quality plot (module docstring) at ``path`` (PNG), atomically; returns the path."""
    import matplotlib.figure

    from .measure import STATUS_NAMES

    n = len(status)
    fps = float(info["frame_rate_hz"])
    t = np.arange(n) / fps
    rms = np.array([np.nan if v is None else v for v in info["quality"]["edge_rms_px"]], float)
    fig = matplotlib.figure.Figure(figsize=(8.0, 4.2))
    ax, bx = fig.subplots(2, 1, sharex=True, gridspec_kw={"height_ratios": [3, 1]})
    ax.plot(t, rms, ".", ms=1.5, color="tab:green", label="measured")
    ax.set_ylabel("edge residual [px]")
    ax.set_title(f"{Path(info['source']).name}: {info['frames_measured']} of {n} frames measured", fontsize=9)
    codes = sorted({int(c) for c in status if c != 0})
    for k, c in enumerate(codes):
        sel = status == c
        bx.plot(t[sel], np.full(sel.sum(), k), "|", ms=8, label=STATUS_NAMES[c])
    bx.set_yticks(range(len(codes)), [STATUS_NAMES[c] for c in codes] if codes else [])
    if not codes:
        bx.text(0.5, 0.5, "every frame measured", transform=bx.transAxes, ha="center", va="center", fontsize=8)
    bx.set_xlabel("t [s] from the first frame")
    ph = info.get("phases")
    if ph:
        for a in (ax, bx):
            a.axvspan(0, ph["drop_time_s"], color="0.85", lw=0, label="at rest" if a is ax else None)
            a.axvspan(ph["drop_time_s"], ph["field_on_time_s"], color="tab:blue", alpha=0.25, lw=0,
                      label="field off" if a is ax else None)
    ax.legend(fontsize=7, loc="upper right")
    fig.tight_layout()
    atomic_save(path, lambda tmp: fig.savefig(tmp, format="png", dpi=110))
    return Path(path)
