"""Tracking: frames per second and accuracy on frames the twin's camera renders (fresh seeds).

Speed: ``tracking`` (compiled kernel, batches of frames shared by numba's threads) against a plain per-frame
scikit-image implementation of the same measurement (threshold at half contrast, ``regionprops`` centroid,
``find_contours`` at half contrast split at the hinge column, each square's face direction from the four-fold
circular mean of its contour segments), both on the same 180 x 150 px frames in the same run.  Target: the camera
rate, 2,000 frames/s on 2 cores.

Accuracy: RMS errors of y and theta against the truth that drew the frames, over pixel size, point-spread width
and image noise (three fresh seeds per case: mean and spread).  ``python -m benchmarks.bench_tracking --figure
docs/figures/tracking_accuracy.png`` also draws the figure of docs/tracking.md.
"""
from __future__ import annotations

import argparse
import math
import os
import time

import numpy as np

from cubedimer.meta import META_DEFAULTS

SIDE = META_DEFAULTS["side_length_m"]
FPS = 2000.0


def _motion(n: int, seed: int):
    rng = np.random.default_rng(seed)
    t = np.arange(n) / FPS
    y = rng.uniform(60e-6, 120e-6) * np.cos(2 * np.pi * rng.uniform(18, 24) * t + rng.uniform(0, 2 * np.pi))
    theta = rng.uniform(-0.2, 0.2) + rng.uniform(0.4, 0.7) * np.sin(2 * np.pi * rng.uniform(1, 5) * t + rng.uniform(0, 6.3))
    return t, y, theta


def _camera(pixel_size=10e-6, psf=1.0, noise=0.02):
    from acousim.twin.video import VideoCamera

    scale = 10e-6 / pixel_size  # the same 1.8 x 1.5 mm field of view
    return VideoCamera(pixel_size=pixel_size, width=int(round(180 * scale)), height=int(round(150 * scale)),
                       psf_sigma=psf, noise=noise)


def _track(frames, cam):
    from tracking.recording import Recording
    from tracking.track import TrackConfig, track_recording

    return track_recording(Recording("bench", "memory", "tiff", frames, FPS, cam.pixel_size, cam.origin[1]), TrackConfig())


def skimage_per_frame(frame: np.ndarray, background: float, contrast: float, polarity: float = -1.0):
    """The plain per-frame scikit-image measurement: (centroid row [px], theta) or (nan, nan)."""
    from skimage import measure

    c = polarity * (frame.astype(np.float32) - background) / contrast
    lab = measure.label(c > 0.5, connectivity=2)
    props = sorted(measure.regionprops(lab), key=lambda p: -p.area)
    if not props:
        return math.nan, math.nan
    big = [p for p in props if p.area > 0.3 * props[0].area][:2]
    rows = np.concatenate([p.coords[:, 0] for p in big])
    cols = np.concatenate([p.coords[:, 1] for p in big])
    v_com = float(rows.mean())
    u_split = 0.5 * (cols.min() + cols.max())
    contours = measure.find_contours(c, 0.5)
    if not contours:
        return v_com, math.nan
    outline = max(contours, key=len)  # the dimer's outline (one, or the largest of two touching at the hinge)
    pts = np.concatenate([cn for cn in contours if len(cn) > 0.3 * len(outline)])
    gam = []
    for left in (True, False):
        # segments of the outline on this cube's side, away from the hinge column
        d = np.diff(outline, axis=0) if len(pts) == len(outline) else np.concatenate(
            [np.diff(cn, axis=0) for cn in contours if len(cn) > 0.3 * len(outline)])
        mids = (outline[:-1] + outline[1:]) / 2 if len(pts) == len(outline) else np.concatenate(
            [(cn[:-1] + cn[1:]) / 2 for cn in contours if len(cn) > 0.3 * len(outline)])
        side = (mids[:, 1] < u_split - 3) if left else (mids[:, 1] > u_split + 3)
        if not side.any():
            return v_com, math.nan
        ang = np.arctan2(-d[side, 0], d[side, 1])  # direction with up = -row
        w = np.hypot(d[side, 0], d[side, 1])
        gam.append(np.angle(np.sum(w * np.exp(4j * ang))) / 4.0 + math.pi / 2)
    wrap = lambda x: (x + math.pi / 4) % (math.pi / 2) - math.pi / 4  # noqa: E731
    phi_a = wrap(gam[0] - 0.75 * math.pi)
    phi_b = wrap(0.25 * math.pi - gam[1])
    return v_com, 2.0 * (phi_a + phi_b) / math.pi


