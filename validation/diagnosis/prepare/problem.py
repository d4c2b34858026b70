"""One data set's diagnosis problem: the simulation model, the runs, and what is computed once for them.

A :class:`DiagnosisProblem` is created per data set (or per set of synthetic runs) and passed to every
step of the diagnosis (:func:`~validation.diagnosis.calibrate.gap_model.fit_gap_model`,
:func:`~validation.diagnosis.identify.identification.identify_effects`,
:func:`~validation.diagnosis.summarise.long_time.long_time_gaps`).  It owns the quantities that do not depend on
the calibration and are needed by many fits: the model's orientation sums at each run's angles (the
costly part of evaluating the Gor'kov forces at the data states) and the twin's surrogate of the model.
Subsets of its runs (the folds of the held-out identification) share them.
"""
from __future__ import annotations

from typing import Sequence

from .runs import RunAccelerations, thin_runs

__all__ = ["DiagnosisProblem"]


class DiagnosisProblem:
    """The simulation model at nominal pressure and the runs a diagnosis fits.

    Parameters
    ----------
    model : acousim.GorkovDimer or acousim.fullwave.FullwaveDimer
        The simulation at nominal pressure (use ``model.interpolated()`` for speed).
    runs : sequence of RunAccelerations
        The runs at the frames the fits use.
    recorded_runs : sequence of RunAccelerations, optional
        The same runs at every recorded frame (initial states, long-time errors); default ``runs``.
    drift : validation.diagnosis.calibrate.drift.PressureDrift, optional
        The pressure's drift in time within each run: the simulation's acoustic terms are scaled by its
        factor (:meth:`pressure_factor`); None: a constant pressure.
    """

    def __init__(self, model, runs: Sequence[RunAccelerations], recorded_runs: Sequence[RunAccelerations] | None = None,
                 *, drift=None, _shared: dict | None = None):
        self.model = model
        self.drift = drift
        self.runs: tuple[RunAccelerations, ...] = tuple(runs)
        self.recorded_runs: tuple[RunAccelerations, ...] = tuple(self.runs if recorded_runs is None else recorded_runs)
        # id(holder) -> (holder, orientation sums); the holder is kept so that its id stays unique
        # the data set's runs are kept for what is computed once per data set (the cavity's reference mode)
        self._shared = _shared if _shared is not None else {"sums": {}, "surrogate": None, "runs": self.runs}

    @classmethod
    def from_recorded(cls, model, recorded_runs: Sequence[RunAccelerations], max_frames_per_run: int) -> "DiagnosisProblem":
        """The problem of ``recorded_runs``, fitted on every run thinned to at most ``max_frames_per_run`` frames."""
        return cls(model, thin_runs(recorded_runs, max_frames_per_run), recorded_runs)

    def subset(self, indices: Sequence[int]) -> "DiagnosisProblem":
        """The problem of the runs at ``indices`` (same model, shared caches)."""
        runs = [self.runs[i] for i in indices]
        return DiagnosisProblem(self.model, runs, drift=self.drift, _shared=self._shared)

    def with_drift(self, drift) -> "DiagnosisProblem":
        """The same problem with the simulation's pressure drifting as ``drift`` (a
        :class:`~validation.diagnosis.calibrate.drift.PressureDrift`, or None for a constant pressure)."""
        return DiagnosisProblem(self.model, self.runs, self.recorded_runs, drift=drift, _shared=self._shared)

    def pressure_factor(self, name: str, t):
        """Factor (p(t) / p_mean)^2 on the simulation's acoustic terms of run ``name`` at times ``t`` [s]
        (None when the pressure is constant)."""
        return None if self.drift is None else self.drift.factor(name, t)

    def __len__(self) -> int:
        return len(self.runs)

    def orientation_sums(self, holder):
        """The model's orientation sums at the angles ``holder.state[:, 2]`` of a run (a
        :class:`RunAccelerations` or its :class:`PositionIntegrals`), computed once per holder."""
        store = self._shared["sums"]
        key = id(holder)
        if key not in store:
            store[key] = (holder, self.model.orientation_sums(holder.state[:, 2]))
        return store[key][1]

    def surrogate(self):
        """The force model of the equations of motion at nominal pressure, built once: the twin's surrogate
        (:func:`acousim.gorkov.energy_surrogate.build_surrogate`) of a Gor'kov model, or the model's own table when it has one
        (``as_force_model``, the full-wave model)."""
        if self._shared["surrogate"] is None:
            from acousim.gorkov.energy_surrogate import build_surrogate

            own = getattr(self.model, "as_force_model", None)
            self._shared["surrogate"] = own() if own is not None else build_surrogate(self.model)
        return self._shared["surrogate"]
