"""The candidates' run planner: what runs determine a candidate effect's parameters, and what runs tell two
candidates apart (``python -m validation plan``).

It is the oracle of :mod:`fitting.uncertainty.oracle` applied to the diagnosis's own columns
(:mod:`validation.planner.reference_runs`): the standard errors that pooled integral-form least squares on the model's
own terms and the named candidates reaches when its columns are evaluated at the twin's *noise-free* runs and the
only noise is the white tracking noise of the positions (``sigma^2 (X^T X)^-1``, exact for that estimator).  Runs
add information, so for n runs the pooled matrix of ``n_draws`` random draws of n reference runs
(:func:`fitting.uncertainty.run_planning.drawn_information`) gives the table of standard errors, and
:func:`fitting.uncertainty.run_planning.runs_needed` the runs for a target (beyond the table: 1/sqrt(n)).

* **A parameter within a relative error at a confidence**: a 95 % interval within +-20 % of the value needs a
  standard error of ``0.2 |c| / 1.96``, an oracle z of 9.8.
* **Two candidates apart**: the alias z of a true candidate T against a rival R is
  ``sqrt(sum_q dRSS_q / sigma_q^2)`` over the equations, with dRSS_q the noise-free residual sum of squares left
  when T's contribution (its columns times its true parameters) is fitted by R's columns together with the model's
  own terms and the other named candidates, jointly over both equations (a parameter acting in both is one, as the
  diagnosis fits them: :func:`joint_information`; :func:`fitting.uncertainty.oracle.replacement_rss`).
  Least squares then prefers R over T in about ``Phi(-alias_z / 2)`` of data sets (2.3 % at alias z 4).  A
  candidate against itself has alias z 0.

Where the velocity coupling is fitted, c5 and c6 also get the standard errors of the diagnosis's trajectory test, which
fits every frame (:mod:`validation.planner.trajectory_oracle`; labelled ``"trajectory test: c6"``).

What it leaves out: the noise of the columns (the diagnosis evaluates them at smoothed noisy states), a pressure
drift, and the held-out rounds' own statistics.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Sequence

import numpy as np
from numpy.typing import NDArray
from scipy.special import ndtri

from cubedimer.config_checks import check_fraction, check_positive, check_that, check_whole
from fitting.uncertainty.oracle import NoiseLevels, alias_probability, covariance_diagonal, replacement_rss
from fitting.uncertainty.run_planning import draw_table, drawn_information, runs_needed
from .reference_runs import EQUATIONS, ReferenceRuns, has_contribution, parameter_labels

__all__ = ["CandidatePlanConfig", "ParameterPlan", "PairPlan", "CandidatePlan", "plan_candidates", "pair_alias_z",
           "joint_information",
           "target_z"]


def target_z(relative_error: float, confidence: float) -> float:
    """The oracle z at which a ``confidence`` two-sided interval lies within +-``relative_error`` of the value:
    ``Phi^-1((1 + confidence) / 2) / relative_error`` (9.8 for 20 % at 95 %)."""
    return float(ndtri(0.5 * (1.0 + confidence)) / relative_error)


@dataclass(frozen=True)
class CandidatePlanConfig:
    """What :func:`plan_candidates` plans.

    Parameters
    ----------
    fitted : tuple of str
        The candidates fitted beside the model's own terms (their parameters get standard errors).
    pairs : tuple of (str, str)
        (true, rival) pairs whose alias z is measured; the true one's contribution is its columns times the twin's
        true parameters.
    relative_error, confidence : float
        The target of every parameter: its ``confidence`` interval within +-``relative_error`` (:func:`target_z`).
    target_alias_z : float
        Alias z that counts as told apart (4: the rival wins in 2.3 % of data sets).
    run_counts : tuple of int
        Rows of the tables.
    n_draws : int
        Random draws of runs per row.
    seed : int
        Seed of the draws.
    """

    fitted: tuple[str, ...]
    pairs: tuple[tuple[str, str], ...] = ()
    relative_error: float = 0.2
    confidence: float = 0.95
    target_alias_z: float = 4.0
    run_counts: tuple[int, ...] = (5, 10, 20, 40)
    n_draws: int = 200
    seed: int = 0

    def __post_init__(self) -> None:
        object.__setattr__(self, "fitted", tuple(self.fitted))
        object.__setattr__(self, "pairs", tuple(tuple(p) for p in self.pairs))
        object.__setattr__(self, "run_counts", tuple(sorted(set(int(n) for n in self.run_counts))))
        check_fraction(self, "relative_error")
        check_fraction(self, "confidence")
        check_positive(self, "target_alias_z")
        check_whole(self, "n_draws")
        check_that(self, len(self.run_counts) > 0 and self.run_counts[0] >= 1,
                   f"run_counts must be whole numbers >= 1, got {self.run_counts!r}")
        check_that(self, all(len(p) == 2 for p in self.pairs), "pairs must be (true, rival) pairs")


@dataclass(frozen=True)
class ParameterPlan:
    """One fitted parameter's plan: its oracle standard error against the number of runs.

    ``table``: (runs, median SE, median z, 10th-percentile z) over the draws; ``std_error_reference``: the SE of all
    the reference runs pooled; ``runs_needed`` (median z reaches ``target_z``; beyond the table extrapolated with
    1/sqrt(n)) and ``runs_needed_90`` (90 % of draws; 0 beyond the table)."""

    label: str
    coefficient: float
    std_error_reference: float
    table: list[tuple[int, float, float, float]]
    scaling_exponent: float
    runs_needed: int
    runs_needed_90: int
    target_z: float


@dataclass(frozen=True)
class PairPlan:
    """A (true, rival) pair's alias z against the number of runs: ``table`` (runs, median alias z, 10th-percentile
    alias z) over the draws, the alias z of all the reference runs, and the runs for ``target_alias_z`` (scaled from
    the reference runs with sqrt(n); 0 when the pair is not told apart at any number of runs: alias z 0)."""

    true: str
    rival: str
    alias_z_reference: float
    table: list[tuple[int, float, float]]
    runs_needed: int
    target_alias_z: float


@dataclass(frozen=True)
class CandidatePlan:
    """The plan of a twin configuration and run design (:func:`plan_candidates`)."""

    parameters: list[ParameterPlan]
    pairs: list[PairPlan]
    noise: NoiseLevels
    n_reference: int
    heights_m: list[float]
    amplitude_m: tuple[float, float, float] = (float("nan"),) * 3
    window_s: tuple[float, float] = (float("nan"), float("nan"))
    notes: list[str] = field(default_factory=list)

    def format_table(self) -> str:
        """The plan as text: one table per parameter, one per pair."""
        lo, med, hi = self.amplitude_m
        heights = ", ".join(f"{h * 1e6:g}" for h in self.heights_m) or "the twin's drop protocol"
        lines = [f"{self.n_reference} reference runs; drop amplitudes [um]: {heights}; largest |y| per run "
                 f"{lo * 1e6:.0f}-{hi * 1e6:.0f} um (median {med * 1e6:.0f}); windows {self.window_s[0] * 1e3:.0f} ms (y), "
                 f"{self.window_s[1] * 1e3:.0f} ms (theta); noise sigma_y = {self.noise.sigma_y:.3g} m, sigma_theta = "
                 f"{self.noise.sigma_theta:.3g}"]
        for p in self.parameters:
            lines += ["", f"{p.label} = {p.coefficient:.4g}: oracle SE {p.std_error_reference:.3g} on the "
                      f"{self.n_reference} reference runs (measured scaling n^{p.scaling_exponent:.2f})",
                      f"{'runs':>6} {'oracle SE':>12} {'rel. SE':>8} {'z':>8} {'z (10 %)':>9}"]
            lines += [f"{n:>6d} {se:>12.4g} {se / abs(p.coefficient) if p.coefficient else float('inf'):>8.3f} "
                      f"{z:>8.2f} {z10:>9.2f}" for n, se, z, z10 in p.table]
            lines.append("true value 0: no relative target" if not p.coefficient else
                         f"runs needed for z >= {p.target_z:.2f}: {_fmt(p.runs_needed, p.table)} (median), "
                         f"{_fmt(p.runs_needed_90, p.table)} (90 % of draws)")
        for a in self.pairs:
            lines += ["", f"{a.true} replaced by {a.rival} (with the model's own terms and the other fitted "
                      f"candidates): alias z {a.alias_z_reference:.2f} on the {self.n_reference} reference runs",
                      f"{'runs':>6} {'alias z':>8} {'z (10 %)':>9}"]
            lines += [f"{n:>6d} {z:>8.2f} {z10:>9.2f}" for n, z, z10 in a.table]
            need = "never (alias z 0)" if a.runs_needed == 0 else str(a.runs_needed)
            lines.append(f"runs needed for alias z >= {a.target_alias_z:g} (the rival preferred in "
                         f"{100 * alias_probability(a.target_alias_z):.1f} % of data sets): {need}")
        return "\n".join(lines + self.notes)


def _fmt(n: int, table: Sequence) -> str:
    first = table[0][0] if table else 0
    return "beyond the table" if n == 0 else f"{n} or fewer" if n == first else str(n)


def joint_information(ref: ReferenceRuns, noise: NoiseLevels) -> tuple[list[str], NDArray[np.float64]]:
    """The runs' information on every parameter of both equations at once, each equation's weighted by its noise
    (``X_q^T X_q / sigma_q^2``): a parameter that acts in both (the cavity's gains) is one parameter, as the diagnosis
    fits every effect parameter jointly over the equations.

    Returns
    -------
    (labels, information (R, P, P)) in the parameters' SI units.
    """
    labels = list(dict.fromkeys(ref.labels[0] + ref.labels[1]))
    out = np.zeros((len(ref), len(labels), len(labels)))
    for q, eq in enumerate(EQUATIONS):
        idx = np.array([labels.index(lab) for lab in ref.labels[q]], int)
        if idx.size:
            out[:, idx[:, None], idx[None, :]] += ref.information[q] / noise.of(eq) ** 2
    return labels, out


def pair_alias_z(information: NDArray, labels: Sequence[str], truth: dict[str, float], true: str, rival: str,
                 fitted: Sequence[str]) -> float:
    """The alias z of candidate ``true`` against ``rival`` on a pooled joint information matrix (module docstring).

    Parameters
    ----------
    information : the pooled noise-weighted matrix (P, P) over ``labels`` (:func:`joint_information` summed over runs)
    labels : the parameters' labels (:func:`validation.planner.reference_runs.parameter_labels`, both equations)
    truth : true coefficients by label (a missing one is 0)
    true, rival : candidate names
    fitted : the other candidates fitted beside the rival (``true`` and ``rival`` themselves are skipped)
    """
    kept = [n for n in fitted if n not in (true, rival)]
    signal = [i for i, lab in enumerate(labels) if lab.split(".")[0] == true]
    if not signal:
        return 0.0
    basis = [i for i, lab in enumerate(labels) if "." not in lab or lab.split(".")[0] in kept + [rival]]
    coef = np.array([truth.get(labels[i], 0.0) for i in signal])
    return float(np.sqrt(replacement_rss(information, signal, coef, basis)))


def _plans(labels: Sequence[str], info: NDArray, truth: dict[str, float], cfg: CandidatePlanConfig,
           stream: tuple[int, ...], keep=lambda label: True) -> list[ParameterPlan]:
    """The table of every parameter of ``labels`` that ``keep`` accepts, from the runs' information ``info`` (R, P,
    P; the noise already in it); the draws of parameter k seeded with ``[cfg.seed, *stream, k]``."""
    tz = target_z(cfg.relative_error, cfg.confidence)
    pooled_se = np.sqrt(covariance_diagonal(info.sum(axis=0)))
    out = []
    for k, label in enumerate(labels):
        if not keep(label):
            continue
        c = float(truth.get(label, 0.0))
        table = draw_table(info, k, 1.0, c, list(cfg.run_counts), cfg.n_draws,
                           np.random.default_rng([cfg.seed, *stream, k]))
        slope, _, needed, needed90 = runs_needed(table, c, tz) if c else (float("nan"), 0.0, 0, 0)
        out.append(ParameterPlan(label, c, float(pooled_se[k]), table, float(slope), int(needed), int(needed90), tz))
    return out


def _parameter_plans(ref: ReferenceRuns, cfg: CandidatePlanConfig, noise: NoiseLevels) -> list[ParameterPlan]:
    """The table of every fitted parameter (the model's own terms and the fitted candidates' columns, fitted jointly
    over both equations)."""
    fitted = parameter_labels(cfg.fitted)
    keep = list(dict.fromkeys(fitted[0] + fitted[1]))
    labels, joint = joint_information(ref, noise)
    idx = [labels.index(lab) for lab in keep]
    return _plans(keep, joint[:, idx][:, :, idx], ref.truth, cfg, ())


def _trajectory_plans(ref: ReferenceRuns, cfg: CandidatePlanConfig) -> list[ParameterPlan]:
    """The tables of c5 and c6 by the velocity coupling's trajectory test (:mod:`validation.planner.trajectory_oracle`;
    its information is in the parameters' units, the noise already in it)."""
    if ref.trajectory is None or "velocity_coupling" not in cfg.fitted:
        return []
    labels, info, truth = ref.trajectory
    return _plans(labels, info, truth, cfg, (9,), keep=lambda label: label.endswith(("c5", "c6")))


