"""How far the gap shrinks once scattering is added: by a fitted stiffness, or by physics.

:func:`compare_simulation_models` puts three calibrated simulations side by side on the same runs:

* the Gor'kov model alone (docs/conventions.md section 3);
* the Gor'kov model plus the phenomenological ``pair_scattering`` of section 5, its kappa fitted;
* the full-wave model (section 7, :class:`acousim.fullwave.FullwaveDimer`), with no fitted stiffness.

Each is calibrated in the same way (pressure amplitude and height origin, :func:`fit_gap_model`) and
judged by the same gap components (y equation, theta equation, energy balance; :mod:`.metrics`) and the
same long-time errors (:mod:`.long_time`).  The full-wave table exists for the default dimer only; on
other experiments, or data bending beyond the table's range, the comparison says why it is missing.
"""
from __future__ import annotations

import logging
from dataclasses import dataclass, field

import numpy as np

from .gap_model import GapFit, fit_gap_model
from .long_time import long_time_gaps, mean_long_time_gap
from .metrics import fit_gaps, scalar_gap
from .problem import DiagnosisProblem

__all__ = ["ModelGap", "ModelComparison", "compare_simulation_models", "MODEL_LABELS"]

log = logging.getLogger(__name__)

#: Row labels of the comparison, in order.
MODEL_LABELS = {"gorkov": "Gor'kov", "gorkov+pair_scattering": "Gor'kov + fitted pair scattering",
                "fullwave": "full wave (no fitted stiffness)"}


@dataclass(frozen=True)
class ModelGap:
    """One calibrated simulation's gap on the runs.

    Attributes
    ----------
    model : str
        Key of :data:`MODEL_LABELS`.
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
    """

    model: str
    pressure_amplitude_pa: float
    origin_offset_m: float
    components: tuple[float, float, float]
    gap: float
    long_time_total: float | None
    params: dict = field(default_factory=dict)

    def to_dict(self) -> dict:
        return {"model": self.model, "label": MODEL_LABELS[self.model], "pressure_amplitude_pa": self.pressure_amplitude_pa,
                "origin_offset_m": self.origin_offset_m, "gap_y": self.components[0], "gap_theta": self.components[1],
                "gap_energy": self.components[2], "gap": self.gap, "long_time_total": self.long_time_total,
                "params": self.params}


@dataclass(frozen=True, eq=False)
class ModelComparison:
    """The side-by-side gaps, and every fit and problem for figures (the full-wave ones missing when the table
    does not apply, with the reason in ``unavailable``).

    Attributes
    ----------
    rows : list of ModelGap
        In the order of :data:`MODEL_LABELS`.
    fits, problems : dict
        :class:`GapFit` and :class:`DiagnosisProblem` per row key.
    unavailable : str or None
        Why the full-wave row is missing.
    """

    rows: list[ModelGap]
    fits: dict
    problems: dict
    unavailable: str | None = None

    def to_dict(self) -> dict:
        return {"rows": [r.to_dict() for r in self.rows], "fullwave_unavailable": self.unavailable}


def _row(name: str, problem: DiagnosisProblem, fit: GapFit, long_time_duration: float | None) -> ModelGap:
    per = fit_gaps(problem.runs, fit)
    lt = None
    if long_time_duration is not None:
        lt = mean_long_time_gap(long_time_gaps(problem, fit, long_time_duration))["total"]
    cal = fit.calibration
    return ModelGap(name, cal.pressure_amplitude_pa, cal.origin_offset_m, tuple(float(v) for v in per.mean(axis=0)),
                    scalar_gap(per), lt, fit.effects)


def compare_simulation_models(problem: DiagnosisProblem, meta: dict, base: GapFit | None = None,
                              long_time_duration: float | None = 2.0, gap: float | None = None) -> ModelComparison:
    """The gaps of the calibrated Gor'kov model, of Gor'kov + fitted pair scattering and of the full-wave model.

    Parameters
    ----------
    problem : DiagnosisProblem
        A diagnosis's problem, on either simulation model (its runs and pressure drift are reused for both).
    meta : dict
        The data set's meta.json (the full-wave table must have been built for this experiment).
    base : GapFit, optional
        The calibrated ``problem.model`` alone, when already fitted (the diagnosis's ``base``).
    long_time_duration : float or None
        Seconds of every run simulated for the long-time error [s]; None: skip it.
    gap : float, optional
        Hinge gap [m] of the full-wave model (default: its default, 0.01 side).
    """
    from acousim.fullwave.statics import FullwaveDimer

    from ..simulation import model_from_meta

    on_fullwave = isinstance(problem.model, FullwaveDimer)

    def sibling(model) -> DiagnosisProblem:
        return DiagnosisProblem(model, problem.runs, problem.recorded_runs, drift=problem.drift)

    problems = {"gorkov": sibling(model_from_meta(meta).interpolated()) if on_fullwave else problem}
    problems["gorkov+pair_scattering"] = problems["gorkov"]
    fits = {"gorkov": base if base is not None and not on_fullwave else fit_gap_model(problems["gorkov"], []),
            "gorkov+pair_scattering": fit_gap_model(problems["gorkov"], ["pair_scattering"])}
    unavailable = None
    if on_fullwave:
        problems["fullwave"] = problem
    else:
        try:
            fw = model_from_meta(meta, model="fullwave", gap=gap)
            fw.orientation_sums(np.concatenate([r.state[:, 2] for r in problem.recorded_runs]))  # the bend range
            problems["fullwave"] = sibling(fw)
        except ValueError as exc:
            log.info("no full-wave comparison: %s", exc)
            unavailable = str(exc)
    if "fullwave" in problems:
        fits["fullwave"] = base if base is not None and on_fullwave else fit_gap_model(problems["fullwave"], [])
    rows = [_row(k, problems[k], fits[k], long_time_duration) for k in MODEL_LABELS if k in fits]
    return ModelComparison(rows, fits, problems, unavailable)
