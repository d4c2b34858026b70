"""Gaps no candidate explains: the remaining residual regressed sparsely on the cubic library.

After the candidate search, the residual of each equation in its integral form (the measured
coordinate minus each window's straight line, minus the detrended double integral of the calibrated
simulation plus the identified effects, :mod:`fitting.derivatives.integral_form`) is white tracking noise for a
model that explains the data.  What remains is regressed on the detrended double integrals of the
35 cubic library terms (:mod:`cubedimer.terms`, at the integral form's column states):

1. **Selection** on all runs: backward elimination until Holm's rule at family-wise ``alpha`` over the
   35 terms declares every remaining term significant: the rule of
   :func:`fitting.derivatives.integral_form.select_integral_form` (Holm levels from :mod:`fitting.multiple_testing`),
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

3. **The energy balance.**  A dissipation changes a coordinate within a window of the integral form by a
   fraction of order ``rate / omega`` of its amplitude (a y-dependent damping ``-c y^2 ydot`` of a few 1/s
   moves y by about 1 % of its amplitude over 0.75 periods), below step 2's practical threshold, while it
   removes a large share of the oscillation energy over the energy balance's windows (0.4 s).  So steps 1
   and 2 are repeated on the energy balance of the fit (:class:`EnergyResidual`, with the work of the terms
   found in the integral form subtracted), the columns being the work per window of the
   :func:`dissipative_terms` of both equations, and the improvements fractions of the oscillation energy's
   sum of squares (the energy component of the gap).  Terms found there carry ``form = "energy"``.  Over
   windows of ten periods only the cycle-averaged dissipation is seen, so terms of the same amplitude
   dependence (``y^2*ydot`` and ``ydot^3`` both remove energy as A^4) are told apart only through the
   decay's shape, and their coefficients are less certain than the integral form's (docs/diagnosis.md).

:func:`validation.diagnosis.discover.joint_model.judge_candidates` then judges the identified candidates against the
discovered terms on held-out runs, and :func:`validation.diagnosis.discover.joint_model.joint_estimates` fits them together.
"""
from __future__ import annotations

import logging
from dataclasses import dataclass, field
from typing import Sequence

import numpy as np
from numpy.typing import NDArray

from cubedimer.folds import run_folds

from ..calibrate.gap_model import GapFit
from ..identify.statistics import sign_flip_pvalue
from ..prepare.problem import DiagnosisProblem
from ..prepare.simulation_terms import SimulationTerms

