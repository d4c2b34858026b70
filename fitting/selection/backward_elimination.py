"""Term selection on the joint long-time loss: backward elimination with a paired Wilcoxon test.

The paper's ensemble rule (:func:`fitting.selection.ensemble.select_terms`: z > 3 over per-run refined
coefficients, plus the damping terms) cannot keep a term whose contribution is a few per cent of
the acceleration: one noisy 3-s run does not determine its coefficient, so the per-run values
scatter more than their mean (z ~ 1-1.5) although every run's model contains the term.  The
information is there in the ensemble, so this module selects on the *joint* loss (mean over all
runs) instead:

1. start from the candidate support (the pooled regression's support plus the damping terms),
   jointly refined on all runs;
2. **backward step**: rank the removable terms (all but the damping terms) by the increase of the
   joint loss when the term is set to zero (no re-optimisation, one evaluation each); re-optimise
   the ``n_try`` cheapest removals jointly (in parallel) and test each against the current model
   with the one-sided paired Wilcoxon signed-rank test on the per-run losses
   (:func:`fitting.compare.paired_wilcoxon`, H1: the reduced model is worse).  The removal with the
   smallest mean loss increase among those with ``p_greater >= alpha`` is accepted, and the step
   repeats; if every tried removal is significantly worse, elimination stops;
3. **forward check** (optional, off by default: not yet measured with its control): every eliminated term is added back to the final support (coefficient 0,
   re-optimised jointly); it is restored if the larger model is significantly better
   (``p < alpha`` with the roles swapped) than the current support re-optimised with the same budget.

A term is thus kept iff dropping it makes the long-time fit of the runs significantly worse in a
paired test over runs, which uses all runs' information (its power grows with the number of runs)
while the long-time loss (not the derivative regression) arbitrates between nearly collinear
monomials (e.g. ``ydot^2`` vs ``y^2`` for a nearly harmonic y).
"""
from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import Sequence

import numpy as np
from numpy.typing import NDArray

from cubedimer.executor import ExecutorConfig, map_ordered
from cubedimer.terms import EQUATION_NAMES, coefficient_label
from ..compare import paired_wilcoxon
from ..derivatives.savitzky_golay import Derivatives
from ..model import TERMS, PolynomialModel, Scales, damping_mask
from ..refinement.long_time import Objective, RefineConfig, default_substeps, refine, scaled_reference
from .rules import SelectionConfig  # defined beside the rules it names

def _without_term(coef: np.ndarray, mask: np.ndarray, q: int, j: int) -> tuple[np.ndarray, np.ndarray]:
    """Copies of ``coef`` and ``mask`` with term j of equation q removed."""
    c, m = coef.copy(), mask.copy()
    c[q, j] = 0.0
    m[q, j] = False
    return c, m


__all__ = ["SelectionConfig", "SelectionStep", "SelectionResult", "backward_elimination"]

logger = logging.getLogger(__name__)


@dataclass(frozen=True)
class SelectionStep:
    """One tested change of the support."""

    action: str            # "drop" / "keep" (removal rejected) / "add" / "reject-add"
    equation: str
    term: str
    mean_loss_before: float
    mean_loss_after: float
    p_value: float         # one-sided Wilcoxon: drop -> p(reduced worse); add -> p(smaller model worse)

    def to_dict(self) -> dict:
        return dict(self.__dict__)


@dataclass(frozen=True, eq=False)
class SelectionResult:
    """Selected support, its jointly optimised model and the search log."""

    mask: NDArray[np.bool_]
    model: PolynomialModel
    per_run: list[float]
    steps: list[SelectionStep]


def _reopt_task(task: tuple) -> tuple[NDArray, list[float]]:
    """Joint re-optimisation of ``coef`` (SI) on ``mask``; module-level so it can be pickled."""
    coef, mask, derivs, scales, config = task
    r = refine(PolynomialModel(coef), derivs, scales, config, mask=mask)
    return r.model.coef, [t.total for t in r.per_run_end]


def _per_run(obj_cache: dict, coef_si: NDArray, mask: NDArray, derivs, scales: Scales, config: RefineConfig) -> list[float]:
    key = mask.tobytes()
    if key not in obj_cache:
        refs = obj_cache.setdefault("refs", [scaled_reference(d, scales) for d in derivs])
        c = scales.to_scaled(coef_si)
        obj_cache[key] = Objective(refs, mask, default_substeps(c, refs[0].dt, config.h_omega), config.weights)
    return [t.total for t in obj_cache[key].per_run(np.where(mask, scales.to_scaled(coef_si), 0.0))]


