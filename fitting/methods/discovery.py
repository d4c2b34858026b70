"""The default fit: integral-form discovery, long-time polish, attractor check, fallback.

Steps of :meth:`DiscoveryMethod.fit` (settings :class:`fitting.method_settings.DiscoveryMethodConfig`, the default
of :class:`fitting.config.FitConfig` and of ``python -m fitting fit``):

1. :func:`fitting.selection.integral_discovery.discover_model` selects the terms and fits them by integral-form least
   squares on all runs pooled (with their standard errors).
2. The long-time refinement (:func:`fitting.refinement.long_time.refine`: attractor shape, Poincare map, frequency)
   polishes the discovered coefficients jointly on all runs inside a box of ``polish_se``
   standard errors around them (``polish``), so the polish cannot undo what the data resolve.
   The per-run losses of the polished model are the attractor check.
3. If the polished model blows up on any run, the fallbacks are tried: the discovered model as the
   regression gave it, then those of :func:`fitting.uncertainty.final_checks.fallback_candidates` (the terms dropped in
   the order of the discovery's own z, smallest first); the best sane one is
   re-optimised and ``model.json["fallback"]`` says so; with none, :class:`fitting.uncertainty.final_checks.NoSaneModelError`.
4. Per run, least squares of the smoothed accelerations on the selected terms (one run at a time) gives
   ``per_run`` and the across-run ``zscores`` of ``model.json`` (docs/formats.md); it is not refined per run.
5. Oracle standard errors of the final model's terms (:mod:`fitting.uncertainty.oracle`).
"""
from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import Sequence

import numpy as np

from cubedimer.terms import EQUATION_NAMES
from ..config import FitConfig
from ..description import (FIT_FIGURES, DescriptionTable, MethodDescription, anti_damping_text, damping_rates,
                           model_found_text)
from ..method_settings import DiscoveryMethodConfig
from ..model import PolynomialModel, Scales
from ..output.model_file import fit_record, recorded_settings
from ..refinement.long_time import refine
from ..results import EnsembleExtras, FitResult, PreparedRun, RunEstimate
from ..selection.ensemble import least_squares_on_support, select_terms, term_statistics
from ..selection.discovery_config import FEW_RUNS_MODE, MODEL_ERROR_MODE
from ..selection.integral_discovery import DiscoveryResult, discover_model
from ..selection.rules import support_text
from ..selection.sparse_regression import scaled_data, scaled_library
from ..uncertainty.final_checks import fall_back, final_oracle
from .registry import FitContext, register_method

__all__ = ["DiscoveryMethod", "DiscoveryExtras", "discovery_description", "PARETO_FIGURE", "FRONT_FIGURE"]

logger = logging.getLogger(__name__)


@dataclass(frozen=True, eq=False)
class DiscoveryExtras(EnsembleExtras):
    """What the discovery produces beyond :class:`fitting.results.FitResult` (its ``extras``).

    Attributes
    ----------
    stats, mask_zscore :
        As :class:`fitting.results.EnsembleExtras` (of the per-run least squares on the selected terms).
    discovery : DiscoveryResult
        The integral-form discovery: its passes, standard errors and Pareto front.
    """

    discovery: DiscoveryResult | None = None

    def record(self, result: FitResult) -> dict:
        """:class:`~fitting.results.EnsembleExtras`'s keys, ``discovery`` and, in ``integral_form``, the
        discovery's pooled integral-form estimates in the cross-check's place (same keys)."""
        disc = self.discovery.to_json()
        integral = {"method": disc["method"], **{
            eq: {k: disc[eq][k] for k in ("terms", "window_s", "residual_std")} for eq in EQUATION_NAMES}}
        return {**super().record(result), "integral_form": integral, "discovery": disc}


