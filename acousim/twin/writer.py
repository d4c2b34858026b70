"""Writing a twin data set (docs/formats.md): run CSVs, ``meta.json``, ``truth.json`` and the exact states.

:func:`simulate_dataset` writes ``runNN.csv`` (columns ``t, y, theta``), ``meta.json`` (the
*nominal* settings, docs/formats.md keys), ``truth.json`` (the true pressure, the effects with their
parameters, the seed and every other setting, including each run's drawn initial conditions) and
``truth_states.npz`` (the exact integrated states at every frame, for tests and diagnostics; with a resonator
also ``truth_mode.npz``, the cavity mode's complex amplitude A / p0 at every frame), into
a temporary folder renamed into place at the end, so a failure leaves nothing behind.  With a
:class:`~acousim.twin.video.VideoCamera` it also writes, per run, the frames the high-speed camera
records (``video/runNN.tif``, :mod:`acousim.twin.video`) and the true ``t, y, theta`` beside them
(``video/runNN_truth.csv``).
"""
from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from cubedimer.atomic import atomic_directory, atomic_save, default_dir_mode, write_json
from cubedimer.dataset import write_run_csv

from ..dynamics.integrator import DimerDynamics
from ..medium import ParticleMaterial
from .config import TwinConfig, TwinError
from .simulation import SimulatedRun, simulate_field_drop_runs
from .video import VideoCamera, drop_protocol_motion, record_video, write_video_tiff

__all__ = ["simulate_dataset", "meta_dict", "truth_dict", "check_output_dir", "write_run", "write_run_video",
           "video_seed"]


def write_run(path: str | os.PathLike, run: SimulatedRun, index: int, total: int) -> Path:
    """Write the CSV of one run (docs/formats.md): comments, header ``t,y,theta``, one row per frame,
    missing frames as ``nan``."""
    comments = [f"acousim digital twin, run {index} of {total}: free oscillation after the field is back on at t = 0",
                "units: t [s], y [m] (centre-of-mass height above the levitation height), theta [-]"]
    return write_run_csv(path, run.t, run.y, run.theta, comments, t_decimals=9, y_digits=10, theta_decimals=10,
                         missing="nan")


def video_seed(seed: int, index: int) -> np.random.SeedSequence:
    """The image-noise stream of run ``index`` (0-based): independent of the runs' own streams."""
    return np.random.SeedSequence(int(seed), spawn_key=(2, int(index)))


def write_run_video(directory: str | os.PathLike, stem: str, run: SimulatedRun, side: float, camera: VideoCamera,
                    seed: np.random.SeedSequence | int, dynamics: DimerDynamics | None = None,
                    ring_time_s: float = 0.0) -> list[int]:
    """Write one run's video (``stem.tif``, or ``stem.mp4`` with the H.264 codec) and its true ``t, y, theta``
    (``stem_truth.csv``) into ``directory``; returns the indices of the lost frames.  With rest frames
    (:class:`~acousim.twin.imperfections.Imperfections`) the video and the truth begin with the dimer at rest at
    y = 0 and the run's first theta, and the run's times are shifted by them."""
    directory = Path(directory)
    imp = camera.imperfections
    dt = float(run.t[1] - run.t[0])
    fps = 1.0 / dt
    y, theta = run.state[:, 0], run.state[:, 2]
    k = int(imp.rest_frames)
    note = ""
    if k and dynamics is not None:
        y, theta, ph = drop_protocol_motion(dynamics, run, k, ring_time_s)
        note = (f"; the drive stops at frame {ph['drop_frame']:.3f} and the field is back at frame "
                f"{ph['field_on_frame']} (t = {ph['field_on_frame'] * dt:.9f} s)")
    elif k:
        y = np.concatenate([np.zeros(k), y])
        theta = np.concatenate([np.full(k, theta[0]), theta])
    t = np.arange(y.size) * dt
    frames, lost = record_video(t, y, theta, side, camera, seed)
    if imp.codec == "h264":
        from .imperfections import encode_h264

        name = f"{stem}.mp4"
        atomic_save(directory / name, lambda tmp: encode_h264(tmp, frames, fps, imp.crf))
    else:
        name = f"{stem}.tif"
        extra = {"side_length_m": float(side)}
        if not imp.record_origin:
            extra["levitation_row_px"] = None
        write_video_tiff(directory / name, frames, fps, camera, extra)
    write_run_csv(directory / f"{stem}_truth.csv", t, y, theta,
                  ["acousim digital twin: the true motion recorded in " + f"{name} (lost frames included){note}",
                   "units: t [s], y [m] (centre-of-mass height above the levitation height), theta [-]"],
                  t_decimals=9, y_digits=10, theta_decimals=10)
    return [int(i) for i in lost]


def meta_dict(config: TwinConfig, dynamics: DimerDynamics) -> dict:
    """meta.json: the docs/formats.md keys with the *nominal* pressure amplitude."""
    st = dynamics.force_model.settings
    return {
        "side_length_m": float(config.side),
        "particle_density_kg_m3": float(st["particle_density_kg_m3"]),
        # the full-wave model treats the cubes as rigid; the record keeps the material's value
        "bulk_modulus_pa": float(st.get("bulk_modulus_pa", ParticleMaterial().bulk_modulus_pa)),
        "frequency_hz": float(st["frequency_hz"]),
        "sound_speed_m_s": float(st["sound_speed_m_s"]),
        "air_density_kg_m3": float(st["air_density_kg_m3"]),
        "pressure_amplitude_pa": float(config.pressure_amplitude_pa),
        "source": "acousim digital twin (synthetic)",
    }


