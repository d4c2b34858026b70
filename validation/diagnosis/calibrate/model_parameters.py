"""Calibrating a simulation model's own geometric parameter from the data: the hinge gap of the full-wave model.

The full-wave hinge stiffness depends strongly on the gap g between the cubes (docs/fullwave.md), and no real
dimer's gap is known.  A model type that has such a parameter declares its range
(:attr:`acousim.models.ForceModelType.calibratable`); unless the user fixes it, the diagnosis profiles it:

* for each trial value the model is rebuilt and calibrated as always (pressure and origin from the vertical
  equation), with the nuisance effect ``linear_damping`` fitted beside it (a damping has no stiffness and
  does not alias with the gap, but left out it would bias the hinge equation's residual);
* the criterion is the hinge equation's chi-square in its integral form (measured theta against the double
  integral of the model; residuals in units of each run's tracking-noise floor), so that it is
  ``chi2(u) ~ chi2_min + (u - u*)^2 / var(u*)`` near the minimum for ``u = log g``;
* the minimum is found by a coarse log-spaced scan over the range and a bounded refinement, and the standard
  error is the larger of two: the curvature's, inflated by ``chi2_min / N`` when the model does not fit within
  the noise (misfit widens the uncertainty; it never narrows it), and the delete-one-run jackknife's (with at
  least :data:`JACKKNIFE_MIN_RUNS` runs): the minimum of the profile without each run in turn, from the same
  three trial values.  The curvature counts every frame as independent and measures the tracking noise only;
  what differs from run to run (a drift model's error, noise correlated along a run) shows in the jackknife.

The value counts as calibrated when the minimum is inside the range (not at its edge) and its relative
standard error is below :data:`MAX_RELATIVE_ERROR`; otherwise the model keeps its default value, and the
result says why (too few runs, too small a hinge amplitude, a flat profile) with the standard error, so that
no false precision is reported.
"""
from __future__ import annotations

import logging
from dataclasses import dataclass, field, replace

import numpy as np
from numpy.typing import NDArray

from ..prepare.problem import DiagnosisProblem

__all__ = ["ParameterCalibration", "calibrate_model_parameter", "calibrate_model_parameters", "parameter_record",
           "jackknife_log_error", "MAX_RELATIVE_ERROR", "NUISANCE_EFFECTS", "JACKKNIFE_MIN_RUNS"]

log = logging.getLogger(__name__)

#: Relative standard error above which a profiled parameter is not called calibrated.
MAX_RELATIVE_ERROR = 0.3
#: Effects fitted beside every trial value (they do not alias with a hinge stiffness).
NUISANCE_EFFECTS = ("linear_damping",)
#: Points of the coarse log-spaced scan.
SCAN_POINTS = 7
#: A minimum closer than this to an end of the range (in log(value), i.e. 2 %) lies at its edge.
EDGE_MARGIN = 0.02
#: Runs needed for the jackknife's standard error (with fewer, the curvature's alone).
JACKKNIFE_MIN_RUNS = 4


@dataclass(frozen=True)
class ParameterCalibration:
    """A profiled model parameter (SI), its standard error and whether the data determine it."""

    name: str
    value: float  #: the value the diagnosis uses (the estimate if calibrated, else the model's default)
    estimate: float  #: where the profile is lowest
    std_error: float  #: standard error of the estimate [same unit]; inf when the profile has no curvature
    calibrated: bool
    note: str
    range: tuple[float, float]
    profile: list = field(default_factory=list)  #: [(value, chi2 / N)] of every trial

    def to_dict(self) -> dict:
        return {"value": self.value, "estimate": self.estimate, "std_error": self.std_error,
                "calibrated": self.calibrated, "note": self.note, "range": list(self.range),
                "profile": [[float(v), float(c)] for v, c in self.profile]}


def _hinge_chi2(problem) -> tuple[NDArray[np.float64], int]:
    """chi2 of the hinge equation per run (integral form, in units of each run's noise floor) and the number of
    rows of all runs."""
    from .gap_model import fit_gap_model

    fit = fit_gap_model(problem, list(NUISANCE_EFFECTS))
    if fit.integral is not None:
        per_run = [float(r.residual @ r.residual) * r.residual.size / max(r.floor, 1e-300) for r in fit.integral]
        return np.asarray(per_run), sum(r.residual.size for r in fit.integral)
    per_run = [float(np.sum(r[:, 1] ** 2)) / max(float(run.noise[1] if np.ndim(run.noise) else run.noise), 1e-300)
               for r, run in zip(fit.residuals, problem.runs)]
    return np.asarray(per_run), sum(len(r) for r in fit.residuals)


