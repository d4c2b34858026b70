"""The registry of term-selection rules of the per-run ensemble: what ``SelectionConfig.rule`` and ``--selection`` choose.

A rule is an object satisfying :class:`SelectionRule`: a name, a one-line summary, its prose for the report and
the figures (``description``, ``selected_by``), the fitting methods it
applies to (:data:`fitting.methods.registry.METHODS`; the discovery selects its terms itself, on the held-out path),
whether it is followed by backward elimination on the joint long-time loss, and ``support(evidence, config)``,
the support mask from the per-run fits.  :class:`SelectionConfig` (defined here, beside the rules it names; also
imported from :mod:`fitting.selection.backward_elimination`) checks its ``rule`` against
:data:`SELECTION_RULES` on construction (before any work), and the fit command offers the registered names.

Built-in rules (method ``"paper"``): ``"significance"`` (default; the ensemble mean significantly non-zero,
t-test with Holm's rule, :func:`fitting.selection.ensemble.select_significant_terms`), ``"zscore"`` (the paper's z > 3
rule, :func:`fitting.selection.ensemble.select_terms`) and ``"backward"`` (backward elimination on the joint loss,
:func:`fitting.selection.backward_elimination.backward_elimination`, from the candidate support).
"""
from __future__ import annotations

import logging
from dataclasses import dataclass, field
from typing import Protocol, runtime_checkable

import numpy as np
from numpy.typing import NDArray

from cubedimer.config_checks import check_choice, check_fraction, check_whole
from cubedimer.terms import EQUATION_NAMES
from ..model import TERMS
from ..refinement.long_time import RefineConfig
from .ensemble import EnsembleConfig, TermStatistics, select_significant_terms

__all__ = ["SelectionConfig", "SelectionEvidence", "SelectionRule", "SELECTION_RULES", "DEFAULT_RULE",
           "register_selection_rule",
           "selection_rule_names", "support_text"]

logger = logging.getLogger(__name__)

#: The rule of ``SelectionConfig()``.
DEFAULT_RULE = "significance"


def support_text(mask: NDArray[np.bool_]) -> str:
    """``"yddot: t1, t2; thetaddot: ..."`` of a support mask (2, 35), for log lines."""
    return "; ".join(f"{eq}: " + ", ".join(t for t, k in zip(TERMS, mask[q]) if k) for q, eq in enumerate(EQUATION_NAMES))


@dataclass(frozen=True, eq=False)
class SelectionEvidence:
    """What a rule selects from.

    Attributes
    ----------
    stats : TermStatistics
        Across-run statistics of the per-run refined models.
    mask_zscore : ndarray of bool (2, 35)
        The paper's z-score rule on them (always computed).
    candidates : ndarray of bool (2, 35)
        The candidate support: the pooled regression's support plus the damping terms.
    ensemble : EnsembleConfig
    """

    stats: TermStatistics
    mask_zscore: NDArray[np.bool_]
    candidates: NDArray[np.bool_]
    ensemble: EnsembleConfig


@runtime_checkable
class SelectionRule(Protocol):
    """A term-selection rule (module docstring).

    Attributes
    ----------
    name : str
    summary : str
        One sentence for the command-line help.
    methods : tuple of str
        The fitting methods the rule applies to.
    description : str
        What the rule keeps, as a noun phrase for the report's account of the fit ("terms whose ...").
    selected_by : str
        How it selects, completing "red: selected ..." in the z-score figure's title ("by ...").
    """

    name: str
    summary: str
    methods: tuple[str, ...]
    description: str
    selected_by: str

    def eliminates(self, config: SelectionConfig) -> bool:
        """Whether backward elimination on the joint loss follows ``support``."""
        ...

    def support(self, evidence: SelectionEvidence, config: SelectionConfig) -> NDArray[np.bool_]:
        """The selected support (2, 35) (the start of the elimination when ``eliminates``)."""
        ...


#: name -> rule, in registration order.
SELECTION_RULES: dict[str, SelectionRule] = {}


def register_selection_rule(rule: SelectionRule) -> SelectionRule:
    """Add ``rule`` to :data:`SELECTION_RULES` under ``rule.name``; returns it (TypeError if it is not a rule)."""
    if not isinstance(rule, SelectionRule) or not isinstance(rule.name, str) or not rule.name:
        raise TypeError(f"{rule!r} is not a SelectionRule (name, summary, methods, description, selected_by, "
                        "eliminates, support)")
    SELECTION_RULES[rule.name] = rule
    return rule


def selection_rule_names(method: str | None = None) -> tuple[str, ...]:
    """The registered rule names (those applying to ``method`` if given)."""
    return tuple(n for n, r in SELECTION_RULES.items() if method is None or method in r.methods)