def truth_dict(config: TwinConfig, dynamics: DimerDynamics, p_true: float, runs: list[SimulatedRun],
               files: list[str]) -> dict:
    """truth.json: true pressure, effects, seed, every setting and each run's initial conditions."""
    fm = dynamics.force_model
    f_y, f_theta = fm.linear_frequencies()
    out = {
        "pressure_amplitude_pa": float(p_true),
        "effects": None,
        "seed": int(config.seed),
        **config.to_dict(),
        "equilibrium_height_m": float(fm.z_eq),
        "escape_height_m": float(fm.escape_height()),
        f"{config.force_model}_linear_frequencies_hz": {"y": f_y, "theta": f_theta},
        "model": {k: v for k, v in fm.settings.items() if k not in ("pressure_amplitude_pa", "equilibrium_height_m")},
    }
    out["effects"] = dynamics.effects.to_dict()  # with the computed air damping unless config.air_damping is False
    out["surrogate"] = fm.provenance()
    out.update({
        "state": ["y", "ydot", "theta", "thetadot"],
        "runs_detail": [
            {"file": f, **r.drop, "state_at_field_on": [float(v) for v in r.state_at_field_on],
             "pressure_at_field_on": _pressure_at_field_on(config, r.drop["t_off_s"]) if r.pressure_at_field_on is None
             else float(r.pressure_at_field_on),
             "missing_frames": [int(i) for i in r.missing], "frames": int(r.t.size), "event": r.event}
            for f, r in zip(files, runs)
        ],
        "folded_runs": sum(r.folded for r in runs),
        "units": "SI",
    })
    if config.cavity_mode is not None:  # with a resonator an escape is an outcome (without one it stops the set)
        out["escaped_runs"] = sum(r.escaped for r in runs)
    return out


def _pressure_at_field_on(config: TwinConfig, t_off: float) -> float:
    """p / p0 when the drive comes back: exp(-t_off / tau), 0 for an instant switch."""
    tau = config.transducer_q / (np.pi * config.frequency)
    return float(np.exp(-t_off / tau)) if tau > 0 else 0.0


def check_output_dir(out_dir: str | os.PathLike, force: bool = False) -> Path:
    """Refuse an existing non-empty directory (or a file) unless ``force``; returns the path."""
    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise TwinError(f"{out} exists and is not a directory")
    if out.is_dir() and any(out.iterdir()) and not force:
        raise TwinError(f"{out} is not empty (use --force to replace it)")
    return out


def simulate_dataset(config: TwinConfig, out_dir: str | os.PathLike, executor=None, force: bool = False,
                     progress: bool = True, video: VideoCamera | None = None) -> dict:
    """Simulate and write a data set (see the module docstring); returns the truth dictionary.

    With ``video``, every run's camera frames are written to ``out_dir/video/`` as well (module
    docstring), and ``truth.json`` holds the camera settings and each run's lost frames under ``"video"``.

    Raises
    ------
    TwinError
        Bad settings, a non-empty ``out_dir`` without ``force``, or a run that leaves the trap;
        nothing is written then.
    """
    out = check_output_dir(out_dir, force)
    runs, dynamics, p_true = simulate_field_drop_runs(config, executor, progress)
    width = max(2, len(str(config.runs)))
    # a run that folded during the drop has no frame: no CSV, its truth entry says why
    files = [f"run{i:0{width}d}.csv" if r.t.size else None for i, r in enumerate(runs, 1)]
    truth = truth_dict(config, dynamics, p_true, runs, files)
    with atomic_directory(out) as tmp:
        for i, (f, r) in enumerate(zip(files, runs), 1):
            if f is not None:
                write_run(tmp / f, r, i, config.runs)
        if video is not None:
            lost = {}
            for i, (f, r) in enumerate(zip(files, runs)):
                if f is None or r.t.size < 2:  # a video needs two frames
                    continue
                lost[Path(f).stem] = write_run_video(tmp / "video", Path(f).stem, r, config.side, video,
                                                     video_seed(config.seed, i), dynamics,
                                                     config.transducer_q / (np.pi * config.frequency))
            truth["video"] = {**video.to_dict(), "fps": float(config.camera.fps), "lost_frames_per_run": lost,
                              "files": [f"video/{stem}.{'mp4' if video.imperfections.codec == 'h264' else 'tif'}"
                                        for stem in lost]}
            os.chmod(tmp / "video", default_dir_mode())
        write_json(tmp / "meta.json", meta_dict(config, dynamics))
        write_json(tmp / "truth.json", truth)
        n = config.n_frames
        # folded (and, with a resonator, escaped) runs: NaN after the end, so that every run shares the frame times
        states = {f"run{i:0{width}d}": np.concatenate([r.state, np.full((n - r.t.size, 4), np.nan)])
                  for i, r in enumerate(runs, 1)}
        modes = {f"run{i:0{width}d}": np.concatenate([r.mode, np.full(n - r.mode.size, np.nan + 0j)])
                 for i, r in enumerate(runs, 1) if r.mode is not None}
        if modes:  # with a resonator: the cavity mode's amplitude A / p0 at the frames (complex), NaN after a fold
            atomic_save(tmp / "truth_mode.npz", lambda path: np.savez(path, t=np.arange(n) / config.camera.fps, **modes))
        atomic_save(tmp / "truth_states.npz", lambda path: np.savez(path, t=np.arange(n) * (1.0 / config.camera.fps),
                                                                     **states))
    return truth