def _parabola_vertex(u: NDArray, c: NDArray) -> tuple[float, float]:
    """Vertex abscissa and second derivative of the parabola through three points (u_i, c_i)."""
    (u0, u1, u2), (c0, c1, c2) = u, c
    d01, d12 = (c1 - c0) / (u1 - u0), (c2 - c1) / (u2 - u1)
    curv = 2.0 * (d12 - d01) / (u2 - u0)
    return (0.5 * (u0 + u1) - d01 / curv if curv > 0 else float("nan")), float(curv)


def jackknife_log_error(u: NDArray, per_run: NDArray) -> float:
    """Standard error of the profile's minimum in log(value) from the delete-one-run jackknife.

    Parameters
    ----------
    u : ndarray, shape (3,)
        Three trial values of log(value) about the minimum, increasing.
    per_run : ndarray, shape (3, R)
        Every run's chi2 at each trial value.

    Returns
    -------
    float
        sqrt((R - 1) / R sum_i (u_i - mean)^2) over the vertices u_i of the profiles without run i; nan when a
        profile without one run has no minimum (then that run alone carries the curvature).
    """
    per_run = np.asarray(per_run, dtype=float)
    r = per_run.shape[1]
    total = per_run.sum(axis=1)
    vertices = np.array([_parabola_vertex(np.asarray(u, float), total - per_run[:, i])[0] for i in range(r)])
    if not np.all(np.isfinite(vertices)):
        return float("nan")
    return float(np.sqrt((r - 1) / r * np.sum((vertices - vertices.mean()) ** 2)))


def calibrate_model_parameter(name: str, lo: float, hi: float, default: float, build_problem,
                              tolerance: float = 1e-3, label: str | None = None) -> ParameterCalibration:
    """Profile the model parameter ``name`` over [lo, hi] (log scale) on the hinge equation.

    Parameters
    ----------
    name : str
        The parameter (e.g. ``"gap_m"``), for the record.
    lo, hi : float
        Its range (> 0), e.g. what the full-wave table family covers.
    default : float
        The value kept when the data do not determine it.
    build_problem : callable
        ``build_problem(value) -> DiagnosisProblem`` with the model rebuilt at that value.
    tolerance : float
        Absolute tolerance of the refinement in log(value): 1e-3 (0.1 %) by default, below the standard error
        of a well-determined gap (0.05-0.3 % on 8 runs of 3 s), so that the estimate is not quantised by it.
    label : str, optional
        How the notes name the parameter (default: ``name``).
    """
    from scipy.optimize import minimize_scalar

    if not (0 < lo < hi):
        raise ValueError(f"{name}: the range must satisfy 0 < lo < hi, got ({lo!r}, {hi!r})")
    cache: dict[float, tuple[NDArray[np.float64], int]] = {}

    def in_range(u: float) -> float:  # the trial value actually evaluated (and the cache's key)
        return float(np.clip(u, np.log(lo), np.log(hi)))

    def chi2(u: float) -> float:
        u = in_range(u)
        if u not in cache:
            per_run, rows = _hinge_chi2(build_problem(float(np.exp(u))))
            cache[u] = (np.atleast_1d(np.asarray(per_run, dtype=float)), int(rows))
            log.debug("%s = %.4g: hinge chi2 / N = %.5g", name, np.exp(u), cache[u][0].sum() / cache[u][1])
        return float(cache[u][0].sum())

    grid = np.linspace(np.log(lo), np.log(hi), SCAN_POINTS)
    values = [chi2(u) for u in grid]
    i = int(np.argmin(values))
    a, b = grid[max(i - 1, 0)], grid[min(i + 1, len(grid) - 1)]
    res = minimize_scalar(chi2, bounds=(a, b), method="bounded", options={"xatol": tolerance})
    u_star = float(res.x) if res.fun <= values[i] else float(grid[i])
    c_min, n = chi2(u_star), cache[in_range(u_star)][1]
    # curvature from the parabola through three trial values 0.05 apart in log (5 %; one-sided at an edge)
    h = 0.05
    up, dn = min(u_star + h, np.log(hi)), max(u_star - h, np.log(lo))
    se_jack = float("nan")
    if up - u_star > 0.5 * h and u_star - dn > 0.5 * h:
        trials = np.array([dn, in_range(u_star), up])
        _, curv = _parabola_vertex(trials, np.array([chi2(t) for t in trials]))
        per_run = np.array([cache[in_range(t)][0] for t in trials])
        if per_run.shape[1] >= JACKKNIFE_MIN_RUNS:
            se_jack = jackknife_log_error(trials, per_run)
    else:  # at an edge: the second difference one-sided
        s = 1.0 if up - u_star > 0.5 * h else -1.0
        u1, u2 = u_star + s * h, u_star + 2 * s * h
        curv = (chi2(u2) - 2 * chi2(u1) + c_min) / h**2
    inflation = max(1.0, c_min / max(n, 1))
    se_u = float(np.sqrt(2.0 * inflation / curv)) if curv > 0 else float("inf")
    if np.isfinite(se_jack):
        se_u = max(se_u, se_jack)
    estimate = float(np.exp(u_star))
    std_error = estimate * se_u if np.isfinite(se_u) else float("inf")
    what = label or name
    at_edge = u_star - np.log(lo) < EDGE_MARGIN or np.log(hi) - u_star < EDGE_MARGIN
    rel = std_error / estimate
    if at_edge:
        note = (f"the data prefer a {what} at the edge of the range [{lo:.3g}, {hi:.3g}] ({estimate:.3g}): outside what "
                f"the model covers or not determined; the default {default:.3g} is kept")
    elif not rel < MAX_RELATIVE_ERROR:
        note = (f"the data do not determine the {what}: relative standard error {rel:.0%} (a flat hinge profile: too "
                f"few runs, too small a hinge amplitude, or degenerate with the pressure); the default {default:.3g} is "
                f"kept")
    else:
        note = f"the {what} calibrated from the hinge equation: {estimate:.4g} +- {std_error:.2g}"
    calibrated = bool(not at_edge and rel < MAX_RELATIVE_ERROR)
    profile = sorted((float(np.exp(u)), float(c.sum()) / m) for u, (c, m) in cache.items())
    return ParameterCalibration(name, estimate if calibrated else float(default), estimate, std_error, calibrated,
                                note, (float(lo), float(hi)), profile)


