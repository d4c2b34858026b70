"""The default fit: integral-form discovery, long-time polish, attractor check, fallback.

Steps of :meth:`DiscoveryMethod.fit` (``FitConfig(method="discovery")``, the default of ``python -m fitting fit``):

1. :func:`fitting.discovery.discover_model` selects the terms and fits them by integral-form least
   squares on all runs pooled (with their standard errors).
2. The long-time refinement (:func:`fitting.refine.refine`: attractor shape, Poincare map, frequency)
   polishes the discovered coefficients jointly on all runs inside a box of ``FitConfig.polish_se``
   standard errors around them (``FitConfig.polish``), so the polish cannot undo what the data resolve.
   The per-run losses of the polished model are the attractor check.
3. If the polished model blows up on any run, the fallbacks are tried: the discovered model as the
   regression gave it, then those of :func:`fitting.final_checks.fallback_candidates`; the best sane one is
   re-optimised and ``model.json["fallback"]`` says so; with none, :class:`fitting.final_checks.NoSaneModelError`.
4. Per run, least squares of the smoothed accelerations on the selected terms (one run at a time) gives
   ``per_run`` and the across-run ``zscores`` of ``model.json`` (docs/formats.md); it is not refined per run.
5. Oracle standard errors of the final model's terms (:mod:`fitting.oracle`).
"""
from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import Sequence

import numpy as np

from .config import FitConfig
from .discovery import discover_model
from .ensemble import least_squares_on_support, select_terms, term_statistics
from .final_checks import fall_back, final_oracle
from .methods import FitContext, register_method
from .model import PolynomialModel, Scales
from .refine import refine
from .regression import scaled_data, scaled_library
from .results import FitResult, PreparedRun, RunEstimate
from .selection_rules import support_text

__all__ = ["DiscoveryMethod"]

logger = logging.getLogger(__name__)


@dataclass(frozen=True)
class DiscoveryMethod:
    """The default fit (module docstring) as a :class:`fitting.methods.FittingMethod`."""

    name: str = "discovery"
    summary: str = ("integral-form discovery with model-based states, polished by the long-time refinement")
    #: the discovery's own settings (a paper fit's model.json leaves them out)
    private_settings: tuple[str, ...] = ("discovery", "polish", "polish_se")

    def fit(self, prepared: Sequence[PreparedRun], scales: Scales, config: FitConfig,
            context: FitContext) -> FitResult:
        """Steps 1-5 of the module docstring on prepared runs; ``rule`` of the result is None (the discovery
        selects the terms itself) and ``discovery`` holds its path."""
        derivs = [p.derivs for p in prepared]
        disc = discover_model([p.run for p in prepared], derivs, config.discovery)
        mask = disc.mask
        logger.info("discovery (%s after %d passes): %d terms: %s", "converged" if disc.converged else "not converged",
                    len(disc.iterations), int(mask.sum()), support_text(mask))
        # ---- long-time polish inside a box of a few standard errors ------------------------------------------------
        start = disc.model
        se_scaled = np.abs(scales.to_scaled(disc.std_errors))
        half = np.where(mask, np.maximum(config.polish_se * se_scaled, 1e-12), 0.0)
        logger.info("long-time polish of the discovered model on %d runs (box +-%g standard errors)", len(derivs),
                    config.polish_se)
        joint = refine(start, derivs, scales, config.polish, mask=mask, half_width=half)
        # ---- per run: least squares on the selected terms (per_run and zscores of model.json) ----------------------
        X, A = scaled_data(derivs, scales)
        lib = scaled_library(derivs, scales, config.regression.matched_filter)
        run_fits = [RunEstimate(name=p.run.name,
                                model=PolynomialModel(scales.to_si(least_squares_on_support([X[k]], [A[k]], mask,
                                                                                            [lib[k]]))),
                                loss=joint.per_run_start[k])  # the discovered model's long-time loss on this run
                    for k, p in enumerate(prepared)]
        stats = term_statistics([f.model for f in run_fits])
        logger.info("final mean loss %.4g (shape %.3g, Poincare %.3g, frequency %.3g)", joint.loss_end.total,
                    joint.loss_end.shape, joint.loss_end.poincare, joint.loss_end.frequency)
        fallback = None
        joint_start = start
        if joint.loss_end.blown_up:
            first = [("discovered model without the polish (integral-form least squares)", start)]
            joint_start, joint, fallback = fall_back(joint, mask, stats, [f.model for f in run_fits], None, derivs,
                                                     scales, config, first=first)
            mask = joint.model.support
        oracle = final_oracle(joint.model, prepared, context.noise)
        return FitResult(runs=list(prepared), scales=scales, pooled_regression=disc.model, run_fits=run_fits,
                         stats=stats, mask=mask, joint_start=joint_start, joint=joint, config=config,
                         mask_zscore=select_terms(stats, config.ensemble), rule=None, fallback=fallback,
                         oracle=oracle, discovery=disc)


register_method(DiscoveryMethod())
