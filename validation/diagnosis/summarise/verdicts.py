"""Every candidate effect's verdict (:class:`~validation.diagnosis.summarise.result.EffectVerdict`), ranked: the model's effects
first, in the order the identification added them, then the other candidates fitted on top of them, by gap."""
from __future__ import annotations

from dataclasses import replace
from typing import Mapping, Sequence

import numpy as np
from numpy.typing import NDArray

from acousim.dynamics.effects import EFFECT_TYPES

from ..calibrate.gap_model import GapFit, fit_gap_model
from ..calibrate.metrics import fit_gaps, scalar_gap
from ..identify.statistics import format_p
from ..prepare.problem import DiagnosisProblem
from .cavity_verdicts import mode_only_with_a_positive_damping, named_only_beyond_cavity, named_only_with_a_mode
from .result import EffectVerdict, rejection
from .uncertainty import ParameterInterval

__all__ = ["ranked_effects", "non_physical_parameters", "gap_without", "not_shrinking", "gap_change",
           "gap_rise", "gap_rises", "gap_change_detail", "GAP_RISE_SIGMAS", "MIN_RUNS_FOR_GAP_ERROR"]

#: A named effect whose addition raises the gap by more than this many standard errors of the rise is rejected
#: (``not_shrinking_gap``): one-sided, about the 2.5 % level of a normal rise (3.5 % with Student's t on 11 degrees of
#: freedom, 12 runs), the report's own threshold for "within its uncertainty". The effect has already passed the
#: held-out test at alpha 0.01; this rule only refuses one that makes the fitted gap measurably worse.
GAP_RISE_SIGMAS = 2.0
#: The fewest runs whose paired differences give the rise a standard error (two degrees of freedom); with fewer, any
#: rise at all rejects the effect.
MIN_RUNS_FOR_GAP_ERROR = 3


def non_physical_parameters(name: str, params: Mapping[str, float]) -> list[str]:
    """The parameters of effect ``name`` fitted with a sign its physics excludes (a negative damping rate or drag
    coefficient: the effect's own non-negative parameters, :mod:`acousim.dynamics.effects`)."""
    allowed = getattr(EFFECT_TYPES.get(name), "_non_negative", ())
    return [p for p in allowed if params.get(p, 0.0) < 0]


