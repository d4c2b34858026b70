"""Every named effect needed given the others: the backward check after the greedy identification.

The greedy rounds of :func:`~validation.diagnosis.identify.identification.identify_effects` add a candidate when it improves
held-out runs on top of the effects chosen *before* it.  An effect chosen early can stand in for one chosen later: a
quadratic drag added before the linear damping absorbs part of the damping's energy loss, and is still in the set
once the damping has been added, although it is no longer needed.  Here every chosen effect is tested again on
held-out runs against the set without it (the same test and practical thresholds as the greedy rounds,
:func:`~validation.diagnosis.identify.identification.candidate_test`).  The weakest failing effect (largest p) is dropped and
the rest are tested again, re-estimated jointly (every fit of :func:`~validation.diagnosis.calibrate.gap_model.fit_gap_model`
is one joint least-squares fit), until every effect left is needed given all the others.

**Indistinguishable pairs.**  Two effects can explain the same part of the gap so alike that the data cannot tell
them apart: neither improves held-out runs given the other, but dropping both loses a significant improvement
(linear damping against quadratic drag over runs of similar amplitude; a hinge stiffness against a constant torque
when theta barely leaves its mean).  Naming either alone would be a guess.  Such a pair is one verdict
(:class:`IndistinguishablePair`), with the evidence: each member's held-out improvement given the other (both not
significant), the pair's improvement together (significant), and the held-out difference between the model with
one and the model with the other, with its two-sided sign-flip p.  The member with the smaller mean held-out gap
stays in the model (the diagnosis needs one to fit the rest), but neither is named alone.
"""
from __future__ import annotations

import logging
from dataclasses import dataclass, field
from typing import Callable, Sequence

import numpy as np
from numpy.typing import NDArray

from ..prepare.candidate_effects import acting_components
from ..prepare.problem import DiagnosisProblem
from .identification import CandidateTest, PracticalThresholds, candidate_test, held_out_gaps
from .statistics import sign_flip_pvalue

__all__ = ["IndistinguishablePair", "Elimination", "backward_check"]

logger = logging.getLogger(__name__)


@dataclass(frozen=True)
class IndistinguishablePair:
    """Two effects the data cannot tell apart: one verdict naming both.

    Attributes
    ----------
    effects : the two effects, in the order the greedy rounds added them
    kept_in_model : the member that stays in the fitted model (smaller mean held-out gap)
    p_given_other : each member's sign-flip p of its held-out improvement given the other (both >= alpha or below
        the practical thresholds)
    median_improvement_given_other : each member's median per-run held-out improvement given the other
    p_together : the pair's p of its held-out improvement given the rest of the set (significant)
    median_improvement_together : the pair's median per-run held-out improvement given the rest
    median_difference : median per-run held-out gap of the model with ``effects[1]`` minus that with
        ``effects[0]`` (the rest of the set in both): > 0 where ``effects[0]`` fits held-out runs better
    p_difference : two-sided sign-flip p of that difference (large: the data do not prefer either)
    """

    effects: tuple[str, str]
    kept_in_model: str
    p_given_other: dict[str, float]
    median_improvement_given_other: dict[str, float]
    p_together: float
    median_improvement_together: float
    median_difference: float
    p_difference: float

    def to_dict(self) -> dict:
        """The diagnosis.json form (``indistinguishable[i]``)."""
        return {"effects": list(self.effects), "kept_in_model": self.kept_in_model,
                "p_given_other": dict(self.p_given_other),
                "median_improvement_given_other": dict(self.median_improvement_given_other),
                "p_together": self.p_together, "median_improvement_together": self.median_improvement_together,
                "median_difference": self.median_difference, "p_difference": self.p_difference}


@dataclass(frozen=True)
class Elimination:
    """Result of :func:`backward_check`."""

    named: list[str]  #: effects needed given all the others, named alone (greedy order)
    model_effects: list[str]  #: ``named`` plus the kept member of each indistinguishable pair (greedy order)
    dropped: list[str] = field(default_factory=list)  #: effects not needed given the others, in the order dropped
    indistinguishable: list[IndistinguishablePair] = field(default_factory=list)
    #: each effect's last test against the set without it (``p_value`` etc. given all the others)
    tests: dict[str, CandidateTest] = field(default_factory=dict)
    #: each dropped effect's test at the time it was dropped
    dropped_tests: dict[str, CandidateTest] = field(default_factory=dict)


