"""Twin-like data sets with causes outside the candidates: a cubic hinge term, a y-dependent damping, a pressure
drifting in time, optionally with candidate effects on top.

The runs integrate the surrogate's equations of motion (docs/conventions.md section 4; the Gor'kov force and torque from the
default dimer's Chebyshev surrogate and :func:`acousim.dynamics.equations.hinge_acceleration`) with classical RK4 at the
frame interval (omega_y dt = 0.07 at 2000 fps), batched over runs, with

* a pressure ``p(t) = p_true (1 + drift sin(2 pi t / T + phase))`` (T and phase drawn per run; the Gor'kov
  forces scale with p^2 at fixed lab height),
* ``-cubic_hinge theta^3`` [1/s^2] added to thetaddot,
* ``-y_damping y^2 ydot`` [1/(m^2 s)] added to yddot, with y measured from the true equilibrium height,
* the accelerations of candidate effects (:class:`acousim.dynamics.effects.EffectSet`, y from the true equilibrium).

The CSVs (docs/formats.md) carry Gaussian tracking noise on y [m] and theta; y is measured from the nominal
equilibrium height and meta.json holds the nominal pressure.  There is no damping beyond the effects given:
unlike :class:`acousim.twin.TwinConfig`, whose default adds the air's computed drag, these data sets are inviscid
apart from their candidate effects and ``y_damping``.  The drops start at |y| of 80-150 um, so that
each run's oscillation dominates its y spectrum (a drift of a few per cent moves the equilibrium by tens of
micrometres).  Every random choice comes from ``seed``.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

import numpy as np
from numpy.typing import NDArray

from cubedimer.atomic import write_json
from cubedimer.config_checks import check_bounds, check_fraction, check_positive, check_that, check_whole
from cubedimer.dataset import write_run_csv
from cubedimer.meta import DEFAULT_TRACKING_NOISE

__all__ = ["TwinLikeConfig", "TwinLikeError", "write_twin_like_dataset"]


class TwinLikeError(ValueError):
    """A run left the trap or closed the hinge; the data set was not written."""


@dataclass(frozen=True)
class TwinLikeConfig:
    """What a twin-like data set holds (module docstring).

    Parameters
    ----------
    runs : int
        Number of runs (CSV files).
    duration : float
        Length of each run [s].
    fps : float
        Frame rate [1/s] (also the RK4 step).
    seed : int
        Seed of every random choice.
    pressure_error : float
        The true mean pressure is nominal x (1 + e), e uniform in +-``pressure_error``.
    drift : float
        Relative amplitude of the sinusoidal pressure drift (0: constant).
    drift_period : (float, float)
        Range of the drift's period [s], drawn per run.
    cubic_hinge : float
        Coefficient k of ``-k theta^3`` in thetaddot [1/s^2].
    y_damping : float
        Coefficient c of ``-c y^2 ydot`` in yddot [1/(m^2 s)].
    effects : dict, optional
        Candidate effects ``{name: {param: value}}`` (:meth:`acousim.dynamics.effects.EffectSet.from_dict`).
    noise : (float, float)
        Tracking noise standard deviations of y [m] and theta [-].
    force_model : acousim.ForceModel, optional
        The acoustic forces at the nominal pressure (e.g. the full-wave model of another dimer,
        :func:`acousim.models.dynamic_model`); default the Gor'kov surrogate of the default dimer.  meta.json then
        records its side.
    """

    runs: int = 8
    duration: float = 3.0
    fps: float = 2000.0
    seed: int = 0
    pressure_error: float = 0.0
    drift: float = 0.0
    drift_period: tuple[float, float] = (1.5, 4.0)
    cubic_hinge: float = 0.0
    y_damping: float = 0.0
    effects: dict | None = None
    noise: tuple[float, float] = (DEFAULT_TRACKING_NOISE["noise_y_m"], DEFAULT_TRACKING_NOISE["noise_theta"])
    force_model: Any = None

    def __post_init__(self) -> None:
        check_whole(self, "runs")
        check_positive(self, "duration")
        check_positive(self, "fps")
        check_fraction(self, "pressure_error", zero=True)
        check_fraction(self, "drift", zero=True)
        check_bounds(self, "drift_period")
        check_that(self, len(self.noise) == 2 and all(n >= 0 for n in self.noise),
                   f"noise must be two standard deviations >= 0 (y [m], theta), got {self.noise!r}")


def write_twin_like_dataset(path: str | Path, config: TwinLikeConfig = TwinLikeConfig()) -> dict:
    """Write ``config.runs`` CSVs and meta.json into ``path`` (see the module docstring).

    Returns
    -------
    dict
        The truth: ``pressure_amplitude_pa`` (mean), ``period_s``, ``phase``, ``relative_half_range`` (per run,
        of p(t) over the recorded frames), ``cubic_hinge``, ``y_damping``, ``effects``, ``files``.

    Raises
    ------
    TwinLikeError
        If a run leaves the trap or theta reaches +-1.
    """
    from acousim import EffectSet, cached_surrogate

    cfg = config
    path = Path(path)
    path.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(cfg.seed)
    sur = cached_surrogate() if cfg.force_model is None else cfg.force_model
    p_nom = sur.pressure_amplitude_pa
    p_true = p_nom * (1 + rng.uniform(-cfg.pressure_error, cfg.pressure_error))
    eff = EffectSet.from_dict(cfg.effects or {})
    n = int(round(cfg.duration * cfg.fps))
    phase = rng.uniform(0, 2 * np.pi, cfg.runs)
    period = rng.uniform(*cfg.drift_period, cfg.runs)
    x = np.column_stack([rng.choice([-1, 1], cfg.runs) * rng.uniform(0.8e-4, 1.5e-4, cfg.runs), np.zeros(cfg.runs),
                         rng.uniform(-0.3, 0.3, cfg.runs), rng.uniform(-2, 2, cfg.runs)])

    def pressure(t):
        return p_true * (1 + cfg.drift * np.sin(2 * np.pi * t / period + phase))

    rhs = _equations_of_motion(sur, cfg, p_true, pressure, eff)
    out = _integrate(rhs, x, n, 1.0 / cfg.fps, np.pi / sur.two_k)
    t = np.arange(n) / cfg.fps
    files = _write_runs(path, t, out, rng, cfg.noise)
    write_json(path / "meta.json", _meta(sur, cfg.force_model is not None))
    p_t = pressure(t[:, None])  # (n, runs)
    return {"pressure_amplitude_pa": float(p_true), "period_s": period.tolist(), "phase": phase.tolist(),
            "relative_half_range": (0.5 * np.ptp(p_t, axis=0) / p_t.mean(axis=0)).tolist(),
            "drift": float(cfg.drift), "cubic_hinge": float(cfg.cubic_hinge), "y_damping": float(cfg.y_damping),
            "effects": eff.to_dict(), "files": files}


def _equations_of_motion(sur, cfg: TwinLikeConfig, p_true: float, pressure: Callable, eff
                         ) -> Callable[[float, NDArray], NDArray]:
    """The right-hand side ``rhs(t, states)`` of the runs' equations of motion, batched over runs (states (runs, 4):
    y from the nominal equilibrium [m], ydot [m/s], theta [-], thetadot [1/s]): the acoustic force and torque at the
    pressure ``pressure(t)``, gravity, the hinge, the cubic hinge term, the y-dependent damping and the effects."""
    from numpy.polynomial import chebyshev as cheb

    from acousim.dynamics.equations import hinge_acceleration

    general = cfg.force_model is not None
    heights = sur.force_coefficients() if general else None
    p_nom = sur.pressure_amplitude_pa
    m, g, two_k, z_eq = sur.mass, sur.gravity, sur.two_k, sur.z_eq
    z_true = sur.with_pressure(p_true).z_eq  # equilibrium at the mean true pressure: the effects' y origin
    if not general:
        _, b, gm, da, db, dg = sur.coefficient_arrays()
        coef = np.stack([b, gm, da, db, dg], axis=1)  # Chebyshev series in theta, one column per function

    def rhs(t, s):
        scale = (pressure(t) / p_nom) ** 2
        th = s[:, 2]
        if general:  # (F_Z, Q_theta) from the model's height structure
            fz, qt = heights.evaluate(th, s[:, 0] + z_eq, two_k)
        else:  # the Gor'kov surrogate's potential series
            bv, gv, dav, dbv, dgv = cheb.chebval(th, coef)
            c, sn = np.cos(two_k * (s[:, 0] + z_eq)), np.sin(two_k * (s[:, 0] + z_eq))
            fz, qt = two_k * (bv * sn - gv * c), -(dav + dbv * c + dgv * sn)
        ay = scale * fz / m - g
        at = hinge_acceleration(scale * qt, sur.hinge_inertia(th), sur.hinge_inertia_derivative(th),
                                s[:, 3]) - cfg.cubic_hinge * th**3
        y_rel = s[:, 0] + z_eq - z_true
        ay = ay - cfg.y_damping * y_rel**2 * s[:, 1]
        if len(eff):
            ey, et = eff.accelerations(y_rel, s[:, 1], th, s[:, 3], sur.wavenumber, z_true)
            ay, at = ay + ey, at + et
        return np.column_stack([s[:, 1], ay, s[:, 3], at])

    return rhs


def _integrate(rhs: Callable[[float, NDArray], NDArray], x: NDArray, n: int, h: float, y_bound: float) -> NDArray:
    """Classical RK4 of ``rhs`` from the states ``x`` (runs, 4), ``n`` frames of step ``h`` [s]: (n, runs, 4).
    :class:`TwinLikeError` when a run is no longer finite, theta reaches +-1 or |y| the trap's half wavelength
    ``y_bound`` [m]."""
    out = np.empty((n, x.shape[0], 4))
    out[0] = x
    with np.errstate(all="ignore"):
        for i in range(1, n):
            t = (i - 1) * h
            k1 = rhs(t, x)
            k2 = rhs(t + h / 2, x + h / 2 * k1)
            k3 = rhs(t + h / 2, x + h / 2 * k2)
            k4 = rhs(t + h, x + h * k3)
            x = x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
            out[i] = x
            if not (np.all(np.isfinite(x)) and np.all(np.abs(x[:, 2]) < 1) and np.all(np.abs(x[:, 0]) < y_bound)):
                raise TwinLikeError(f"a run left the trap or closed the hinge at t = {i * h:.3f} s")
    return out


def _write_runs(path: Path, t: NDArray, out: NDArray, rng: np.random.Generator, noise: tuple[float, float]
                ) -> list[str]:
    """The runs' CSVs (docs/formats.md) with Gaussian tracking noise on y [m] and theta; returns the file names."""
    n = t.size
    files = []
    for r in range(out.shape[1]):
        y = out[:, r, 0] + rng.normal(0, noise[0], n)
        th = out[:, r, 2] + rng.normal(0, noise[1], n)
        name = f"run{r:02d}.csv"
        write_run_csv(path / name, t, y, th, ["twin-like run: surrogate equations of motion",
                                              "units: t [s], y [m], theta [-]"], t_decimals=9, y_digits=10,
                      theta_decimals=10, missing="nan")
        files.append(name)
    return files


def _meta(sur, general: bool) -> dict:
    """meta.json: the nominal pressure, and for a given force model its dimer and field."""
    meta = {"pressure_amplitude_pa": sur.pressure_amplitude_pa}
    if general:  # the dimer and the field of the given model
        st = sur.settings
        meta.update({k: float(st[sk]) for k, sk in (("side_length_m", "side_m"), ("frequency_hz", "frequency_hz"),
                                                     ("sound_speed_m_s", "sound_speed_m_s"),
                                                     ("air_density_kg_m3", "air_density_kg_m3"),
                                                     ("particle_density_kg_m3", "particle_density_kg_m3"))
                     if sk in st})
    return meta
