"""The paper's method (``--method paper``): per-run SINDy and long-time refinement, ensemble selection, joint fit.

Steps of :meth:`PaperMethod.fit`:

1. The pooled integral-form selection (:func:`fitting.derivatives.integral_form.integral_form_selection`), a cross-check
   reported next to the model.
2. The regression C0 on all runs pooled; its support plus the damping terms are the candidate terms.
3. Per run, the regression C0 on the candidate terms and its long-time refinement (:func:`refine_run`, in
   parallel through :func:`cubedimer.executor.map_ordered`).  Each finished refinement is saved to
   ``cache_dir/<file stem>.json`` with a fingerprint of its input and settings, so an interrupted fit resumes.
4. z-scores and inclusion frequencies across runs; the selection rule (``SelectionConfig.rule``, a registered
   :class:`fitting.selection.rules.SelectionRule`) selects the minimal model, backward elimination on the joint
   long-time loss following where the rule asks for it.
5. Joint re-optimisation of the minimal model on all runs; the fallback when it blows up and the oracle standard
   errors (:mod:`fitting.uncertainty.final_checks`).
"""
from __future__ import annotations

import hashlib
import json
import logging
from dataclasses import dataclass
from pathlib import Path
from typing import Sequence

import numpy as np

from cubedimer.atomic import write_json
from cubedimer.executor import map_ordered
from cubedimer.terms import EQUATION_NAMES
from ..config import FitConfig
from ..derivatives.integral_form import METHOD as INTEGRAL_METHOD
from ..derivatives.integral_form import IntegralSelection, integral_form_selection
from ..derivatives.savitzky_golay import Derivatives
from ..description import DescriptionTable, MethodDescription, anti_damping_text, damping_rates, model_found_text
from ..method_settings import PaperMethodConfig
from ..model import DAMPING_TERMS, TERMS, PolynomialModel, Scales
from ..refinement.long_time import Objective, RefineConfig, RefineResult, default_substeps, refine, scaled_reference
from ..results import EnsembleExtras, FitResult, PreparedRun, RunFit, support_terms
from ..selection.backward_elimination import SelectionResult, backward_elimination
from ..selection.ensemble import least_squares_on_support, select_terms, term_statistics
from ..selection.rules import SELECTION_RULES, SelectionEvidence, support_text
from ..selection.sparse_regression import fit_regression, scaled_data, scaled_library
from ..uncertainty.final_checks import fall_back, final_oracle
from .registry import FitContext, register_method

__all__ = ["PaperMethod", "PaperExtras", "candidate_terms", "refine_run"]

logger = logging.getLogger(__name__)


@dataclass(frozen=True, eq=False)
class PaperExtras(EnsembleExtras):
    """What the paper's method produces beyond :class:`fitting.results.FitResult` (its ``extras``).

    Attributes
    ----------
    stats, mask_zscore :
        As :class:`fitting.results.EnsembleExtras` (of the per-run refined models).
    rule : str
        The selection rule that produced the support (:data:`fitting.selection.rules.SELECTION_RULES`).
    selection, candidate_fit : SelectionResult, RefineResult or None
        Backward elimination and the joint fit of its candidate support (rules that eliminate), else None.
    integral_form : dict or None
        The pooled integral-form cross-check per equation (None: the runs are shorter than one window).
    """

    rule: str = "zscore"
    selection: SelectionResult | None = None
    candidate_fit: RefineResult | None = None
    integral_form: dict[str, IntegralSelection] | None = None

    def record(self, result: FitResult) -> dict:
        """:class:`~fitting.results.EnsembleExtras`'s keys, the elimination in ``selection`` and the cross-check
        in ``integral_form``."""
        selection = self.selection_record(result, self.rule)
        if self.selection is not None:
            selection["backward"] = {"alpha": result.config.method.selection.alpha,
                                     "selected_terms": support_terms(self.selection.mask),
                                     "steps": [s.to_dict() for s in self.selection.steps]}
        if self.candidate_fit is not None:
            selection["candidate_fit"] = {"equations": self.candidate_fit.model.equations(),
                                          "loss": self.candidate_fit.loss_end.to_dict()}
        integral = None if self.integral_form is None else {
            "method": INTEGRAL_METHOD, **{eq: s.to_json() for eq, s in self.integral_form.items()}}
        return {**super().record(result), "selection": selection, "integral_form": integral}


def candidate_terms(c0_joint: PolynomialModel) -> np.ndarray:
    """Candidate terms for the per-run fits: the pooled regression's support plus the damping terms."""
    mask = c0_joint.support.copy()
    for q, eq in enumerate(EQUATION_NAMES):
        mask[q, TERMS.index(DAMPING_TERMS[eq])] = True
    return mask


