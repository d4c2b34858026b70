"""The real-recording table of docs/tracking.md: each imperfection of the twin's camera alone, tracked on fresh
seeds; ``python docs/scripts/tracking_real_recordings.py [--figure docs/figures/tracking_real_frames.png]``
(about 10 minutes on one core).

Each recording: 2,000 frames at 2,000 frames/s, 200 rest frames then a decaying oscillation, no levitation row in
the file (the origin from the frames).  Printed per case: mean +- spread over the seeds of the y RMS error about
its mean [um], the origin error (the mean y error) [um], the theta RMS error, the frames unmeasured [%], and the
noise estimates over the RMS errors (y / theta).
"""
from __future__ import annotations

import argparse

import numpy as np

SIDE = 500e-6
FPS = 2000.0
SEEDS = (4401, 4402, 4403)
#: case -> (Imperfections keywords, polarity, TrackConfig keywords, starts mid-oscillation)
CASES = {
    "clean": ({}, "dark", {}, False),
    "light: 30 % gradient, 5 % flicker at 100 Hz": (dict(gradient=0.3, flicker=0.05), "dark", {}, False),
    "static bands of 12 px at top and bottom": (dict(bands_px=12), "dark", {}, False),
    "a dust speck crossing (200 frames; masked near the dimer)": (dict(dust=1), "dark", {}, False),
    "transparent crystals, dark outline": (dict(transparent=True), "dark", {}, False),
    "transparent crystals, bright outline": (dict(transparent=True), "bright", {}, False),
    "hinge line tilted 10 degrees (no option)": (dict(tilt_deg=10.0), "dark", {}, False),
    "H.264 mp4 (crf 23)": (dict(codec="h264"), "dark", {}, False),
    "starts mid-oscillation (no rest frame)": ({}, "dark", {}, True),
    "hinge line tilted 6 degrees (no option)": (dict(tilt_deg=6.0), "dark", {}, False),
    "hinge line tilted 14 degrees (no option)": (dict(tilt_deg=14.0), "dark", {}, False),
}


def motion(n: int, seed: int, rest: int = 200, mid: bool = False):
    rng = np.random.default_rng(seed)
    t = np.arange(n) / FPS
    ts = t + 0.05 if mid else np.clip(t - rest / FPS, 0, None)
    a, f, tau = rng.uniform(100e-6, 150e-6), rng.uniform(18, 24), rng.uniform(0.3, 0.6)
    th0, b, f2, ph = rng.uniform(-0.2, 0.2), rng.uniform(0.15, 0.3), rng.uniform(2, 5), rng.uniform(0, 6.3)
    y = -a * np.exp(-ts / tau) * np.sin(2 * np.pi * f * ts)
    theta = th0 + b * np.exp(-ts) * (np.sin(2 * np.pi * f2 * ts + ph) - np.sin(ph))
    if not mid:
        y[t < rest / FPS] = 0.0
    return t, y, theta


def run(case: str, seed: int, n: int = 2000):
    """(TrackResult or refusal text, true y, true theta, frames)."""
    from acousim.twin.imperfections import Imperfections, h264_roundtrip
    from acousim.twin.video import VideoCamera, record_video
    from tracking.recording import Recording, TrackingError
    from tracking.track import TrackConfig, track_recording

    kw, polarity, cfg, mid = CASES[case]
    imp = Imperfections(**kw)
    cam = VideoCamera(polarity=polarity, imperfections=Imperfections(**{k: v for k, v in kw.items() if k != "codec"}))
    t, y, theta = motion(n, seed, mid=mid)
    frames = record_video(t, y, theta, SIDE, cam, seed)[0]
    if imp.codec == "h264":
        frames = h264_roundtrip(frames, FPS, imp.crf)
    try:
        res = track_recording(Recording(case, "memory", "tiff", frames, FPS, cam.pixel_size, None), TrackConfig(**cfg))
    except TrackingError as exc:
        return str(exc), y, theta, frames
    return res, y, theta, frames


def numbers(res, y, theta) -> tuple:
    ok = res.status == 0
    ey = res.y[ok] - y[ok]
    et = res.theta[ok] - theta[ok]
    y_rms, t_rms = float(np.std(ey)), float(np.sqrt(np.mean(et ** 2)))
    ne = res.info["noise_estimate"]
    return (y_rms * 1e6, abs(float(np.mean(ey))) * 1e6, t_rms, 100 * (1 - ok.mean()), ne["y_m"] / y_rms,
            ne["theta"] / t_rms)


