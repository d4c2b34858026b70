"""The simulation's accelerations, energies and integral-form columns at the measured states.

:class:`SimulationTerms` wraps the simulation's equations of motion (the Gor'kov model of docs/conventions.md
section 4 at nominal pressure; the hinge's velocity term is :func:`acousim.dynamics.equations.hinge_acceleration`, the
effects' columns :meth:`acousim.dynamics.effects.Effect.regressors`) for the diagnosis: per run, the
acoustic force and torque, the potential for the energy balance, and the double integrals of the
accelerations for the integral form.  The calibration scales the acoustic parts by
s = (p0 / p_nom)^2; the candidate effects' columns come from :func:`validation.diagnosis.prepare.candidate_effects.effect_regressors`.
"""
from __future__ import annotations

from typing import Sequence

import numpy as np
from numpy.typing import NDArray

from acousim.dynamics.equations import hinge_acceleration

from .candidate_effects import effect_regressors
from .problem import DiagnosisProblem
from .runs import RunAccelerations

__all__ = ["SimulationTerms", "ENERGY_WINDOW_S"]

#: Length of the energy-balance windows [s] (about ten periods of the vertical motion).
ENERGY_WINDOW_S = 0.4


class SimulationTerms:
    """Static Gor'kov terms at the data states for a fast (interpolated) model at nominal pressure.

    Wraps the simulation's equations of motion (docs/conventions.md section 4, as :class:`acousim.GorkovDimer`
    evaluates them) at the measured states of the problem's runs; computed values are cached per
    instance (one instance per fit).
    """

    def __init__(self, problem: DiagnosisProblem, energy_window: float = ENERGY_WINDOW_S):
        self.energy_window = float(energy_window)
        self.problem = problem
        model = problem.model
        self.model = model
        self.runs = problem.runs
        self.mass = model.dimer.total_mass
        self.g = model.gravity
        self.k = model.wave.wavenumber
        self._cache: dict = {}  # the memoised per-run values by origin height (:meth:`_memo`)

    def forces(self, z0: float) -> list[tuple[NDArray, NDArray]]:
        """Per run: (F_Z/M [m/s^2], Q_theta/I [1/s^2]) at nominal pressure."""
        return self._static(z0)

    def _height_harmonics(self, kind: str, holder, evaluate) -> list[NDArray]:
        """(A, B, C) of ``evaluate(z0) = A + B cos(2k z0) + C sin(2k z0)`` for one run, from three heights.

        Every acoustic quantity of the model at the data states (forces, torque, potential, and any linear
        map of them: smoothing, drift factor, integral-form columns) depends on the origin height z0 only
        through the phase exp(2ik (z0 + y + offset)) of the standing wave's intensity (docs/conventions.md
        section 3), so three evaluations give it at every z0 to round-off; the calibration's height search
        then costs no force evaluation.  Shared by the problem's subsets (the folds) for the same drift.
        """
        store = self.problem._shared.setdefault("harmonics", {})
        drift = self.problem.drift
        key = (kind, id(holder), id(drift))
        if key not in store:
            quarter = np.pi / (4.0 * self.k)  # 2k z0 = pi/2
            v0, v1, v2 = (evaluate(z) for z in (0.0, quarter, 2.0 * quarter))
            harmonics = []
            for a0, a1, a2 in zip(v0, v1, v2):
                const = 0.5 * (a0 + a2)
                harmonics.append((const, 0.5 * (a0 - a2), a1 - const))
            store[key] = (holder, drift, harmonics)  # holder and drift kept so that their ids stay unique
        return store[key][2]

    def _at_height(self, harmonics, z0: float) -> tuple[NDArray, ...]:
        c, s = np.cos(2.0 * self.k * z0), np.sin(2.0 * self.k * z0)
        return tuple(a + c * b + s * d for a, b, d in harmonics)

    def _memo(self, key, build):
        """``build()``, computed once per ``key`` (beyond 64 entries the cache starts over)."""
        if key not in self._cache:
            if len(self._cache) > 64:
                self._cache.clear()
            self._cache[key] = build()
        return self._cache[key]

    def _static(self, z0: float) -> list[tuple[NDArray, NDArray]]:
        return self._memo(round(z0, 12), lambda: [
            self._at_height(self._height_harmonics("static", r, lambda z, r=r: self._static_run(r, z)), z0)
            for r in self.runs])

    def _static_run(self, r: RunAccelerations, z0: float) -> tuple[NDArray, NDArray]:
        """(smoothed F_Z / M, smoothed Q_theta / I) of one run at origin height z0, as the data see them."""
        y, th = r.state[:, 0], r.state[:, 2]
        s = self.model.integrals_at_height(th, z0 + y, self.problem.orientation_sums(r))
        fz, qt = s.force_z / self.mass, s.q_theta / self.model.dimer.hinge_inertia(th)
        f = self.problem.pressure_factor(r.name, r.t)
        if f is not None:  # a drifting pressure scales the acoustic forces in time
            fz, qt = f * fz, f * qt
        return r.smooth(fz), r.smooth(qt)

    def _potentials(self, z0: float) -> list[NDArray]:
        """Per run: U_ac [J] at nominal pressure along the energy balance's states (:meth:`_potential_run`)."""
        return self._memo(("potential", round(z0, 12)), lambda: [
            self._at_height(self._height_harmonics("potential", r.balance, lambda z, r=r: (self._potential_run(r, z),)),
                            z0)[0]
            for r in self.runs])

    def _potential_run(self, r: RunAccelerations, z0: float) -> NDArray:
        """U_ac [J] of run r along its energy balance's states at origin height z0, used raw (not filtered).

        For a model without a potential (``conservative = False``, the full-wave model) U_ac is the acoustic
        energy along the run's path, whose changes are minus the work of the acoustic forces: the model's
        (path) potential U at each frame minus the work, since the first frame, of the part of the forces that
        U does not give (see :meth:`_nonconservative_force_z`).  Only that small part is integrated over time
        (trapezoid at the frames): the work of the whole force, integrated so, would carry the trapezoid's
        error on the oscillation's power (on the fitted frames, 2 ms apart, 10-40 % of a weak damping's work
        per 0.4 s window) and the velocity noise into the energy balance."""
        y, yd, th = r.balance.state[:, 0], r.balance.state[:, 1], r.balance.state[:, 2]
        sums = self.problem.orientation_sums(r.balance)
        s = self.model.integrals_at_height(th, z0 + y, sums)
        potential = s.potential
        if not getattr(self.model, "conservative", True):
            power = self._nonconservative_force_z(th, z0 + y, sums, s) * yd
            potential = potential - np.concatenate([[0.0], np.cumsum(0.5 * (power[1:] + power[:-1]) * np.diff(r.t))])
        return potential

    def _nonconservative_force_z(self, theta: NDArray, z: NDArray, sums, static) -> NDArray:
        """F_Z + dU/dZ [N] at (theta, Z): the part of the acoustic force that the model's potential U does not give.

        The (path) potential of a model without one gives the torque exactly, Q_theta = -dU/dtheta
        (:mod:`acousim.fullwave.statics`), so only the vertical force can leave a remainder.  U depends on the
        height as A + B cos(2kZ) + C sin(2kZ) (docs/conventions.md section 3), so the central difference over a
        quarter wave of 2kZ is its derivative to round-off: dU/dZ = k (U(Z + d) - U(Z - d)), 2k d = pi/2."""
        d = np.pi / (4.0 * self.k)
        up = self.model.integrals_at_height(theta, z + d, sums).potential
        down = self.model.integrals_at_height(theta, z - d, sums).potential
        return static.force_z + self.k * (up - down)

    def energy_terms(self, z0: float, effects: Sequence[str], z_eq: float | None = None) -> list[dict]:
        """Per run, per energy window: the data side of the energy balance and the effect work columns.

        Keys: ``dk`` (change of M ydot^2/2 + I thetadot^2/2 + M g y) [J], ``du`` (change of U_ac at
        nominal pressure) [J], ``work`` (n_windows, n_params) work of each effect parameter's unit
        term [J per unit parameter], ``e_osc`` (n_windows,) oscillation energy at the window start
        without the acoustic part, ``u_osc`` its acoustic part at nominal pressure [J].
        """
        key = ("energy", round(z0, 12), tuple(effects), z_eq)  # the fit and its evaluation ask for the same ones
        return self._memo(key, lambda: self._energy_terms(z0, effects, z_eq))

    def _energy_terms(self, z0: float, effects: Sequence[str], z_eq: float | None) -> list[dict]:
        d = self.model.dimer
        rest_u = float(self.model.integrals_at_height(0.0, z0).potential)  # U_ac at the data's origin, theta = 0
        out = []
        for r, pot in zip(self.runs, self._potentials(z0)):
            state = r.balance.state
            y, yd, th, thd = state.T
            inertia = d.hinge_inertia(th)
            kin = 0.5 * self.mass * yd**2 + 0.5 * inertia * thd**2 + self.mass * self.g * y
            a, b = self.energy_windows(r)
            f = self.problem.pressure_factor(r.name, r.t)
            if f is None:
                du, u0 = pot[b] - pot[a], pot[a]
            else:  # the acoustic forces are f(t) times the nominal ones: the balance holds with int f dU_ac
                cum_u = np.concatenate([[0.0], np.cumsum(0.5 * (f[1:] + f[:-1]) * np.diff(pot))])
                du = cum_u[b] - cum_u[a]
                # oscillation energy at the window's pressure: E_rest(s f) ~ E_rest(s) + s (f - 1) U_ac(rest)
                u0 = f[a] * pot[a] - (f[a] - 1.0) * rest_u
            regs = [effect_regressors(n, state, z0 + y, self.k, z_eq, self.problem) for n in effects]
            regs = np.concatenate(regs, axis=2) if regs else np.zeros((len(r.t), 2, 0))
            out.append({"dk": kin[b] - kin[a], "du": du, "work": self.window_work(r, regs), "k0": kin[a], "u0": u0})
        return out

    def energy_windows(self, r: RunAccelerations) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
        """(first, last) frame of each energy window of run r: consecutive windows of ``energy_window`` seconds,
        the last one ending at the run's last frame."""
        dt = float(np.median(np.diff(r.t)))
        step = max(2, int(round(self.energy_window / dt)))
        idx = np.arange(0, len(r.t), step)
        if idx[-1] != len(r.t) - 1:
            idx = np.append(idx, len(r.t) - 1)
        return idx[:-1], idx[1:]

    def window_work(self, r: RunAccelerations, accelerations: NDArray) -> NDArray[np.float64]:
        """Work per energy window (n_windows, p) [J] of p acceleration terms ``accelerations`` (n, 2, p)
        [m/s^2, 1/s^2] of run r, evaluated at its energy-balance states (:attr:`RunAccelerations.balance`):
        the trapezoid integral of the power M ydot a_y + I(theta) thetadot a_theta."""
        _, yd, th, thd = r.balance.state.T
        power = (self.mass * yd[:, None] * accelerations[:, 0, :]
                 + self.model.dimer.hinge_inertia(th)[:, None] * thd[:, None] * accelerations[:, 1, :])
        cum = np.concatenate([np.zeros((1, power.shape[1])),
                              np.cumsum(0.5 * (power[1:] + power[:-1]) * np.diff(r.t)[:, None], axis=0)])
        a, b = self.energy_windows(r)
        return cum[b] - cum[a]

    def rest_energy(self, s: float, z0: float) -> float:
        """Minimum of M g y + s U_ac(0, z0 + y): the energy of the dimer at rest at its equilibrium [J]."""
        from scipy.optimize import minimize_scalar

        f = lambda y: self.mass * self.g * y + s * float(self.model.integrals_at_height(0.0, z0 + y).potential)  # noqa: E731
        res = minimize_scalar(f, bounds=(-4e-4, min(4e-4, -z0 - 1e-6)), method="bounded", options={"xatol": 1e-10})
        return float(res.fun)

    def integral_known(self, z0: float, q: int) -> list[tuple[NDArray, NDArray]]:
        """Per run (runs must carry integral data), for coordinate q (0: y, 1: theta): the integral-form
        columns of (the acoustic acceleration at nominal pressure, to be scaled by s; the rest of the
        simulation's acceleration): (F_Z / M, -g) or (Q_theta / I, -I' thetadot^2 / (2 I)), at every frame.
        Only the coordinate asked for is integrated (the calibration's height search needs y alone)."""
        def build():
            out = []
            for r in self.runs:
                acoustic, rest = self._height_harmonics(f"integral{q}", r.integral,
                                                        lambda z, r=r: self._integral_run(r, z, q))
                out.append((self._at_height([acoustic], z0)[0], rest[0]))
            return out

        return self._memo(("integral", q, round(z0, 12)), build)

    def integral_known_harmonics(self, q: int) -> list[tuple[tuple[NDArray, NDArray, NDArray], NDArray]]:
        """Per run: ((A, B, C), rest) with :meth:`integral_known` ``(z0, q)`` = (A + B cos(2k z0) + C sin(2k z0), rest)."""
        out = []
        for r in self.runs:
            acoustic, rest = self._height_harmonics(f"integral{q}", r.integral, lambda z, r=r: self._integral_run(r, z, q))
            out.append((acoustic, rest[0]))
        return out

    def _integral_run(self, r: RunAccelerations, z0: float, q: int) -> tuple[NDArray, NDArray]:
        """Integral-form columns of (acoustic acceleration at nominal pressure, the rest) of one run at z0."""
        d = self.model.dimer
        pi = r.integral
        y, th, thd = pi.state[:, 0], pi.state[:, 2], pi.state[:, 3]
        st = self.model.integrals_at_height(th, z0 + y, self.problem.orientation_sums(pi))
        f = self.problem.pressure_factor(r.name, pi.times)
        f = 1.0 if f is None else f  # a drifting pressure scales the acoustic forces in time
        if q == 0:
            return pi.columns(0, f * st.force_z / self.mass), pi.columns(0, np.full(y.shape, -self.g))
        inertia = d.hinge_inertia(th)
        return (pi.columns(1, f * st.q_theta / inertia),
                pi.columns(1, hinge_acceleration(0.0, inertia, d.hinge_inertia_derivative(th), thd)))

    def integral_effect_columns(self, z0: float, effects: Sequence[str], z_eq: float | None, q: int) -> list[NDArray]:
        """Per run: integral-form columns (rows, n_params) of the effects' accelerations of coordinate q.

        With ``z_eq`` None the effects' y is the data's y, so an effect that does not depend on the height
        above the node (:attr:`acousim.dynamics.effects.Effect.depends_on_node_height`) has the same columns at every
        z0: they are computed once per run and shared by the problem's subsets."""
        key = ("integral_effects", q, round(z0, 12), tuple(effects), z_eq)  # asked again by the fit's evaluation
        return self._memo(key, lambda: self._integral_effect_columns(z0, effects, z_eq, q))

    def _integral_effect_columns(self, z0: float, effects: Sequence[str], z_eq: float | None, q: int) -> list[NDArray]:
        from acousim.dynamics.effects import EFFECT_TYPES

        store = self.problem._shared.setdefault("effect_columns", {})
        out = []
        for r in self.runs:
            pi = r.integral
            blocks = []
            for n in effects:
                fixed = z_eq is None and n in EFFECT_TYPES and not EFFECT_TYPES[n].depends_on_node_height
                key = (n, q, id(pi))
                if fixed and key in store:
                    blocks.append(store[key][1])
                    continue
                cols = pi.columns(q, effect_regressors(n, pi.state, z0 + pi.state[:, 0], self.k, z_eq, self.problem)[:, q, :])
                if fixed:
                    store[key] = (pi, cols)  # the holder is kept so that its id stays unique
                blocks.append(cols)
            out.append(np.concatenate(blocks, axis=1) if blocks else pi.columns(q, np.zeros((pi.state.shape[0], 0))))
        return out

    def effect_accelerations(self, z0: float, effects: Sequence[str], z_eq: float | None) -> list[NDArray]:
        """Per run: the effects' regressors (n, 2, n_params) at the run's states, smoothed as the data
        (:meth:`RunAccelerations.smooth`), the effects' y from ``z_eq`` (None: the data's y)."""
        def build():
            out = []
            for r in self.runs:
                regs = [effect_regressors(n, r.state, z0 + r.state[:, 0], self.k, z_eq, self.problem) for n in effects]
                out.append(r.smooth(np.concatenate(regs, axis=2)) if regs else np.zeros((len(r.t), 2, 0)))
            return out

        return self._memo(("effect_accelerations", round(z0, 12), tuple(effects), z_eq), build)

    def centrifugal(self, r: RunAccelerations) -> NDArray:
        """The velocity part of Lagrange's theta equation, -1/2 I' thetadot^2 / I [1/s^2] (smoothed as the data)."""
        th, thd = r.state[:, 2], r.state[:, 3]
        d = self.model.dimer
        return r.smooth(hinge_acceleration(0.0, d.hinge_inertia(th), d.hinge_inertia_derivative(th), thd))
