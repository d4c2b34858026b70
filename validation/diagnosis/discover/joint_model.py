"""The identified candidates against the discovered library terms: held-out judgement and the joint model.

After the library search (:mod:`validation.diagnosis.discover.library_terms`), :func:`judge_candidates` judges the identified
candidates against the discovered terms on held-out runs: a candidate that no longer improves held-out runs once
the discovered terms are fitted (for example pair scattering's linear hinge stiffness standing in for a cubic
hardening) is not named.  :func:`joint_estimates` fits the named effects and the discovered terms together.
"""
from __future__ import annotations

import logging
from dataclasses import replace
from typing import Mapping, Sequence

import numpy as np
from numpy.typing import NDArray

from cubedimer.folds import run_folds

from .library_terms import (EQUATIONS, Discovery, dissipation_rows, integral_residuals, integrated_columns,
                            library_columns)
from ..calibrate.gap_model import GapFit, apply_gap_model, fit_gap_model
from ..calibrate.metrics import fit_gaps
from ..identify.statistics import sign_flip_pvalue
from ..prepare.problem import DiagnosisProblem
from ..prepare.simulation_terms import SimulationTerms

__all__ = ["judge_candidates", "joint_estimates"]

logger = logging.getLogger(__name__)


def _fraction(problem: DiagnosisProblem, i: int, q: int, rss: float) -> float:
    """Unexplained fraction beyond noise of coordinate q of run i for a residual sum of squares ``rss``."""
    pi = problem.runs[i].integral
    return (rss - pi.floor(q)) / max(float(np.sum(pi.target(q) ** 2)), 1e-300)


def _held_out_scores(problem: DiagnosisProblem, effects: Sequence[str], discovery: Discovery,
                     folds: int) -> NDArray[np.float64]:
    """K-fold over runs: per run, the mean over the three gap components (beyond noise) of a fit of ``effects``
    and then of the discovered terms made on the other folds.  Without energy-form terms, the integral-form
    terms are fitted on the fit's integral-form residuals (the y and theta components in their integral form)
    and the energy component is the fit's own; with them, every component comes from the rows the
    energy-form terms were found on (:func:`dissipation_rows`, which subtract the integral-form terms)."""
    energy_terms = discovery.names("energy")
    out = np.empty(len(problem))
    for train, test in run_folds(len(problem), folds):
        tr, te = problem.subset(train), problem.subset(test)
        fit = fit_gap_model(tr, effects)
        held = apply_gap_model(te, fit.calibration, fit.effects)
        if any(energy_terms.values()):
            cols_tr, res_tr, _ = dissipation_rows(tr, fit, discovery, energy_terms)
            cols_te, res_te, floors_te = dissipation_rows(te, held, discovery, energy_terms)
            coef = _least_squares(cols_tr, res_tr)
            # a run's weighted residual sum of squares is the sum of its three components beyond their floors
            rss = np.array([float(np.sum((b - c @ coef) ** 2)) for c, b in zip(cols_te, res_te)])
            out[test] = (rss - floors_te) / 3.0
        else:
            out[test] = _integral_components(tr, te, fit, held, discovery.names("integral")).mean(axis=1)
    return out


def _integral_components(tr: DiagnosisProblem, te: DiagnosisProblem, fit: GapFit, held: GapFit,
                         integral_terms: dict[str, list[str]]) -> NDArray[np.float64]:
    """Per test run (n_test, 3): the y and theta components in their integral form after ``integral_terms``
    fitted on the training runs' residuals, and the energy component of ``held``."""
    from cubedimer.terms import library_terms

    names = library_terms()
    res_tr, res_te = integral_residuals(tr, fit), integral_residuals(te, held)
    comps = np.zeros((len(te), 3))
    comps[:, 2] = fit_gaps(te.runs, held)[:, 2]
    for q, eq in enumerate(EQUATIONS):
        idx = [names.index(t) for t in integral_terms[eq]]
        e_te = [r[q] for r in res_te]
        if idx:
            c_tr = integrated_columns(tr, [c[:, idx] for c in library_columns(tr, q)], q)
            c_te = integrated_columns(te, [c[:, idx] for c in library_columns(te, q)], q)
            coef = _least_squares(c_tr, [r[q] for r in res_tr])
            e_te = [e - c @ coef for e, c in zip(e_te, c_te)]
        comps[:, q] = [_fraction(te, i, q, float(e @ e)) for i, e in enumerate(e_te)]
    return comps


