"""What every method does to its final model: the fallback when it blows up, and its oracle standard errors.

Never a blown-up model: when the final model leaves the blow-up bound on any run, :func:`fall_back` replaces it
by the best of the candidates the method offers first, (a) the model without its least significant terms (by the
method's own z when it has them, else by the per-run ensemble's p-values), (b)
the regression-only ensemble (median of the per-run regressions on the selected terms) and (c) the pooled
integral-form model, each integrated over every run and scored with the long-time loss; the winner is
re-optimised jointly and ``model.json["fallback"]`` says what happened.  If none of them integrates over every
run with a loss below :data:`MAX_SANE_LOSS`, :class:`NoSaneModelError` is raised and nothing is written.
"""
from __future__ import annotations

import logging
from typing import Sequence

import numpy as np

from cubedimer.terms import coefficient_labels
from ..derivatives.integral_form import IntegralSelection
from ..derivatives.savitzky_golay import Derivatives
from ..model import PolynomialModel, Scales, damping_mask
from ..refinement.long_time import Objective, RefineConfig, RefineResult, default_substeps, refine, scaled_reference
from ..refinement.losses import LossTerms
from ..selection.ensemble import TermStatistics, mean_pvalues
from .oracle import NoiseLevels, OracleResult, estimate_tracking_noise, oracle_standard_errors, runs_from_data

__all__ = ["MAX_SANE_LOSS", "NoSaneModelError", "fallback_candidates", "fall_back", "final_oracle"]

logger = logging.getLogger(__name__)

#: A fallback model must integrate over every run and have a mean long-time loss below this (the rest
#: model, a trajectory sitting at the origin, scores ~2.5: shape ~0.5, Poincare 1, frequency 1).
MAX_SANE_LOSS = 1.0


class NoSaneModelError(RuntimeError):
    """The final model blows up and no fallback integrates over every run (nothing is written)."""


def _n_blown(per_run: Sequence[LossTerms]) -> int:
    return sum(int(t.blown_up) for t in per_run)


def fallback_candidates(model: PolynomialModel, mask: np.ndarray, stats: TermStatistics,
                        per_run_regressions: Sequence[PolynomialModel],
                        integral: dict[str, IntegralSelection] | None,
                        z: np.ndarray | None = None) -> list[tuple[str, PolynomialModel]]:
    """The models tried when the final model blows up, in order of preference.

    1. ``model`` without its k least significant terms (the damping terms stay), for k = 1, 2, ...: the
       smallest ``|z|`` first when the method gives its own ``z`` (the discovery's coefficient over standard
       error, from all runs pooled), else the largest ensemble-mean p-value of the per-run models.  Per-run
       p-values make collinear terms (the cubic couplings of a large hinge swing) all look weak, and their
       chain then drops a term the motion needs first.
    2. The regression-only ensemble: the median over runs of the per-run regression models on ``mask``.
    3. The pooled integral-form model (its selected terms and coefficients), if available.

    Parameters
    ----------
    z : ndarray (2, 35), optional
        The method's coefficient / standard error of every term on ``model``'s support.
    """
    out: list[tuple[str, PolynomialModel]] = []
    with np.errstate(divide="ignore"):
        p = mean_pvalues(stats) if z is None else 1.0 / np.abs(np.asarray(z, float))  # larger: weaker
    removable = np.flatnonzero((model.support & ~damping_mask()).ravel())
    order = removable[np.argsort(-p.ravel()[removable], kind="stable")]  # least significant first
    labels = coefficient_labels().ravel()
    names = [labels[i] for i in order]
    keep = model.support.copy().ravel()
    for k, idx in enumerate(order[:-1] if len(order) > 1 else []):
        keep[idx] = False
        out.append((f"minimal model without {', '.join(names[:k + 1])}", model.with_mask(keep.reshape(mask.shape))))
    if len(per_run_regressions):
        c0 = np.median([m.coef for m in per_run_regressions], axis=0)
        out.append(("regression-only ensemble (median of the per-run C0 on the selected terms)",
                    PolynomialModel(np.where(mask, c0, 0.0))))
    if integral is not None:
        eqs = {eq: dict(zip(s.terms, map(float, s.coefficients))) for eq, s in integral.items()}
        out.append(("pooled integral-form model", PolynomialModel.from_equations(eqs)))
    return out