def _label(name: str) -> str:
    """A model parameter's name in prose: the field without its unit (``gap_m`` -> ``gap``)."""
    return name.rsplit("_", 1)[0].replace("_", " ")


def calibrate_model_parameters(spec, conditions, recorded_runs, max_frames_per_run: int,
                               log=None, drift=None) -> tuple[object, dict]:
    """The conditions with every model parameter the data may determine (and the user left unset) calibrated,
    and their :class:`~validation.diagnosis.calibrate.model_parameters.ParameterCalibration` by field name.

    ``drift`` (a :class:`~validation.diagnosis.calibrate.drift.PressureDrift`) is followed by every trial model, so that a
    pressure drifting within runs does not bias the hinge profile."""
    log = log or logging.getLogger(__name__).info
    mtype = spec.type
    out = {}
    for name, (lo, hi, default) in mtype.calibration_ranges(conditions).items():
        if getattr(conditions, name) is not None:
            continue
        if not hi > lo * (1 + 1e-9):  # the model covers one value only: nothing to profile
            out[name] = ParameterCalibration(name, float(default), float(lo), float("inf"), False,
                                             f"the model's tables cover one {_label(name)} ({lo:.3g}) only: nothing "
                                             f"to profile; the default {default:.3g} is kept", (lo, hi))
            conditions = replace(conditions, **{name: float(default)})
            continue
        log("profiling the %s model's %s over [%.3g, %.3g] on the hinge equation", spec.name, name, lo, hi)

        def build(value: float, name=name):
            sim = spec.static(replace(conditions, **{name: value})).interpolated()
            trial = DiagnosisProblem.from_recorded(sim, recorded_runs, max_frames_per_run)
            return trial if drift is None else trial.with_drift(drift)

        pc = calibrate_model_parameter(name, lo, hi, default, build, label=_label(name))
        log("%s", pc.note)
        out[name] = pc
        conditions = replace(conditions, **{name: pc.value})
    return conditions, out


def parameter_record(conditions, calibrated: dict, spec) -> dict:
    """diagnosis.json calibration keys of the model's own parameters: ``gap_m``, ``gap_std_m``,
    ``gap_calibrated`` (and the profile) for every parameter the model type declares calibratable, and
    ``gap_model_error_m`` for a calibrated one whose model states its error (the systematic error the model's own
    stated accuracy implies; None otherwise)."""
    mtype = spec.type
    out = {}
    model_errors = None
    for name in mtype.calibration_ranges(conditions):
        base, unit = name.rsplit("_", 1)
        pc = calibrated.get(name)
        out[name] = float(getattr(conditions, name))
        out[f"{base}_std_{unit}"] = None if pc is None or not np.isfinite(pc.std_error) else pc.std_error
        out[f"{base}_calibrated"] = bool(pc is not None and pc.calibrated)
        model_error = None
        if pc is not None and pc.calibrated and mtype.parameter_model_error is not None:
            if model_errors is None:
                model_errors = mtype.parameter_model_error(conditions)
            rel = model_errors.get(name)
            model_error = None if rel is None or not np.isfinite(rel) else float(rel) * out[name]
        out[f"{base}_model_error_{unit}"] = model_error
        out[f"{base}_note"] = pc.note if pc is not None else f"the {_label(name)} given by the user"
        if pc is not None:
            out[f"{base}_profile"] = pc.to_dict()
    return out