def ranked_effects(problem: DiagnosisProblem, candidates: Sequence[str], ident, elim, identified: list[str],
                   named: list[str], in_pair: dict, replaced: dict, joint_params: dict, final: GapFit,
                   per_before: NDArray, uncertainty: Mapping[str, Mapping[str, ParameterInterval]] | None = None,
                   derived: Mapping[str, Mapping[str, ParameterInterval]] | None = None) -> tuple[EffectVerdict, ...]:
    """diagnosis.json's ``effects``.

    Parameters
    ----------
    problem : the calibrated diagnosis problem
    candidates : every candidate effect's name
    ident, elim : the greedy identification and its backward check
    identified : the effects of the final model, in the order added; ``named`` those named as causes
    in_pair : the indistinguishable pair of each effect in one
    replaced : the p-value of every candidate the discovered terms replaced, by name
    joint_params : the model effects' parameters re-estimated with the discovered terms
    final : the fit of the final model's effects
    per_before : the calibrated simulation's gap per run and component (n_runs, 3), alone
        (:attr:`~validation.diagnosis.identify.identification_step.Identified.per_before`)
    uncertainty : the model effects' parameter intervals (:func:`~validation.diagnosis.summarise.uncertainty.jackknife_errors`)

    Every candidate the model does not fit is ``rejected`` (one of an indistinguishable pair excepted), with its
    reasons: not significant, removed by the backward check, replaced by the discovered terms, withheld, and a
    non-physical sign of its fit on top of the model.
    """
    runs = problem.runs
    gap_before = scalar_gap(per_before)
    # the per-run gaps of the calibrated simulation and of each cumulative fit: the rise of the gap an effect causes
    # is paired run by run (the same runs without and with it)
    per_run = [per_before] + [fit_gaps(runs, fit_gap_model(problem, identified[:i]))
                              for i in range(1, len(identified) + 1)]
    model_effects = [_model_effect(problem, ident, elim, identified, i, named, in_pair, joint_params, gap_before,
                                   per_run[i], per_run[i + 1], final, (uncertainty or {}).get(identified[i]),
                                   (derived or {}).get(identified[i]))
                     for i in range(len(identified))]
    model_effects = [replace(e, **_change_given_others(problem, identified, i, per_run))
                     for i, e in enumerate(model_effects)]
    # an effect named on the whole trajectories (the velocity coupling's output-error test) is judged there, not on
    # the gap of the windows that could not see it
    by_trajectory = {n for n in identified if n in ident.identified
                     and ident.rounds[ident.identified.index(n)].candidates[n].output_error is not None}
    model_effects = [e if e.name in by_trajectory else
                     _named_only_if_shrinking(e, model_effects[i - 1].gap_after if i else gap_before)
                     for i, e in enumerate(model_effects)]
    model_effects = [named_only_with_a_mode(e) for e in model_effects]
    # pair scattering within the cavity's own share of the hinge's stiffness is not told from the cavity
    model_effects = named_only_beyond_cavity(model_effects, problem, final.calibration)
    model_effects = mode_only_with_a_positive_damping(model_effects)
    last_tests = ident.last_tests()
    others = []
    for name in candidates:
        if name in identified:
            continue
        fit = fit_gap_model(problem, identified + [name])
        g = scalar_gap(fit_gaps(runs, fit))
        test = last_tests.get(name)
        given = elim.dropped_tests.get(name)
        status, reasons = ("indistinguishable", ()) if name in in_pair else (
            "rejected", _rejections(name, fit.effects[name], ident, elim, test, replaced))
        others.append(EffectVerdict(
            name, fit.effects[name], g, 1 - g / gap_before, False, test.p_value if test else None,
            test.wilcoxon_p if test else None, test.median_improvement_fraction if test else None,
            note=_why_not_in_model(name, ident, elim, given, in_pair, replaced),
            p_value_given_others=given.p_value if given else None,
            median_improvement_given_others=given.median_improvement if given else None,
            status=status, rejected_because=reasons))
    return tuple(model_effects + sorted(others, key=lambda e: e.gap_after))


def gap_without(effects: Sequence[EffectVerdict], gap_before: float, effect: EffectVerdict) -> float:
    """The gap a model effect was added to: the gap with the model's effects before it (``gap_after`` of the model
    effect before it, in the order added), or the calibrated simulation's gap for the first."""
    model = [e for e in effects if e.significant]
    i = next(i for i, e in enumerate(model) if e.name == effect.name)
    return model[i - 1].gap_after if i else gap_before


def not_shrinking(effect: EffectVerdict) -> bool:
    """A model effect that improved held-out runs but whose addition raises the gap beyond its error (rejected with
    the code ``not_shrinking_gap``)."""
    return any(r.get("code") == "not_shrinking_gap" for r in effect.rejected_because)


def gap_change(per_before: NDArray, per_after: NDArray) -> tuple[float, float | None]:
    """The change of the scalar gap an effect causes, with its standard error over runs.

    Parameters
    ----------
    per_before, per_after : the per-run gap components (n_runs, 3) without and with the effect
        (:func:`~validation.diagnosis.calibrate.metrics.fit_gaps`, the same runs)

    Returns
    -------
    change : the mean over runs of ``d_r``, each run's change of its mean-over-components gap (equal to the change of
        the scalar gap)
    std_error : ``std(d, ddof=1) / sqrt(R)`` over the R runs; None with fewer than :data:`MIN_RUNS_FOR_GAP_ERROR`
    """
    d = np.mean(np.asarray(per_after, float), axis=1) - np.mean(np.asarray(per_before, float), axis=1)
    std_error = float(np.std(d, ddof=1) / np.sqrt(d.size)) if d.size >= MIN_RUNS_FOR_GAP_ERROR else None
    return float(np.mean(d)), std_error


