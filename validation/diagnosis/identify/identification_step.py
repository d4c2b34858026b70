"""The diagnosis's second step, identify: the candidate effects that improve held-out runs (greedy rounds), each
still needed given all the others (the backward check), and the fitted model, :func:`identification_step`."""
from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ..calibrate.gap_model import GapFit, fit_gap_model
from ..calibrate.metrics import fit_gaps, noise_floors, scalar_gap
from ..prepare.candidate_effects import alias_partners, default_candidates
from ..prepare.problem import DiagnosisProblem
from .elimination import backward_check
from .identification import identify_effects
from .statistics import runs_needed, smallest_sign_flip_pvalue

if TYPE_CHECKING:
    from ..steps import DiagnoseConfig

__all__ = ["Identified", "identification_step"]

logger = logging.getLogger(__name__)


@dataclass(frozen=True, eq=False)
class Identified:
    """The identification step's outcome: the greedy rounds, the backward check and the fitted model."""

    ident: object  #: Identification
    elim: object  #: the backward check
    pairs: list
    identified: list[str]
    base: GapFit
    final: GapFit
    per_before: np.ndarray  #: the calibrated simulation's gap per run
    noise_floor: float  #: the mean noise floor


def identification_step(problem: DiagnosisProblem, config: "DiagnoseConfig", progress: bool, log) -> Identified:
    """The candidate effects that improve held-out runs (greedy rounds), each still needed given all the others
    (the backward check; pairs that only work as either one are one verdict naming both), and the fitted model."""
    n = len(problem.runs)
    p_floor = smallest_sign_flip_pvalue(n)
    if p_floor > config.alpha:  # logged in quiet mode too: it changes what "identified: none" means
        logger.warning("with %d runs no effect can be identified at --alpha %g (smallest attainable p %.3g of the "
                       "held-out sign-flip test, 2^-%d); record at least %d runs", n, config.alpha, p_floor,
                       n, runs_needed(config.alpha))
    base = fit_gap_model(problem, [])
    per_before, floor = fit_gaps(problem.runs, base), float(np.mean(noise_floors(problem.runs, base)))
    log("gap before = %.3g (noise floor %.3g); identifying effects", scalar_gap(per_before), floor)
    held_out_cache: dict = {}
    ident = identify_effects(problem, config.candidates, alpha=config.alpha, thresholds=config.thresholds,
                             progress=progress, cache=held_out_cache)
    # a candidate that can stand for a chosen one is checked beside it (the greedy rounds judged it only on top)
    tried = default_candidates() if config.candidates is None else config.candidates
    partners = alias_partners(ident.identified, tried) if ident.identified else []
    if partners:
        log("backward check: %s checked beside %s, which can stand for it", partners, ident.identified)
    elim = backward_check(problem, list(ident.identified) + partners, alpha=config.alpha, thresholds=config.thresholds,
                          log=log, cache=held_out_cache)
    identified = list(elim.model_effects)  # what the model fits; the named ones are decided in the summary
    return Identified(ident, elim, list(elim.indistinguishable), identified, base, fit_gap_model(problem, identified),
                       per_before, floor)