def _least_squares(cols: Sequence[NDArray], rhs: Sequence[NDArray]) -> NDArray[np.float64]:
    """Coefficients of stacked columns against stacked right-hand sides (columns scaled to unit norm)."""
    x, b = np.concatenate(cols), np.concatenate(rhs)
    scale = np.maximum(np.sqrt(np.sum(x * x, axis=0)), 1e-300)
    return np.linalg.lstsq(x / scale, b, rcond=None)[0] / scale


def judge_candidates(problem: DiagnosisProblem, identified: Sequence[str], discovery: Discovery, alpha: float = 0.01,
                     folds: int = 5, group: Sequence[str] = (), partners: Mapping[str, str] | None = None
                     ) -> tuple[list[str], dict[str, float]]:
    """The identified candidates that still improve held-out runs once the discovered terms are fitted.

    Each candidate (last added first) is tested by the one-sided sign-flip test of the per-run held-out
    improvement it gives on top of the other kept candidates and the discovered terms; one that does not
    reach ``alpha`` is dropped: the discovered terms explain its share of the gap at least as well.

    The candidates of ``group`` that were identified are first tested together, as one: two candidate
    dampings can together mimic a dissipation that neither describes, and each then still improves on top of
    the other (the effects are fitted before the discovered terms).  A candidate is judged against the
    discovered terms without the library copies of its own columns (:data:`LIBRARY_EQUIVALENTS`): linear
    damping is not replaced by the terms ``ydot`` and ``thetadot``.  ``partners`` maps the model's member of an
    indistinguishable pair to the other member, which it stands for: the other's copies are not its rivals either
    (the cavity's lag kept for the pair it makes with linear damping is not replaced by ``ydot``).

    Returns
    -------
    (kept, p_values)
        The kept candidates in their order, and each tested candidate's p-value.
    """
    from ..prepare.candidate_effects import LIBRARY_EQUIVALENTS

    partners = partners or {}

    def rivals(tested: Sequence[str]) -> Discovery:  # the discovered terms, without the tested candidates' copies
        own: dict[str, list[str]] = {e: [] for e in EQUATIONS}
        for c in list(tested) + [partners[c] for c in tested if c in partners]:
            for e, names in LIBRARY_EQUIVALENTS.get(c, {}).items():
                own[e] += names
        return discovery.without(own)

    if discovery.empty or not identified:
        return list(identified), {}
    kept = list(identified)
    pvals = {}
    together = [c for c in group if c in kept]
    if len(together) > 1:
        with_g = _held_out_scores(problem, kept, rivals(together), folds)
        without = _held_out_scores(problem, [e for e in kept if e not in together], rivals(together), folds)
        p = sign_flip_pvalue(without - with_g)
        if not p < alpha:
            logger.info("%s are not named: the discovered terms explain their share of the gap on held-out runs "
                        "(p = %.2g)", " and ".join(together), p)
            pvals.update({c: p for c in together})
            kept = [e for e in kept if e not in together]
    for c in reversed(list(kept)):
        with_c = _held_out_scores(problem, kept, rivals([c]), folds)
        without = _held_out_scores(problem, [e for e in kept if e != c], rivals([c]), folds)
        p = sign_flip_pvalue(without - with_c)
        pvals[c] = p
        if not p < alpha:
            logger.info("%s is not named: the discovered terms explain its share of the gap on held-out runs (p = %.2g)", c, p)
            kept.remove(c)
    return kept, pvals


