"""The model-discovery pipeline: data -> prepared runs -> the registered method -> one :class:`FitResult`.

:func:`fit_dataset` loads a data set (:func:`cubedimer.dataset.load_dataset`), smooths and differentiates every
run and classifies its attractor (:func:`prepare_runs`), and hands the prepared runs to the method whose settings
``FitConfig.method`` holds, in :data:`fitting.methods.registry.METHODS` (:func:`fit_runs`): ``"discovery"``
(:mod:`fitting.methods.discovery`, the default) or ``"paper"`` (:mod:`fitting.methods.paper`).  It writes nothing but the
method's resume cache (``cache_dir``); the fit command writes model.json and the figures
(:func:`fitting.output.model_file.write_fit`).

Never a blown-up model: every method ends with :func:`fitting.uncertainty.final_checks.fall_back` when its model leaves the
blow-up bound, which raises :class:`fitting.uncertainty.final_checks.NoSaneModelError` if no fallback integrates.  Beside every
selected term, the result carries the oracle standard error and z of the final model (:mod:`fitting.uncertainty.oracle`) at
the data's tracking noise, and the term's closest library alias with its alias z.
"""
from __future__ import annotations

import logging
import os
from dataclasses import replace
from typing import Sequence

import numpy as np

from cubedimer.attractors import classify_trajectory
from cubedimer.dataset import Dataset, DatasetError, Run, load_dataset
from cubedimer.executor import ExecutorConfig
from cubedimer.spectra import dominant_frequency
from .config import FitConfig
from .derivatives.decimation import block_average, decimation_factor
from .derivatives.savitzky_golay import SmoothingFailure, run_derivatives
from .methods import discovery, paper  # noqa: F401 - registers the built-in methods
from .methods.registry import FitContext, get_method
from .model import Scales
from .results import FitResult, PreparedRun
from .selection.sparse_regression import dataset_scales
from .uncertainty.oracle import NoiseLevels, recorded_tracking_noise

__all__ = ["prepare_runs", "fit_runs", "fit_dataset"]

logger = logging.getLogger(__name__)


def prepare_runs(runs: Sequence[Run], config: FitConfig = FitConfig()) -> tuple[list[PreparedRun], Scales]:
    """Smooth/differentiate and classify every run; common scales of the data set."""
    out = []
    for r in runs:
        q = decimation_factor(r.dt, max(dominant_frequency(r.y, r.dt), dominant_frequency(r.theta, r.dt)),
                              config.smoothing.max_frames_per_period)
        r = block_average(r, q)
        fy = dominant_frequency(r.y, r.dt)
        try:
            d = run_derivatives(r.t, r.y, r.theta, fy, config.smoothing, velocities=r.velocities)
        except SmoothingFailure as exc:
            raise DatasetError(f"{r.name}: {exc}") from None
        att = classify_trajectory(d.t, d.state, config.classify)
        out.append(PreparedRun(run=r, derivs=d, f_y=fy, attractor=att, frames_averaged=q))
    if any(p.frames_averaged > 1 for p in out):
        logger.info("high frame rate: %s recorded frames averaged per fitted frame (fitting.derivatives.decimation)",
                    "/".join(str(q) for q in sorted({p.frames_averaged for p in out})))
    scales = dataset_scales([p.derivs for p in out], [p.f_y for p in out])
    return out, scales


def fit_runs(prepared: Sequence[PreparedRun], scales: Scales, config: FitConfig = FitConfig(),
             executor: ExecutorConfig | None = None, cache_dir: str | os.PathLike | None = None,
             progress: bool = True, noise: NoiseLevels | None = None) -> FitResult:
    """Fit prepared runs with the registered method whose settings ``config.method`` holds.

    Parameters
    ----------
    prepared, scales : the output of :func:`prepare_runs`
    config : FitConfig
    executor : ExecutorConfig, optional
        Where parallel work runs.
    cache_dir : path-like, optional
        Resume cache of per-run work (None: none).
    progress : bool
        Progress bars of parallel work.
    noise : NoiseLevels, optional
        The oracle's tracking noise (default: estimated from the runs).
    """
    method = get_method(config.method.name)
    return method.fit(prepared, scales, config, FitContext(executor, cache_dir, progress, noise))


def fit_dataset(data: Dataset | str | os.PathLike, config: FitConfig = FitConfig(),
                executor: ExecutorConfig | None = None, strict: bool = False, progress: bool = True,
                cache_dir: str | os.PathLike | None = None) -> FitResult:
    """Fit a data set (module docstring); writes nothing but the method's resume cache in ``cache_dir``.

    ``data`` is a loaded :class:`~cubedimer.dataset.Dataset` (fitted as it is: pass the one object to every step
    that reads the data set, so that all see the same runs), or the path of one, loaded with ``config.load``
    (``strict``: stop at the first bad file).

    Raises
    ------
    DatasetError
        Bad input, or fewer than two usable runs.
    fitting.uncertainty.final_checks.NoSaneModelError
        The final model blows up and no fallback integrates over every run.
    """
    ds = data if isinstance(data, Dataset) else load_dataset(data, strict=strict, config=config.load)
    if len(ds.runs) < 2:
        raise DatasetError(f"{ds.path}: the ensemble step needs at least 2 usable runs, found {len(ds.runs)}")
    prepared, scales = prepare_runs(ds.runs, config)
    logger.info("%d runs loaded (%d skipped, %d glitch frames masked); scales: %s, time %.3g s", len(prepared),
                len(ds.skipped), ds.n_glitches, ds.system.describe((scales.length_y, scales.length_theta)), scales.time)
    noise = _fitted_noise(recorded_tracking_noise(ds.meta), prepared)
    if noise is not None:
        logger.info("oracle noise from meta.json's tracking block: %s",
                    ds.system.describe((noise.sigma_y, noise.sigma_theta)))
    res = fit_runs(prepared, scales, config, executor, cache_dir=cache_dir, progress=progress, noise=noise)
    return replace(res, skipped=tuple(ds.skipped_files()), n_glitches=ds.n_glitches, system=ds.system, meta=dict(ds.meta))


def _fitted_noise(noise: NoiseLevels | None, prepared: Sequence[PreparedRun]) -> NoiseLevels | None:
    """The recorded tracking noise at the fitted frame rate: block means of q frames carry 1/sqrt(q) of it; None
    (estimate it from the runs) when the runs were averaged by different factors."""
    factors = {p.frames_averaged for p in prepared}
    if noise is None or factors == {1}:
        return noise
    if len(factors) > 1:
        logger.info("runs averaged by different factors: the oracle's noise is estimated from the runs")
        return None
    q = factors.pop()
    return replace(noise, sigma_y=noise.sigma_y / np.sqrt(q), sigma_theta=noise.sigma_theta / np.sqrt(q),
                   source=f"{noise.source}, divided by sqrt({q}) for the means of {q} frames")
