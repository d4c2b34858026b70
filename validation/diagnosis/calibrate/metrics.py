"""The gap: how much of the measured motion the (calibrated) simulation leaves unexplained.

Three components per run, each an unexplained fraction minus its noise floor (the value a model that
explains the data would show), each described by a :class:`GapComponent` that also computes it:

* ``yddot``, acceleration form: ``R_y = sum (a_data - a_sim)^2 / sum (a_data - mean)^2`` of the
  Savitzky-Golay second derivative, 1 for a model no better than a constant and 0 for a perfect one;
  floor: the tracking-noise variance times the filter's derivative gain, per frame.
* ``thetaddot``, integral form when every run carries integral data: ``sum r^2 / sum (P theta)^2`` with
  ``P theta`` the measured theta minus each window's straight line and ``r`` its difference from the
  detrended double integral of the simulated thetaddot; its residual is the white tracking noise itself
  for a model that explains the data, so the floor is ``(frames - 2 per window) sigma_theta^2`` (the
  accelerations carry that noise times the derivative gain: thetaddot on the soft Gor'kov hinge is
  ~95 % noise).  Without integral data, acceleration form as for y.
* ``energy``, energy-balance form: ``R_E = sum_k (dE_k,data - W_k,sim)^2 / sum_k (E_k - E_rest)^2``,
  the unexplained energy change per window relative to the oscillation energy; floor: the velocity
  noise of the window energies.

The scalar ``gap`` (:func:`scalar_gap`) is the mean over runs of the mean over the three components:
the unexplained fraction *in excess of measurement noise* (about 0 for a model that explains the data
within its noise; slightly negative values occur because the floor is an estimate).
:func:`gap_definition` composes its description from the components actually used.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from typing import Sequence

import numpy as np
from numpy.typing import NDArray

from ..prepare.runs import RunAccelerations
from ..prepare.simulation_terms import ENERGY_WINDOW_S
from .gap_model import EnergyResidual, GapFit, IntegralResidual

__all__ = ["GapComponent", "AccelerationGap", "IntegralGap", "EnergyGap", "gap_components", "gap_definition",
           "short_time_gaps", "noise_floors", "fit_gaps", "fit_components", "scalar_gap"]


@dataclass(frozen=True)
class GapComponent:
    """One component of the gap: its name (a diagnosis.json ``gap_components`` entry), the form of the
    equation it compares (``acceleration``, ``integral`` or ``energy balance``) and its quantities."""

    name: str
    form: str
    ratio: str  #: the unexplained fraction, as a formula
    floor: str  #: the noise floor subtracted from it

    def describe(self) -> str:
        """One clause of the gap definition: name, form, ratio and floor."""
        return f"{self.name} ({self.form} form): {self.ratio}, minus {self.floor}"

    def per_run(self, runs: Sequence[RunAccelerations], residuals: Sequence[NDArray],
                energy: Sequence[EnergyResidual] | None, integral: Sequence[IntegralResidual] | None,
                subtract_floor: bool) -> NDArray[np.float64]:
        """The component of every run (n_runs,)."""
        raise NotImplementedError


@dataclass(frozen=True)
class AccelerationGap(GapComponent):
    """Unexplained fraction of the measured acceleration variance of coordinate ``q`` (0: y, 1: theta)."""

    q: int = 0

    def per_run(self, runs, residuals, energy, integral, subtract_floor):
        out = np.zeros(len(runs))
        for i, (r, e) in enumerate(zip(runs, residuals)):
            var = np.sum((r.accel - r.accel.mean(axis=0)) ** 2, axis=0)
            v = np.sum(e**2, axis=0) / np.maximum(var, 1e-300)
            if subtract_floor and r.noise is not None:
                v = v - len(r.t) * r.noise[:2] / np.maximum(var, 1e-300)
            out[i] = v[self.q]
        return out


@dataclass(frozen=True)
class IntegralGap(GapComponent):
    """Unexplained fraction of the detrended measured theta (integral form)."""

    def per_run(self, runs, residuals, energy, integral, subtract_floor):
        out = np.zeros(len(runs))
        for i, ir in enumerate(integral):
            out[i] = (float(np.sum(ir.residual**2)) - (ir.floor if subtract_floor else 0.0)) / max(ir.norm, 1e-300)
        return out


@dataclass(frozen=True)
class EnergyGap(GapComponent):
    """Unexplained energy change per window relative to the oscillation energy."""

    def per_run(self, runs, residuals, energy, integral, subtract_floor):
        out = np.zeros(len(runs))
        if energy is None:
            return out
        for i, er in enumerate(energy):
            norm = max(float(np.sum(er.oscillation_energy**2)), 1e-300)
            out[i] = float(np.sum(er.residual**2)) / norm - (len(er.residual) * er.noise_variance / norm if subtract_floor else 0.0)
        return out


_ACCELERATION_FLOOR = "the derivative-noise variance per frame over the same normalisation"
Y_ACCELERATION = AccelerationGap(
    "yddot", "acceleration", "sum(a_data - a_sim)^2 / sum(a_data - mean)^2 of the Savitzky-Golay yddot, the model "
    "filtered alike", _ACCELERATION_FLOOR, q=0)
THETA_ACCELERATION = AccelerationGap(
    "thetaddot", "acceleration", "sum(a_data - a_sim)^2 / sum(a_data - mean)^2 of the Savitzky-Golay thetaddot, the "
    "model filtered alike", _ACCELERATION_FLOOR, q=1)


@lru_cache(maxsize=None)
def _theta_integral() -> IntegralGap:
    from fitting.derivatives.integral_form import integral_window

    periods, (lo, hi) = integral_window.__defaults__
    return IntegralGap(
        "thetaddot", "integral", "sum(P theta - P K[a_sim])^2 / sum(P theta)^2, with theta the measured angle, K[a_sim] "
        "the double integral of the simulated thetaddot and P the removal of each window's straight line (windows of "
        f"{periods:g} hinge periods within {1e3 * lo:g}-{1e3 * hi:g} ms)",
        "(frames - 2 per window) sigma_theta^2 over the same normalisation")


ENERGY_BALANCE = EnergyGap(
    "energy", "energy balance", f"sum(dE_data - W_sim)^2 / sum(E_osc)^2 over windows of {ENERGY_WINDOW_S:g} s, dE_data the change of "
    "the calibrated mechanical energy and W_sim the work of the effects", "the velocity-noise variance of dE per window "
    "over the same normalisation")


def gap_components(integral_theta: bool) -> tuple[GapComponent, GapComponent, GapComponent]:
    """The components (y, theta, energy) of the gap; the theta component in its integral form when
    ``integral_theta`` (every run carries integral data), else in acceleration form."""
    return (Y_ACCELERATION, _theta_integral() if integral_theta else THETA_ACCELERATION, ENERGY_BALANCE)


def gap_definition(components: Sequence[GapComponent]) -> str:
    """The definition of the scalar gap as text (diagnosis.json ``gap_definition``), composed from ``components``."""
    count = {2: "two", 3: "three"}.get(len(components), str(len(components)))
    return (f"mean over runs of the mean of {count} unexplained fractions, each minus its noise floor: "
            + "; ".join(c.describe() for c in components) + " (validation.diagnosis)")


def short_time_gaps(runs: Sequence[RunAccelerations], residuals: Sequence[NDArray],
                    energy: Sequence[EnergyResidual] | None = None, subtract_floor: bool = True,
                    integral: Sequence[IntegralResidual] | None = None) -> NDArray[np.float64]:
    """Per run (n_runs, 3): the components of :func:`gap_components` (y, theta, energy), each minus its
    noise floor unless ``subtract_floor`` is False.

    The theta component uses the integral form when ``integral`` (integral-form residuals) is given; the
    energy component is 0 without ``energy``."""
    comps = gap_components(integral is not None)
    return np.column_stack([c.per_run(runs, residuals, energy, integral, subtract_floor) for c in comps]) if runs else np.zeros((0, 3))


def noise_floors(runs: Sequence[RunAccelerations], fit: GapFit) -> NDArray[np.float64]:
    """Per run (n_runs, 3): the floors subtracted by :func:`short_time_gaps`."""
    raw = short_time_gaps(runs, fit.residuals, fit.energy, subtract_floor=False, integral=fit.integral)
    return raw - short_time_gaps(runs, fit.residuals, fit.energy, integral=fit.integral)


def fit_gaps(runs: Sequence[RunAccelerations], fit: GapFit) -> NDArray[np.float64]:
    """Per-run gap components (n_runs, 3) of a fit on these runs."""
    return short_time_gaps(runs, fit.residuals, fit.energy, integral=fit.integral)


def fit_components(fit: GapFit) -> tuple[GapComponent, GapComponent, GapComponent]:
    """The gap components :func:`fit_gaps` computes for ``fit``."""
    return gap_components(fit.integral is not None)


def scalar_gap(per_run: NDArray) -> float:
    """The documented scalar: mean over runs of the mean over the three components (y, theta, energy)."""
    return float(np.mean(per_run))
