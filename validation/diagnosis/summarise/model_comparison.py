"""How far the gap shrinks once scattering is added: by a fitted stiffness, or by physics.

:func:`compare_simulation_models` puts the calibrated simulations of every registered force model
(:mod:`acousim.models`) side by side on the same runs:

* the reference model, the registry's first (the Gor'kov model, docs/conventions.md section 3), alone;
* the reference model plus the phenomenological ``pair_scattering`` of section 5, its kappa fitted;
* every other registered model (the full-wave model, section 7, :class:`acousim.fullwave.FullwaveDimer`) with no
  fitted stiffness, at its default options.

Each is calibrated in the same way (pressure amplitude and height origin, :func:`fit_gap_model`) and
judged by the same gap components (y equation, theta equation, energy balance; :mod:`.metrics`) and the
same long-time errors (:mod:`.long_time`).  The full-wave table exists for the default dimer only; on
other experiments, or data bending beyond the table's range, the comparison says why it is missing.
"""
from __future__ import annotations

import logging
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from ..calibrate.gap_model import GapFit, fit_gap_model
from ..calibrate.metrics import fit_gaps, scalar_gap
from ..prepare.problem import DiagnosisProblem
from .long_time import long_time_gaps, mean_long_time_gap

if TYPE_CHECKING:
    from acousim.models import ModelSpec

__all__ = ["ModelGap", "ModelComparison", "compare_simulation_models", "row_label", "SCATTERING_FITTED"]

log = logging.getLogger(__name__)

#: The effect fitted on the reference model in the comparison's second row (its key: ``"<model>+<effect>"``).
SCATTERING_FITTED = "pair_scattering"


def row_label(key: str) -> str:
    """A comparison row's label: the model's registry label, with the effect fitted on it, or marked as having no
    fitted stiffness (every model but the reference one)."""
    from acousim.models import force_model_names, force_model_type

    name, _, effect = key.partition("+")
    label = force_model_type(name).label
    if effect:
        return f"{label} + fitted {effect.replace('_', ' ')}"
    return label if name == force_model_names()[0] else f"{label} (no fitted stiffness)"


@dataclass(frozen=True)
class ModelGap:
    """One calibrated simulation's gap on the runs.

    Attributes
    ----------
    model : str
        The row's key: a registered model name, or ``"<reference model>+pair_scattering"``.
    pressure_amplitude_pa, origin_offset_m : float
        Calibrated pressure [Pa] and the offset delta [m] of the simulation's y from the data's.
    components : tuple of float
        Mean over runs of the y, theta and energy gap components (fractions of the variance beyond noise).
    gap : float
        Their mean (the diagnosis's scalar gap).
    long_time_total : float or None
        Mean long-time error (0 perfect, ~1 no motion); None when not computed.
    params : dict
        Fitted effect parameters (kappa of pair scattering).
    long_time_stopped : tuple of (int, int, str) or None
        Runs whose simulation stopped before the run's end, out of how many, and why (e.g. the cube faces touch): such
        a run's long-time error is a penalty for the lost frames (up to the refinement's penalty), not a distance.
    """

    model: str
    pressure_amplitude_pa: float
    origin_offset_m: float
    components: tuple[float, float, float]
    gap: float
    long_time_total: float | None
    params: dict = field(default_factory=dict)
    long_time_stopped: tuple | None = None

    def to_dict(self) -> dict:
        return {"model": self.model, "label": row_label(self.model), "pressure_amplitude_pa": self.pressure_amplitude_pa,
                "origin_offset_m": self.origin_offset_m, "gap_y": self.components[0], "gap_theta": self.components[1],
                "gap_energy": self.components[2], "gap": self.gap, "long_time_total": self.long_time_total,
                "params": self.params,
                **({} if self.long_time_stopped is None else {"long_time_stopped": {
                    "runs": self.long_time_stopped[0], "of": self.long_time_stopped[1],
                    "why": self.long_time_stopped[2]}})}

    @classmethod
    def from_dict(cls, doc: dict) -> "ModelGap":
        """The row of a stored comparison (:meth:`to_dict`)."""
        return cls(doc["model"], doc["pressure_amplitude_pa"], doc["origin_offset_m"],
                   (doc["gap_y"], doc["gap_theta"], doc["gap_energy"]), doc["gap"], doc.get("long_time_total"),
                   dict(doc.get("params") or {}),
                   None if doc.get("long_time_stopped") is None else tuple(doc["long_time_stopped"][k]
                                                                            for k in ("runs", "of", "why")))