def speed(n: int = 4000, seed: int = 9001) -> dict:
    """Frames per second of the tracking (all of numba's threads and one) and of the scikit-image baseline, and
    the accuracy of each on the same fresh frames."""
    import numba

    from acousim.twin.video import record_video
    from tracking.measure import measure_frames

    cam = _camera()
    t, y, theta = _motion(n, seed)
    frames, _ = record_video(t, y, theta, SIDE, cam, seed)
    res = _track(frames[:200], cam)  # compile / load the kernel, calibrate
    from tracking.track import calibrate, TrackConfig

    settings = calibrate(frames, TrackConfig()).settings(TrackConfig())
    out = {}
    for threads in sorted({1, numba.get_num_threads()}):
        best = math.inf
        for _ in range(3):
            t0 = time.perf_counter()
            rows = measure_frames(frames, settings, threads=threads)
            best = min(best, time.perf_counter() - t0)
        out[f"tracking, {threads} thread(s)"] = n / best
    t0 = time.perf_counter()
    res = _track(frames, cam)
    out["tracking, whole command path (calibration + flags), all threads"] = n / (time.perf_counter() - t0)
    ok = res.status == 0
    acc = {"tracking": (np.sqrt(np.mean((res.y[ok] - y[ok]) ** 2)), np.sqrt(np.mean((res.theta[ok] - theta[ok]) ** 2)),
                        ok.mean())}
    m = min(n, 600)
    bg, fg = cam.levels
    full = 255.0
    t0 = time.perf_counter()
    sk = np.array([skimage_per_frame(f, bg * full, abs(fg - bg) * full) for f in frames[:m]])
    out["scikit-image per frame (1 thread)"] = m / (time.perf_counter() - t0)
    good = np.isfinite(sk).all(axis=1)
    ys = (cam.origin[1] - sk[:, 0]) * cam.pixel_size
    acc["scikit-image per frame"] = (np.sqrt(np.mean((ys[good] - y[:m][good]) ** 2)),
                                     np.sqrt(np.mean((sk[good, 1] - theta[:m][good]) ** 2)), good.mean())
    return {"rates": out, "accuracy": acc, "threads": numba.get_num_threads(), "frames": n}


CASES = ([("pixel size", dict(pixel_size=p)) for p in (5e-6, 10e-6, 20e-6)]
         + [("blur", dict(psf=s)) for s in (0.5, 1.0, 2.0)]
         + [("noise", dict(noise=e)) for e in (0.005, 0.02, 0.05)])


def accuracy(n: int = 400, seeds=(7101, 7102, 7103)) -> list[dict]:
    """RMS errors of y [m] and theta against the truth per case (:data:`CASES`), mean and std over ``seeds``."""
    from acousim.twin.video import record_video

    rows = []
    for what, kw in CASES:
        cam = _camera(**kw)
        ey, et, fr, ny, nt = [], [], [], [], []
        for s in seeds:
            t, y, theta = _motion(n, s)
            frames, _ = record_video(t, y, theta, SIDE, cam, s)
            res = _track(frames, cam)
            ok = res.status == 0
            ey.append(np.sqrt(np.mean((res.y[ok] - y[ok]) ** 2)))
            et.append(np.sqrt(np.mean((res.theta[ok] - theta[ok]) ** 2)))
            fr.append(1.0 - ok.mean())
            ny.append(res.info["noise_estimate"]["y_m"])
            nt.append(res.info["noise_estimate"]["theta"])
        rows.append({"varied": what, "pixel_size_um": cam.pixel_size * 1e6, "psf_px": cam.psf_sigma,
                     "noise": cam.noise, "y_rms_um": (np.mean(ey) * 1e6, np.std(ey) * 1e6),
                     "theta_rms": (np.mean(et), np.std(et)), "unmeasured": float(np.mean(fr)),
                     "noise_estimate_y_um": float(np.mean(ny)) * 1e6, "noise_estimate_theta": float(np.mean(nt))})
    return rows