def backward_check(problem: DiagnosisProblem, chosen: Sequence[str], alpha: float = 0.01,
                   thresholds: PracticalThresholds = PracticalThresholds(), folds: int = 5,
                   log: Callable[..., None] = logger.info,
                   cache: dict[tuple[str, ...], NDArray[np.float64]] | None = None) -> Elimination:
    """Test every chosen effect against the set without it on held-out runs; drop the weakest failing one and
    repeat; pair up effects that only work as either one (module docstring).

    Parameters
    ----------
    problem : DiagnosisProblem
    chosen : the effects of the greedy rounds, in the order added
    alpha, thresholds : the greedy rounds' significance level and practical thresholds
    folds : K of the K-fold over runs
    log : where the decisions are logged
    cache : held-out gaps by sorted effect names, shared with the greedy rounds (filled here)
    """
    cache = {} if cache is None else cache

    def gaps(effects: Sequence[str]) -> NDArray[np.float64]:
        key = tuple(sorted(effects))
        if key not in cache:
            cache[key] = held_out_gaps(problem, list(effects), folds)
        return cache[key]

    order = list(chosen)
    kept = list(chosen)
    paired: dict[str, str] = {}  # kept member -> the other member of its pair
    pairs: list[IndistinguishablePair] = []
    dropped: list[str] = []
    tests: dict[str, CandidateTest] = {}
    dropped_tests: dict[str, CandidateTest] = {}
    while kept:
        full = gaps(kept)
        round_tests = {e: candidate_test(gaps([x for x in kept if x != e]), full, acting_components(e), alpha,
                                         thresholds) for e in kept}
        tests.update(round_tests)
        failing = sorted((e for e in kept if not round_tests[e].significant),
                         key=lambda e: (-round_tests[e].p_value, round_tests[e].median_improvement))
        if not failing:
            break
        weakest = failing[0]
        partner = None
        if weakest not in paired:
            for f in failing[1:]:
                if f in paired:
                    continue
                comps = sorted(set(acting_components(weakest)) | set(acting_components(f)))
                both = candidate_test(gaps([x for x in kept if x not in (weakest, f)]), full, comps, alpha, thresholds)
                if both.significant:
                    partner = f
                    break
        if partner is None:
            log("backward check: %s is not needed given %s (held-out p = %.2g, median improvement %.3g); dropped",
                weakest, [e for e in kept if e != weakest] or "the calibration", round_tests[weakest].p_value,
                round_tests[weakest].median_improvement)
            kept.remove(weakest)
            dropped.append(weakest)
            dropped_tests[weakest] = round_tests[weakest]
            if weakest in paired:  # the pair as a whole is not needed
                pairs = [p for p in pairs if p.kept_in_model != weakest]
                dropped.append(paired.pop(weakest))
            continue
        pair = _pair(problem, kept, (weakest, partner), order, gaps, round_tests, alpha, thresholds)
        other = partner if pair.kept_in_model == weakest else weakest
        log("backward check: %s and %s explain the same part of the gap and the data cannot tell them apart "
            "(each given the other: p = %.2g and %.2g; together p = %.2g; held-out difference p = %.2g); %s is kept "
            "in the model, neither is named alone", *pair.effects, *(pair.p_given_other[e] for e in pair.effects),
            pair.p_together, pair.p_difference, pair.kept_in_model)
        kept.remove(other)
        paired[pair.kept_in_model] = other
        pairs.append(pair)
    named = [e for e in kept if e not in paired]
    return Elimination(named, kept, dropped, pairs, {e: tests[e] for e in kept}, dropped_tests)


def _pair(problem: DiagnosisProblem, kept: Sequence[str], members: tuple[str, str], order: Sequence[str],
          gaps: Callable[[Sequence[str]], NDArray], tests: dict[str, CandidateTest], alpha: float,
          thresholds: PracticalThresholds) -> IndistinguishablePair:
    """The verdict on two effects that only work as either one: the evidence, and which one the model keeps."""
    a, b = sorted(members, key=order.index)
    full = gaps(kept)
    rest = [x for x in kept if x not in (a, b)]
    with_a, with_b = gaps(rest + [a]).mean(axis=1), gaps(rest + [b]).mean(axis=1)
    comps = sorted(set(acting_components(a)) | set(acting_components(b)))
    together = candidate_test(gaps(rest), full, comps, alpha, thresholds)
    diff = with_b - with_a
    p_two = min(1.0, 2.0 * min(sign_flip_pvalue(diff), sign_flip_pvalue(-diff)))
    return IndistinguishablePair(
        (a, b), a if float(np.mean(with_a)) <= float(np.mean(with_b)) else b,
        {a: tests[a].p_value, b: tests[b].p_value},
        {a: tests[a].median_improvement, b: tests[b].median_improvement},
        together.p_value, together.median_improvement, float(np.median(diff)), float(p_two))
