"""The diagnosis's third step, discover: the library terms that carry what the identified effects leave, and the
identified candidates judged against them, :func:`discovery_step`."""
from __future__ import annotations

from functools import partial
from typing import TYPE_CHECKING

from acousim.dynamics.effects import EFFECT_TYPES

from ..calibrate.gap_model import GapFit, fit_gap_model
from ..identify.identification_step import Identified
from ..prepare.problem import DiagnosisProblem
from .joint_model import judge_candidates
from .library_terms import Discovery, discover_terms

if TYPE_CHECKING:
    from ..steps import DiagnoseConfig

__all__ = ["discovery_step", "AIR_DAMPINGS"]

#: The candidate dampings (the air's effects), judged together against discovered terms.
AIR_DAMPINGS = tuple(n for n, t in EFFECT_TYPES.items() if t.acts_without_field and t.candidate)


def _dissipation_rivals(problem: DiagnosisProblem, base: GapFit, identified: list[str], discover) -> Discovery:
    """The dissipative terms found without the identified candidate dampings: on the calibration alone, and, with
    two or more dampings identified, also beside each of them alone (the other effects kept), united.

    Two candidate dampings together can mimic a dissipation neither describes (linear damping and quadratic drag
    reproduce a loss growing as the amplitude^4); on the calibration alone the search can then find its leading term
    only (measured on the centred y-dependent damping: ``y^2*ydot`` at 23 % under the truth, without the ``y*ydot``
    that its centre off the data's origin adds), and the two dampings still improve every held-out run on top of it.
    Beside one damping, the rest of the dissipation's shape is found (there: ``y*ydot`` and ``y^2*ydot``)."""
    out = discover(base, forms=("energy",))
    dampings = [e for e in identified if e in AIR_DAMPINGS]
    if len(dampings) > 1:
        for d in dampings:
            keep = [e for e in identified if e not in dampings or e == d]
            out = out.union(discover(fit_gap_model(problem, keep), forms=("energy",)))
    return out


def discovery_step(problem: DiagnosisProblem, found: Identified, config: "DiagnoseConfig", log):
    """The library terms that carry what the identified effects leave, and the identified candidates judged against
    them: ``(discovery, replaced, identified, final)``, where ``replaced`` holds the p-value of every candidate the
    discovered terms replaced."""
    identified, final = found.identified, found.final
    discovery, replaced = Discovery(), {}
    if not config.discover:
        return discovery, replaced, identified, final
    log("regressing the remaining residual on the library (held-out runs)")
    discover = partial(discover_terms, problem, alpha=config.alpha,
                       min_absolute_improvement=config.discovery_min_improvement,
                       min_relative_improvement=config.min_relative_improvement)
    discovery = discover(final)
    # the model's member of an indistinguishable pair stands for both: the other's library copy is no rival
    partners = {p.kept_in_model: next(e for e in p.effects if e != p.kept_in_model) for p in found.pairs}
    # the candidates are judged against the terms found on top of them, and against the dissipative terms
    # found without them: a candidate damping can absorb the energy loss of a dissipation it does not
    # describe, leaving nothing to discover on top of it
    # a velocity coupling named on the whole trajectories (its output-error test) is not judged again by the windows'
    # held-out test, which could not see it
    oe = found.output_error
    by_trajectory = ["velocity_coupling"] if oe is not None and oe.significant and "velocity_coupling" in identified else []
    for rivals in (discovery, _dissipation_rivals(problem, found.base, identified, discover) if identified
                   else Discovery()):
        judged = [e for e in identified if e not in by_trajectory]
        if rivals.empty or not judged:
            continue
        kept, pvals = judge_candidates(problem, judged, rivals, alpha=config.alpha, group=AIR_DAMPINGS,
                                       partners=partners)
        if kept != judged:
            replaced.update({c: pvals[c] for c in judged if c not in kept})
            identified = [e for e in identified if e in kept or e in by_trajectory]
            final = fit_gap_model(problem, identified)
            discovery = discover(final)
    return discovery, replaced, identified, final
