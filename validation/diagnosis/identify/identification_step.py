"""The diagnosis's second step, identify: the candidate effects that improve held-out runs (greedy rounds), each
still needed given all the others (the backward check), and the fitted model, :func:`identification_step`."""
from __future__ import annotations

import logging
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np

from ..calibrate.gap_model import GapFit, fit_gap_model
from ..calibrate.metrics import fit_gaps, noise_floors, scalar_gap
from ..prepare.candidate_effects import alias_partners, default_candidates
from ..prepare.problem import DiagnosisProblem
from .elimination import backward_check
from .identification import Identification, IdentificationRound, identify_effects
from .output_error import OutputErrorTest, velocity_coupling_output_error
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
    #: the velocity coupling's output-error test (None: not made, :func:`trajectory_test`)
    output_error: OutputErrorTest | None = None


def identification_step(problem: DiagnosisProblem, config: "DiagnoseConfig", progress: bool, log,
                        conditions=None) -> Identified:
    """The candidate effects that improve held-out runs (greedy rounds), each still needed given all the others
    (the backward check; pairs that only work as either one are one verdict naming both), the velocity coupling
    judged on the whole trajectories where the held-out test missed it beside a damping (:func:`trajectory_test`,
    with the experiment ``conditions`` of the air's damping law), and the fitted model."""
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
    ident, identified, oe = trajectory_test(problem, ident, elim, identified, config, conditions, log)
    return Identified(ident, elim, list(elim.indistinguishable), identified, base, fit_gap_model(problem, identified),
                      per_before, floor, oe)


def trajectory_test(problem: DiagnosisProblem, ident: Identification, elim, identified: list[str],
                    config: "DiagnoseConfig", conditions, log) -> tuple[Identification, list[str], OutputErrorTest | None]:
    """The velocity coupling judged on the runs' whole trajectories
    (:func:`~validation.diagnosis.identify.output_error.velocity_coupling_output_error`) beside linear damping, with
    ``config.trajectory_test`` and the experiment ``conditions``.  Where the greedy rounds did not choose it and the
    test is significant, it joins the model as a round of its own, whose test is the candidate's last held-out test
    with the output-error test's p-value (its chi-square's) and record.  Where they chose it (and the backward
    check kept it), the test is made against the model without it, and when significant its record joins the
    coupling's round: its estimates and errors are then the trajectories' (the summary), whose c6 the windows got
    wrong in sign on 3 of 8 strong couplings of the tuning sets.

    Returns
    -------
    the identification (with that round), the model's effects, and the test (None when not made)
    """
    name = "velocity_coupling"
    if (not config.trajectory_test or conditions is None or name not in config.candidates
            or "linear_damping" not in identified or ident.withheld):
        return ident, identified, None
    if name in ident.identified:  # chosen by the held-out rounds: its estimates and errors from the trajectories
        if name not in identified:  # removed by the backward check
            return ident, identified, None
        others = [e for e in identified if e != name]
        oe = velocity_coupling_output_error(problem, fit_gap_model(problem, others), conditions, config.alpha)
        if oe is not None and oe.significant:
            i = ident.identified.index(name)
            chosen = ident.rounds[i]
            tests = {**chosen.candidates, name: replace(chosen.candidates[name], output_error=oe.to_dict())}
            ident = replace(ident, rounds=ident.rounds[:i] + [replace(chosen, candidates=tests)] + ident.rounds[i + 1:])
        return ident, identified, oe
    held_out = ident.last_tests().get(name)
    if held_out is None:
        return ident, identified, None
    log("velocity coupling: not chosen by the held-out rounds; judged on the whole trajectories (output error)")
    oe = velocity_coupling_output_error(problem, fit_gap_model(problem, identified), conditions, config.alpha)
    if oe is None:
        return ident, identified, oe
    if not oe.significant:  # its record beside the held-out test it did not overturn
        last = ident.rounds[-1]
        if "velocity_coupling" in last.candidates:
            tests = {**last.candidates, "velocity_coupling": replace(held_out, output_error=oe.to_dict())}
            ident = replace(ident, rounds=ident.rounds[:-1] + [replace(last, candidates=tests)])
        return ident, identified, oe
    log("velocity coupling named by its output-error test (Delta chi2 = %.1f noise units, p = %.2g, sign-flip p = "
        "%.2g)", oe.statistic, oe.p_value, oe.sign_flip_p)
    test = replace(held_out, p_value=oe.p_value, significant=True, output_error=oe.to_dict())
    # round i added ident.identified[i]: the coupling's round goes before the greedy rounds' last (where nothing
    # was significant)
    added = IdentificationRound(list(identified), ident.rounds[-1].base_held_out_gap, {"velocity_coupling": test})
    k = len(ident.identified)
    rounds = ident.rounds[:k] + [added] + ident.rounds[k:]
    ident = replace(ident, identified=ident.identified + ["velocity_coupling"], rounds=rounds)
    return ident, identified + ["velocity_coupling"], oe
