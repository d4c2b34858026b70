"""What a fit produces: prepared runs, per-run results of each method and the one :class:`FitResult`."""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Protocol, Sequence, Union, runtime_checkable

import numpy as np

from cubedimer.attractors import AttractorClass
from cubedimer.dataset import Run
from cubedimer.system import LEVITATED_DIMER, SystemSpec
from cubedimer.terms import EQUATION_NAMES
from .config import FitConfig
from .derivatives.preparation import RunPreparation
from .derivatives.savitzky_golay import Derivatives
from .model import TERMS, PolynomialModel, Scales
from .refinement.long_time import RefineResult
from .refinement.losses import LossTerms
from .selection.ensemble import TermStatistics, mean_pvalues
from .uncertainty.oracle import OracleResult

__all__ = ["PreparedRun", "RunFit", "RunEstimate", "PerRunResult", "MethodExtras", "EnsembleExtras", "FitResult",
           "support_terms"]


def support_terms(mask: np.ndarray) -> dict[str, list[str]]:
    """``{equation: [term, ...]}`` of a support mask (2, 35), as model.json lists selected terms."""
    return {eq: [t for t, k in zip(TERMS, mask[q]) if k] for q, eq in enumerate(EQUATION_NAMES)}


@dataclass(frozen=True, eq=False)
class PreparedRun:
    """A loaded run with its derivatives and attractor class.

    ``run`` is the run as fitted: block-averaged by ``frames_averaged`` recorded frames per fitted frame at high
    frame rates (:mod:`fitting.derivatives.decimation`; 1: every recorded frame).  ``preparation``: the run's one
    preparation (:class:`fitting.derivatives.preparation.RunPreparation`) that ``run``, ``derivs`` and ``f_y`` are read
    from (None: made without one)."""

    run: Run
    derivs: Derivatives
    f_y: float
    attractor: AttractorClass
    frames_averaged: int = 1
    preparation: RunPreparation | None = None


@dataclass(frozen=True, eq=False)
class RunFit:
    """Per-run result of the paper's method: regression model C0 and its long-time refinement."""

    name: str
    c0: PolynomialModel
    refined: PolynomialModel
    loss_c0: LossTerms
    loss_refined: LossTerms
    history: np.ndarray
    n_evals: int
    status: int

    @property
    def model(self) -> PolynomialModel:
        """The run's model: the refined one."""
        return self.refined

    @property
    def regression(self) -> PolynomialModel:
        """The run's regression model (C0)."""
        return self.c0

    def to_json(self) -> dict:
        """Everything, for the resume cache (with the optimisation history)."""
        return {"file": self.name, "equations": self.refined.equations(), "c0": self.c0.equations(),
                "loss_c0": self.loss_c0.to_dict(), "loss_refined": self.loss_refined.to_dict(),
                "n_evals": self.n_evals, "nlopt_status": self.status, "history": self.history.tolist()}

    def model_json(self) -> dict:
        """The run's ``per_run`` entry of model.json (the cache entry without the history)."""
        d = self.to_json()
        d.pop("history")
        return d

    @classmethod
    def from_json(cls, d: dict) -> "RunFit":
        return cls(name=d["file"], c0=PolynomialModel.from_equations(d["c0"]),
                   refined=PolynomialModel.from_equations(d["equations"]),
                   loss_c0=LossTerms(**d["loss_c0"]), loss_refined=LossTerms(**d["loss_refined"]),
                   history=np.asarray(d["history"], float), n_evals=int(d["n_evals"]),
                   status=int(d["nlopt_status"]))


@dataclass(frozen=True, eq=False)
class RunEstimate:
    """Per-run result of the discovery: least squares of the smoothed accelerations on the selected terms.

    Attributes
    ----------
    name : str
        The run's file name.
    model : PolynomialModel
        The run's least-squares coefficients on the pooled model's support (SI).
    loss : LossTerms
        Long-time loss of the pooled discovered model on this run.
    """

    name: str
    model: PolynomialModel
    loss: LossTerms

    @property
    def regression(self) -> PolynomialModel:
        """The run's regression model: its least squares."""
        return self.model

    def model_json(self) -> dict:
        """The run's ``per_run`` entry of model.json."""
        return {"file": self.name, "equations": self.model.equations(),
                "fit": "least squares of the smoothed accelerations on the selected terms (this run alone)"}


