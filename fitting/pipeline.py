"""The model-discovery pipeline: data -> C0 -> refined runs -> minimal model.

:func:`fit_dataset` loads a data set, smooths and differentiates every run, classifies its
attractor, fits the regression model C0 (per run, and once jointly for reference), refines
every run's C0 against its long-time features in parallel (through
:func:`cubedimer.executor.map_ordered`), computes z-scores and inclusion frequencies, selects
the minimal model and re-optimises it jointly on all runs.  Each finished per-run refinement is
saved to ``OUT_DIR/runs/<file stem>.json`` together with a fingerprint of its input and settings,
so an interrupted fit resumes without recomputing it.

Never a blown-up model: when the jointly re-optimised minimal model leaves the blow-up bound on any
run, :func:`fit_runs` falls back to the best of (a) the minimal model without its least significant
terms, (b) the regression-only ensemble (median of the per-run C0 on the selected terms) and (c) the
pooled integral-form model, each integrated over every run and scored with the long-time loss; the
winner is re-optimised jointly and ``model.json["fallback"]`` says what happened.  If none of them
integrates over every run with a loss below :data:`MAX_SANE_LOSS`, :class:`NoSaneModelError` is raised
and nothing is written.

Beside every selected term, ``model.json["oracle"]`` gives the oracle standard error and z of the final
model (:mod:`fitting.oracle`) at the data's estimated tracking noise, and the term's closest library alias
with its alias z.
"""
from __future__ import annotations

import hashlib
import json
import os
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Callable, Sequence

import numpy as np

from cubedimer.atomic import write_json
from cubedimer.cli import UserInputError
from cubedimer.attractors import AttractorClass, ClassifyConfig, classify_trajectory
from cubedimer.dataset import Dataset, LoadConfig, Run, load_dataset
from .derivatives import Derivatives, SmoothingConfig, run_derivatives
from .discovery import DiscoveryConfig, DiscoveryResult
from .ensemble import (EnsembleConfig, TermStatistics, least_squares_on_support, mean_pvalues, select_significant_terms, select_terms,
                       term_statistics)
from cubedimer.executor import ExecutorConfig, map_ordered
from .integral_form import METHOD as INTEGRAL_METHOD, IntegralSelection, integral_form_selection
from cubedimer.terms import EQUATION_NAMES, STATE_NAMES
from .losses import LossTerms
from .model import DAMPING_TERMS, TERMS, PolynomialModel, Scales, damping_mask
from .oracle import NoiseLevels, OracleResult, estimate_tracking_noise, oracle_standard_errors, recorded_tracking_noise, runs_from_data
from .refine import JOINT_REFINE, Objective, RefineConfig, RefineResult, default_substeps, refine, scaled_reference
from .regression import RegressionConfig, dataset_scales, fit_regression, scaled_data, scaled_library
from .selection import SelectionConfig, SelectionResult, backward_elimination
from cubedimer.spectra import dominant_frequency

__all__ = ["FitConfig", "METHODS", "PreparedRun", "RunFit", "FitResult", "prepare_runs", "candidate_terms", "refine_run", "fit_runs",
           "fit_dataset", "model_json", "NoSaneModelError", "MAX_SANE_LOSS", "fallback_candidates"]

#: A fallback model must integrate over every run and have a mean long-time loss below this (the rest
#: model, a trajectory sitting at the origin, scores ~2.5: shape ~0.5, Poincare 1, frequency 1).
MAX_SANE_LOSS = 1.0


class NoSaneModelError(UserInputError):
    """The minimal model blows up and no fallback integrates over every run (nothing is written)."""