def refine_run(task: tuple[str, Derivatives, Scales, PaperMethodConfig, np.ndarray | None]) -> RunFit:
    """Per-run regression (C0) and long-time refinement; module-level so it can be pickled."""
    name, d, scales, config, candidates = task
    c0 = fit_regression([d], scales, config.regression, candidates=candidates)
    mask = c0.support.copy()
    for q, eq in enumerate(EQUATION_NAMES):  # damping terms are always refined (and always kept)
        mask[q, TERMS.index(DAMPING_TERMS[eq])] = True
    res = refine(c0, [d], scales, config.refine, mask=mask)
    return RunFit(name=name, c0=c0, refined=res.model, loss_c0=res.loss_start, loss_refined=res.loss_end,
                  history=res.history, n_evals=res.n_evals, status=res.status)


def _fingerprint(p: PreparedRun, scales: Scales, config: FitConfig, candidates: np.ndarray) -> str:
    h = hashlib.sha256()
    for a in (p.run.t, p.run.y, p.run.theta):
        h.update(np.ascontiguousarray(a).tobytes())
    h.update(repr((scales, config.smoothing, config.method.regression, config.method.refine)).encode())
    h.update(np.packbits(candidates).tobytes())
    return h.hexdigest()[:32]


def _refine_runs(prepared: Sequence[PreparedRun], scales: Scales, config: FitConfig, candidates: np.ndarray,
                 context: FitContext) -> list[RunFit]:
    """Step 3 of the module docstring, resumable from ``context.cache_dir``."""
    derivs = [p.derivs for p in prepared]
    fits: list[RunFit | None] = [None] * len(prepared)
    fps = [_fingerprint(p, scales, config, candidates) for p in prepared]
    cache = Path(context.cache_dir) if context.cache_dir is not None else None
    todo = []
    for i, p in enumerate(prepared):
        if cache is not None:
            f = cache / f"{Path(p.run.name).stem}.json"
            if f.exists():
                try:
                    d = json.loads(f.read_text())
                    if d.get("fingerprint") == fps[i]:
                        fits[i] = RunFit.from_json(d)
                        continue
                except (ValueError, KeyError, TypeError):
                    pass  # unreadable cache: recompute
        todo.append(i)
    if len(todo) < len(prepared):
        logger.info("resuming: %d of %d run refinements loaded from %s", len(prepared) - len(todo), len(prepared), cache)

    def save(k: int, rf: RunFit) -> None:
        i = todo[k]
        fits[i] = rf
        if cache is not None:
            write_json(cache / f"{Path(rf.name).stem}.json", {**rf.to_json(), "fingerprint": fps[i]})

    map_ordered(refine_run, [(prepared[i].run.name, derivs[i], scales, config.method, candidates) for i in todo],
                config=context.executor, desc="refining runs", progress=context.progress, on_result=save)
    return list(fits)  # type: ignore[arg-type]


