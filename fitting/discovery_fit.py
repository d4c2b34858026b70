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
4. Per run, the regression model C0 restricted to the selected terms (pysindy STLSQ, one run at a time) gives
   ``per_run`` and the across-run ``zscores`` of ``model.json`` (FORMATS.md); it is not refined per run.
5. Oracle standard errors of the final model's terms (:mod:`fitting.oracle`).
"""
from __future__ import annotations

from typing import Callable, Sequence

import numpy as np

from .discovery import discover_model
from .ensemble import term_statistics, select_terms
from .model import TERMS, Scales
from .refine import Objective, default_substeps, refine, scaled_reference
from .regression import fit_regression
from cubedimer.terms import EQUATION_NAMES

__all__ = ["fit_discovery"]


def fit_discovery(prepared: Sequence, scales: Scales, config, log: Callable[[str], None]):
    """Steps 1-5 of the module docstring on prepared runs.

    Parameters
    ----------
    prepared : list of :class:`fitting.pipeline.PreparedRun`
    scales : Scales
    config : :class:`fitting.pipeline.FitConfig` with ``method == "discovery"``
    log : callable taking one message

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
    # ---- per-run regression on the selected terms (per_run and zscores of model.json) -------------------------
    run_fits = []
    for p, d in zip(prepared, derivs):
        c0 = fit_regression([d], scales, config.regression, candidates=mask)
        cs = scales.to_scaled(c0.coef)
        ref = scaled_reference(d, scales)
        lt = Objective([ref], c0.support, default_substeps(cs, ref.dt, config.polish.h_omega),
                       config.polish.weights).per_run(cs)[0]
        run_fits.append(RunFit(name=p.run.name, c0=c0, refined=c0, loss_c0=lt, loss_refined=lt,
                               history=np.array([lt.total]), n_evals=0, status=0))
    stats = term_statistics([f.refined for f in run_fits])
    # ---- long-time polish inside a box of a few standard errors ------------------------------------------------
    start = disc.model
    se_scaled = np.abs(scales.to_scaled(disc.std_errors))
    half = np.where(mask, np.maximum(config.polish_se * se_scaled, 1e-12), 0.0)
    log(f"long-time polish of the discovered model on {len(derivs)} runs (box +-{config.polish_se:g} standard errors)")
    joint = refine(start, derivs, scales, config.polish, mask=mask, half_width=half)
    log(f"final mean loss {joint.loss_end.total:.4g} (shape {joint.loss_end.shape:.3g}, "
        f"Poincare {joint.loss_end.poincare:.3g}, frequency {joint.loss_end.frequency:.3g})")
    fallback = None
    joint_start = start
    if joint.loss_end.blown_up:
        first = [("discovered model without the polish (integral-form least squares)", start)]
        joint_start, joint, fallback = _fall_back(joint, mask, stats, run_fits, None, derivs, scales, config, log,
                                                  first=first)
        mask = joint.model.support
    oracle = _oracle(joint.model, prepared, log)
    return FitResult(runs=list(prepared), scales=scales, c0_joint=disc.model, run_fits=run_fits, stats=stats,
                     mask=mask, joint_start=joint_start, joint=joint, config=config,
                     mask_zscore=select_terms(stats, config.ensemble), rule="discovery", fallback=fallback,
                     oracle=oracle, discovery=disc)