@dataclass(frozen=True)
class FitConfig:
    """All settings of the pipeline (every stage has its own frozen config)."""

    load: LoadConfig = field(default_factory=LoadConfig)
    smoothing: SmoothingConfig = field(default_factory=SmoothingConfig)
    regression: RegressionConfig = field(default_factory=RegressionConfig)
    refine: RefineConfig = field(default_factory=RefineConfig)
    joint: RefineConfig = JOINT_REFINE
    ensemble: EnsembleConfig = field(default_factory=EnsembleConfig)
    selection: SelectionConfig = field(default_factory=SelectionConfig)
    #: joint refinement of the whole candidate support (start of the backward elimination)
    candidate_joint: RefineConfig = field(default_factory=lambda: RefineConfig(
        max_evals=300, rel_bound=0.3, abs_bound=0.005, horizons=(0.5, 1.0)))
    classify: ClassifyConfig = field(default_factory=ClassifyConfig)
    #: ``"discovery"``: integral-form discovery (:func:`fitting.discovery.discover_model`) selects and fits the
    #: model, the long-time refinement polishes it inside a box of ``polish_se`` of its standard errors;
    #: ``"paper"``: per-run SINDy and long-time refinement, ensemble selection (``selection.rule``), joint
    #: re-optimisation of the minimal model
    method: str = "discovery"
    discovery: DiscoveryConfig = field(default_factory=DiscoveryConfig)
    #: long-time polish of the discovered model (method "discovery")
    polish: RefineConfig = field(default_factory=lambda: RefineConfig(max_evals=150))
    #: half-width of the polish box in the discovery's standard errors
    polish_se: float = 0.5

    def __post_init__(self) -> None:
        if self.method not in METHODS:
            raise ValueError(f"unknown method {self.method!r} (use one of {', '.join(METHODS)})")
        if not self.polish_se > 0:
            raise ValueError(f"polish_se must be positive, got {self.polish_se}")

    def with_heldout_tolerance(self, tolerance: float | None) -> "FitConfig":
        """This configuration with the discovery's practical threshold ``DiscoveryConfig.heldout_tolerance`` (None:
        unchanged); ValueError for the paper's method or a tolerance outside [0, 1)."""
        if tolerance is None:
            return self
        if self.method != "discovery" or not 0.0 <= tolerance < 1.0:
            raise ValueError(f"{tolerance:g}: needs a fraction in [0, 1) and --method discovery (0.002 keeps the "
                             "smallest support within 0.2 % of the best held-out error)")
        return replace(self, discovery=replace(self.discovery, heldout_tolerance=float(tolerance)))


#: Model-discovery methods of :class:`FitConfig` (the first is the default).
METHODS = ("discovery", "paper")
#: FitConfig fields that only the discovery method uses (left out of a paper fit's recorded settings).
DISCOVERY_FIELDS = ("discovery", "polish", "polish_se")


@dataclass(frozen=True, eq=False)
class PreparedRun:
    """A loaded run with its derivatives and attractor class."""

    run: Run
    derivs: Derivatives
    f_y: float
    attractor: AttractorClass


@dataclass(frozen=True, eq=False)
class RunFit:
    """Per-run result: regression model C0 and its long-time refinement."""

    name: str
    c0: PolynomialModel
    refined: PolynomialModel
    loss_c0: LossTerms
    loss_refined: LossTerms
    history: np.ndarray
    n_evals: int
    status: int

    def to_json(self) -> dict:
        return {"file": self.name, "equations": self.refined.equations(), "c0": self.c0.equations(),
                "loss_c0": self.loss_c0.to_dict(), "loss_refined": self.loss_refined.to_dict(),
                "n_evals": self.n_evals, "nlopt_status": self.status, "history": self.history.tolist()}

    @classmethod
    def from_json(cls, d: dict) -> "RunFit":
        return cls(name=d["file"], c0=PolynomialModel.from_equations(d["c0"]),
                   refined=PolynomialModel.from_equations(d["equations"]),
                   loss_c0=LossTerms(**d["loss_c0"]), loss_refined=LossTerms(**d["loss_refined"]),
                   history=np.asarray(d["history"], float), n_evals=int(d["n_evals"]),
                   status=int(d["nlopt_status"]))


@dataclass(frozen=True, eq=False)
class FitResult:
    """Everything the pipeline produced."""

    runs: list[PreparedRun]
    scales: Scales
    c0_joint: PolynomialModel
    run_fits: list[RunFit]
    stats: TermStatistics
    mask: np.ndarray
    joint_start: PolynomialModel
    joint: RefineResult
    config: FitConfig
    skipped: tuple[dict, ...] = ()
    n_glitches: int = 0
    #: the paper's rule (z > threshold plus damping terms) on the per-run refinements; equals
    #: ``mask`` when ``config.selection.rule == "zscore"``
    mask_zscore: np.ndarray | None = None
    #: backward elimination on the joint loss (``rule == "backward"``), else None
    selection: SelectionResult | None = None
    candidate_fit: RefineResult | None = None
    #: the selection rule that produced ``mask`` ("zscore", "significance" or "backward")
    rule: str = "zscore"
    #: the pooled integral-form selection per equation (:func:`fitting.integral_form.integral_form_selection`),
    #: a cross-check reported next to the minimal model; None if the runs are too short for its windows
    integral_form: dict[str, IntegralSelection] | None = None
    #: when the selected minimal model blew up: ``{"reason", "used", "blown_up_model", "candidates"}``
    fallback: dict | None = None
    #: oracle standard errors of the final model's terms at the data's tracking noise
    oracle: OracleResult | None = None
    #: the integral-form discovery (method "discovery"), else None
    discovery: DiscoveryResult | None = None

    @property
    def model(self) -> PolynomialModel:
        """The minimal model, jointly re-optimised (SI)."""
        return self.joint.model