@dataclass(frozen=True)
class PaperMethod:
    """The source paper's pipeline (module docstring) as a :class:`fitting.methods.registry.FittingMethod`."""

    name: str = "paper"
    summary: str = ("per-run SINDy and long-time refinement, ensemble selection (--selection), joint "
                    "re-optimisation of the minimal model")
    #: its settings (``FitConfig.method``), with the options it accepts
    config_type: type = PaperMethodConfig

    def fit(self, prepared: Sequence[PreparedRun], scales: Scales, config: FitConfig,
            context: FitContext) -> FitResult:
        """Steps 1-5 of the module docstring on prepared runs."""
        derivs = [p.derivs for p in prepared]
        settings: PaperMethodConfig = config.method
        try:
            integral = integral_form_selection([p.run for p in prepared], derivs, alpha=settings.selection.alpha,
                                               prepared=[p.preparation for p in prepared])
            logger.info("pooled integral form (cross-check): %s", "; ".join(
                f"{eq}: " + ", ".join(f"{t} {c:.3g} +- {e:.2g}" for t, c, e in zip(s.terms, s.coefficients, s.std_errors))
                for eq, s in integral.items()))
        except ValueError as err:  # runs shorter than one window
            logger.info("pooled integral form skipped: %s", err)
            integral = None
        c0_joint = fit_regression(derivs, scales, settings.regression)
        candidates = candidate_terms(c0_joint)
        run_fits = _refine_runs(prepared, scales, config, candidates, context)
        # ---- ensemble and selection ----------------------------------------------------
        stats = term_statistics([f.refined for f in run_fits])
        mask_z = select_terms(stats, settings.ensemble)
        logger.info("z-score rule (z > %g plus damping): %d terms: %s", settings.ensemble.z_threshold,
                    int(mask_z.sum()), support_text(mask_z))
        X, A = scaled_data(derivs, scales)
        lib = scaled_library(derivs, scales, settings.regression.matched_filter)
        refs = [scaled_reference(d, scales) for d in derivs]
        per_run_scaled = np.array([scales.to_scaled(f.refined.coef) for f in run_fits])

        def best_start(mask: np.ndarray, jcfg: RefineConfig) -> tuple[float, np.ndarray]:
            """The better (lower joint loss) of the per-run median and least squares on ``mask``."""
            best = None
            for c in (np.where(mask, np.median(per_run_scaled, axis=0), 0.0),
                      least_squares_on_support(X, A, mask, lib)):
                obj = Objective(refs, mask, default_substeps(c, refs[0].dt, jcfg.h_omega), jcfg.weights)
                val = obj(c[mask])
                if best is None or val < best[0]:
                    best = (val, c)
            return best

        selection = cand_fit = None
        rule = SELECTION_RULES[settings.selection.rule]
        eliminate = rule.eliminates(settings.selection)
        if eliminate and 0.5 ** len(derivs) >= settings.selection.alpha:
            # the one-sided paired Wilcoxon test on R runs cannot reach p < alpha (min p = 2^-R)
            logger.info("%d runs are too few for the Wilcoxon test at alpha = %g: using the z-score rule", len(derivs),
                        settings.selection.alpha)
            rule, eliminate = SELECTION_RULES["zscore"], False
        mask = rule.support(SelectionEvidence(stats, mask_z, candidates, settings.ensemble), settings.selection)
        if eliminate:
            val, c = best_start(mask, settings.candidate_joint)
            logger.info("joint refinement of the %d candidate terms (start loss %.4g)", int(mask.sum()), val)
            cand_fit = refine(PolynomialModel(scales.to_si(c)), derivs, scales, settings.candidate_joint, mask=mask)
            logger.info("backward elimination on the joint loss (start loss %.4g)", cand_fit.loss_end.total)
            selection = backward_elimination(cand_fit.model, mask, derivs, scales, settings.selection, context.executor)
            mask = selection.mask
            c = scales.to_scaled(selection.model.coef)
            val = float(np.mean(selection.per_run))
        else:
            val, c = best_start(mask, settings.joint)
        logger.info("selected (%s) %d terms: %s", rule.name, int(mask.sum()), support_text(mask))
        # ---- joint re-optimisation of the minimal model -----------------------------------
        joint_start = PolynomialModel(scales.to_si(c))
        logger.info("joint re-optimisation of the minimal model on %d runs (start loss %.4g)", len(derivs), val)
        joint = refine(joint_start, derivs, scales, settings.joint, mask=mask)
        logger.info("final mean loss %.4g (shape %.3g, Poincare %.3g, frequency %.3g)", joint.loss_end.total,
                    joint.loss_end.shape, joint.loss_end.poincare, joint.loss_end.frequency)
        fallback = None
        if joint.loss_end.blown_up:
            joint_start, joint, fallback = fall_back(joint, mask, stats, [f.c0 for f in run_fits], integral, derivs,
                                                     scales, settings.joint)
            mask = joint.model.support
        oracle = final_oracle(joint.model, prepared, context.noise)
        extras = PaperExtras(stats=stats, mask_zscore=mask_z, rule=rule.name, selection=selection,
                             candidate_fit=cand_fit, integral_form=integral)
        return FitResult(runs=list(prepared), scales=scales, pooled_regression=c0_joint, run_fits=run_fits, mask=mask,
                         joint_start=joint_start, joint=joint, config=config, extras=extras, fallback=fallback,
                         oracle=oracle)

    def describe(self, result: FitResult) -> MethodDescription:
        """The regression, the per-run refinements and the selection rule (its own ``description``) that gave the
        minimal model, with each term's z-score and the p-value of its ensemble mean."""
        from ..output.model_file import fit_record

        return self.describe_record(fit_record(result))

    def describe_record(self, doc: dict) -> MethodDescription:
        """:meth:`describe` from the fit's model.json document (a stored fit)."""
        rule = SELECTION_RULES.get(doc.get("selection", {}).get("rule", "zscore"))
        rule_text = rule.description if rule is not None else doc.get("selection", {}).get("rule", "zscore")
        text = ("Regression on accelerations, refinement of every run against its long-time behaviour, and the ensemble "
                "rule, " + rule_text + ", plus viscous damping, "
                + model_found_text(doc, "give the minimal model", "gave a minimal model")
                + anti_damping_text(damping_rates(doc["equations"])))
        pvalues = doc.get("selection", {}).get("mean_pvalues", {})
        table = DescriptionTable("Minimal model (SI)", ("equation", "term", "coefficient", "z-score",
                                                        "p (ensemble mean = 0)"),
                                 tuple((eq, t, c, doc["zscores"][eq].get(t), pvalues.get(eq, {}).get(t))
                                       for eq in ("yddot", "thetaddot") for t, c in doc["equations"][eq].items()))
        return MethodDescription(text, table, selected_by=rule.selected_by if rule is not None else "")


register_method(PaperMethod())