@dataclass(frozen=True)
class DiscoveryMethod:
    """The default fit (module docstring) as a :class:`fitting.methods.registry.FittingMethod`."""

    name: str = "discovery"
    summary: str = ("integral-form discovery with model-based states, polished by the long-time refinement")
    #: its settings (``FitConfig.method``), with the options it accepts
    config_type: type = DiscoveryMethodConfig

    def fit(self, prepared: Sequence[PreparedRun], scales: Scales, config: FitConfig,
            context: FitContext) -> FitResult:
        """Steps 1-5 of the module docstring on prepared runs; the result's ``extras`` (:class:`DiscoveryExtras`)
        hold the discovery's path."""
        derivs = [p.derivs for p in prepared]
        settings: DiscoveryMethodConfig = config.method
        disc = discover_model([p.run for p in prepared], derivs, settings.selection,
                              prepared=[p.preparation for p in prepared])
        mask = disc.mask
        logger.info("discovery (%s after %d passes): %d terms: %s", "converged" if disc.converged else "not converged",
                    len(disc.iterations), int(mask.sum()), support_text(mask))
        # ---- long-time polish inside a box of a few standard errors ------------------------------------------------
        start = disc.model
        se_scaled = np.abs(scales.to_scaled(disc.std_errors))
        half = np.where(mask, np.maximum(settings.polish_se * se_scaled, 1e-12), 0.0)
        logger.info("long-time polish of the discovered model on %d runs (box +-%g standard errors)", len(derivs),
                    settings.polish_se)
        joint = refine(start, derivs, scales, settings.polish, mask=mask, half_width=half)
        # ---- per run: least squares on the selected terms (per_run and zscores of model.json) ----------------------
        X, A = scaled_data(derivs, scales)
        lib = scaled_library(derivs, scales, settings.regression.matched_filter)
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
                                                     scales, settings.joint, first=first, z=disc.z)
            mask = joint.model.support
        oracle = final_oracle(joint.model, prepared, context.noise)
        extras = DiscoveryExtras(stats=stats, mask_zscore=select_terms(stats, settings.ensemble), discovery=disc)
        return FitResult(runs=list(prepared), scales=scales, pooled_regression=disc.model, run_fits=run_fits, mask=mask,
                         joint_start=joint_start, joint=joint, config=config, extras=extras, fallback=fallback,
                         oracle=oracle)

    def describe(self, result: FitResult) -> MethodDescription:
        """:func:`discovery_description` of the result's model.json record."""
        return discovery_description(fit_record(result))

    def describe_record(self, record: dict) -> MethodDescription:
        """:meth:`describe` from the fit's model.json document (a stored fit)."""
        return discovery_description(record)


#: The Pareto-front figure of a discovery fit (written by :func:`fitting.output.plots.plot_fit`) and its caption.
PARETO_FIGURE = ("pareto.png", "Pareto front of the discovery: held-out error (5-fold over runs) against the number of "
                               "terms, per equation; red: selected; blue square: the knee.")


#: The front figure of a discovery fit (model size against the held-out long-time error) and its caption.
FRONT_FIGURE = ("front.png", "Front of the discovery: held-out long-time error from each held-out run's first state "
                             "(mean and standard error over folds of runs) against the terms of both equations; red: the "
                             "selected model (the default); blue square: the knee (smallest within one standard error "
                             "of the best).")