def prepare_runs(runs: Sequence[Run], config: FitConfig = FitConfig()) -> tuple[list[PreparedRun], Scales]:
    """Smooth/differentiate and classify every run; common scales of the data set."""
    out = []
    for r in runs:
        fy = dominant_frequency(r.y, r.dt)
        d = run_derivatives(r.t, r.y, r.theta, fy, config.smoothing)
        att = classify_trajectory(d.t, d.state, config.classify)
        out.append(PreparedRun(run=r, derivs=d, f_y=fy, attractor=att))
    scales = dataset_scales([p.derivs for p in out], [p.f_y for p in out])
    return out, scales


def candidate_terms(c0_joint: PolynomialModel) -> np.ndarray:
    """Candidate terms for the per-run fits: the pooled regression's support plus the damping terms."""
    mask = c0_joint.support.copy()
    for q, eq in enumerate(EQUATION_NAMES):
        mask[q, TERMS.index(DAMPING_TERMS[eq])] = True
    return mask


def refine_run(task: tuple[str, Derivatives, Scales, FitConfig, np.ndarray | None]) -> RunFit:
    """Per-run regression (C0) and long-time refinement; module-level so it can be pickled."""
    name, d, scales, config, candidates = task
    c0 = fit_regression([d], scales, config.regression, candidates=candidates)
    mask = c0.support.copy()
    for q, eq in enumerate(EQUATION_NAMES):  # damping terms are always refined (and always kept)
        mask[q, TERMS.index(DAMPING_TERMS[eq])] = True
    res = refine(c0, [d], scales, config.refine, mask=mask)
    return RunFit(name=name, c0=c0, refined=res.model, loss_c0=res.loss_start, loss_refined=res.loss_end,
                  history=res.history, n_evals=res.n_evals, status=res.status)


def _fingerprint(p: PreparedRun, scales: Scales, config: FitConfig, candidates: np.ndarray) -> str:
    h = hashlib.sha256()
    for a in (p.run.t, p.run.y, p.run.theta):
        h.update(np.ascontiguousarray(a).tobytes())
    h.update(repr((scales, config.smoothing, config.regression, config.refine)).encode())
    h.update(np.packbits(candidates).tobytes())
    return h.hexdigest()[:32]


