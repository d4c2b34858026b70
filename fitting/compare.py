"""Model comparison: a variant against the minimal model on every run.

Each model is simulated from every run's initial state; the per-run shape and Poincare errors
(:mod:`fitting.refinement.losses`) are compared with the Wilcoxon signed-rank test on the paired per-run
differences (scipy.stats.wilcoxon, one-sided ``variant worse than reference``, and two-sided).
A variant is typically the minimal model without some terms (by default its cross-coupling
terms: theta/thetadot terms in yddot and y/ydot terms in thetaddot), re-optimised jointly on all
runs with the same loss so that the comparison is between the best models of each structure.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np
from numpy.typing import NDArray
from scipy.stats import wilcoxon

from cubedimer.terms import EQUATION_NAMES, parse_term
from .derivatives.savitzky_golay import Derivatives
from .model import EXPONENTS, TERMS, PolynomialModel, Scales
from .refinement.long_time import JOINT_REFINE, Objective, RefineConfig, default_substeps, refine, scaled_reference
from .refinement.losses import LossTerms, LossWeights

__all__ = ["per_run_losses", "cross_coupling_mask", "drop_terms", "WilcoxonResult", "paired_wilcoxon",
           "Comparison", "compare_models"]


def per_run_losses(model: PolynomialModel, derivs: Sequence[Derivatives], scales: Scales,
                   weights: LossWeights = LossWeights(), h_omega: float = 0.05) -> list[LossTerms]:
    """Loss terms of ``model`` on every run (simulated from each run's initial state)."""
    refs = [scaled_reference(d, scales) for d in derivs]
    c = scales.to_scaled(model.coef)
    mask = model.support if model.support.any() else np.ones_like(model.support)
    obj = Objective(refs, mask, default_substeps(c, refs[0].dt, h_omega), weights)
    return obj.per_run(c)


def cross_coupling_mask(model: PolynomialModel) -> NDArray[np.bool_]:
    """Mask (2, 35) of the model's cross-coupling terms: terms of yddot containing theta or
    thetadot, terms of thetaddot containing y or ydot."""
    e = EXPONENTS
    in_y = (e[:, 2] + e[:, 3]) > 0
    in_t = (e[:, 0] + e[:, 1]) > 0
    return model.support & np.vstack([in_y, in_t])


def drop_terms(model: PolynomialModel, terms: Sequence[str]) -> PolynomialModel:
    """Copy of ``model`` without the given terms, written ``eq:term`` (e.g. ``thetaddot:y^2*theta``)
    or ``term`` (both equations)."""
    mask = model.support.copy()
    index = {tuple(v): j for j, v in enumerate(EXPONENTS)}
    for spec in terms:
        eq, _, term = spec.rpartition(":")
        j = index.get(tuple(parse_term(term.strip())))
        if j is None:
            raise ValueError(f"term {term!r} is not in the cubic library")
        rows = range(2) if not eq else [EQUATION_NAMES.index(eq.strip())]
        for q in rows:
            mask[q, j] = False
    return model.with_mask(mask)


@dataclass(frozen=True)
class WilcoxonResult:
    """Paired test on per-run errors: median difference (variant - reference) and p-values."""

    statistic: float
    p_greater: float
    p_two_sided: float
    median_difference: float
    n: int


def paired_wilcoxon(variant: NDArray, reference: NDArray) -> WilcoxonResult:
    """Wilcoxon signed-rank test of ``variant - reference`` (H1 for ``p_greater``: variant larger)."""
    a, b = np.asarray(variant, float), np.asarray(reference, float)
    d = a - b
    if np.all(d == 0):
        return WilcoxonResult(0.0, 1.0, 1.0, 0.0, d.size)
    g = wilcoxon(a, b, alternative="greater")
    t = wilcoxon(a, b, alternative="two-sided")
    return WilcoxonResult(float(g.statistic), float(g.pvalue), float(t.pvalue), float(np.median(d)), d.size)


@dataclass(frozen=True, eq=False)
class Comparison:
    """Per-run errors of a variant and of the reference model, and the paired tests."""

    names: list[str]
    reference: PolynomialModel
    variant: PolynomialModel
    reference_losses: list[LossTerms]
    variant_losses: list[LossTerms]
    shape_test: WilcoxonResult
    poincare_test: WilcoxonResult

    def to_json(self) -> dict:
        from dataclasses import asdict
        return {
            "reference": self.reference.equations(), "variant": self.variant.equations(), "units": "SI",
            "per_run": [{"file": n, "reference": r.to_dict(), "variant": v.to_dict()}
                        for n, r, v in zip(self.names, self.reference_losses, self.variant_losses)],
            "wilcoxon_shape": asdict(self.shape_test), "wilcoxon_poincare": asdict(self.poincare_test),
        }


def compare_models(reference: PolynomialModel, variant: PolynomialModel, derivs: Sequence[Derivatives],
                   scales: Scales, names: Sequence[str] | None = None, reoptimise: bool = True,
                   config: RefineConfig = JOINT_REFINE) -> Comparison:
    """Compare ``variant`` (re-optimised jointly on all runs if ``reoptimise``) with ``reference``."""
    if reoptimise and variant.support.any():
        variant = refine(variant, derivs, scales, config).model
    ref_l = per_run_losses(reference, derivs, scales, config.weights)
    var_l = per_run_losses(variant, derivs, scales, config.weights)
    names = list(names) if names is not None else [f"run{i + 1:02d}" for i in range(len(derivs))]
    return Comparison(names=names, reference=reference, variant=variant, reference_losses=ref_l,
                      variant_losses=var_l,
                      shape_test=paired_wilcoxon([v.shape for v in var_l], [r.shape for r in ref_l]),
                      poincare_test=paired_wilcoxon([v.poincare for v in var_l], [r.poincare for r in ref_l]))
