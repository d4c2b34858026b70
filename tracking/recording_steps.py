"""The registry of per-recording steps: what the tracking works out from a whole tracked recording, beyond y and theta.

A step is an object satisfying :class:`RecordingStep`: a ``name`` (its entry in RUN.json and in
:attr:`tracking.track.TrackResult.info`) and ``run(tracked)``, which reads the :class:`TrackedRecording` (the
recording, its settings, the frames' measurement rows and status, and t, y, theta) and returns a JSON-able ``dict``
(or None: nothing to record).  Its own settings are the fields of the step (a frozen dataclass).  It is registered
once with :func:`register_recording_step`, at the import of the module that defines it (so that the worker processes
of a folder's tracking have it too); :func:`tracking.track.track_recording` runs every registered step, in
registration order, after y and theta are known, and stores each result under the step's name.  A step runs inside
the task that tracks its recording (:func:`cubedimer.executor.map_ordered`) and opens no pool of its own.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np
from numpy.typing import NDArray

from .frame_row import COLUMNS
from .recording import Recording, TrackingError
from .track_config import TrackConfig

__all__ = ["TrackedRecording", "RecordingStep", "RECORDING_STEPS", "register_recording_step", "run_recording_steps"]


@dataclass(frozen=True, eq=False)
class TrackedRecording:
    """What a per-recording step reads: one recording as the tracking measured it.

    Attributes
    ----------
    recording : Recording
        The frames and what the file records.
    config : TrackConfig
        The tracking's settings.
    fps, pixel_size : float
        Frame rate [1/s] and pixel size in the object plane [m] the tracking used.
    t, y, theta : ndarray (n,)
        Times from the first frame [s], height above the levitation height [m] (up), bend [-]; NaN where a frame
        was not measured.
    status : ndarray (n,) int
        :data:`tracking.frame_row.STATUS` code of each frame (0: measured).
    rows : ndarray (n, len(COLUMNS))
        The kernel's measurement of every frame (pixel units; :meth:`column` by name).
    """

    recording: Recording
    config: TrackConfig
    fps: float
    pixel_size: float
    t: NDArray[np.float64]
    y: NDArray[np.float64]
    theta: NDArray[np.float64]
    status: NDArray[np.int64]
    rows: NDArray[np.float64]

    @property
    def measured(self) -> NDArray[np.bool_]:
        """The frames that were measured."""
        return self.status == 0

    def column(self, name: str) -> NDArray[np.float64]:
        """The column ``name`` (:data:`tracking.frame_row.COLUMNS`) of every frame's measurement row."""
        return self.rows[:, COLUMNS.index(name)]


@runtime_checkable
class RecordingStep(Protocol):
    """A per-recording step (module docstring).

    Attributes
    ----------
    name : str
        Its entry in RUN.json and in ``TrackResult.info`` (a name the run's record does not use already).
    """

    name: str

    def run(self, tracked: TrackedRecording) -> dict | None:
        """What the step finds in ``tracked``, JSON-able (None: nothing to record)."""
        ...


#: name -> step, in registration order (the order they run in).
RECORDING_STEPS: dict[str, RecordingStep] = {}


def register_recording_step(step: RecordingStep) -> RecordingStep:
    """Add ``step`` to :data:`RECORDING_STEPS` under ``step.name`` (replacing a step of that name); returns it.

    Raises
    ------
    TypeError
        ``step`` does not satisfy :class:`RecordingStep` (a non-empty ``name`` and ``run``).
    """
    if not isinstance(step, RecordingStep) or not isinstance(step.name, str) or not step.name:
        raise TypeError(f"{step!r} is not a RecordingStep (name, run)")
    RECORDING_STEPS[step.name] = step
    return step


def run_recording_steps(tracked: TrackedRecording, record: dict) -> dict:
    """``record`` (the run's RUN.json document) with the result of every registered step under its name.

    Raises
    ------
    TrackingError
        One line naming the recording and the step: a step whose name the record uses already.
    """
    out = dict(record)
    for name, step in RECORDING_STEPS.items():
        if name in record:
            raise TrackingError(f"{tracked.recording.path}: the recording step {name!r} would replace RUN.json's own "
                                f"{name!r}; register it under another name")
        out[name] = step.run(tracked)
    return out