def fit_runs(prepared: Sequence[PreparedRun], scales: Scales, config: FitConfig = FitConfig(),
             executor: ExecutorConfig | None = None, cache_dir: str | os.PathLike | None = None,
             progress: bool = True, log: Callable[[str], None] | None = None,
             noise: NoiseLevels | None = None) -> FitResult:
    """Steps 2-4 on prepared runs (see :func:`fit_dataset`); ``config.method`` chooses the method.  ``noise`` is the
    oracle's tracking noise (default: estimated from the runs)."""
    log = log or (lambda m: None)
    if config.method == "discovery":
        from .discovery_fit import fit_discovery
        return fit_discovery(prepared, scales, config, log, noise=noise)
    derivs = [p.derivs for p in prepared]
    try:
        integral = integral_form_selection([p.run for p in prepared], derivs, alpha=config.selection.alpha)
        log("pooled integral form (cross-check): " + "; ".join(
            f"{eq}: " + ", ".join(f"{t} {c:.3g} +- {e:.2g}" for t, c, e in zip(s.terms, s.coefficients, s.std_errors))
            for eq, s in integral.items()))
    except ValueError as err:  # runs shorter than one window
        log(f"pooled integral form skipped: {err}")
        integral = None
    c0_joint = fit_regression(derivs, scales, config.regression)
    candidates = candidate_terms(c0_joint)
    # ---- per-run refinement, resumable -----------------------------------------------
    fits: list[RunFit | None] = [None] * len(prepared)
    fps = [_fingerprint(p, scales, config, candidates) for p in prepared]
    cache = Path(cache_dir) if cache_dir is not None else None
    todo = []
    for i, p in enumerate(prepared):
        if cache is not None:
            f = cache / f"{Path(p.run.name).stem}.json"
            if f.exists():
                try:
                    d = json.loads(f.read_text())
                    if d.get("fingerprint") == fps[i]:
                        fits[i] = RunFit.from_json(d)
                        continue
                except (ValueError, KeyError, TypeError):
                    pass  # unreadable cache: recompute
        todo.append(i)
    if len(todo) < len(prepared):
        log(f"resuming: {len(prepared) - len(todo)} of {len(prepared)} run refinements loaded from {cache}")

    def save(k: int, rf: RunFit) -> None:
        i = todo[k]
        fits[i] = rf
        if cache is not None:
            write_json(cache / f"{Path(rf.name).stem}.json", {**rf.to_json(), "fingerprint": fps[i]})

    map_ordered(refine_run, [(prepared[i].run.name, derivs[i], scales, config, candidates) for i in todo],
                config=executor, desc="refining runs", progress=progress, on_result=save)
    run_fits: list[RunFit] = list(fits)  # type: ignore[arg-type]
    # ---- ensemble ------------------------------------------------------------------
    stats = term_statistics([f.refined for f in run_fits])
    mask_z = select_terms(stats, config.ensemble)
    fmt = lambda m: "; ".join(f"{eq}: " + ", ".join(t for t, k in zip(TERMS, m[q]) if k)  # noqa: E731
                              for q, eq in enumerate(EQUATION_NAMES))
    log(f"z-score rule (z > {config.ensemble.z_threshold:g} plus damping): {int(mask_z.sum())} terms: {fmt(mask_z)}")
    X, A = scaled_data(derivs, scales)
    lib = scaled_library(derivs, scales, config.regression.matched_filter)
    refs = [scaled_reference(d, scales) for d in derivs]
    per_run_scaled = np.array([scales.to_scaled(f.refined.coef) for f in run_fits])

    def best_start(mask: np.ndarray, jcfg: RefineConfig) -> tuple[float, np.ndarray]:
        """The better (lower joint loss) of the per-run median and least squares on ``mask``."""
        best = None
        for c in (np.where(mask, np.median(per_run_scaled, axis=0), 0.0), least_squares_on_support(X, A, mask, lib)):
            obj = Objective(refs, mask, default_substeps(c, refs[0].dt, jcfg.h_omega), jcfg.weights)
            val = obj(c[mask])
            if best is None or val < best[0]:
                best = (val, c)
        return best

    selection = cand_fit = None
    rule = config.selection.rule
    if rule not in ("zscore", "significance", "backward"):
        raise ValueError(f"unknown selection rule {rule!r} (use 'significance', 'backward' or 'zscore')")
    eliminate = rule == "backward" or (rule == "significance" and config.selection.prune)
    if eliminate and 0.5 ** len(derivs) >= config.selection.alpha:
        # the one-sided paired Wilcoxon test on R runs cannot reach p < alpha (min p = 2^-R)
        log(f"{len(derivs)} runs are too few for the Wilcoxon test at alpha = {config.selection.alpha:g}: "
            "using the z-score rule")
        rule, eliminate = "zscore", False
    if rule == "zscore":
        mask = mask_z
    elif rule == "significance":
        mask = select_significant_terms(stats, config.selection.alpha, config.ensemble.keep_damping)
        log(f"significant ensemble means (t-test, Holm, alpha = {config.selection.alpha:g}): "
            f"{int(mask.sum())} terms: {fmt(mask)}")
    else:
        mask = candidates | mask_z
    if eliminate:
        val, c = best_start(mask, config.candidate_joint)
        log(f"joint refinement of the {int(mask.sum())} candidate terms (start loss {val:.4g})")
        cand_fit = refine(PolynomialModel(scales.to_si(c)), derivs, scales, config.candidate_joint, mask=mask)
        log(f"backward elimination on the joint loss (start loss {cand_fit.loss_end.total:.4g})")
        selection = backward_elimination(cand_fit.model, mask, derivs, scales, config.selection, executor, log=log)
        mask = selection.mask
        c = scales.to_scaled(selection.model.coef)
        val = float(np.mean(selection.per_run))
    else:
        val, c = best_start(mask, config.joint)
    log(f"selected ({rule}) {int(mask.sum())} terms: {fmt(mask)}")
    # ---- joint re-optimisation of the minimal model -----------------------------------
    joint_start = PolynomialModel(scales.to_si(c))
    log(f"joint re-optimisation of the minimal model on {len(derivs)} runs (start loss {val:.4g})")
    joint = refine(joint_start, derivs, scales, config.joint, mask=mask)
    log(f"final mean loss {joint.loss_end.total:.4g} (shape {joint.loss_end.shape:.3g}, "
        f"Poincare {joint.loss_end.poincare:.3g}, frequency {joint.loss_end.frequency:.3g})")
    fallback = None
    if joint.loss_end.blown_up:
        joint_start, joint, fallback = _fall_back(joint, mask, stats, run_fits, integral, derivs, scales, config, log)
        mask = joint.model.support
    oracle = _oracle(joint.model, prepared, log, noise)
    return FitResult(runs=list(prepared), scales=scales, c0_joint=c0_joint, run_fits=run_fits, stats=stats,
                     mask=mask, joint_start=joint_start, joint=joint, config=config, mask_zscore=mask_z,
                     selection=selection, candidate_fit=cand_fit, rule=rule, integral_form=integral,
                     fallback=fallback, oracle=oracle)


