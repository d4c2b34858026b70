"""Gaps no candidate explains: the remaining residual regressed sparsely on the cubic library.

After the candidate search, the residual of each equation in its integral form (the measured
coordinate minus each window's straight line, minus the detrended double integral of the calibrated
simulation plus the identified effects, :mod:`fitting.integral_form`) is white tracking noise for a
model that explains the data.  What remains is regressed on the detrended double integrals of the
35 cubic library terms (:mod:`cubedimer.terms`, at the integral form's column states):

1. **Selection** on all runs: backward elimination until Holm's rule at family-wise ``alpha`` over the
   35 terms declares every remaining term significant: the rule of
   :func:`fitting.integral_form.select_integral_form` (Holm levels from :mod:`fitting.multiple_testing`),
   applied to the normal equations (35 x 35 per run) instead of the ~50,000 stacked rows, which makes
   the many refits of step 2 cheap.
2. **Held out** (K-fold over runs, as the identification): each selected term is judged against the
   others kept: the coefficients are fitted on the other folds' residuals, with and without it, and
   scored on the held-out runs.  A term is kept when the one-sided sign-flip test of its per-run
   held-out improvement gives p < ``alpha`` and its median improvement exceeds both
   ``min_absolute_improvement`` of the coordinate's variance and ``min_relative_improvement`` of the
   equation's remaining gap; the weakest failing term is dropped and the others judged again, so
   terms that only work together (a cubic hardening and the linear stiffness that undoes a
   candidate's) are judged together.

A large number of frames makes even a tiny systematic misfit significant in step 1; step 2's practical
thresholds are what keeps such terms off clean data (measured in docs/diagnosis.md).

:func:`judge_candidates` then judges the identified candidates against the discovered terms on
held-out runs: a candidate that no longer improves held-out runs once the discovered terms are fitted
(for example pair scattering's linear hinge stiffness standing in for a cubic hardening) is not named.
"""
from __future__ import annotations

import logging
from dataclasses import dataclass, field
from typing import Sequence

import numpy as np
from numpy.typing import NDArray

from .gap_model import GapFit, apply_gap_model, fit_gap_model
from .metrics import fit_gaps
from .problem import DiagnosisProblem
from .simulation_model import SimulationTerms
from .statistics import sign_flip_pvalue

__all__ = ["DiscoveredTerm", "Discovery", "integral_residuals", "discover_terms", "judge_candidates", "discovered_equations",
           "EQUATIONS"]

logger = logging.getLogger(__name__)

#: The equations in the order of the integral form's coordinate index q.
EQUATIONS = ("yddot", "thetaddot")


@dataclass(frozen=True)
class DiscoveredTerm:
    """A library term that carries part of the remaining gap of one equation."""

    term: str
    coefficient: float  #: SI, fitted on all runs with the other kept terms of the equation
    std_error: float  #: white-noise standard error of the integral form
    shrink: float  #: fraction of the equation's remaining gap (beyond noise) it removes, added in order
    p_value: float  #: one-sided sign-flip test of its held-out improvement
    held_out_improvement: float  #: median per-run held-out improvement (fraction of the coordinate's variance)

    def to_dict(self) -> dict:
        """The diagnosis.json form (``remaining_gap.discovered_terms[equation][i]``)."""
        return {"term": self.term, "coefficient": self.coefficient, "std_error": self.std_error, "shrink": self.shrink,
                "p_value": self.p_value, "held_out_improvement": self.held_out_improvement}


@dataclass(frozen=True)
class Discovery:
    """Result of :func:`discover_terms`: per equation, the kept terms (strongest first), and what step 1 selected."""

    terms: dict[str, list[DiscoveredTerm]] = field(default_factory=lambda: {e: [] for e in EQUATIONS})
    selected: dict[str, list[str]] = field(default_factory=lambda: {e: [] for e in EQUATIONS})
    #: per equation: remaining gap (unexplained fraction of the detrended coordinate beyond noise) before the terms
    remaining: dict[str, float] = field(default_factory=dict)

    @property
    def empty(self) -> bool:
        return not any(self.terms.values())

    def names(self) -> dict[str, list[str]]:
        return {e: [t.term for t in self.terms[e]] for e in EQUATIONS}

    def to_dict(self) -> dict:
        """``{"yddot": [...], "thetaddot": [...]}`` (FORMATS.md ``remaining_gap.discovered_terms``)."""
        return {e: [t.to_dict() for t in self.terms[e]] for e in EQUATIONS}