@dataclass(frozen=True, eq=False)
class ModelComparison:
    """The side-by-side gaps, and every fit and problem for figures (the full-wave ones missing when the table
    does not apply, with the reason in ``unavailable``).

    Attributes
    ----------
    rows : list of ModelGap
        The reference model, with pair scattering fitted, then the other registered models in registry order.
    fits, problems : dict
        :class:`GapFit` and :class:`DiagnosisProblem` per row key.
    unavailable : dict
        Why a model's row is missing, by model name (None for a model that has its row).
    """

    rows: list[ModelGap]
    fits: dict
    problems: dict
    unavailable: dict = field(default_factory=dict)

    def to_dict(self) -> dict:
        return {"rows": [r.to_dict() for r in self.rows],
                **{f"{name}_unavailable": reason for name, reason in self.unavailable.items()}}

    @classmethod
    def from_dict(cls, doc: dict) -> "ModelComparison":
        """The comparison of a stored record (diagnosis.json's ``model_comparison``): its rows and why a model is
        missing, without the fits and problems (a view of the stored results)."""
        suffix = "_unavailable"
        return cls([ModelGap.from_dict(r) for r in doc["rows"]], {}, {},
                   {k[:-len(suffix)]: v for k, v in doc.items() if k.endswith(suffix)})


def _row(name: str, problem: DiagnosisProblem, fit: GapFit, long_time_duration: float | None) -> ModelGap:
    per = fit_gaps(problem.runs, fit)
    lt, stopped = None, None
    if long_time_duration is not None:
        gaps = long_time_gaps(problem, fit, long_time_duration)
        lt = mean_long_time_gap(gaps)["total"]
        why = sorted({g.status for g in gaps if g.diverged})
        if why:
            stopped = (sum(g.diverged for g in gaps), len(gaps), "; ".join(why))
    cal = fit.calibration
    return ModelGap(name, cal.pressure_amplitude_pa, cal.origin_offset_m, tuple(float(v) for v in per.mean(axis=0)),
                    scalar_gap(per), lt, fit.effects, stopped)


def compare_simulation_models(problem: DiagnosisProblem, spec: "ModelSpec", meta: dict, base: GapFit | None = None,
                              long_time_duration: float | None = 2.0) -> ModelComparison:
    """The gaps of every registered model, calibrated, and of the reference model with fitted pair scattering.

    Parameters
    ----------
    problem : DiagnosisProblem
        A diagnosis's problem, on the model of ``spec`` (its runs and pressure drift are reused for every model).
    spec : ModelSpec
        The diagnosis's model: its row is ``problem`` itself (with the diagnosis's calibrated parameters); every
        other model is built at its default options.
    meta : dict
        The data set's meta.json.
    base : GapFit, optional
        The calibrated ``problem.model`` alone, when already fitted (the diagnosis's ``base``).
    long_time_duration : float or None
        Seconds of every run simulated for the long-time error [s]; None: skip it.
    """
    from acousim.models import ModelSpec, force_model_names

    from ...simulation import model_from_meta

    def sibling(model) -> DiagnosisProblem:
        return DiagnosisProblem(model, problem.runs, problem.recorded_runs, drift=problem.drift)

    problems, unavailable = {}, {}
    for name in force_model_names():
        if name == spec.name:
            problems[name] = problem
            continue
        try:
            other = model_from_meta(meta, ModelSpec(name)).interpolated()
            # a tabulated model refuses data bending beyond its table (ValueError) here, not in the middle of a fit
            other.orientation_sums(np.concatenate([r.state[:, 2] for r in problem.recorded_runs]))
            problems[name] = sibling(other)
        except ValueError as exc:
            log.info("no %s comparison: %s", name, exc)
            unavailable[name] = str(exc)
    reference = force_model_names()[0]
    fits = {name: base if base is not None and name == spec.name else fit_gap_model(p, [])
            for name, p in problems.items()}
    with_scattering = f"{reference}+{SCATTERING_FITTED}"
    fits[with_scattering] = fit_gap_model(problems[reference], [SCATTERING_FITTED])
    problems[with_scattering] = problems[reference]
    others = force_model_names()[1:]
    rows = [_row(k, problems[k], fits[k], long_time_duration) for k in (reference, with_scattering, *others)
            if k in fits]
    return ModelComparison(rows, fits, problems, {n: unavailable.get(n) for n in others})
