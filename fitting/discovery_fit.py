"""The default fit: integral-form discovery, long-time polish, attractor check, fallback.

Steps of :func:`fit_discovery` (``FitConfig(method="discovery")``, the default of ``python -m fitting fit``):

1. :func:`fitting.discovery.discover_model` selects the terms and fits them by integral-form least
   squares on all runs pooled (with their standard errors).  A selected term (damping terms aside) whose
   oracle alias z is below :data:`UNRESOLVED_ALIAS_Z` cannot be told from its closest library alias: which of
   the two least squares picks is a coin toss (the alias wins in Phi(-alias z / 2), over 30 % of data sets).
   Such terms are excluded and the discovery is run again without them (:func:`resolved_discovery`; at most
   :data:`MAX_RESOLUTION_ROUNDS` times), so the model keeps only terms the data resolve.
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

__all__ = ["fit_discovery", "resolved_discovery", "UNRESOLVED_ALIAS_Z", "MAX_RESOLUTION_ROUNDS"]

#: A selected term whose oracle alias z is below this cannot be told from its closest library alias.
UNRESOLVED_ALIAS_Z = 1.0
#: Most re-runs of the discovery without unresolved terms (each costs one discovery and one oracle).
MAX_RESOLUTION_ROUNDS = 2


def resolved_discovery(runs: Sequence, derivs: Sequence, config, log: Callable[[str], None] = lambda m: None):
    """:func:`fitting.discovery.discover_model`, re-run without the selected terms (damping terms aside) whose
    oracle alias z at the data's tracking noise is below :data:`UNRESOLVED_ALIAS_Z` (module docstring, step 1).

    Returns
    -------
    (DiscoveryResult, list of str)
        The discovery and the excluded terms (``"EQUATION:TERM"``, empty when every selected term is resolved).
    """
    from dataclasses import replace

    from .model import damping_mask
    from .oracle import estimate_tracking_noise, oracle_standard_errors, runs_from_data

    disc = discover_model(runs, derivs, config)
    excluded: list[str] = list(config.excluded)
    try:
        noise = estimate_tracking_noise(runs)
        oracle_runs = runs_from_data(derivs)
    except ValueError as err:
        log(f"resolution check skipped: {err}")
        return disc, []
    forced = damping_mask() if config.keep_damping else np.zeros_like(disc.mask)
    for _ in range(MAX_RESOLUTION_ROUNDS):
        try:
            orc = oracle_standard_errors(disc.model, oracle_runs, noise)
        except ValueError as err:
            log(f"resolution check skipped: {err}")
            break
        unresolved = [f"{eq}:{t}" for q, eq in enumerate(EQUATION_NAMES) for t, o in orc.terms[eq].items()
                      if not forced[q, TERMS.index(t)] and o.alias_z < UNRESOLVED_ALIAS_Z]
        if not unresolved:
            break
        log("terms the data cannot tell from their closest library alias (alias z < "
            f"{UNRESOLVED_ALIAS_Z:g}), excluded and the discovery repeated: " + ", ".join(
                f"{u} / {orc.terms[u.split(':')[0]][u.split(':')[1]].alias} (alias z "
                f"{orc.terms[u.split(':')[0]][u.split(':')[1]].alias_z:.2g})" for u in unresolved))
        excluded += unresolved
        disc = discover_model(runs, derivs, replace(config, excluded=tuple(excluded)))
    return disc, excluded[len(config.excluded):]


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
    disc, _ = resolved_discovery([p.run for p in prepared], derivs, config.discovery, log)
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

