"""Which effect causes the gap: greedy, held-out identification over the candidate effects.

A candidate is fitted (with the calibration) on all runs but one fold and scored on the held-out runs
(K-fold over runs, :func:`held_out_gaps`), giving one held-out gap per run with and without the
candidate.  The improvement is significant when

* the one-sided sign-flip permutation test of the mean per-run held-out improvement
  (:func:`~validation.diagnosis.identify.statistics.sign_flip_pvalue`, exact) gives p < ``alpha``, and
* it is practically significant (:class:`PracticalThresholds`): the median held-out improvement exceeds
  ``min_absolute_improvement`` of the variance, and its improvement of the gap components the candidate
  acts in (its equations and the energy) exceeds ``min_relative_improvement`` of what remains in them
  (a hinge effect is not judged against a remaining gap of the vertical equation it cannot touch).

Held-out scoring is the penalty for added parameters: a parameter that only fits noise, or a
run-specific disturbance, does not improve other runs.  Candidates are added greedily (largest median
held-out improvement first) while a significant one remains.  Each run's held-out gap is a fraction of
its own variance (and energy), so every run counts equally: weighing runs by their share of the pooled
variance loses a constant hinge torque (mirror_asymmetry, beta0 = 60 1/s^2, in the unit tests), whose
signal is the same in every run while the energy residual's noise grows with the run's energy.

No cause is named while the calibration equation itself stays unexplained (``max_vertical_gap``).
"""
from __future__ import annotations

import logging
from dataclasses import dataclass, field
from typing import Sequence

import numpy as np
from numpy.typing import NDArray

from cubedimer.config_checks import check_non_negative, check_positive
from cubedimer.folds import run_folds

from ..calibrate.gap_model import apply_gap_model, fit_gap_model
from ..calibrate.metrics import fit_gaps
from ..prepare.candidate_effects import CANDIDATE_EFFECTS, acting_components, default_candidates
from ..prepare.problem import DiagnosisProblem
from .statistics import sign_flip_pvalue, wilcoxon_greater_pvalue

__all__ = ["PracticalThresholds", "CandidateTest", "IdentificationRound", "Identification", "held_out_gaps",
           "candidate_test", "identify_effects"]

logger = logging.getLogger(__name__)


@dataclass(frozen=True)
class PracticalThresholds:
    """How large a significant held-out improvement must be to count, and when no cause is named.

    Parameters
    ----------
    min_relative_improvement : float
        Median improvement of the gap components the candidate acts in, as a fraction of what remains in them.
    min_absolute_improvement : float
        Median improvement of the gap, as a fraction of the variance (beyond noise).
    max_vertical_gap : float
        No cause is named when the vertical (calibration) equation stays unexplained beyond this fraction
        of its variance (beyond noise) even with the chosen effects.
    """

    min_relative_improvement: float = 0.05
    min_absolute_improvement: float = 5e-6
    max_vertical_gap: float = 0.05

    def __post_init__(self) -> None:
        check_non_negative(self, "min_relative_improvement")
        check_positive(self, "min_absolute_improvement")
        check_positive(self, "max_vertical_gap")


@dataclass(frozen=True)
class CandidateTest:
    """One candidate tested on top of a round's base set (gaps beyond the noise floor)."""

    held_out_gap: float  #: mean held-out gap with the candidate
    median_improvement: float  #: median per-run held-out improvement of the gap
    median_improvement_fraction: float  #: the same relative to the current gap
    threshold: float  #: min_absolute_improvement
    components: list[int]  #: gap components the candidate acts in (0: y, 1: theta, 2: energy)
    median_improvement_in_components: float
    remaining_gap_in_components: float
    p_value: float  #: one-sided sign-flip permutation test
    wilcoxon_p: float  #: one-sided Wilcoxon signed-rank test (reported only)
    significant: bool
    per_run_held_out: list[float]
    #: the output-error test that named the candidate when the held-out test did not
    #: (:func:`~validation.diagnosis.identify.output_error.velocity_coupling_output_error`); None: held-out only
    output_error: dict | None = None

    def to_dict(self) -> dict:
        """The diagnosis.json form (``identification_rounds[i].candidates[name]``)."""
        extra = {} if self.output_error is None else {"output_error": self.output_error}
        return {**extra, "held_out_gap": self.held_out_gap, "median_improvement": self.median_improvement,
                "median_improvement_fraction": self.median_improvement_fraction, "threshold": self.threshold,
                "components": self.components, "median_improvement_in_components": self.median_improvement_in_components,
                "remaining_gap_in_components": self.remaining_gap_in_components,
                "p_value": self.p_value, "wilcoxon_p": self.wilcoxon_p, "significant": self.significant,
                "per_run_held_out": self.per_run_held_out}


@dataclass(frozen=True)
class IdentificationRound:
    """One greedy round: the effects chosen before it, their mean held-out gap, and every candidate's test."""

    base: list[str]
    base_held_out_gap: float
    candidates: dict[str, CandidateTest]

    def to_dict(self) -> dict:
        """The diagnosis.json form (``identification_rounds[i]``)."""
        return {"base": self.base, "base_held_out_gap": self.base_held_out_gap,
                "candidates": {c: t.to_dict() for c, t in self.candidates.items()}}