def joint_estimates(problem: DiagnosisProblem, fit: GapFit, discovery: Discovery
                    ) -> tuple[dict[str, dict[str, float]], Discovery, dict[str, list[str]]]:
    """The final joint model: the identified effects' parameters and the discovered terms' coefficients estimated
    together, without discovered copies of the effects' own columns.

    The discovery fits its terms to the residual of ``fit`` (the calibrated simulation plus the identified effects,
    fitted without them).  A term that only works together with a linear partner (a cubic hinge hardening beside
    pair scattering, whose stiffness fitted alone absorbed part of the hardening) is found with that partner: a
    library copy of the effect's own column (``theta``), which then carries part of the effect's parameter.  Here,
    per equation with integral-form terms, the copies (:func:`~validation.diagnosis.prepare.candidate_effects.own_library_columns`)
    are dropped and the parameters of the effects acting on that equation and the remaining terms' coefficients are
    one least-squares fit of the equation's integral form at the calibrated pressure and origin: the effect's column
    takes the copy's place.  Parameters acting on no such equation keep ``fit``'s values, as do energy-balance terms.

    Returns
    -------
    (effects, discovery, folded)
        ``{name: {parameter: value}}`` of the final joint model, the discovery without the copies and with the joint
        coefficients, and per equation the copies folded into the effects.
    """
    from cubedimer.terms import library_terms

    from ..prepare.candidate_effects import CANDIDATE_EFFECTS, own_library_columns

    names = list(fit.effects)
    params = {n: dict(v) for n, v in fit.effects.items()}
    terms_out = {eq: list(discovery.terms[eq]) for eq in EQUATIONS}
    folded: dict[str, list[str]] = {eq: [] for eq in EQUATIONS}
    if not names or not any(t.form == "integral" for eq in EQUATIONS for t in discovery.terms[eq]):
        return params, discovery, folded
    copies = own_library_columns(names)
    slots = [(n, p) for n in names for p in CANDIDATE_EFFECTS[n]]
    pv = fit.effect_parameter_vector(names)
    terms = SimulationTerms(problem)
    cal = fit.calibration
    library = library_terms()
    for q, eq in enumerate(EQUATIONS):
        found = [t for t in discovery.terms[eq] if t.form == "integral"]
        if not found:
            continue
        ecols = terms.integral_effect_columns(cal.z_origin_m, names, cal.equilibrium_height_m, q)
        acting = np.flatnonzero(sum(np.sum(c * c, axis=0) for c in ecols) > 0)
        if not acting.size:
            continue
        folded[eq] = [t.term for t in found if t.term in copies[eq]]
        found = [t for t in found if t.term not in copies[eq]]
        others = np.setdiff1d(np.arange(len(slots)), acting)
        known = terms.integral_known(cal.z_origin_m, q)
        idx = [library.index(t.term) for t in found]
        dcols = integrated_columns(problem, [c[:, idx] for c in library_columns(problem, q)], q)
        cols, rhs = [], []
        for r, kn, ec, dc in zip(problem.runs, known, ecols, dcols):
            b = r.integral.target(q) - cal.pressure_scale * kn[0] - kn[1]
            if others.size:
                b = b - ec[:, others] @ pv[others]
            cols.append(np.hstack([ec[:, acting], dc]))
            rhs.append(b)
        sol = _least_squares(cols, rhs)
        for k, j in enumerate(acting):
            n, p = slots[j]
            params[n][p] = float(sol[k])
        joint = dict(zip([t.term for t in found], sol[acting.size:].tolist()))
        terms_out[eq] = [replace(t, coefficient=float(joint[t.term])) if t.term in joint else t
                         for t in discovery.terms[eq] if not (t.form == "integral" and t.term in folded[eq])]
    return params, Discovery(terms_out, discovery.selected, discovery.remaining), folded