def _change_given_others(problem: DiagnosisProblem, identified: list[str], i: int,
                         per_run: Sequence[NDArray]) -> dict:
    """The ``gap_*_given_others`` fields of the model's ``i``-th effect: the final model's per-run gaps
    (``per_run[-1]``) against those of the model refitted without it (the calibrated simulation's for a model of one
    effect; the cumulative fit before it for the last one added), paired run by run."""
    if i == len(identified) - 1:
        per_others = per_run[-2]
    else:
        per_others = fit_gaps(problem.runs, fit_gap_model(problem, identified[:i] + identified[i + 1:]))
    change, std_error = gap_change(per_others, per_run[-1])
    return {"gap_without_given_others": scalar_gap(per_others), "gap_change_given_others": change,
            "gap_change_given_others_std_error": std_error}


def gap_rise(effect: EffectVerdict, before: float) -> tuple[float, float, float, float | None]:
    """(the gap without ``effect``, the gap with it, the change, its standard error or None) of the effect's addition,
    as the rule ``not_shrinking_gap`` judges it: given the model's other effects where the verdict carries it (the
    final model refitted without it), else in the order added, to a model whose gap was ``before`` (a diagnosis.json
    written before the given-others keys)."""
    if effect.gap_change_given_others is not None and effect.gap_without_given_others is not None:
        without = effect.gap_without_given_others
        return (without, without + effect.gap_change_given_others, effect.gap_change_given_others,
                effect.gap_change_given_others_std_error)
    change = effect.gap_change if effect.gap_change is not None else effect.gap_after - before
    return before, effect.gap_after, change, effect.gap_change_std_error


def gap_rises(effect: EffectVerdict, before: float) -> bool:
    """Whether adding ``effect`` raises the gap (:func:`gap_rise`: given the model's other effects, or to a model
    whose gap was ``before``): by more than :data:`GAP_RISE_SIGMAS` standard errors of the rise where the verdict
    carries one, by anything at all where it does not (too few runs, or a diagnosis.json written before the rise
    carried its error)."""
    without, with_it, change, error = gap_rise(effect, before)
    if with_it < without:
        return False
    if error is None:
        return True
    return change > GAP_RISE_SIGMAS * error


def gap_change_detail(effect: EffectVerdict, before: float) -> str:
    """Both gaps and, where the verdict carries its error, the relative change with it (:func:`gap_rise`):
    ``"given the other effects 0.002293 -> 0.002329, +1.6 +- 2.0 %"``."""
    without, with_it, change, error = gap_rise(effect, before)
    given = "given the other effects " if effect.gap_change_given_others is not None else ""
    text = f"{given}{without:.4g} -> {with_it:.4g}"
    if error is None or not without > 0:
        return text
    change, error = 100 * change / without, 100 * error / without
    # the error to two significant digits (at least one decimal), the change to the same decimals
    decimals = int(min(4, max(1, 1 - np.floor(np.log10(error))))) if error > 0 else 1
    return text + f", {change:+.{decimals}f} +- {error:.{decimals}f} %"


def _named_only_if_shrinking(effect: EffectVerdict, before: float) -> EffectVerdict:
    """A named model effect whose addition raises the gap significantly (:func:`gap_rises`) is not named: it is
    rejected with both gaps and the change with its error (it stays in the fitted model, whose gap it is part of). One
    whose change is within its error stays named."""
    if effect.status != "named" or not gap_rises(effect, before):
        return effect
    return replace(effect, named=False, status="rejected",
                   rejected_because=(rejection("not_shrinking_gap", gap_change_detail(effect, before)),))