def integral_residuals(problem: DiagnosisProblem, fit: GapFit) -> list[list[NDArray[np.float64]]]:
    """Per run, per coordinate q (0: y, 1: theta): the detrended measured coordinate minus the detrended double
    integral of the fit's accelerations (the calibrated simulation plus its effects), stacked over windows."""
    terms = SimulationTerms(problem)
    cal = fit.calibration
    names = list(fit.effects)
    pv = fit.effect_parameter_vector(names)
    out = [[None, None] for _ in problem.runs]
    for q in (0, 1):
        known = terms.integral_known(cal.z_origin_m, q)
        cols = terms.integral_effect_columns(cal.z_origin_m, names, cal.equilibrium_height_m, q)
        for i, (r, kn, c) in enumerate(zip(problem.runs, known, cols)):
            out[i][q] = r.integral.target(q) - cal.pressure_scale * kn[0] - kn[1] - (c @ pv if pv.size else 0.0)
    return out


def _library_columns(problem: DiagnosisProblem, q: int) -> list[NDArray[np.float64]]:
    """Per run: the library evaluated at the column states, stacked over the windows of coordinate q
    (rows aligned with :func:`integral_residuals`); (rows, 35)."""
    from cubedimer.terms import evaluate_library

    out = []
    for r in problem.runs:
        pi = r.integral
        idx = (pi.starts(q)[:, None] + np.arange(pi.windows[q])[None, :]).ravel()
        out.append(evaluate_library(pi.state)[idx])
    return out


def _integrated(problem: DiagnosisProblem, lib: Sequence[NDArray], q: int) -> list[NDArray[np.float64]]:
    """Per run: detrended double integrals of stacked library columns over their windows."""
    from fitting.integral_form import integral_columns, window_starts

    out = []
    for r, f in zip(problem.runs, lib):
        w = r.integral.windows[q]
        out.append(integral_columns(f, r.integral.dt, window_starts(f.shape[0], w), w))
    return out


def _fraction(problem: DiagnosisProblem, i: int, q: int, rss: float) -> float:
    """Unexplained fraction beyond noise of coordinate q of run i for a residual sum of squares ``rss``."""
    pi = problem.runs[i].integral
    return (rss - pi.floor(q)) / max(float(np.sum(pi.target(q) ** 2)), 1e-300)


class _Normal:
    """Per-run normal equations of the integral-form regression of a residual on the library columns
    (scaled by one global factor per column): G_i = X_i^T X_i, h_i = X_i^T b_i, bb_i = b_i^T b_i."""

    def __init__(self, cols: Sequence[NDArray], res: Sequence[NDArray]):
        self.scale = np.maximum(np.sqrt(sum(np.sum(c * c, axis=0) for c in cols)), 1e-300)
        xs = [c / self.scale for c in cols]
        self.g = np.array([x.T @ x for x in xs])
        self.h = np.array([x.T @ b for x, b in zip(xs, res)])
        self.bb = np.array([float(b @ b) for b in res])

    def solve(self, runs: Sequence[int], terms: Sequence[int]) -> NDArray:
        """Scaled coefficients of ``terms`` fitted on ``runs``."""
        t, r = list(terms), list(runs)
        g = self.g[r].sum(axis=0)[np.ix_(t, t)]
        return np.linalg.lstsq(g, self.h[r].sum(axis=0)[t], rcond=None)[0]

    def rss(self, i: int, terms: Sequence[int], coef: NDArray) -> float:
        """Residual sum of squares of run i with scaled coefficients ``coef`` of ``terms``."""
        t = list(terms)
        return float(self.bb[i] - 2 * coef @ self.h[i, t] + coef @ self.g[i][np.ix_(t, t)] @ coef)

    def held_out_rss(self, terms: Sequence[int], folds: int) -> NDArray:
        """K-fold over runs: per run, the residual sum of squares after ``terms`` fitted on the other folds."""
        n = self.bb.size
        if not terms:
            return self.bb.copy()
        k = min(folds, n)
        out = np.empty(n)
        for f in range(k):
            coef = self.solve([i for i in range(n) if i % k != f], terms)
            for i in range(f, n, k):
                out[i] = self.rss(i, terms, coef)
        return out

    def select(self, names: Sequence[str], dof_base: int, alpha: float) -> list[int]:
        """Backward elimination on all runs with Holm's rule over the whole library: the rule of
        :func:`fitting.integral_form.select_integral_form` (velocity terms dropped first while one is not
        significant at the Bonferroni level), on the normal equations.  Returns the kept column indices."""
        from cubedimer.terms import is_velocity_free
        from fitting.multiple_testing import holm_z_threshold

        n_lib = len(names)
        allruns = range(self.bb.size)
        keep = list(range(n_lib))
        velocity = np.array([not is_velocity_free(t) for t in names])
        thresholds = np.array([holm_z_threshold(alpha, n_lib, k + 1) for k in range(n_lib)])
        while keep:
            coef = self.solve(allruns, keep)
            s2 = sum(self.rss(i, keep, coef) for i in allruns) / max(dof_base - len(keep), 1)
            se = np.sqrt(np.clip(np.diag(np.linalg.pinv(self.g.sum(axis=0)[np.ix_(keep, keep)])) * s2, 0, None))
            absz = np.abs(np.nan_to_num(coef / np.where(se > 0, se, np.inf)))
            if np.all(np.sort(absz)[::-1] >= thresholds[: len(keep)]):
                return keep
            weak_velocity = velocity[keep] & (absz < thresholds[0])
            pool = np.flatnonzero(weak_velocity) if weak_velocity.any() else np.arange(len(keep))
            keep.pop(int(pool[np.argmin(absz[pool])]))
        return []