def backward_elimination(model: PolynomialModel, mask: NDArray[np.bool_], derivs: Sequence[Derivatives],
                         scales: Scales, config: SelectionConfig = SelectionConfig(),
                         executor: ExecutorConfig | None = None) -> SelectionResult:
    """Backward elimination (plus forward check) from ``model`` on ``mask`` (see module docstring).

    ``model`` should already be jointly optimised on ``mask`` (its loss is the first reference).
    """
    derivs = list(derivs)
    keep = damping_mask()
    cur_mask = np.asarray(mask, bool) | keep
    cur = model.coef * cur_mask
    cache: dict = {}
    cur_loss = _per_run(cache, cur, cur_mask, derivs, scales, config.screen)
    steps: list[SelectionStep] = []
    dropped: list[tuple[int, int]] = []
    for _ in range(config.max_steps):
        removable = [(q, j) for q, j in zip(*np.nonzero(cur_mask & ~keep))]
        if not removable:
            break
        # rank by the joint-loss increase of simply zeroing the term
        inc = []
        for q, j in removable:
            c, m = _without_term(cur, cur_mask, q, j)
            inc.append(np.mean(_per_run(cache, c, m, derivs, scales, config.screen)) - np.mean(cur_loss))
        order = [removable[k] for k in np.argsort(inc)[: config.n_try]]
        tasks = [(*_without_term(cur, cur_mask, q, j), derivs, scales, config.screen) for q, j in order]
        outs = map_ordered(_reopt_task, tasks, config=executor, desc="backward step", progress=False)
        best = None
        for (q, j), (c, loss) in zip(order, outs):
            w = paired_wilcoxon(loss, cur_loss)
            d = float(np.mean(loss) - np.mean(cur_loss))
            logger.info("  drop %s: mean loss %.4g -> %.4g, p = %.2g", coefficient_label(q, j), np.mean(cur_loss),
                        np.mean(loss), w.p_greater)
            if w.p_greater >= config.alpha and (best is None or d < best[0]):
                best = (d, q, j, c, loss, w.p_greater)
            else:
                steps.append(SelectionStep("keep", EQUATION_NAMES[q], TERMS[j], float(np.mean(cur_loss)),
                                           float(np.mean(loss)), w.p_greater))
        if best is None:
            break
        d, q, j, c, loss, p = best
        steps.append(SelectionStep("drop", EQUATION_NAMES[q], TERMS[j], float(np.mean(cur_loss)),
                                   float(np.mean(loss)), p))
        cur_mask[q, j] = False
        cur, cur_loss = c * cur_mask, loss
        dropped.append((q, j))
    if config.forward and dropped:
        tasks = []
        for q, j in dropped:
            m = cur_mask.copy()
            m[q, j] = True
            tasks.append((cur.copy(), m, derivs, scales, config.screen))
        # control: the current support re-optimised with the same budget, so that the test sees the
        # term and not the extra optimisation (measured: without it every add-back was "significant")
        tasks.append((cur.copy(), cur_mask.copy(), derivs, scales, config.screen))
        outs = map_ordered(_reopt_task, tasks, config=executor, desc="forward check", progress=False)
        ctrl_c, ctrl_loss = outs.pop()
        if np.mean(ctrl_loss) < np.mean(cur_loss):
            cur, cur_loss = ctrl_c * cur_mask, ctrl_loss
        best = None
        for (q, j), (c, loss) in zip(dropped, outs):
            w = paired_wilcoxon(cur_loss, loss)  # H1: the smaller (current) model is worse
            logger.info("  add back %s: mean loss %.4g -> %.4g, p = %.2g", coefficient_label(q, j), np.mean(cur_loss),
                        np.mean(loss), w.p_greater)
            ok = w.p_greater < config.alpha
            steps.append(SelectionStep("add" if ok else "reject-add", EQUATION_NAMES[q], TERMS[j],
                                       float(np.mean(cur_loss)), float(np.mean(loss)), w.p_greater))
            if ok and (best is None or np.mean(loss) < best[0]):
                best = (float(np.mean(loss)), q, j, c, loss)
        if best is not None:  # restore the single most useful term (greedy; one pass)
            _, q, j, c, loss = best
            cur_mask[q, j] = True
            cur, cur_loss = c * cur_mask, loss
    return SelectionResult(mask=cur_mask, model=PolynomialModel(cur * cur_mask), per_run=list(cur_loss), steps=steps)
