"""One preparation of a data set's runs, made once and read by the fit and the diagnosis.

:func:`prepare_dataset` turns a loaded :class:`cubedimer.dataset.Dataset` into a :class:`PreparedDataset`: per run
(:class:`RunPreparation`) the run as prepared (block-averaged at high frame rates,
:mod:`fitting.derivatives.decimation`), its oscillation frequencies f_y and f_theta (one rule,
:func:`oscillation_frequencies`), the Savitzky-Golay states and derivatives (:func:`~.savitzky_golay.run_derivatives`),
the column states of the integral form (:func:`~.integral_form.column_states`), its windows
(:func:`~.integral_form.integral_window`) and the white tracking noise of y and theta
(:func:`cubedimer.noise.white_noise_std`).  The fit (:func:`fitting.fit.prepare_runs`, which adds the attractor
class) and the diagnosis (``validation.diagnosis.prepare.runs.prepare_diagnosis_runs``) are views of it, so both work
on the same arrays; ``python -m validation report`` prepares the data set once and passes the object to both.
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray

from cubedimer.dataset import Dataset, DatasetError, Run
from cubedimer.noise import white_noise_std
from .decimation import block_average, decimation_factor
from .frequencies import THETA_MIN_CYCLES, Y_MIN_CYCLES, oscillation_frequencies
from .integral_form import column_states, integral_form_states, integral_window
from .savitzky_golay import Derivatives, SmoothingConfig, SmoothingFailure, run_derivatives

__all__ = ["RunPreparation", "PreparedDataset", "prepare_dataset", "prepare_run", "oscillation_frequencies", "flipped_y",
           "integral_form_states", "Y_MIN_CYCLES", "THETA_MIN_CYCLES"]

def flipped_y(run: Run) -> Run:
    """``run`` with y -> -y (and its measured y rate, if any)."""
    v = run.velocities
    return replace(run, y=-run.y, velocities=None if v is None else v * np.array([-1.0, 1.0]))


@dataclass(frozen=True, eq=False)
class RunPreparation:
    """One run as the fit and the diagnosis read it (SI).

    Attributes
    ----------
    run : the run as prepared: ``frames_averaged`` recorded frames per frame (:func:`~.decimation.block_average`;
        1: as recorded)
    frames_averaged : int
    f_y, f_theta : oscillation frequencies [Hz] of ``run`` (:func:`oscillation_frequencies`)
    derivs : Savitzky-Golay states and derivatives (:class:`~.savitzky_golay.Derivatives`), window 0.75 / f_y
    columns : (n, 4) states [y, ydot, theta, thetadot] at which the integral form evaluates its columns, at every
        frame (:func:`~.integral_form.column_states`); None for a run shorter than the hinge's smoothing window
    column_edge : frames of ``columns`` to leave out at each end (0 without columns)
    windows : frames per integral-form window of y and theta, 0.75 of each coordinate's period within 30-500 ms
        (:func:`~.integral_form.integral_window`)
    noise_var : variances of the white tracking noise of y [m^2] and theta [-] (:func:`cubedimer.noise.white_noise_std`)
    """

    run: Run
    frames_averaged: int
    f_y: float
    f_theta: float
    derivs: Derivatives
    columns: NDArray[np.float64] | None
    column_edge: int
    windows: tuple[int, int]
    noise_var: tuple[float, float]

    def flipped_y(self) -> "RunPreparation":
        """The preparation of the run with y -> -y: every step is linear in y (and the frequencies and the noise do
        not depend on its sign), so the y columns change sign, exactly."""
        flip = np.array([-1.0, -1.0, 1.0, 1.0])
        d = replace(self.derivs, state=self.derivs.state * flip, accel=self.derivs.accel * np.array([-1.0, 1.0]))
        return replace(self, run=flipped_y(self.run), derivs=d, columns=None if self.columns is None else self.columns * flip)


@dataclass(frozen=True, eq=False)
class PreparedDataset:
    """A loaded data set and the preparation of its runs (:func:`prepare_dataset`), in the data set's order."""

    dataset: Dataset
    smoothing: SmoothingConfig
    runs: tuple[RunPreparation, ...]

    @property
    def names(self) -> list[str]:
        """The runs' names."""
        return [p.run.name for p in self.runs]

    def flipped_y(self) -> "PreparedDataset":
        """The preparation of the data set with y -> -y in every run (:meth:`RunPreparation.flipped_y`)."""
        return replace(self, dataset=replace(self.dataset, runs=tuple(flipped_y(r) for r in self.dataset.runs)),
                       runs=tuple(p.flipped_y() for p in self.runs))

    def restricted_to(self, dataset: Dataset) -> "PreparedDataset":
        """The preparations of ``dataset``'s runs (a data set with some of this one's runs left out)."""
        by_name = {p.run.name: p for p in self.runs}
        return replace(self, dataset=dataset, runs=tuple(by_name[r.name] for r in dataset.runs))


def prepare_run(run: Run, smoothing: SmoothingConfig = SmoothingConfig()) -> RunPreparation:
    """:class:`RunPreparation` of one gap-filled run.

    Raises
    ------
    DatasetError
        The smoothing does not follow the run (:class:`~.savitzky_golay.SmoothingFailure`), naming the run.
    """
    frequencies = oscillation_frequencies(run)
    q = decimation_factor(run.dt, max(frequencies), smoothing.max_frames_per_period)
    if q > 1:
        run = block_average(run, q)
        frequencies = oscillation_frequencies(run)
    f_y, f_theta = frequencies
    try:
        d = run_derivatives(run.t, run.y, run.theta, f_y, smoothing, velocities=run.velocities)
    except SmoothingFailure as exc:
        raise DatasetError(f"{run.name}: {exc}") from None
    try:
        columns, edge = column_states(run.dt, run.y, run.theta, d.state[:, 1], f_y, f_theta, int(d.trim),
                                      smoothing.polyorder)
    except ValueError:  # shorter than the hinge's smoothing window
        columns, edge = None, 0
    noise = tuple(float(white_noise_std([np.asarray(x, float)]) ** 2) for x in (run.y, run.theta))
    return RunPreparation(run, q, float(f_y), float(f_theta), d, columns, int(edge),
                          (integral_window(run.dt, f_y), integral_window(run.dt, f_theta)), noise)


def prepare_dataset(dataset: Dataset, smoothing: SmoothingConfig = SmoothingConfig()) -> PreparedDataset:
    """Prepare every run of a loaded data set once (module docstring).

    Parameters
    ----------
    dataset : cubedimer.dataset.Dataset
    smoothing : SmoothingConfig
        The Savitzky-Golay settings and the block averaging (``FitConfig.smoothing``).

    Raises
    ------
    DatasetError
        A run whose smoothing does not follow its signal, naming the run.
    """
    return PreparedDataset(dataset, smoothing, tuple(prepare_run(r, smoothing) for r in dataset.runs))