def fall_back(joint: RefineResult, mask: np.ndarray, stats: TermStatistics,
              per_run_regressions: Sequence[PolynomialModel], integral: dict[str, IntegralSelection] | None,
              derivs: Sequence[Derivatives], scales: Scales, config: RefineConfig,
              first: Sequence[tuple[str, PolynomialModel]] = (),
              z: np.ndarray | None = None) -> tuple[PolynomialModel, RefineResult, dict]:
    """Replace a blown-up final model by the best sane fallback (module docstring), re-optimised jointly.

    Parameters
    ----------
    joint : RefineResult
        The final joint optimisation whose model blew up.
    mask : ndarray of bool
        Its support.
    stats : TermStatistics
        Across-run statistics of the per-run models (which terms are least significant when ``z`` is not given).
    per_run_regressions : sequence of PolynomialModel
        Every run's regression model (their median on ``mask`` is a candidate).
    integral : dict or None
        The pooled integral-form selection per equation, a candidate if given.
    derivs, scales : the runs' derivatives and scales
    config : RefineConfig
        The joint re-optimisation (the method's ``joint`` settings), which scores and re-optimises the candidates.
    first : sequence of (name, PolynomialModel)
        Candidates tried before those of :func:`fallback_candidates`.
    z : ndarray (2, 35), optional
        The method's own z of the terms, which orders the terms dropped (:func:`fallback_candidates`).

    Returns
    -------
    (start of the re-optimisation, its result, the ``fallback`` record)

    Raises
    ------
    NoSaneModelError
        No candidate integrates over every run with a loss below ``MAX_SANE_LOSS``.
    """
    n_blown = _n_blown(joint.per_run_end)
    reason = (f"the re-optimised minimal model ({int(mask.sum())} terms) blows up on {n_blown} of "
              f"{len(derivs)} runs")
    logger.info("%s: trying fallbacks", reason)
    refs = [scaled_reference(d, scales) for d in derivs]
    tried, best = [], None
    for name, model in [*first, *fallback_candidates(joint.model, mask, stats, per_run_regressions, integral, z)]:
        c = scales.to_scaled(model.coef)
        m = model.support
        obj = Objective(refs, m, default_substeps(c, refs[0].dt, config.h_omega), config.weights)
        per = obj.per_run(np.where(m, c, 0.0))
        total = float(np.mean([t.total for t in per]))
        nb = _n_blown(per)
        tried.append({"name": name, "loss": total, "blown_up_runs": nb, "n_terms": int(m.sum())})
        logger.info("  fallback %s: %d terms, mean loss %.4g, blows up on %d runs", name, int(m.sum()), total, nb)
        if nb == 0 and total < MAX_SANE_LOSS and (best is None or total < best[0]):
            best = (total, name, model)
    if best is None:
        raise NoSaneModelError(f"{reason}, and no fallback (the model without its weakest terms, the regression-only "
                               "ensemble, the pooled integral-form model) integrates over every run; no model written")
    _, name, model = best
    logger.info("fallback used: %s; re-optimising it jointly", name)
    # refine never ends worse than its start, and a blow-up scores above MAX_SANE_LOSS: res integrates everywhere
    res = refine(model, derivs, scales, config, mask=model.support)
    logger.info("fallback final mean loss %.4g (shape %.3g, Poincare %.3g, frequency %.3g)", res.loss_end.total,
                res.loss_end.shape, res.loss_end.poincare, res.loss_end.frequency)
    record = {"reason": reason, "used": name, "order": "ensemble p-value" if z is None else "z", "candidates": tried,
              "blown_up_model": {"equations": joint.model.equations(), "loss": joint.loss_end.to_dict()}}
    return model, res, record


def final_oracle(model: PolynomialModel, prepared: Sequence, noise: NoiseLevels | None = None) -> OracleResult | None:
    """Oracle standard errors of ``model``'s terms on the prepared runs (:class:`fitting.results.PreparedRun`).

    At the tracking noise ``noise`` (the one the data set records, :func:`fitting.uncertainty.oracle.recorded_tracking_noise`),
    else at the noise estimated from the runs; None (logged) when the runs do not allow it.
    """
    derivs = [p.derivs for p in prepared]
    try:
        noise = noise or estimate_tracking_noise([p.run for p in prepared])
        res = oracle_standard_errors(model, runs_from_data(derivs), noise)
    except ValueError as err:
        logger.info("oracle skipped: %s", err)
        return None
    logger.info("oracle z at tracking noise (y, theta) %.3g, %.3g (SI): %s", noise.sigma_y, noise.sigma_theta, "; ".join(
        f"{eq}: " + ", ".join(f"{t} {o.z:.3g}" for t, o in terms.items()) for eq, terms in res.terms.items()))
    close = [f"{eq}: {t} / {o.alias} (alias z {o.alias_z:.2g})" for eq, terms in res.terms.items()
             for t, o in terms.items() if o.alias_z < 3.0]
    if close:
        logger.info("terms the data barely tell from their closest library alias (least squares picks the alias in "
                    "Phi(-alias_z / 2) of data sets): %s", "; ".join(close))
    return res