def _oracle(model: PolynomialModel, prepared: Sequence[PreparedRun], log: Callable[[str], None],
            noise: NoiseLevels | None = None) -> OracleResult | None:
    """Oracle standard errors of ``model``'s terms on the runs at the tracking noise ``noise`` (the one the data
    set records, :func:`fitting.oracle.recorded_tracking_noise`), else at the noise estimated from the runs."""
    derivs = [p.derivs for p in prepared]
    try:
        noise = noise or estimate_tracking_noise([p.run for p in prepared])
        res = oracle_standard_errors(model, runs_from_data(derivs), noise)
    except ValueError as err:
        log(f"oracle skipped: {err}")
        return None
    log(f"oracle z at tracking noise {noise.sigma_y:.3g} m / {noise.sigma_theta:.3g}: " + "; ".join(
        f"{eq}: " + ", ".join(f"{t} {o.z:.3g}" for t, o in terms.items()) for eq, terms in res.terms.items()))
    close = [f"{eq}: {t} / {o.alias} (alias z {o.alias_z:.2g})" for eq, terms in res.terms.items()
             for t, o in terms.items() if o.alias_z < 3.0]
    if close:
        log("terms the data barely tell from their closest library alias (least squares picks the alias in "
            "Phi(-alias_z / 2) of data sets): " + "; ".join(close))
    return res


def _n_blown(per_run: Sequence[LossTerms]) -> int:
    return sum(int(t.blown_up) for t in per_run)


def fallback_candidates(model: PolynomialModel, mask: np.ndarray, stats: TermStatistics, run_fits: Sequence[RunFit],
                        integral: dict[str, IntegralSelection] | None) -> list[tuple[str, PolynomialModel]]:
    """The models tried when the minimal model blows up, in order of preference.

    1. ``model`` without its k least significant terms (largest ensemble-mean p-value; the damping terms
       stay), for k = 1, 2, ...: the terms the selection let in last.
    2. The regression-only ensemble: the median over runs of the per-run regression models C0 on ``mask``.
    3. The pooled integral-form model (its selected terms and coefficients), if available.
    """
    out: list[tuple[str, PolynomialModel]] = []
    p = mean_pvalues(stats)
    removable = np.flatnonzero((model.support & ~damping_mask()).ravel())
    order = removable[np.argsort(-p.ravel()[removable], kind="stable")]  # least significant first
    names = [f"{EQUATION_NAMES[i // len(TERMS)]}:{TERMS[i % len(TERMS)]}" for i in order]
    keep = model.support.copy().ravel()
    for k, idx in enumerate(order[:-1] if len(order) > 1 else []):
        keep[idx] = False
        out.append((f"minimal model without {', '.join(names[:k + 1])}", model.with_mask(keep.reshape(mask.shape))))
    if run_fits:
        c0 = np.median([f.c0.coef for f in run_fits], axis=0)
        out.append(("regression-only ensemble (median of the per-run C0 on the selected terms)",
                    PolynomialModel(np.where(mask, c0, 0.0))))
    if integral is not None:
        eqs = {eq: dict(zip(s.terms, map(float, s.coefficients))) for eq, s in integral.items()}
        out.append(("pooled integral-form model", PolynomialModel.from_equations(eqs)))
    return out