def _pair_plans(ref: ReferenceRuns, cfg: CandidatePlanConfig, noise: NoiseLevels) -> list[PairPlan]:
    """The alias table of every (true, rival) pair."""
    labels, joint = joint_information(ref, noise)
    out = []
    for i, (true, rival) in enumerate(cfg.pairs):
        z_ref = pair_alias_z(joint.sum(axis=0), labels, ref.truth, true, rival, cfg.fitted)
        rng = np.random.default_rng([cfg.seed, 7, i])
        table = []
        for n in cfg.run_counts:
            draws = drawn_information(joint, n, cfg.n_draws, rng)
            zs = np.array([pair_alias_z(m, labels, ref.truth, true, rival, cfg.fitted) for m in draws])
            table.append((int(n), float(np.median(zs)), float(np.percentile(zs, 10))))
        needed = int(np.ceil(len(ref) * (cfg.target_alias_z / z_ref) ** 2)) if z_ref > 0 else 0
        out.append(PairPlan(true, rival, z_ref, table, needed, float(cfg.target_alias_z)))
    return out


def plan_candidates(ref: ReferenceRuns, noise: NoiseLevels, config: CandidatePlanConfig) -> CandidatePlan:
    """The plan of the fitted candidates and the pairs on reference runs (module docstring).

    Parameters
    ----------
    ref : ReferenceRuns
        :func:`validation.planner.reference_runs.reference_runs` of the twin configuration and run design, with the
        columns of every candidate of ``config.fitted`` and ``config.pairs``.
    noise : NoiseLevels
        White tracking noise of y [m] and theta [-].
    config : CandidatePlanConfig

    Returns
    -------
    CandidatePlan
    """
    missing = sorted({n for n in list(config.fitted) + [c for p in config.pairs for c in p]
                      if not any(l.split(".")[0] == n for lab in ref.labels for l in lab)})
    if missing:
        raise ValueError(f"the reference runs hold no columns of {', '.join(missing)}: measure them with these names")
    for true, _ in config.pairs:
        if not has_contribution(ref.truth, true):
            raise ValueError(f"pair {true}: the twin configuration has no {true} (its true contribution is zero); "
                             "give its strengths")
    heights = sorted({float(h) for h in ref.heights if np.isfinite(h)})
    amps = np.percentile(ref.amplitudes, [0, 50, 100])
    parameters = _parameter_plans(ref, config, noise) + _trajectory_plans(ref, config)
    return CandidatePlan(parameters, _pair_plans(ref, config, noise), noise, len(ref), heights,
                         tuple(float(a) for a in amps), ref.window_s)