@dataclass(frozen=True)
class Identification:
    """Result of :func:`identify_effects`."""

    identified: list[str]  #: effects named as causes, in the order they were added
    rounds: list[IdentificationRound] = field(default_factory=list)
    #: unexplained fraction (beyond noise) of the vertical equation, with the effects the greedy rounds chose
    vertical_gap: float = float("nan")
    #: effects the greedy rounds chose but that are not named because the calibration is not trustworthy
    withheld: list[str] = field(default_factory=list)

    def last_tests(self) -> dict[str, CandidateTest]:
        """Each candidate's test in the last round it was tested in."""
        out: dict[str, CandidateTest] = {}
        for r in self.rounds:
            out.update(r.candidates)
        return out


def held_out_gaps(problem: DiagnosisProblem, effects: Sequence[str], folds: int = 5) -> NDArray[np.float64]:
    """K-fold over runs (run i is in fold i mod K): per run, the gap components (beyond the noise floor;
    (n_runs, 3): y, theta, energy) of a fit made on the other folds.

    Every run is held out exactly once, so each run gets one held-out score (leave-one-run-out when
    K >= the number of runs)."""
    out = np.empty((len(problem), 3))
    for train, test in run_folds(len(problem), folds):
        fit = fit_gap_model(problem.subset(train), effects)
        held = problem.subset(test)
        out[test] = fit_gaps(held.runs, apply_gap_model(held, fit.calibration, fit.effects))
    return out


def candidate_test(base: NDArray[np.float64], trial: NDArray[np.float64], components: Sequence[int], alpha: float,
                   thresholds: PracticalThresholds) -> CandidateTest:
    """The held-out test of one candidate: per-run held-out gap components (n_runs, 3) without it (``base``) and
    with it (``trial``), judged by the sign-flip test and the practical thresholds (module docstring)."""
    min_abs = thresholds.min_absolute_improvement
    comps = list(components)
    current, tried = base.mean(axis=1), trial.mean(axis=1)
    diff = current - tried  # > 0: the candidate helps the held-out run (the floor cancels)
    p = sign_flip_pvalue(diff)
    gain = float(np.median(diff))
    base_c = max(float(np.mean(base[:, comps])), 0.0)
    gain_c = float(np.median(base[:, comps].mean(axis=1) - trial[:, comps].mean(axis=1)))
    rel = gain / max(float(np.mean(current)), min_abs)
    significant = bool(p < alpha and gain > min_abs and gain_c > thresholds.min_relative_improvement * base_c)
    return CandidateTest(float(np.mean(tried)), gain, rel, min_abs, comps, gain_c, base_c, p,
                         wilcoxon_greater_pvalue(diff), significant, tried.tolist())


def identify_effects(problem: DiagnosisProblem, candidates: Sequence[str] | None = None,
                     alpha: float = 0.01, thresholds: PracticalThresholds = PracticalThresholds(),
                     progress: bool = True, cache: dict | None = None) -> Identification:
    """Greedy, held-out identification of the effects present (module docstring).

    A trustworthy calibration is required for naming any cause: the pressure and origin come from the
    vertical equation alone, so if that equation stays unexplained beyond ``thresholds.max_vertical_gap``
    of its variance (beyond noise) even with the chosen effects, the calibration is distorted by something
    outside the candidates (e.g. a pressure drifting during the runs), and hinge effects fitted on top of
    it mostly compensate the distortion (measured: a 6 % pressure drift calibrated 9 % low, and pair
    scattering then explained 94 % of the resulting hinge gap).  The chosen effects are then reported in
    ``withheld`` and ``identified`` is empty.

    Parameters
    ----------
    problem : DiagnosisProblem
        At least 3 runs.
    candidates : names from CANDIDATE_EFFECTS (default: all of them)
    alpha : float
        Significance level of the sign-flip test.
    thresholds : PracticalThresholds
    progress : bool
        Log each test at INFO level (else DEBUG).
    cache : dict, optional
        Held-out gaps (:func:`held_out_gaps`) by sorted effect names, filled here and reused by the caller's
        backward check (:func:`validation.diagnosis.identify.elimination.backward_check`).
    """
    if len(problem) < 3:
        raise ValueError("identification needs at least 3 runs (held-out runs are the significance test)")
    log = logger.info if progress else logger.debug
    cache = {} if cache is None else cache

    def gaps(effects: list[str]) -> NDArray[np.float64]:
        key = tuple(sorted(effects))
        if key not in cache:
            cache[key] = held_out_gaps(problem, effects)
        return cache[key]

    chosen: list[str] = []
    rounds: list[IdentificationRound] = []
    current_c = gaps(chosen)
    current = current_c.mean(axis=1)
    remaining = list(default_candidates() if candidates is None else candidates)
    while remaining:
        tests: dict[str, CandidateTest] = {}
        base, base_gap = list(chosen), float(np.mean(current))
        best, best_gain = None, 0.0
        for c in remaining:
            log("testing %s on top of %s", c, chosen or "calibration")
            trial_c = gaps(chosen + [c])
            test = candidate_test(current_c, trial_c, acting_components(c), alpha, thresholds)
            tests[c] = test
            if test.significant and test.median_improvement_fraction > best_gain:
                best, best_gain, best_trial = c, test.median_improvement_fraction, trial_c
        rounds.append(IdentificationRound(base, base_gap, tests))
        if best is None:
            break
        chosen.append(best)
        remaining.remove(best)
        current_c = best_trial
        current = current_c.mean(axis=1)
    vertical_gap = float(np.mean(fit_gaps(problem.runs, fit_gap_model(problem, chosen))[:, 0]))
    withheld: list[str] = []
    if vertical_gap > thresholds.max_vertical_gap:
        withheld, chosen = chosen, []
    return Identification(chosen, rounds, vertical_gap, withheld)