def discover_terms(problem: DiagnosisProblem, fit: GapFit, alpha: float = 0.01, folds: int = 5,
                   min_absolute_improvement: float = 1e-3, min_relative_improvement: float = 0.05) -> Discovery:
    """Library terms that carry the residual of ``fit`` (module docstring).

    Parameters
    ----------
    problem : DiagnosisProblem
        Its runs need integral-form data (else nothing is discovered).
    fit : GapFit
        The calibrated simulation plus the identified effects, fitted to ``problem``.
    alpha : family-wise level of the selection and level of the held-out sign-flip tests
    folds : K of the K-fold over runs
    min_absolute_improvement : a kept term's median held-out improvement, as a fraction of the variance
    min_relative_improvement : the same, as a fraction of the equation's remaining gap

    Returns
    -------
    Discovery
    """
    from cubedimer.terms import library_terms

    from .preparation import uses_integral_form

    if len(problem) < 3 or not uses_integral_form(problem.runs):
        return Discovery()
    names = library_terms()
    residuals = integral_residuals(problem, fit)
    out = Discovery()
    n = len(problem)
    allruns = range(n)
    for q, eq in enumerate(EQUATIONS):
        res = [r[q] for r in residuals]
        norms = np.array([float(np.sum(r.integral.target(q) ** 2)) for r in problem.runs])
        floors = np.array([r.integral.floor(q) for r in problem.runs])
        ne = _Normal(_integrated(problem, _library_columns(problem, q), q), res)
        remaining = float(np.mean((ne.bb - floors) / norms))  # the equation's remaining gap beyond noise
        out.remaining[eq] = remaining
        n_win = sum(r.integral.starts(q).size for r in problem.runs)
        dof_base = sum(b.size for b in res) - 2 * n_win
        kept = ne.select(names, dof_base, alpha)
        out.selected[eq] = [names[j] for j in kept]
        # held out: each term against the others kept; the weakest failing term goes, the rest are judged again
        tests: dict[int, tuple[float, float, bool]] = {}
        while kept:
            full = ne.held_out_rss(kept, folds)
            tests = {}
            for j in kept:
                diff = (ne.held_out_rss([k for k in kept if k != j], folds) - full) / norms
                gain, p = float(np.median(diff)), sign_flip_pvalue(diff)
                ok = p < alpha and gain > min_absolute_improvement and gain > min_relative_improvement * max(remaining, 0.0)
                logger.debug("discovery %s %s: p = %.3g, median held-out improvement %.3g", eq, names[j], p, gain)
                tests[j] = (p, gain, ok)
            failing = [j for j in kept if not tests[j][2]]
            if not failing:
                break
            kept.remove(min(failing, key=lambda j: tests[j][1]))
        if not kept:
            continue
        # coefficients on all runs; each term's shrink: what it removes when added in order (greedy, in-sample)
        frac = lambda terms: float(np.mean((np.array([ne.rss(i, terms, ne.solve(allruns, terms)) for i in allruns])  # noqa: E731
                                            - floors) / norms))
        order: list[int] = []
        while len(order) < len(kept):
            order.append(min((j for j in kept if j not in order), key=lambda j: frac(order + [j])))
        kept = order
        coef = ne.solve(allruns, kept)
        s2 = sum(ne.rss(i, kept, coef) for i in allruns) / max(dof_base - len(kept), 1)
        se = np.sqrt(np.clip(np.diag(np.linalg.pinv(ne.g.sum(axis=0)[np.ix_(kept, kept)])) * s2, 0, None))
        prev, terms_out = remaining, []
        for m, j in enumerate(kept):
            now = frac(kept[: m + 1])
            shrink = (prev - now) / remaining if remaining > 0 else 0.0
            prev = now
            terms_out.append(DiscoveredTerm(names[j], float(coef[m] / ne.scale[j]), float(se[m] / ne.scale[j]),
                                            float(shrink), tests[j][0], tests[j][1]))
        out.terms[eq] = terms_out
    return out