def table(cases=None, seeds=SEEDS) -> str:
    lines = ["| recording | y RMS [um] | origin error [um] | theta RMS | frames unmeasured | noise / error (y / theta) |",
             "|---|---|---|---|---|---|"]
    for case in cases or CASES:
        rows, refused = [], []
        for seed in seeds:
            res, y, theta, _ = run(case, seed)
            (refused.append(res) if isinstance(res, str) else rows.append(numbers(res, y, theta)))
        if refused:
            lines.append(f"| {case} | refused on {len(refused)} of {len(seeds)}: {refused[0]} |")
            continue
        a = np.array(rows)
        m, s = a.mean(axis=0), a.std(axis=0)
        lines.append(f"| {case} | {m[0]:.3f} +- {s[0]:.3f} | {m[1]:.3f} +- {s[1]:.3f} | {m[2]:.5f} +- {s[2]:.5f} | "
                     f"{m[3]:.2f} % (max {a[:, 3].max():.2f} %) | {m[4]:.2f} / {m[5]:.2f} (min {a[:, 4].min():.2f} / "
                     f"{a[:, 5].min():.2f}) |")
    return "\n".join(lines)


def _hexagon(centre, e1, e2, half_side, tau):
    """The outline (closed) of a cube's square of faces along ``e1``, ``e2`` (image (u, v)) seen with the hinge line
    tilted by ``tau``: shortened across by cos(tau) about its centre, swept by +-(s/2) sin(tau) along the rows
    (``half_side`` is the silhouette's, larger than the cube's by the root of the area factor)."""
    from scipy.spatial import ConvexHull

    from tracking.tilt import area_factor

    a = half_side / np.sqrt(area_factor(tau))
    shrink = np.array([np.cos(tau), 1.0])
    pts = np.array([centre + a * shrink * (p * e1 + q * e2) + np.array([d * a * np.sin(tau), 0.0])
                    for p, q in ((1, 1), (-1, 1), (-1, -1), (1, -1)) for d in (-1, 1)])
    hull = pts[ConvexHull(pts).vertices]
    return list(hull) + [hull[0]]


def figure(path: str) -> None:
    """One frame of each case with the tracked squares drawn on it."""
    import matplotlib.pyplot as plt

    from tracking.measure import COLUMNS

    C = {k: i for i, k in enumerate(COLUMNS)}
    fig, axes = plt.subplots(3, 3, figsize=(12, 8.4))
    for ax, case in zip(axes.ravel(), list(CASES)[:9]):  # the tilts of 6 and 14 degrees have no panel
        res, y, theta, frames = run(case, SEEDS[0], n=600)
        i = 420
        ax.imshow(frames[i], cmap="gray", vmin=0, vmax=255)
        if not isinstance(res, str) and res.status[i] == 0:
            r = res.rows[i]
            a = r[C["half_side"]]
            x0, y0 = (res.info["roi_px"] or [0, 0, 0, 0])[0], (res.info["roi_px"] or [0, 0, 0, 0])[2]
            tilt = res.info.get("tilt_correction")
            for cu, cv, g in ((r[C["u_a"]], r[C["v_a"]], r[C["gamma_a"]]), (r[C["u_b"]], r[C["v_b"]], r[C["gamma_b"]])):
                e1 = np.array([np.cos(g), -np.sin(g)])
                e2 = np.array([-np.sin(g), -np.cos(g)])
                if tilt:  # the cube's square as the tilted camera sees it: shortened across, swept along the rows
                    pts = _hexagon(np.array([cu + x0, cv + y0]), e1, e2, a, np.radians(tilt["tilt_deg"]))
                else:
                    pts = [np.array([cu + x0, cv + y0]) + a * (p * e1 + q * e2)
                           for p, q in ((1, 1), (-1, 1), (-1, -1), (1, -1), (1, 1))]
                ax.plot([p[0] for p in pts], [p[1] for p in pts], "-", color="tab:orange", lw=1)
            ax.set_title(f"{case[:38]}\ntheta {res.theta[i]:+.3f} (true {theta[i]:+.3f})", fontsize=8)
        else:
            why = "refused: " + res.split(": ", 1)[1][:40] if isinstance(res, str) else "frame not measured"
            ax.set_title(f"{case[:38]}\n{why}", fontsize=8)
        ax.set_xticks([])
        ax.set_yticks([])
    fig.tight_layout()
    fig.savefig(path, dpi=70)


if __name__ == "__main__":
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--figure", default=None, help="also draw one frame of each case with its fitted squares")
    p.add_argument("--no-table", action="store_true")
    p.add_argument("--cases", default=None, help="only the cases whose names start with these, comma-separated")
    p.add_argument("--seeds", default=None, help="seeds, comma-separated (default 4401,4402,4403)")
    a = p.parse_args()
    if not a.no_table:
        chosen = [c for c in CASES if any(c.startswith(k) for k in a.cases.split(","))] if a.cases else None
        print(table(chosen, tuple(int(x) for x in a.seeds.split(",")) if a.seeds else SEEDS))
    if a.figure:
        figure(a.figure)