@dataclass(frozen=True)
class SelectionConfig:
    """Settings of the joint-loss selection.

    Parameters
    ----------
    rule : str
        ``"significance"`` (default): terms whose mean coefficient across the per-run refinements is
        significantly non-zero (one-sample t-test, Holm-Bonferroni at ``alpha``, plus the damping
        terms; :func:`fitting.selection.ensemble.select_significant_terms`).  ``"zscore"``: the paper's rule,
        z > ``EnsembleConfig.z_threshold`` plus damping terms; it is always computed and reported, but
        it drops terms that a single 3-s run cannot determine however many runs agree (measured: the
        three weak terms of the reduced model, per-run z 1.2-1.6).  ``"backward"``: backward
        elimination on the joint long-time loss from the pooled regression's support (slow: 410 s
        on 30 runs, and it dropped y*ydot*thetadot, to which the long-time loss is insensitive).
    prune : bool
        With ``"significance"``: follow it by backward elimination on the joint loss (off: measured
        to drop y*ydot*thetadot on the 30-run benchmark, see ``rule``).
    alpha : float
        Family-wise level of the significance rule; level of the one-sided paired Wilcoxon test on
        per-run losses in backward elimination.
    n_try : int
        Removals re-optimised per backward step (the cheapest by the no-refit loss increase).
    screen : RefineConfig
        Joint re-optimisation of a reduced (or enlarged) support during the search.
    forward : bool
        Run the forward check on eliminated terms.
    max_steps : int
    """

    rule: str = DEFAULT_RULE
    alpha: float = 0.01
    n_try: int = 2
    screen: RefineConfig = field(default_factory=lambda: RefineConfig(
        max_evals=150, rel_bound=0.5, abs_bound=0.005, horizons=(1.0,)))
    forward: bool = False
    max_steps: int = 30
    prune: bool = False

    def __post_init__(self) -> None:
        check_choice(self, "rule", tuple(SELECTION_RULES), what="selection rule")
        check_fraction(self, "alpha")
        check_whole(self, "n_try")
        check_whole(self, "max_steps")


@dataclass(frozen=True)
class SignificanceRule:
    """Terms whose mean coefficient across runs is significantly non-zero (t-test, Holm at ``alpha``), plus damping;
    followed by backward elimination when ``SelectionConfig.prune``."""

    name: str = "significance"
    summary: str = ("the mean coefficient across runs is significantly non-zero (t-test with Holm correction at "
                    "0.01; default)")
    methods: tuple[str, ...] = ("paper",)
    description: str = ("terms whose mean coefficient across runs is significantly non-zero (one-sample t-test, "
                        "Holm-Bonferroni at 0.01; the paper's z > 3 rule is shown for comparison)")
    selected_by: str = "by the ensemble-mean t-test, Holm"

    def eliminates(self, config: SelectionConfig) -> bool:
        return bool(config.prune)

    def support(self, evidence: SelectionEvidence, config: SelectionConfig) -> NDArray[np.bool_]:
        mask = select_significant_terms(evidence.stats, config.alpha, evidence.ensemble.keep_damping)
        logger.info("significant ensemble means (t-test, Holm, alpha = %g): %d terms: %s", config.alpha,
                    int(mask.sum()), support_text(mask))
        return mask


@dataclass(frozen=True)
class ZScoreRule:
    """The paper's rule: z > ``EnsembleConfig.z_threshold`` plus the damping terms."""

    name: str = "zscore"
    summary: str = "the paper's z > 3 rule (always reported)"
    methods: tuple[str, ...] = ("paper",)
    description: str = "the paper's rule (terms with z > 3 across runs)"
    selected_by: str = "by z > threshold"

    def eliminates(self, config: SelectionConfig) -> bool:
        return False

    def support(self, evidence: SelectionEvidence, config: SelectionConfig) -> NDArray[np.bool_]:
        return evidence.mask_zscore


@dataclass(frozen=True)
class BackwardRule:
    """Backward elimination on the joint long-time loss from the candidate support and the z-rule's terms."""

    name: str = "backward"
    summary: str = "elimination on the joint long-time loss (slow)"
    methods: tuple[str, ...] = ("paper",)
    description: str = "backward elimination on the joint long-time loss"
    selected_by: str = "by backward elimination"

    def eliminates(self, config: SelectionConfig) -> bool:
        return True

    def support(self, evidence: SelectionEvidence, config: SelectionConfig) -> NDArray[np.bool_]:
        return evidence.candidates | evidence.mask_zscore


for _rule in (SignificanceRule(), ZScoreRule(), BackwardRule()):
    register_selection_rule(_rule)
