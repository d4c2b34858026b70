"""Calibration of the simulation to a data set: pressure amplitude and the lab height of the data's origin.

The simulated accelerations at nominal pressure ``p_nom`` are ``a_y = s F_Z(theta, Z)/M - g`` and
``a_theta = (s Q_theta(theta, Z) - I'(theta) thetadot^2 / 2) / I(theta)`` with ``s = (p0/p_nom)^2``
(the Gor'kov forces scale exactly with p0^2 at fixed lab height) and ``Z = z0 + y``: ``z0`` is the lab
height of the data's y origin.  ``s`` and ``z0`` are fitted to the *y equation only*: the vertical trap
is what the acoustic model describes best, while the hinge is where the largest expected gap lies (pair
scattering), which must not be absorbed into the pressure.  For fixed ``z0`` the fit is linear (in
``s`` and any y-effect parameters); ``z0`` is found by a bounded scalar search.

With integral data on every run the y equation is used in its integral form, against the measured y
(:class:`~validation.diagnosis.prepare.runs.PositionIntegrals`): on no-effect twin data it calibrates
the pressure within 0.02 %, where the Savitzky-Golay accelerations give +0.1 %, enough of a
hinge-stiffness mismatch for pair scattering to absorb.  Without integral data the accelerations are used.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np
from numpy.typing import NDArray

from ..prepare.candidate_effects import CANDIDATE_EFFECTS, effect_regressors, height_expansion, parameter_slots
from ..prepare.runs import uses_integral_form
from ..prepare.simulation_terms import SimulationTerms

__all__ = ["Calibration", "vertical_system", "calibrate", "CALIBRATED_ON"]

#: What the calibration is fitted to (diagnosis.json ``calibration.calibrated_on``).
CALIBRATED_ON = "yddot equation only (pressure and origin); see validation.diagnosis"


@dataclass(frozen=True)
class Calibration:
    """Calibrated settings: pressure scale s = (p0 / p_nom)^2, the lab height z0 [m] of the data's y = 0,
    and the equilibrium height Z_eq [m] of the simulation at the calibrated pressure (the origin of
    the effects' y, docs/conventions.md section 5)."""

    pressure_scale: float
    z_origin_m: float
    nominal_pressure_pa: float
    equilibrium_height_m: float = float("nan")

    @classmethod
    def at(cls, model, pressure_scale: float, z_origin_m: float) -> "Calibration":
        """Calibration with the equilibrium height of ``model`` (an :class:`acousim.GorkovDimer` at nominal
        pressure) rescaled to ``s``; NaN when the calibrated pressure cannot levitate the dimer."""
        p_nom = model.wave.pressure_amplitude_pa
        try:
            z_eq = model.with_pressure(p_nom * np.sqrt(pressure_scale)).equilibrium_height if pressure_scale > 0 else float("nan")
        except ValueError:
            z_eq = float("nan")  # the calibrated pressure cannot levitate the dimer: reported by the caller
        return cls(float(pressure_scale), float(z_origin_m), p_nom, float(z_eq))

    @property
    def origin_offset_m(self) -> float:
        """delta = z0 - Z_eq(calibrated): the simulation's y is the data's y + delta [m]."""
        return self.z_origin_m - self.equilibrium_height_m

    @property
    def pressure_amplitude_pa(self) -> float:
        """The calibrated pressure amplitude p0 = p_nom sqrt(s) [Pa]."""
        return float(self.nominal_pressure_pa * np.sqrt(max(self.pressure_scale, 0.0)))


def vertical_system(terms: SimulationTerms, z0: float, effects: Sequence[str]) -> tuple[NDArray, NDArray]:
    """Stacked y-equation design [s column, every effect column] and target at origin ``z0`` [m].

    Integral form against the measured y when every run carries integral data, else the Savitzky-Golay
    yddot against the model's accelerations through the matched filter."""
    runs = terms.runs
    if uses_integral_form(runs):
        known = terms.integral_known(z0, 0)
        cols = terms.integral_effect_columns(z0, effects, None, 0)
        x = np.concatenate([np.column_stack([kn[0], c]) for kn, c in zip(known, cols)])
        b = np.concatenate([r.integral.target(0) - kn[1] for r, kn in zip(runs, known)])
        return x, b
    forces = terms.forces(z0)
    cols_per_run, target_per_run = [], []
    for r, (fz, _) in zip(runs, forces):
        z = z0 + r.state[:, 0]
        regs = [r.smooth(effect_regressors(n, r.state, z, terms.k, problem=terms.problem)[:, 0, :]) for n in effects]
        regs = np.concatenate(regs, axis=1) if regs else np.zeros((r.state.shape[0], 0))
        cols_per_run.append(np.column_stack([fz, regs]))
        target_per_run.append(r.accel[:, 0] + terms.g)
    return np.concatenate(cols_per_run), np.concatenate(target_per_run)


def _depends_on_node_height(name: str) -> bool:
    from acousim.dynamics.effects import EFFECT_TYPES

    return name not in EFFECT_TYPES or EFFECT_TYPES[name].depends_on_node_height


def _height_search_rows(terms: SimulationTerms, effects: Sequence[str], y_effects_cols: Sequence[int],
                        expansions: dict | None = None):
    """``z0 -> (x, b)``: the integral-form y system of :func:`vertical_system` reduced to its R factor.

    The acoustic column is A + B cos(2k z0) + C sin(2k z0) (:meth:`SimulationTerms.integral_known_harmonics`);
    for effects that do not depend on the height above the node every other column and the target are the same at
    every z0, and an effect that does (the cavity's lag) is a fixed combination of a few blocks of columns with
    weights that depend on z0 alone (``expansions``: name -> :class:`~validation.diagnosis.prepare.cavity_lag.
    HeightExpansion`).  With R the triangular factor of M = [A B C E blocks b] (all runs stacked),
    ``||M v|| = ||R v||`` for every v, so the least squares at any z0 is solved on R's few rows: the same
    solution and residual to round-off, without touching the tens of thousands of rows again.
    """
    expansions = expansions or {}
    harmonics = terms.integral_known_harmonics(0)
    fixed = [n for n in effects if n not in expansions]
    cols = terms.integral_effect_columns(0.0, fixed, None, 0)  # the same at every z0 for these effects
    # each effect's y-acting parameters (the calibration's columns, in the order of ``effects``)
    y_params, first = {}, 1
    for n in effects:
        count = len(CANDIDATE_EFFECTS[n])
        y_params[n] = [c - first for c in y_effects_cols if first <= c < first + count]
        first += count
    blocks = []
    for i, (r, ((a, b_, c), rest), e) in enumerate(zip(terms.runs, harmonics, cols)):
        parts, start = [a, b_, c], 0
        for n in fixed:
            count = len(CANDIDATE_EFFECTS[n])
            parts.append(e[:, [start + j for j in y_params[n]]])
            start += count
        for n, ex in expansions.items():  # (n_blocks, rows, p) -> (rows, n_blocks * p), block-major
            sel = ex.blocks[i][:, :, y_params[n]]
            parts.append(np.transpose(sel, (1, 0, 2)).reshape(sel.shape[1], -1))
        blocks.append(np.column_stack(parts + [r.integral.target(0) - rest]))
    m = np.vstack(blocks)
    r_factor = np.linalg.qr(m, mode="r")
    two_k = 2.0 * terms.k
    # where each effect's y parameters sit among the solution's columns (after the pressure's)
    out_col, k = {}, 1
    for n in effects:
        out_col[n] = list(range(k, k + len(y_params[n])))
        k += len(y_params[n])

    def rows(z0: float):
        combo = np.zeros((m.shape[1], k))
        combo[:3, 0] = (1.0, np.cos(two_k * z0), np.sin(two_k * z0))
        row = 3
        for n in fixed:
            for j in out_col[n]:
                combo[row, j] = 1.0
                row += 1
        for n, ex in expansions.items():
            w = ex.weights(z0)
            p = len(out_col[n])
            for b, wb in enumerate(w):
                for j_i, j in enumerate(out_col[n]):
                    combo[row + b * p + j_i, j] = wb
            row += len(w) * p
        return r_factor @ combo, r_factor[:, -1]

    return rows


def calibrate(terms: SimulationTerms, effects: Sequence[str] = (), z0_window: float = 4e-4) -> Calibration:
    """Fit the pressure scale s and the origin height z0 to the y equation (with the y parameters of ``effects``).

    Parameters
    ----------
    terms : SimulationTerms
        The simulation at the runs' states.
    effects : names from CANDIDATE_EFFECTS
        Their y-equation parameters are fitted jointly with s (and then discarded).
    z0_window : float
        z0 is searched within +-z0_window [m] of the nominal Z_eq (kept below the node).

    Raises
    ------
    ValueError
        If the calibrated pressure cannot levitate the dimer.
    """
    from scipy.optimize import minimize_scalar

    model = terms.model
    effects = [n for n in effects if parameter_slots([n], 0)]  # only effects acting in y enter the y equation
    y_effects_cols = [c for _, _, c in parameter_slots(effects, 0)]

    def solve_rows(z0: float):
        x, b = vertical_system(terms, z0, effects)
        return x[:, [0] + y_effects_cols], b

    if uses_integral_form(terms.runs):
        expansions = {n: height_expansion(n, terms.problem, terms.runs, 0) for n in effects if _depends_on_node_height(n)}
        if all(ex is not None for ex in expansions.values()):
            solve_rows = _height_search_rows(terms, effects, y_effects_cols, expansions)

    def solve_y(z0: float):
        x, b = solve_rows(z0)
        scale = np.maximum(np.abs(x).max(axis=0), 1e-300)
        sol, *_ = np.linalg.lstsq(x / scale, b, rcond=None)
        sol = sol / scale
        resid = b - x @ sol
        return sol, float(resid @ resid)

    z_eq = model.equilibrium_height
    lo, hi = z_eq - z0_window, min(z_eq + z0_window, -1e-6)
    res = minimize_scalar(lambda z: solve_y(z)[1], bounds=(lo, hi), method="bounded", options={"xatol": 1e-9})
    z0 = float(res.x)
    sol_y, _ = solve_y(z0)
    cal = Calibration.at(model, float(sol_y[0]), z0)
    if not np.isfinite(cal.equilibrium_height_m):
        raise ValueError(f"the calibrated pressure ({cal.pressure_amplitude_pa:.0f} Pa) cannot levitate the dimer: "
                         "the data do not look like a levitated dimer of the meta.json size and material")
    return cal
