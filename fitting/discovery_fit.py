"""The default fit: integral-form discovery, long-time polish, attractor check, fallback.

Steps of :func:`fit_discovery` (``FitConfig(method="discovery")``, the default of ``python -m fitting fit``):

1. :func:`fitting.discovery.discover_model` selects the terms and fits them by integral-form least
   squares on all runs pooled (with their standard errors).
2. The long-time refinement (:func:`fitting.refine.refine`: attractor shape, Poincare map, frequency)
   polishes the discovered coefficients jointly on all runs inside a box of ``FitConfig.polish_se``
   standard errors around them (``FitConfig.polish``), so the polish cannot undo what the data resolve.
   The per-run losses of the polished model are the attractor check.
3. If the polished model blows up on any run, the fallbacks are tried: the discovered model as the
   regression gave it, then those of :func:`fitting.pipeline.fallback_candidates`; the best sane one is
   re-optimised and ``model.json["fallback"]`` says so; with none, :class:`fitting.pipeline.NoSaneModelError`.
4. Per run, least squares of the smoothed accelerations on the selected terms (one run at a time) gives
   ``per_run`` and the across-run ``zscores`` of ``model.json`` (docs/formats.md); it is not refined per run.
5. Oracle standard errors of the final model's terms (:mod:`fitting.oracle`).
"""
from __future__ import annotations

from typing import Callable, Sequence

import numpy as np

from .discovery import discover_model
from .ensemble import least_squares_on_support, select_terms, term_statistics
from .model import TERMS, PolynomialModel, Scales
from .refine import refine
from .regression import scaled_data, scaled_library
from cubedimer.terms import EQUATION_NAMES

__all__ = ["fit_discovery"]


def fit_discovery(prepared: Sequence, scales: Scales, config, log: Callable[[str], None], noise=None):
    """Steps 1-5 of the module docstring on prepared runs.

    Parameters
    ----------
    prepared : list of :class:`fitting.pipeline.PreparedRun`
    scales : Scales
    config : :class:`fitting.pipeline.FitConfig` with ``method == "discovery"``
    log : callable taking one message
    noise : :class:`fitting.oracle.NoiseLevels`, optional
        The oracle's tracking noise (default: estimated from the runs)

    Returns
    -------
    :class:`fitting.pipeline.FitResult` (``rule == "discovery"``, ``discovery`` set)
    """
    from .pipeline import FitResult, RunFit, _fall_back, _oracle

    derivs = [p.derivs for p in prepared]
    disc = discover_model([p.run for p in prepared], derivs, config.discovery)
    mask = disc.mask
    fmt = lambda m: "; ".join(f"{eq}: " + ", ".join(t for t, k in zip(TERMS, m[q]) if k)  # noqa: E731
                              for q, eq in enumerate(EQUATION_NAMES))
    log(f"discovery ({'converged' if disc.converged else 'not converged'} after {len(disc.iterations)} passes): "
        f"{int(mask.sum())} terms: {fmt(mask)}")
    # ---- long-time polish inside a box of a few standard errors ------------------------------------------------
    start = disc.model
    se_scaled = np.abs(scales.to_scaled(disc.std_errors))
    half = np.where(mask, np.maximum(config.polish_se * se_scaled, 1e-12), 0.0)
    log(f"long-time polish of the discovered model on {len(derivs)} runs (box +-{config.polish_se:g} standard errors)")
    joint = refine(start, derivs, scales, config.polish, mask=mask, half_width=half)
    # ---- per run: least squares on the selected terms (per_run and zscores of model.json) ----------------------
    X, A = scaled_data(derivs, scales)
    lib = scaled_library(derivs, scales, config.regression.matched_filter)
    run_fits = []
    for k, p in enumerate(prepared):
        m = PolynomialModel(scales.to_si(least_squares_on_support([X[k]], [A[k]], mask, [lib[k]])))
        lt = joint.per_run_start[k]  # the discovered model's long-time loss on this run
        run_fits.append(RunFit(name=p.run.name, c0=m, refined=m, loss_c0=lt, loss_refined=lt, history=np.zeros(0),
                               n_evals=0, status=0))
    stats = term_statistics([f.refined for f in run_fits])
    log(f"final mean loss {joint.loss_end.total:.4g} (shape {joint.loss_end.shape:.3g}, "
        f"Poincare {joint.loss_end.poincare:.3g}, frequency {joint.loss_end.frequency:.3g})")
    fallback = None
    joint_start = start
    if joint.loss_end.blown_up:
        first = [("discovered model without the polish (integral-form least squares)", start)]
        joint_start, joint, fallback = _fall_back(joint, mask, stats, run_fits, None, derivs, scales, config, log,
                                                  first=first)
        mask = joint.model.support
    oracle = _oracle(joint.model, prepared, log, noise)
    return FitResult(runs=list(prepared), scales=scales, c0_joint=disc.model, run_fits=run_fits, stats=stats,
                     mask=mask, joint_start=joint_start, joint=joint, config=config,
                     mask_zscore=select_terms(stats, config.ensemble), rule="discovery", fallback=fallback,
                     oracle=oracle, discovery=disc)