__all__ = ["DiscoveredTerm", "Discovery", "integral_residuals", "energy_balance_residuals", "dissipative_terms",
           "discover_terms", "discovered_equations", "library_columns", "integrated_columns", "dissipation_rows",
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
    #: the balance it was found in: ``"integral"`` (the equation's integral form; shrink and improvement are
    #: fractions of the detrended coordinate) or ``"energy"`` (the energy balance; fractions of the
    #: oscillation energy's sum of squares, as the energy gap component)
    form: str = "integral"

    def to_dict(self) -> dict:
        """The diagnosis.json form (``remaining_gap.discovered_terms[equation][i]``)."""
        return {"term": self.term, "coefficient": self.coefficient, "std_error": self.std_error, "shrink": self.shrink,
                "p_value": self.p_value, "held_out_improvement": self.held_out_improvement, "form": self.form}


@dataclass(frozen=True)
class Discovery:
    """Result of :func:`discover_terms`: per equation, the kept terms (strongest first), and what step 1 selected."""

    terms: dict[str, list[DiscoveredTerm]] = field(default_factory=lambda: {e: [] for e in EQUATIONS})
    selected: dict[str, list[str]] = field(default_factory=lambda: {e: [] for e in EQUATIONS})
    #: per equation: remaining gap (unexplained fraction of the detrended coordinate beyond noise) before the
    #: terms; ``"energy"``: the energy balance's remaining gap before the dissipative terms
    remaining: dict[str, float] = field(default_factory=dict)

    @property
    def empty(self) -> bool:
        return not any(self.terms.values())

    def names(self, form: str | None = None) -> dict[str, list[str]]:
        """Per equation, the discovered terms' names (of one ``form`` only, if given)."""
        return {e: [t.term for t in self.terms[e] if form is None or t.form == form] for e in EQUATIONS}

    def without(self, terms: dict[str, Sequence[str]]) -> "Discovery":
        """The same discovery without the named terms (per equation)."""
        return Discovery({e: [t for t in self.terms[e] if t.term not in terms.get(e, ())] for e in EQUATIONS},
                         self.selected, self.remaining)

    def union(self, other: "Discovery") -> "Discovery":
        """The terms of both discoveries (per equation; a term in both keeps this discovery's entry)."""
        terms = {e: list(self.terms[e]) + [t for t in other.terms[e] if t.term not in self.names()[e]]
                 for e in EQUATIONS}
        selected = {e: list(dict.fromkeys(self.selected.get(e, []) + other.selected.get(e, []))) for e in EQUATIONS}
        return Discovery(terms, selected, {**other.remaining, **self.remaining})

    def to_dict(self) -> dict:
        """``{"yddot": [...], "thetaddot": [...]}`` (docs/formats.md ``remaining_gap.discovered_terms``)."""
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


def library_columns(problem: DiagnosisProblem, q: int) -> list[NDArray[np.float64]]:
    """Per run: the library evaluated at the column states, stacked over the windows of coordinate q
    (rows aligned with :func:`integral_residuals`); (rows, 35)."""
    from cubedimer.terms import evaluate_library

    out = []
    for r in problem.runs:
        pi = r.integral
        idx = (pi.starts(q)[:, None] + np.arange(pi.windows[q])[None, :]).ravel()
        out.append(evaluate_library(pi.state)[idx])
    return out


def integrated_columns(problem: DiagnosisProblem, lib: Sequence[NDArray], q: int) -> list[NDArray[np.float64]]:
    """Per run: detrended double integrals of stacked library columns over their windows."""
    from fitting.derivatives.integral_form import integral_columns, window_starts

    out = []
    for r, f in zip(problem.runs, lib):
        w = r.integral.windows[q]
        out.append(integral_columns(f, r.integral.dt, window_starts(f.shape[0], w), w))
    return out


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
        out = np.empty(n)
        for train, test in run_folds(n, folds):
            coef = self.solve(train, terms)
            for i in test:
                out[i] = self.rss(i, terms, coef)
        return out

    def select(self, names: Sequence[str], dof_base: int, alpha: float) -> list[int]:
        """Backward elimination on all runs with Holm's rule over the whole library: the rule of
        :func:`fitting.derivatives.integral_form.select_integral_form` (velocity terms dropped first while one is not
        significant at the Bonferroni level), on the normal equations.  Returns the kept column indices."""
        from cubedimer.terms import is_velocity_free
        from fitting.multiple_testing import holm_all_significant, holm_backward_elimination, holm_z_threshold

        n_lib = len(names)
        allruns = range(self.bb.size)
        velocity = np.array([not is_velocity_free(t) for t in names])

        def score(keep: list[int]):
            if not keep:
                return np.zeros(0), None
            coef = self.solve(allruns, keep)
            s2 = sum(self.rss(i, keep, coef) for i in allruns) / max(dof_base - len(keep), 1)
            se = np.sqrt(np.clip(np.diag(np.linalg.pinv(self.g.sum(axis=0)[np.ix_(keep, keep)])) * s2, 0, None))
            return np.abs(np.nan_to_num(coef / np.where(se > 0, se, np.inf))), None

        for keep, absz, _ in holm_backward_elimination(score, range(n_lib), velocity, np.ones(n_lib, bool),
                                                       holm_z_threshold(alpha, n_lib, 1)):
            if holm_all_significant(absz, alpha, n_lib):  # (vacuously so once every term is gone)
                return keep
        return []


def discover_terms(problem: DiagnosisProblem, fit: GapFit, alpha: float = 0.01, folds: int = 5,
                   min_absolute_improvement: float = 1e-3, min_relative_improvement: float = 0.05,
                   forms: Sequence[str] = ("integral", "energy")) -> Discovery:
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
    forms : where to search: ``"integral"``, the integral form of each equation on the whole library;
        ``"energy"``, the energy balance on the :func:`dissipative_terms` (after the integral form, with its
        terms' work subtracted)

    Returns
    -------
    Discovery
    """
    from cubedimer.terms import library_terms

    from ..prepare.runs import uses_integral_form

    if len(problem) < 3 or not uses_integral_form(problem.runs):
        return Discovery()
    names = library_terms()
    residuals = integral_residuals(problem, fit)
    out = Discovery()
    for q, eq in enumerate(EQUATIONS if "integral" in forms else ()):
        res = [r[q] for r in residuals]
        norms = np.array([float(np.sum(r.integral.target(q) ** 2)) for r in problem.runs])
        floors = np.array([r.integral.floor(q) for r in problem.runs])
        ne = _Normal(integrated_columns(problem, library_columns(problem, q), q), res)
        out.remaining[eq] = float(np.mean((ne.bb - floors) / norms))  # the equation's remaining gap beyond noise
        n_win = sum(r.integral.starts(q).size for r in problem.runs)
        dof_base = sum(b.size for b in res) - 2 * n_win
        kept = ne.select(names, dof_base, alpha)
        out.selected[eq] = [names[j] for j in kept]
        out.terms[eq] = _held_out_terms(ne, names, kept, norms, floors, out.remaining[eq], dof_base, alpha, folds,
                                        min_absolute_improvement, min_relative_improvement, "integral")
    if "energy" in forms:
        _discover_dissipation(problem, fit, out, alpha, folds, min_absolute_improvement, min_relative_improvement)
    return out


def _held_out_terms(ne: _Normal, names: Sequence[str], kept: list[int], norms: NDArray, floors: NDArray,
                    remaining: float, dof_base: int, alpha: float, folds: int, min_absolute_improvement: float,
                    min_relative_improvement: float, form: str) -> list[DiscoveredTerm]:
    """Step 2 of the module docstring on the selected columns ``kept`` of ``ne``: each term judged on held-out
    runs against the others kept (the weakest failing term dropped, the rest judged again); the kept terms
    ordered by what each removes when added in turn, with their coefficients on all runs."""
    n = ne.bb.size
    allruns = range(n)
    kept = list(kept)
    tests: dict[int, tuple[float, float, bool]] = {}
    while kept:
        full = ne.held_out_rss(kept, folds)
        tests = {}
        for j in kept:
            diff = (ne.held_out_rss([k for k in kept if k != j], folds) - full) / norms
            gain, p = float(np.median(diff)), sign_flip_pvalue(diff)
            ok = p < alpha and gain > min_absolute_improvement and gain > min_relative_improvement * max(remaining, 0.0)
            logger.debug("discovery (%s form) %s: p = %.3g, median held-out improvement %.3g", form, names[j], p, gain)
            tests[j] = (p, gain, ok)
        failing = [j for j in kept if not tests[j][2]]
        if not failing:
            break
        kept.remove(min(failing, key=lambda j: tests[j][1]))
    if not kept:
        return []
    # coefficients on all runs; each term's shrink: what it removes when added in order (greedy, in-sample)
    frac = lambda terms: float(np.mean((np.array([ne.rss(i, terms, ne.solve(allruns, terms)) for i in allruns])  # noqa: E731
                                        - floors) / norms))
    order: list[int] = []
    while len(order) < len(kept):
        order.append(min((j for j in kept if j not in order), key=lambda j: frac(order + [j])))
    coef = ne.solve(allruns, order)
    s2 = sum(ne.rss(i, order, coef) for i in allruns) / max(dof_base - len(order), 1)
    se = np.sqrt(np.clip(np.diag(np.linalg.pinv(ne.g.sum(axis=0)[np.ix_(order, order)])) * s2, 0, None))
    prev, out = remaining, []
    for m, j in enumerate(order):
        now = frac(order[: m + 1])
        shrink = (prev - now) / remaining if remaining > 0 else 0.0
        prev = now
        out.append(DiscoveredTerm(names[j], float(coef[m] / ne.scale[j]), float(se[m] / ne.scale[j]), float(shrink),
                                  tests[j][0], tests[j][1], form))
    return out


def dissipative_terms() -> dict[str, list[str]]:
    """Per equation, the library terms the energy balance can attribute to it: the equation's own velocity
    times an even function of the velocities up to degree 3 (``ydot``, ``y*ydot``, ``ydot*theta``,
    ``y^2*ydot``, ``y*ydot*theta``, ``ydot*theta^2``, ``ydot^3`` for yddot, likewise for thetaddot).

    Such a term ``c phi`` in yddot does the work ``c M int ydot phi dt``, of one sign over a window when
    ``phi / ydot`` keeps its sign: the energy balance sees a dissipation that the windowed integral form of
    the equation sees only at a fraction of its amplitude over a window.  A term with the other velocity
    (``thetadot`` in yddot) does the same work as a term of the other equation (``ydot`` in thetaddot,
    ``M`` against ``I``), and a conservative term (even in the velocities) does no net work over a period:
    neither is resolved by the energy balance, so neither is searched there.
    """
    from cubedimer.terms import term_name

    factors = ((0, 0), (1, 0), (0, 1), (2, 0), (1, 1), (0, 2))  # powers of (y, theta)
    out = {}
    for q, eq in enumerate(EQUATIONS):
        own = 1 + 2 * q  # index of the equation's velocity in (y, ydot, theta, thetadot)
        names = []
        for py, pt in factors:
            e = [py, 0, pt, 0]
            e[own] += 1
            names.append(term_name(e))
        e = [0, 0, 0, 0]
        e[own] = 3
        names.append(term_name(e))
        out[eq] = names
    return out


def energy_balance_residuals(problem: DiagnosisProblem, fit: GapFit, discovery: Discovery | None = None
                             ) -> list[NDArray[np.float64]]:
    """Per run, per energy window: the energy balance's residual under ``fit`` (:class:`EnergyResidual`),
    minus the work of ``discovery``'s integral-form terms at their coefficients [J]."""
    terms = SimulationTerms(problem)
    out = [e.residual.copy() for e in fit.energy]
    found = [] if discovery is None else [(q, t) for q, eq in enumerate(EQUATIONS) for t in discovery.terms[eq]
                                          if t.form == "integral"]
    if found:
        from cubedimer.terms import evaluate_library, library_terms

        names = library_terms()
        for i, r in enumerate(problem.runs):
            lib = evaluate_library(r.balance.state)
            acc = np.zeros((len(r.t), 2, 1))
            for q, t in found:
                acc[:, q, 0] += t.coefficient * lib[:, names.index(t.term)]
            out[i] = out[i] - terms.window_work(r, acc)[:, 0]
    return out


def _dissipation_work(problem: DiagnosisProblem, names_per_eq: dict[str, list[str]]) -> list[NDArray[np.float64]]:
    """Per run: the work per energy window (n_windows, p) of each term of ``names_per_eq`` with unit coefficient,
    the columns in equation order."""
    from cubedimer.terms import evaluate_library, library_terms

    terms = SimulationTerms(problem)
    lib_names = library_terms()
    out = []
    for r in problem.runs:
        lib = evaluate_library(r.balance.state)
        blocks = []
        for q, eq in enumerate(EQUATIONS):
            acc = np.zeros((len(r.t), 2, len(names_per_eq[eq])))
            acc[:, q, :] = lib[:, [lib_names.index(t) for t in names_per_eq[eq]]]
            blocks.append(terms.window_work(r, acc))
        out.append(np.concatenate(blocks, axis=1))
    return out


def _discover_dissipation(problem: DiagnosisProblem, fit: GapFit, out: Discovery, alpha: float, folds: int,
                          min_absolute_improvement: float, min_relative_improvement: float) -> None:
    """Steps 1 and 2 of the module docstring on the energy balance, for the :func:`dissipative_terms` of both
    equations together; the terms found are appended to ``out.terms`` with ``form="energy"``."""
    per_eq = dissipative_terms()
    names = [t for eq in EQUATIONS for t in per_eq[eq]]
    owner = [eq for eq in EQUATIONS for _ in per_eq[eq]]
    cols, res, floors = dissipation_rows(problem, fit, out, per_eq)
    norms = np.ones(len(res))
    ne = _Normal(cols, res)
    remaining = float(np.mean(ne.bb - floors))
    out.remaining["energy"] = remaining
    dof_base = sum(b.size for b in res)
    kept = ne.select(names, dof_base, alpha)
    for j in kept:
        out.selected[owner[j]].append(names[j] + " (energy)")
    found = _held_out_terms(ne, names, kept, norms, floors, remaining, dof_base, alpha, folds,
                            min_absolute_improvement, min_relative_improvement, "energy")
    for t in found:  # the names are distinct across the equations
        out.terms[owner[names.index(t.term)]].append(t)


def dissipation_rows(problem: DiagnosisProblem, fit: GapFit, discovery: Discovery, per_eq: dict[str, list[str]]
                      ) -> tuple[list[NDArray], list[NDArray], NDArray]:
    """Per run, the rows on which dissipative terms ``per_eq`` are fitted and judged: (columns, residual) of the
    energy balance and of both equations' integral forms, and the sum of the three noise floors.

    The energy rows are the work per window (:func:`energy_balance_residuals`, with the work of
    ``discovery``'s integral-form terms subtracted); the integral rows are the equations' integral-form
    residuals (:func:`integral_residuals`, those terms subtracted) with the terms' integral-form columns.  Each
    block of a run is scaled by 1/sqrt of its normalisation (the oscillation energy's sum of squares; the
    detrended coordinate's), so that a residual sum of squares is the sum of the run's three gap components
    and the least squares minimise their mean over runs: the energy balance fixes the cycle-averaged
    dissipation, the integral forms its shape within the cycle (``y^2*ydot`` and ``ydot^3`` remove the same
    energy from a harmonic oscillation, but move y differently within it).
    """
    from cubedimer.terms import library_terms

    lib_names = library_terms()
    n_terms = sum(len(v) for v in per_eq.values())
    w = [1.0 / np.sqrt(max(float(np.sum(e.oscillation_energy**2)), 1e-300)) for e in fit.energy]
    res = [wi * r for wi, r in zip(w, energy_balance_residuals(problem, fit, discovery))]
    cols = [wi * c for wi, c in zip(w, _dissipation_work(problem, per_eq))]
    floors = np.array([wi**2 * e.residual.size * e.noise_variance for wi, e in zip(w, fit.energy)])
    residuals = integral_residuals(problem, fit)
    offset = 0
    for q, eq in enumerate(EQUATIONS):
        idx = [lib_names.index(t) for t in per_eq[eq]]
        found = [t for t in discovery.terms[eq] if t.form == "integral"]
        fidx = [lib_names.index(t.term) for t in found]
        integ = integrated_columns(problem, [c[:, idx + fidx] for c in library_columns(problem, q)], q)
        for i, r in enumerate(problem.runs):
            wq = 1.0 / np.sqrt(max(float(np.sum(r.integral.target(q) ** 2)), 1e-300))
            c = integ[i]
            b = residuals[i][q] - (c[:, len(idx):] @ np.array([t.coefficient for t in found]) if found else 0.0)
            block = np.zeros((c.shape[0], n_terms))
            block[:, offset:offset + len(idx)] = c[:, :len(idx)]
            cols[i] = np.vstack([cols[i], wq * block])
            res[i] = np.concatenate([res[i], wq * b])
            floors[i] += wq**2 * r.integral.floor(q)
        offset += len(idx)
    return cols, res, floors


def discovered_equations(discovery: Discovery) -> dict[str, str]:
    """Per equation with discovered terms, the equation as text, e.g.
    ``"thetaddot = simulation + identified effects + [discovered: -2.42e+04 theta^3]"``; a term found in the
    energy balance is marked, e.g. ``-6.1e+08 y^2*ydot (energy balance)``."""
    out = {}
    for eq in EQUATIONS:
        terms = discovery.terms[eq]
        if terms:
            sum_ = " ".join(f"{'-' if t.coefficient < 0 else '+'} {abs(t.coefficient):.3g} {t.term}"
                            + (" (energy balance)" if t.form == "energy" else "") for t in terms)
            sum_ = sum_[2:] if sum_.startswith("+ ") else "-" + sum_[2:]
            out[eq] = f"{eq} = simulation + identified effects + [discovered: {sum_}]"
    return out