def accuracy_markdown(rows: list[dict]) -> list[str]:
    lines = ["| varied | pixel size [um] | PSF sigma [px] | image noise [contrast] | y RMS [um] | theta RMS | "
             "frames unmeasured | tracking's noise estimate y [um] / theta |", "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['varied']} | {r['pixel_size_um']:g} | {r['psf_px']:g} | {100 * r['noise']:g} % | "
                     f"{r['y_rms_um'][0]:.3f} +- {r['y_rms_um'][1]:.3f} | {r['theta_rms'][0]:.5f} +- {r['theta_rms'][1]:.5f} | "
                     f"{100 * r['unmeasured']:.2f} % | {r['noise_estimate_y_um']:.3f} / {r['noise_estimate_theta']:.5f} |")
    return lines


def accuracy_figure(rows: list[dict], path) -> None:
    """Three panels (pixel size, blur, noise): RMS errors of y and theta with their spread over seeds."""
    import matplotlib.pyplot as plt

    from cubedimer.atomic import save_figure

    fig, axes = plt.subplots(1, 3, figsize=(11, 3.4), constrained_layout=True)
    for ax, (what, key, label) in zip(axes, (("pixel size", "pixel_size_um", "pixel size [um]"),
                                             ("blur", "psf_px", "PSF sigma [px]"),
                                             ("noise", "noise", "image noise [fraction of contrast]"))):
        sel = [r for r in rows if r["varied"] == what]
        x = np.array([r[key] for r in sel])
        ax.errorbar(x, [r["y_rms_um"][0] for r in sel], [r["y_rms_um"][1] for r in sel], marker="o", color="tab:blue",
                    label="y RMS [um]")
        ax.set_xlabel(label)
        ax.set_ylabel("y RMS error [um]", color="tab:blue")
        ax.axhline(1.0, color="tab:blue", ls=":", lw=0.8)
        ax2 = ax.twinx()
        ax2.errorbar(x, [r["theta_rms"][0] for r in sel], [r["theta_rms"][1] for r in sel], marker="s", color="tab:red",
                     label="theta RMS")
        ax2.set_ylabel("theta RMS error", color="tab:red")
        ax2.axhline(0.005, color="tab:red", ls=":", lw=0.8)
        ax.set_ylim(0, max(1.1, 1.2 * max(r["y_rms_um"][0] for r in sel)))
        ax2.set_ylim(0, max(0.0055, 1.2 * max(r["theta_rms"][0] for r in sel)))
        ax.set_title(f"varying the {what} (others: 10 um, 1 px, 2 %)", fontsize=9)
    fig.suptitle("Tracking accuracy on rendered frames (3 fresh seeds, 400 frames each; dotted: targets)", fontsize=10)
    save_figure(fig, path)


def main() -> str:
    load = os.getloadavg()[0]
    sp = speed()
    rows = accuracy()
    lines = [f"## tracking: frames per second and accuracy on rendered 180 x 150 px frames ({os.cpu_count()} cores, "
             f"{sp['threads']} numba threads)", "",
             f"Load average {load:.1f} when the run started (other work shares the cores: a second thread only helps "
             "on idle cores).", "",
             "| implementation | frames / s |", "|---|---|"]
    for k, v in sp["rates"].items():
        lines.append(f"| {k} | {v:,.0f} |")
    lines += ["", "| same frames | y RMS [um] | theta RMS | frames measured |", "|---|---|---|---|"]
    for k, (ey, et, fr) in sp["accuracy"].items():
        lines.append(f"| {k} | {ey * 1e6:.3f} | {et:.5f} | {100 * fr:.1f} % |")
    lines += ["", "Accuracy against pixel size, blur and noise (mean +- std over 3 fresh seeds of 400 frames; the "
              "targets are 1 um and 0.005 at 10 um, 1 px, 2 %):", ""] + accuracy_markdown(rows)
    return "\n".join(lines)


if __name__ == "__main__":
    p = argparse.ArgumentParser(description=__doc__)
    p.add_argument("--figure", default=None, help="also draw the accuracy figure to this PNG")
    a = p.parse_args()
    r = accuracy()
    print("\n".join(accuracy_markdown(r)))
    if a.figure:
        accuracy_figure(r, a.figure)
