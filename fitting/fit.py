"""The model-discovery pipeline: data -> prepared runs -> the registered method -> one :class:`FitResult`.

:func:`fit_dataset` loads a data set (:func:`cubedimer.dataset.load_dataset`), prepares every run once
(:func:`fitting.derivatives.preparation.prepare_dataset`: block averaging, frequencies, smoothing and derivatives, the
integral form's column states and windows, the noise) and classifies its attractor (:func:`prepare_runs`, the fit's
view of the preparation), and hands the prepared runs to the method whose settings
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
from .config import FitConfig
from .derivatives.preparation import PreparedDataset, prepare_run
from .methods import discovery, paper  # noqa: F401 - registers the built-in methods
from .methods.registry import FitContext, get_method
from .model import Scales
from .results import FitResult, PreparedRun
from .selection.sparse_regression import dataset_scales
from .uncertainty.oracle import NoiseLevels, recorded_tracking_noise

__all__ = ["prepare_runs", "fit_runs", "fit_dataset"]

logger = logging.getLogger(__name__)


def prepare_runs(runs: Sequence[Run] | PreparedDataset, config: FitConfig = FitConfig()
                 ) -> tuple[list[PreparedRun], Scales]:
    """The fit's view of prepared runs: each :class:`~fitting.derivatives.preparation.RunPreparation` with its
    attractor class (``config.classify``), and the common scales of the data set.

    ``runs`` is a :class:`~fitting.derivatives.preparation.PreparedDataset` (prepared once, e.g. by
    ``python -m validation report`` for the fit and the diagnosis; its smoothing must be ``config.smoothing``), or
    loaded runs, prepared here (:func:`fitting.derivatives.preparation.prepare_run`).
    """
    if isinstance(runs, PreparedDataset):
        if runs.smoothing != config.smoothing:
            raise ValueError(f"the runs were prepared with {runs.smoothing}, the fit asks for {config.smoothing}")
        preparations = runs.runs
    else:
        preparations = tuple(prepare_run(r, config.smoothing) for r in runs)
    out = [PreparedRun(run=p.run, derivs=p.derivs, f_y=p.f_y,
                       attractor=classify_trajectory(p.derivs.t, p.derivs.state, config.classify),
                       frames_averaged=p.frames_averaged, preparation=p) for p in preparations]
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


def fit_dataset(data: PreparedDataset | Dataset | str | os.PathLike, config: FitConfig = FitConfig(),
                executor: ExecutorConfig | None = None, strict: bool = False, progress: bool = True,
                cache_dir: str | os.PathLike | None = None) -> FitResult:
    """Fit a data set (module docstring); writes nothing but the method's resume cache in ``cache_dir``.

    ``data`` is a prepared data set (:func:`fitting.derivatives.preparation.prepare_dataset` with
    ``config.smoothing``: pass the one object to every step that reads the data set, so that all see the same runs
    and derivatives), a loaded :class:`~cubedimer.dataset.Dataset` (fitted as it is, prepared here), or the path of
    one, loaded with ``config.load`` (``strict``: stop at the first bad file).

    Raises
    ------
    DatasetError
        Bad input, or fewer than two usable runs.
    fitting.uncertainty.final_checks.NoSaneModelError
        The final model blows up and no fallback integrates over every run.
    """
    if isinstance(data, PreparedDataset):
        ds = data.dataset
    else:
        ds = data if isinstance(data, Dataset) else load_dataset(data, strict=strict, config=config.load)
    if len(ds.runs) < 2:
        raise DatasetError(f"{ds.path}: the ensemble step needs at least 2 usable runs, found {len(ds.runs)}")
    prepared, scales = prepare_runs(data if isinstance(data, PreparedDataset) else ds.runs, config)
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