def discovery_description(record: dict) -> MethodDescription:
    """The account of a model found by the integral-form discovery, from its model.json ``record``
    (:func:`fitting.output.model_file.fit_record`): how it was found, each term with its standard error, oracle standard
    error and closest alias, the damping rule and the knee of the Pareto front."""
    disc = record.get("discovery") or {}
    oracle = record.get("oracle") or {}
    n_terms = sum(len(v) for v in record["equations"].values())
    rows, close = [], []
    for eq in ("yddot", "thetaddot"):
        for t, c in record["equations"][eq].items():
            d = disc.get(eq, {}).get("terms", {}).get(t, {})
            o = oracle.get(eq, {}).get(t, {})
            rows.append((eq, t, c, d.get("std_error"), d.get("z"), o.get("std_error"), o.get("z"), o.get("alias"),
                         o.get("alias_z")))
            if o.get("alias_z") is not None and np.isfinite(o["alias_z"]) and o["alias_z"] < 3.0:
                close.append(f"{eq}: {t} / {o['alias']} ({o['alias_z']:.1f})")
    found = model_found_text(record, f"gives a model of {n_terms} terms", "gave a model")
    text = ("The integral-form discovery (positions regressed on the double integrals of the 35 library terms in windows "
            "of 0.75 periods, pooled over the runs; Holm's rule at family-wise 0.01 with stepwise swaps; held-out "
            "pruning over runs; columns at the model's own velocities), polished against the long-time behaviour within "
            f"half a standard error, {found} Beside each term the "
            "oracle standard error says what the data could resolve at best (least squares on this support at the "
            "model's own noise-free trajectories, at the tracking noise estimated from the data), and the alias z how "
            "many noise standard deviations separate the support from the one where the term is replaced by its "
            "closest library rival: below about 3 no estimator tells the two apart reliably (the rival wins in "
            "Phi(-alias z / 2) of data sets).")
    damping = [f"{t} in {eq}" for eq, t in (("yddot", "ydot"), ("thetaddot", "thetadot")) if t in record["equations"][eq]]
    rates = damping_rates(record["equations"])
    selection = recorded_settings(record)["discovery"].get("selection") or {}
    if damping and selection.get("keep_damping", True):
        text += (f" The damping terms ({', '.join(damping)}) are kept as physical damping whatever their significance, as in "
                 "the source paper; Holm's rule selects the other terms.")
    # the rule keeps them as damping; a fitted rate of the wrong sign is said to be none
    text += anti_damping_text(rates)
    text += model_error_text(disc, selection)
    if close:
        text += " Terms close to an alias: " + "; ".join(close) + "."
    text += (" The Pareto front shows how much held-out error each further term buys: on a truth that is not sparse in "
             "the library (real dimers) the data resolve many small terms, and the knee of the front is the smaller "
             "model a physicist may prefer.")
    knee = disc.get("knee") or {}
    knee_terms = {eq: knee[eq] for eq in ("yddot", "thetaddot") if eq in knee}
    if len(knee_terms) == 2 and sum(len(t) for t in knee_terms.values()) < n_terms:
        tol = knee["tolerance"]
        text += (f" The smallest supports within {100 * tol:g} % of the best held-out error (the knee) have "
                 f"{sum(len(t) for t in knee_terms.values())} terms ("
                 + "; ".join(f"{eq}: {', '.join(t)}" for eq, t in knee_terms.items())
                 + f"); `--heldout-tolerance {tol:g}` (of `python -m fitting fit` and of this report) fits that model "
                 "(it also drops weak true terms near the information limit).")
    table = DescriptionTable("Discovered model (SI)", ("equation", "term", "coefficient", "std error", "z",
                                                       "oracle std error", "oracle z", "alias", "alias z"), tuple(rows))
    front = disc.get("front")
    figures = (PARETO_FIGURE, FRONT_FIGURE) if front else (PARETO_FIGURE,)
    text += front_text(front)
    return MethodDescription(text, table, (*figures, *FIT_FIGURES), selected_by="by integral-form discovery")


def front_text(front: dict | None) -> str:
    """The sentence on the front (model.json's ``discovery["front"]``): the selected model's held-out long-time error
    and the knee's; empty without a front."""
    from ..selection.front import ALONG_HORIZON_PERIODS

    if not front:
        return ""
    points = front["points"]
    sel = next((p for p in points if p["selected"]), None)
    knee = next((p for p in points if p["max_terms"] == front.get("knee_max_terms")), None)

    def said(p: dict) -> str:
        n = sum(p["n_terms"].values())
        se = f" +- {100 * p['error_se']:.2g}" if p.get("error_se") is not None else ""
        along = (f" ({100 * p['error_along']:.3g} % along the runs)" if p.get("error_along") is not None else "")
        return (f"{n} terms at {100 * p['error']:.3g}{se} %{along}" if p.get("error") is not None
                else f"{n} terms (blown up)")

    text = (f" On the front of model size against the held-out long-time error ({front['n_folds']}-fold over runs, "
            f"from each held-out run's first state, and along the runs restarted from the data every "
            f"{ALONG_HORIZON_PERIODS:g} slow periods)")
    if sel is not None:
        text += f", the selected model has {said(sel)}"
    if knee is not None and knee is not sel:
        text += (f"; the smallest within one standard error of the best has {said(knee)} (`--max-terms "
                 f"{knee['max_terms']}` fits it)")
    return text + "."