def _fall_back(joint: RefineResult, mask: np.ndarray, stats: TermStatistics, run_fits: Sequence[RunFit],
               integral: dict[str, IntegralSelection] | None, derivs: Sequence[Derivatives], scales: Scales,
               config: FitConfig, log: Callable[[str], None],
               first: Sequence[tuple[str, PolynomialModel]] = ()) -> tuple[PolynomialModel, RefineResult, dict]:
    """Replace a blown-up minimal model by the best sane fallback (module docstring), re-optimised jointly.

    ``first``: (name, model) candidates tried before those of :func:`fallback_candidates`.

    Returns (start of the re-optimisation, its result, the ``fallback`` record); raises
    :class:`NoSaneModelError` if no candidate integrates over every run with a loss below ``MAX_SANE_LOSS``."""
    n_blown = _n_blown(joint.per_run_end)
    reason = (f"the re-optimised minimal model ({int(mask.sum())} terms) blows up on {n_blown} of "
              f"{len(derivs)} runs")
    log(f"{reason}: trying fallbacks")
    refs = [scaled_reference(d, scales) for d in derivs]
    tried, best = [], None
    for name, model in [*first, *fallback_candidates(joint.model, mask, stats, run_fits, integral)]:
        c = scales.to_scaled(model.coef)
        m = model.support
        obj = Objective(refs, m, default_substeps(c, refs[0].dt, config.joint.h_omega), config.joint.weights)
        per = obj.per_run(np.where(m, c, 0.0))
        total = float(np.mean([t.total for t in per]))
        nb = _n_blown(per)
        tried.append({"name": name, "loss": total, "blown_up_runs": nb, "n_terms": int(m.sum())})
        log(f"  fallback {name}: {int(m.sum())} terms, mean loss {total:.4g}, blows up on {nb} runs")
        if nb == 0 and total < MAX_SANE_LOSS and (best is None or total < best[0]):
            best = (total, name, model)
    if best is None:
        raise NoSaneModelError(f"{reason}, and no fallback (the model without its weakest terms, the regression-only "
                               "ensemble, the pooled integral-form model) integrates over every run; no model written")
    _, name, model = best
    log(f"fallback used: {name}; re-optimising it jointly")
    # refine never ends worse than its start, and a blow-up scores above MAX_SANE_LOSS: res integrates everywhere
    res = refine(model, derivs, scales, config.joint, mask=model.support)
    log(f"fallback final mean loss {res.loss_end.total:.4g} (shape {res.loss_end.shape:.3g}, "
        f"Poincare {res.loss_end.poincare:.3g}, frequency {res.loss_end.frequency:.3g})")
    record = {"reason": reason, "used": name, "candidates": tried,
              "blown_up_model": {"equations": joint.model.equations(), "loss": joint.loss_end.to_dict()}}
    return model, res, record


def model_json(res: FitResult) -> dict:
    """The docs/formats.md ``model.json`` content (plus extra keys)."""
    eq_mask = {eq: [t for t, m in zip(TERMS, res.mask[q]) if m] for q, eq in enumerate(EQUATION_NAMES)}
    per_run = []
    for p, f, lt in zip(res.runs, res.run_fits, res.joint.per_run_end):
        if res.rule == "discovery":
            d = {"file": f.name, "equations": f.refined.equations(),
                 "fit": "least squares of the smoothed accelerations on the selected terms (this run alone)"}
        else:
            d = f.to_json()
            d.pop("history")
        d["attractor"] = p.attractor.to_dict()
        d["loss_minimal_model"] = lt.to_dict()
        per_run.append(d)
    settings = json.loads(json.dumps(asdict(res.config), default=float))
    if res.config.method == "paper":
        for key in DISCOVERY_FIELDS:
            settings.pop(key)
    out = {
        "state": list(STATE_NAMES),
        "equations": res.model.equations(),
        "zscores": res.stats.as_dict(res.stats.zscore),
        "per_run": per_run,
        "units": "SI",
        "inclusion_frequency": res.stats.as_dict(res.stats.inclusion),
        "coefficient_mean": res.stats.as_dict(res.stats.mean),
        "coefficient_std": res.stats.as_dict(res.stats.std),
        "selected_terms": eq_mask,
        "regression_c0": res.c0_joint.equations(),
        "joint_start": res.joint_start.equations(),
        "loss": {"joint_start": res.joint.loss_start.to_dict(), "final": res.joint.loss_end.to_dict(),
                 "n_evals": res.joint.n_evals, "nlopt_status": res.joint.status},
        "scales": res.scales.to_dict(),
        "settings": settings,
        "skipped_files": list(res.skipped),
        "glitch_frames_masked": res.n_glitches,
        "selection": _selection_json(res),
        "integral_form": _integral_form_json(res),
        "fallback": res.fallback,
        "oracle": res.oracle.to_json() if res.oracle is not None else None,
        "method": res.config.method,
    }
    if res.discovery is not None:
        out["discovery"] = disc = res.discovery.to_json()
        # the discovery is the pooled integral form: its estimates in the cross-check's place (same keys)
        out["integral_form"] = {"method": disc["method"], **{
            eq: {k: disc[eq][k] for k in ("terms", "window_s", "residual_std")} for eq in EQUATION_NAMES}}
    return out