def _rejections(name: str, params: Mapping[str, float], ident, elim, test, replaced: dict) -> tuple[dict, ...]:
    """Why a candidate the model does not fit is rejected (codes of :data:`~validation.diagnosis.summarise.result.REJECTIONS`)."""
    out = []
    if name in replaced:
        out.append(rejection("replaced_by_discovered_terms", format_p(replaced[name])))
    elif name in elim.dropped:
        given = elim.dropped_tests.get(name)
        out.append(rejection("removed_by_backward_check", format_p(given.p_value) if given else ""))
    elif name in ident.withheld:
        out.append(rejection("withheld", f"vertical gap {ident.vertical_gap:.2g}"))
    else:
        out.append(rejection("not_significant", format_p(test.p_value) if test else "never tested"))
    bad = non_physical_parameters(name, params)
    if bad:
        out.append(rejection("non_physical_sign", ", ".join(f"{p} = {params[p]:.3g} < 0" for p in bad)))
    return tuple(out)


def _model_effect(problem: DiagnosisProblem, ident, elim, identified: list[str], i: int, named: list[str],
                  in_pair: dict, joint_params: dict, gap_before: float, per_without: NDArray, per_with: NDArray,
                  final: GapFit, uncertainty: Mapping[str, ParameterInterval] | None,
                  derived: Mapping[str, ParameterInterval] | None = None) -> EffectVerdict:
    """The verdict of the model's ``i``-th effect, with the gap after the cumulative fit of the first ``i + 1``
    (per run ``per_with``; ``per_without`` that of the first ``i``) and the change with its standard error."""
    name = identified[i]
    g = scalar_gap(per_with)
    change, change_error = gap_change(per_without, per_with)
    test, added = _greedy_test(ident, name)
    given = elim.tests.get(name)
    return EffectVerdict(
        name, joint_params[name], g, 1 - g / gap_before, True, test.p_value, test.wilcoxon_p,
        test.median_improvement_fraction, added_in_round=added, named=name in named,
        p_value_given_others=given.p_value if given else None,
        median_improvement_given_others=given.median_improvement if given else None,
        indistinguishable_from=tuple(e for e in in_pair[name].effects if e != name) if name in in_pair else None,
        # fitted beside discovered terms: the effects-only values too
        params_without_discovered_terms=final.effects[name] if joint_params[name] != final.effects[name] else None,
        status="named" if name in named else "indistinguishable", gap_change=change, gap_change_std_error=change_error,
        uncertainty=None if uncertainty is None else dict(uncertainty), derived=None if derived is None else dict(derived))


def _greedy_test(ident, name: str):
    """(the greedy rounds' test of ``name`` when it was added, its round) for a chosen effect; for a candidate the
    backward check tested beside a chosen one it can stand for (an alias partner), its test in the last round it was
    tried in, and no round."""
    if name in ident.identified:
        i = ident.identified.index(name)
        return ident.rounds[i].candidates[name], i + 1
    return ident.last_tests()[name], None


def _why_not_in_model(name: str, ident, elim, given, in_pair: dict, replaced: dict) -> str:
    """The note of a candidate the final model does not fit."""
    note = "fitted on top of the identified effects; not a significant held-out improvement"
    if name in elim.dropped:
        t, added = _greedy_test(ident, name)
        first = (f"improved held-out runs when added ({format_p(t.p_value)})" if added is not None else
                 "checked beside the chosen effect it can stand for")
        note = (f"{first}, but not given the other effects "
                f"(backward check{', ' + format_p(given.p_value) if given else ''}): the others explain its share "
                "of the gap")
    if name in in_pair:
        other = [e for e in in_pair[name].effects if e != name][0]
        note = (f"indistinguishable from {other}: the data cannot tell them apart (see indistinguishable); "
                f"{other} stands for both in the fitted model")
    if name in replaced:
        note = (f"improved held-out runs, but not once the discovered terms are fitted ({format_p(replaced[name])}): "
                "the discovered terms explain its share of the gap better")
    return note