def model_error_text(disc: dict, settings: dict) -> str:
    """The sentences on the equations selected by held-out prediction because their residual showed model error
    (model.json's ``discovery[eq]["selection"]``, the rule's settings ``settings``: the discovery's selection
    settings, :func:`fitting.output.model_file.recorded_settings` ``["discovery"]["selection"]``) and on the
    output-error refinement of the coefficients (``discovery["output_error"]``); empty when every equation was
    selected by significance."""
    parts = []
    for eq in EQUATION_NAMES:
        sel = (disc.get(eq) or {}).get("selection") or {}
        if sel.get("rule") not in (MODEL_ERROR_MODE, FEW_RUNS_MODE):
            continue
        ratio, infl = sel.get("residual_to_noise"), sel.get("heldout_inflation")
        signs = []
        if ratio is not None and np.isfinite(ratio):
            signs.append(f"residual {ratio:.3f} times the tracking noise")
        if infl is not None and np.isfinite(infl):
            signs.append(f"held-out misfit above the in-sample one by {infl:.3g} times what white noise explains")
        parts.append(f"{eq} ({', '.join(signs)})" if signs else eq)
    if not parts:
        return ""
    se, tol = settings.get("model_error_se", 1.0), settings.get("model_error_tolerance", 0.0)
    within = f"{se:g} paired standard error{'' if se == 1 else 's'}"
    if tol:
        within += f", or {100 * tol:g} % of the held-out misfit's model-error part,"
    practical = settings.get("heldout_tolerance") or 0.0
    if practical:
        within += f" or {100 * practical:g} % of the best held-out RMS error (the practical threshold),"
    text = (" Model error: the cubic library does not hold the truth in " + " and ".join(parts) + ", so the "
            "standard errors and Holm's rule lose their meaning there; those equations were selected by held-out "
            f"prediction over runs instead (the smallest support on the elimination path within {within} of the "
            "best held-out error), and their standard errors are those of a residual that is partly model error.")
    overruled = [eq for eq in EQUATION_NAMES if ((disc.get(eq) or {}).get("selection") or {}).get("rule") == FEW_RUNS_MODE]
    if overruled:
        text += (f" In {' and '.join(overruled)} the few runs disagreed (a held-out run predicted more than "
                 f"{100 * (settings.get('few_runs_excess') or 0.1):g} % worse without terms the significance rule "
                 "holds), so the significance rule's support was kept instead.")
    oe = disc.get("output_error") or {}
    if oe.get("segments"):
        pruned, added = oe.get("pruned") or [], oe.get("added") or []
        support = oe.get("misfit_support", oe["misfit"]) if pruned or added else oe["misfit"]
        text += (f" The discovered coefficients were then refined by the output error: the model's trajectories "
                 f"fitted to {oe['segments']} segments of {oe['segment_s']:.3g} s of the runs, which lowered their "
                 f"RMS misfit from {oe['misfit_start']:.3g} to {support:.3g} times the tracking noise.")
        changes = []
        if pruned:
            changes.append(f"{_count(pruned)} the trajectories do not need {_were(pruned)} then pruned "
                           f"({', '.join(pruned)})")
        if added:
            changes.append(f"{_count(added)} {'they' if pruned else 'the trajectories'} need {_were(added)} "
                           f"{'' if pruned else 'then '}added ({', '.join(added)})")
        if changes:
            text += f" {' and '.join(changes)}, at a misfit of {oe['misfit']:.3g}."
        if practical and (settings.get("output_error") or {}).get("support_tolerance") is not None:
            text += (f" The practical threshold held there too: a term went if it raised the RMS misfit by at most "
                     f"{100 * practical:g} %, and none was added that lowered it by less.")
    return text


def _count(terms: list[str]) -> str:
    return f"{len(terms)} term{'s' if len(terms) > 1 else ''}"


def _were(terms: list[str]) -> str:
    return "were" if len(terms) > 1 else "was"


register_method(DiscoveryMethod())