def _integral_form_json(res: FitResult) -> dict | None:
    """The pooled integral-form selection per equation (a cross-check; not the minimal model)."""
    if res.integral_form is None:
        return None
    return {"method": INTEGRAL_METHOD, **{eq: s.to_json() for eq, s in res.integral_form.items()}}


def _selection_json(res: FitResult) -> dict:
    """Which rule produced ``equations`` and what the other rule gives."""
    terms = lambda m: {eq: [t for t, k in zip(TERMS, m[q]) if k] for q, eq in enumerate(EQUATION_NAMES)}  # noqa: E731
    out: dict = {"rule": res.rule, "mean_pvalues": res.stats.as_dict(mean_pvalues(res.stats))}
    if res.mask_zscore is not None:
        out["zscore_rule"] = {"z_threshold": res.config.ensemble.z_threshold, "selected_terms": terms(res.mask_zscore)}
    if res.selection is not None:
        out["backward"] = {"alpha": res.config.selection.alpha, "selected_terms": terms(res.selection.mask),
                           "steps": [s.to_dict() for s in res.selection.steps]}
    if res.candidate_fit is not None:
        out["candidate_fit"] = {"equations": res.candidate_fit.model.equations(),
                                "loss": res.candidate_fit.loss_end.to_dict()}
    return out


def fit_dataset(data_dir: str | os.PathLike, out_dir: str | os.PathLike, config: FitConfig = FitConfig(),
                executor: ExecutorConfig | None = None, strict: bool = False, plots: bool = True,
                progress: bool = True, log: Callable[[str], None] | None = None) -> FitResult:
    """Run steps 1-4 on ``data_dir`` and write ``out_dir/model.json`` (and plots).

    Bad input raises :class:`~cubedimer.dataset.DatasetError` before anything is written; a minimal
    model that blows up with no sane fallback raises :class:`NoSaneModelError` and writes no model.json.
    """
    log = log or (lambda m: None)
    ds: Dataset = load_dataset(data_dir, strict=strict, config=config.load)
    if len(ds.runs) < 2:
        from cubedimer.dataset import DatasetError
        raise DatasetError(f"{data_dir}: the ensemble step needs at least 2 usable runs, found {len(ds.runs)}")
    prepared, scales = prepare_runs(ds.runs, config)
    log(f"{len(prepared)} runs loaded ({len(ds.skipped)} skipped, {ds.n_glitches} glitch frames masked); scales: y {scales.length_y:.3g} m, "
        f"theta {scales.length_theta:.3g}, time {scales.time:.3g} s")
    out = Path(out_dir)
    noise = recorded_tracking_noise(ds.meta)
    if noise is not None:
        log(f"oracle noise from meta.json's tracking block: {noise.sigma_y:.3g} m / {noise.sigma_theta:.3g}")
    res = fit_runs(prepared, scales, config, executor, cache_dir=out / "runs", progress=progress, log=log, noise=noise)
    res = FitResult(**{**res.__dict__, "skipped": tuple(ds.skipped_files()), "n_glitches": ds.n_glitches})
    write_json(out / "model.json", model_json(res))
    if plots:
        from .plots import plot_fit
        plot_fit(res, out)
    return res
