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
  error from the curvature, inflated by ``chi2_min / N`` when the model does not fit within the noise
  (misfit widens the uncertainty; it never narrows it).

The value counts as calibrated when the minimum is inside the range (not at its edge) and its relative
standard error is below :data:`MAX_RELATIVE_ERROR`; otherwise the model keeps its default value, and the
result says why (too few runs, too small a hinge amplitude, a flat profile) with the standard error, so that
no false precision is reported.
"""
from __future__ import annotations

import logging
from dataclasses import dataclass, field

import numpy as np

__all__ = ["ParameterCalibration", "calibrate_model_parameter", "MAX_RELATIVE_ERROR", "NUISANCE_EFFECTS"]

log = logging.getLogger(__name__)

#: Relative standard error above which a profiled parameter is not called calibrated.
MAX_RELATIVE_ERROR = 0.3
#: Effects fitted beside every trial value (they do not alias with a hinge stiffness).
NUISANCE_EFFECTS = ("linear_damping",)
#: Points of the coarse log-spaced scan.
SCAN_POINTS = 7


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


def _hinge_chi2(problem) -> tuple[float, int]:
    """chi2 of the hinge equation (integral form, in units of each run's noise floor) and its number of rows."""
    from .gap_model import fit_gap_model

    fit = fit_gap_model(problem, list(NUISANCE_EFFECTS))
    if fit.integral is not None:
        chi2 = sum(float(r.residual @ r.residual) * r.residual.size / max(r.floor, 1e-300) for r in fit.integral)
        return chi2, sum(r.residual.size for r in fit.integral)
    res = np.concatenate([r[:, 1] for r in fit.residuals])
    noise = np.concatenate([np.full(len(r), run.noise[1] if np.ndim(run.noise) else run.noise)
                            for r, run in zip(fit.residuals, problem.runs)])
    return float(np.sum(res**2 / np.maximum(noise, 1e-300))), int(res.size)


def calibrate_model_parameter(name: str, lo: float, hi: float, default: float, build_problem,
                              tolerance: float = 0.01, label: str | None = None) -> ParameterCalibration:
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
        Absolute tolerance of the refinement in log(value).
    label : str, optional
        How the notes name the parameter (default: ``name``).
    """
    from scipy.optimize import minimize_scalar

    if not (0 < lo < hi):
        raise ValueError(f"{name}: the range must satisfy 0 < lo < hi, got ({lo!r}, {hi!r})")
    cache: dict[float, tuple[float, int]] = {}

    def chi2(u: float) -> float:
        u = float(np.clip(u, np.log(lo), np.log(hi)))
        if u not in cache:
            cache[u] = _hinge_chi2(build_problem(float(np.exp(u))))
            log.debug("%s = %.4g: hinge chi2 / N = %.5g", name, np.exp(u), cache[u][0] / cache[u][1])
        return cache[u][0]

    grid = np.linspace(np.log(lo), np.log(hi), SCAN_POINTS)
    values = [chi2(u) for u in grid]
    i = int(np.argmin(values))
    a, b = grid[max(i - 1, 0)], grid[min(i + 1, len(grid) - 1)]
    res = minimize_scalar(chi2, bounds=(a, b), method="bounded", options={"xatol": tolerance})
    u_star = float(res.x) if res.fun <= values[i] else float(grid[i])
    c_min, n = chi2(u_star), cache[float(np.clip(u_star, np.log(lo), np.log(hi)))][1]
    # curvature by central differences (one-sided at an edge), step 0.05 in log (5 %)
    h = 0.05
    up, dn = min(u_star + h, np.log(hi)), max(u_star - h, np.log(lo))
    if up - u_star > 0.5 * h and u_star - dn > 0.5 * h:
        curv = (chi2(up) - 2 * c_min + chi2(dn)) / ((up - u_star) * (u_star - dn))
    else:  # at an edge: the second difference one-sided
        s = 1.0 if up - u_star > 0.5 * h else -1.0
        u1, u2 = u_star + s * h, u_star + 2 * s * h
        curv = (chi2(u2) - 2 * chi2(u1) + c_min) / h**2
    inflation = max(1.0, c_min / max(n, 1))
    se_u = float(np.sqrt(2.0 * inflation / curv)) if curv > 0 else float("inf")
    estimate = float(np.exp(u_star))
    std_error = estimate * se_u if np.isfinite(se_u) else float("inf")
    what = label or name
    at_edge = u_star - np.log(lo) < 2 * tolerance or np.log(hi) - u_star < 2 * tolerance
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
    profile = sorted((float(np.exp(u)), c / m) for u, (c, m) in cache.items())
    return ParameterCalibration(name, estimate if calibrated else float(default), estimate, std_error, calibrated,
                                note, (float(lo), float(hi)), profile)
