"""The digital twin: synthetic field-drop experiments written as data sets (docs/formats.md).

* :mod:`acousim.twin.config` - settings: :class:`DropProtocol`, :class:`Camera`, :class:`TwinConfig`,
  presets (:data:`PAPER_LIKE`) and :class:`TwinError`;
* :mod:`acousim.twin.simulation` - the field-drop simulation of one run (:func:`simulate_run`) and of
  every run of a configuration (:func:`simulate_field_drop_runs`);
* :mod:`acousim.twin.writer` - writing a data set with its truth files (:func:`simulate_dataset`);
* :mod:`acousim.twin.figures` - figures of a twin data set (:func:`write_twin_figures`);
* :mod:`acousim.twin.video` - the high-speed camera: rendered frames of the dimer (:class:`VideoCamera`,
  :func:`record_video`).
"""
from .config import (PAPER, PAPER_LIKE, PRESETS, WINDOW_RESONATOR, Camera, DropProtocol, TwinConfig, TwinError,
                     TwinPreset)
from .figures import write_twin_figures
from .simulation import SimulatedRun, run_seeds, simulate_field_drop_runs, simulate_run, true_pressure, twin_dynamics
from .video import VideoCamera, dimer_squares, record_video, render_coverage, render_frames, write_video_tiff
from .writer import check_output_dir, meta_dict, simulate_dataset, truth_dict, write_run, write_run_video

__all__ = [
    "DropProtocol",
    "Camera",
    "TwinConfig",
    "TwinPreset",
    "TwinError",
    "PAPER_LIKE",
    "PAPER",
    "WINDOW_RESONATOR",
    "PRESETS",
    "SimulatedRun",
    "simulate_run",
    "simulate_field_drop_runs",
    "simulate_dataset",
    "true_pressure",
    "run_seeds",
    "twin_dynamics",
    "meta_dict",
    "truth_dict",
    "check_output_dir",
    "write_run",
    "write_twin_figures",
    "VideoCamera",
    "dimer_squares",
    "record_video",
    "render_coverage",
    "render_frames",
    "write_video_tiff",
    "write_run_video",
]