#: A method's per-run result (each has ``name``, ``model``, ``regression`` and ``model_json()``).
PerRunResult = Union[RunFit, RunEstimate]


@runtime_checkable
class MethodExtras(Protocol):
    """What a method produces beyond :class:`FitResult` (``FitResult.extras``, typed per method: the paper's
    :class:`fitting.methods.paper.PaperExtras`, the discovery's :class:`fitting.methods.discovery.DiscoveryExtras`)."""

    def record(self, result: "FitResult") -> dict:
        """The method's own keys of model.json (docs/formats.md), e.g. ``zscores``, ``selection``, ``discovery``."""
        ...


@dataclass(frozen=True, eq=False)
class EnsembleExtras:
    """The across-run statistics of the per-run models, for a method that has them.

    Attributes
    ----------
    stats : TermStatistics
        Across-run statistics of the per-run models.
    mask_zscore : ndarray of bool, shape (2, 35)
        The paper's rule (z > threshold plus damping terms) on the per-run models, always reported.
    """

    stats: TermStatistics
    mask_zscore: np.ndarray

    def record(self, result: "FitResult") -> dict:
        """model.json's ``zscores``, ``inclusion_frequency``, ``coefficient_mean``, ``coefficient_std`` and
        ``selection``."""
        s = self.stats
        return {"zscores": s.as_dict(s.zscore), "inclusion_frequency": s.as_dict(s.inclusion),
                "coefficient_mean": s.as_dict(s.mean), "coefficient_std": s.as_dict(s.std),
                "selection": self.selection_record(result)}

    def selection_record(self, result: "FitResult", rule: str | None = None) -> dict:
        """Which rule produced ``equations`` (the method's name when it selects the terms itself) and what the
        z-score rule gives."""
        return {"rule": rule if rule is not None else result.method,
                "mean_pvalues": self.stats.as_dict(mean_pvalues(self.stats)),
                "zscore_rule": {"z_threshold": result.config.method.ensemble.z_threshold,
                                "selected_terms": support_terms(self.mask_zscore)}}


@dataclass(frozen=True, eq=False)
class FitResult:
    """Everything a fitting method produced: what every method produces, and its own ``extras``.

    Attributes
    ----------
    runs : list of PreparedRun
    scales : Scales
    pooled_regression : PolynomialModel
        The regression on all runs pooled that the method starts from (paper: the joint SINDy C0;
        discovery: the integral-form least squares of the discovered support).
    run_fits : list of RunFit or RunEstimate
        One per run, of the method's kind.
    mask : ndarray of bool, shape (2, 35)
        The final model's support.
    joint_start, joint : PolynomialModel, RefineResult
        Start and result of the final joint long-time optimisation (re-optimisation or polish).
    config : FitConfig
    extras : MethodExtras or None
        The method's own results (the paper's: statistics, rule, elimination, integral-form cross-check; the
        discovery's: statistics and its path), with their keys of model.json (``extras.record``).
    fallback : dict or None
        When the selected model blew up: ``{"reason", "used", "blown_up_model", "candidates"}``.
    oracle : OracleResult or None
        Oracle standard errors of the final model's terms at the data's tracking noise.
    skipped, n_glitches :
        Files the loader skipped (with reasons) and glitch frames it masked (set by :func:`fitting.fit_dataset`).
    meta : dict
        The data set's validated meta.json (set by :func:`fitting.fit_dataset`; model.json records its dimer).
    """

    runs: list[PreparedRun]
    scales: Scales
    pooled_regression: PolynomialModel
    run_fits: Sequence[PerRunResult]
    mask: np.ndarray
    joint_start: PolynomialModel
    joint: RefineResult
    config: FitConfig
    extras: MethodExtras | None = None
    fallback: dict | None = None
    oracle: OracleResult | None = None
    skipped: tuple[dict, ...] = ()
    n_glitches: int = 0
    system: SystemSpec = LEVITATED_DIMER
    meta: dict = field(default_factory=dict)

    @property
    def model(self) -> PolynomialModel:
        """The final model, jointly optimised (SI)."""
        return self.joint.model

    @property
    def method(self) -> str:
        """The method that produced the result."""
        return self.config.method.name