def _held_out_scores(problem: DiagnosisProblem, effects: Sequence[str], terms: dict[str, list[str]],
                     folds: int) -> NDArray[np.float64]:
    """K-fold over runs: per run, the mean over the three gap components (beyond noise) of a fit of ``effects``
    and then of the library ``terms`` (on the fit's integral-form residuals) made on the other folds; the
    y and theta components in their integral form."""
    from cubedimer.terms import library_terms

    names = library_terms()
    n = len(problem)
    k = min(folds, n)
    out = np.empty(n)
    for f in range(k):
        test = [i for i in range(n) if i % k == f]
        train = [i for i in range(n) if i % k != f]
        tr, te = problem.subset(train), problem.subset(test)
        fit = fit_gap_model(tr, effects)
        held = apply_gap_model(te, fit.calibration, fit.effects)
        res_tr, res_te = integral_residuals(tr, fit), integral_residuals(te, held)
        comps = np.zeros((len(test), 3))
        comps[:, 2] = fit_gaps(te.runs, held)[:, 2]
        for q, eq in enumerate(EQUATIONS):
            idx = [names.index(t) for t in terms.get(eq, [])]
            e_te = [r[q] for r in res_te]
            if idx:
                c_tr = _integrated(tr, [c[:, idx] for c in _library_columns(tr, q)], q)
                c_te = _integrated(te, [c[:, idx] for c in _library_columns(te, q)], q)
                x, b = np.concatenate(c_tr), np.concatenate([r[q] for r in res_tr])
                scale = np.maximum(np.sqrt(np.sum(x * x, axis=0)), 1e-300)
                coef = np.linalg.lstsq(x / scale, b, rcond=None)[0] / scale
                e_te = [e - c @ coef for e, c in zip(e_te, c_te)]
            comps[:, q] = [_fraction(te, i, q, float(e @ e)) for i, e in enumerate(e_te)]
        out[test] = comps.mean(axis=1)
    return out


def judge_candidates(problem: DiagnosisProblem, identified: Sequence[str], discovery: Discovery, alpha: float = 0.01,
                     folds: int = 5) -> tuple[list[str], dict[str, float]]:
    """The identified candidates that still improve held-out runs once the discovered terms are fitted.

    Each candidate (last added first) is tested by the one-sided sign-flip test of the per-run held-out
    improvement it gives on top of the other kept candidates and the discovered terms; one that does not
    reach ``alpha`` is dropped: the discovered terms explain its share of the gap at least as well.

    Returns
    -------
    (kept, p_values)
        The kept candidates in their order, and each tested candidate's p-value.
    """
    if discovery.empty or not identified:
        return list(identified), {}
    terms = discovery.names()
    kept = list(identified)
    pvals = {}
    for c in reversed(list(identified)):
        with_c = _held_out_scores(problem, kept, terms, folds)
        without = _held_out_scores(problem, [e for e in kept if e != c], terms, folds)
        p = sign_flip_pvalue(without - with_c)
        pvals[c] = p
        if not p < alpha:
            logger.info("%s is not named: the discovered terms explain its share of the gap on held-out runs (p = %.2g)", c, p)
            kept.remove(c)
    return kept, pvals


def discovered_equations(discovery: Discovery) -> dict[str, str]:
    """Per equation with discovered terms, the equation as text, e.g.
    ``"thetaddot = simulation + identified effects + [discovered: -2.42e+04 theta^3]"``."""
    out = {}
    for eq in EQUATIONS:
        terms = discovery.terms[eq]
        if terms:
            sum_ = " ".join(f"{'-' if t.coefficient < 0 else '+'} {abs(t.coefficient):.3g} {t.term}" for t in terms)
            sum_ = sum_[2:] if sum_.startswith("+ ") else "-" + sum_[2:]
            out[eq] = f"{eq} = simulation + identified effects + [discovered: {sum_}]"
    return out
