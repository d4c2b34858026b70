"""tracking: from high-speed video of the dimer to (t, y, theta).

The front end of a real experiment: a camera looking along the hinge line records the two cubes as two
squares sharing a corner; this package measures, in every frame, the centre-of-mass height ``y`` (from the
silhouette, sub-pixel, positive up from the levitation height) and the bend ``theta = (alpha - beta) / pi``
(from sub-pixel fits of the cubes' faces), and writes the docs/formats.md run CSV with a ``RUN.json`` of the
settings, counts and per-frame quality (``python -m tracking``; ``docs/tracking.md``).

* :mod:`tracking.recording` - reading video files, multi-page TIFF, Phantom .cine and folders of images;
* :mod:`tracking.measure` - the compiled per-frame measurement (its steps in :mod:`tracking.segmentation`,
  :mod:`tracking.moments`, :mod:`tracking.face_fit` and :mod:`tracking.hinge_corners`; what a frame's row holds in
  :mod:`tracking.frame_row`);
* :mod:`tracking.track` - calibration, batches, the recording's bounds, y and theta, noise estimates (its settings
  in :mod:`tracking.track_config`, the run's record RUN.json in :mod:`tracking.run_record`); the registry of
  per-recording steps that add to RUN.json, :mod:`tracking.recording_steps` (:func:`register_recording_step`);
* :mod:`tracking.output` - the run's CSV, RUN.json and example frame, or a data set with meta.json;
* :mod:`tracking.cli` - the command.

This package imports only :mod:`cubedimer` from the suite.
"""
import cubedimer  # noqa: F401  (first: sets up the compile cache, cubedimer.compile_cache)
from cubedimer.distribution import __version__
from .recording import Recording, TrackingError, find_recordings, read_recording
from .recording_steps import RecordingStep, TrackedRecording, register_recording_step
from .track import TrackConfig, TrackResult, track_recording

__all__ = ["Recording", "TrackingError", "read_recording", "find_recordings", "TrackConfig", "TrackResult",
           "track_recording", "RecordingStep", "TrackedRecording", "register_recording_step"]
