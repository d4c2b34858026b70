"""A pressure that drifts in time: the pressure calibrated per time window within each run, and a test
of whether it varies.

The calibration (:mod:`~validation.diagnosis.calibrate.calibration`) fits one pressure scale ``s = (p0/p_nom)^2``
per data set to the vertical equation in its integral form.  Here the same equation is fitted with a
pressure scale that varies in time within each run: the cubic spline through nodes ``window_s`` apart,

    yddot = s(t) F_Z(theta, z0 + y) / M - g,    s(t) = sum_k s_k phi_k(t)   (cubic-spline cardinal functions phi_k),

which is exact for the Gor'kov model (its forces scale with p0^2 at fixed lab height) and still linear
in the node values: the columns are the detrended double integrals ``P K[phi_k F_Z / M]`` over the
integral-form windows.  The origin height z0 (one per data set) is found by a bounded scalar search,
as in the calibration.

Test.  The residual of the integral form is the white tracking noise itself for a model that
explains the data (its noise floor is exact, :class:`~validation.diagnosis.prepare.runs.PositionIntegrals`),
so the nested least-squares models "one pressure per data set" (2 parameters: s, z0) and "a pressure
per node and run" (``sum K_r + 1``) are compared by the F-test of their residual sums of squares.  The
level is far below the usual 0.01 (:data:`DRIFT_ALPHA`), and a drift must also be large enough to
matter (:data:`MIN_RELATIVE_AMPLITUDE` of the pressure), because the F-test inherits any systematic
misfit of the vertical equation (an unmodelled y effect such as damping leaves a structured residual
that a per-window pressure can absorb a little of); both were set on no-drift data (docs/diagnosis.md).

When the drift is significant, :class:`PressureDrift` (the factor ``s(t) / mean s`` per run) is
given to the :class:`~validation.diagnosis.prepare.problem.DiagnosisProblem`, and every later fit (the
calibration of the mean pressure, the candidate effects, the held-out identification) uses the
simulation at that drifting pressure.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np
from numpy.typing import NDArray

from cubedimer.config_checks import check_fraction, check_non_negative, check_positive, check_whole
from ..prepare.problem import DiagnosisProblem
from ..prepare.runs import uses_integral_form

__all__ = ["DriftSettings", "PressureDrift", "DriftTest", "detect_pressure_drift", "drift_basis", "DRIFT_ALPHA",
           "MIN_RELATIVE_AMPLITUDE"]

#: Level of the F-test (set on no-drift twin data, docs/diagnosis.md).
DRIFT_ALPHA = 1e-6
#: A drift smaller than this relative pressure amplitude (half its range within a run, median over runs)
#: is not reported.
MIN_RELATIVE_AMPLITUDE = 0.005


@dataclass(frozen=True)
class DriftSettings:
    """Settings of the drift test.

    Parameters
    ----------
    window_s : spacing of the pressure's nodes within each run [s].  0.3 s puts five nodes on a drift of period
        1.5 s; with 0.4 s the spline's error through the nodes (three times larger, ~h^4) still left the energy
        balance of a weak damping under a 4 % drift with a spurious ``ydot*theta`` (docs/fullwave.md)
    alpha : level of the F-test
    min_relative_amplitude : smallest relative pressure amplitude reported as a drift
    z0_window : the origin height is searched within +-z0_window [m] of the nominal Z_eq
    max_nodes_per_run : most pressure nodes of one run (270: runs up to 80 s); a longer run is refused with a
        message (a run of hours is not a free oscillation after a field drop: its time is in other units), so
        that the per-node fit (a dense column per node) stays bounded
    """

    window_s: float = 0.3
    alpha: float = DRIFT_ALPHA
    min_relative_amplitude: float = MIN_RELATIVE_AMPLITUDE
    z0_window: float = 4e-4
    max_nodes_per_run: int = 270

    def __post_init__(self) -> None:
        check_positive(self, "window_s")
        check_fraction(self, "alpha")
        check_non_negative(self, "min_relative_amplitude")
        check_whole(self, "max_nodes_per_run", minimum=2)


@dataclass(frozen=True, eq=False)
class PressureDrift:
    """The pressure's drift within each run: per run name, node times [s] and the factor
    ``f = s(t) / mean s`` (the simulation's acoustic forces are scaled by it), the cubic spline through the
    nodes in between (:func:`drift_basis`) and constant beyond the end nodes."""

    nodes: dict[str, tuple[NDArray[np.float64], NDArray[np.float64]]]

    def factor(self, name: str, t: NDArray) -> NDArray[np.float64] | None:
        """The factor at times ``t`` [s] of run ``name`` (None for a run without drift nodes)."""
        if name not in self.nodes:
            return None
        times, f = self.nodes[name]
        return drift_basis(np.asarray(t, float), times) @ np.asarray(f, float)


@dataclass(frozen=True, eq=False)
class DriftTest:
    """Result of :func:`detect_pressure_drift`."""

    detected: bool
    tested: bool  #: False when the runs carry no integral-form data (nothing is tested)
    p_value: float
    f_statistic: float
    dof: tuple[int, int]
    relative_amplitude: float  #: half the range of p(t) within a run over its mean, median over runs
    time_scale_s: float  #: rms(p - mean) / rms(dp/dt), median over runs (T / 2 pi for a sinusoid of period T)
    #: per run name: node times [s], pressure amplitude [Pa] and its standard error [Pa] at the nodes
    nodes: dict[str, tuple[NDArray, NDArray, NDArray]]
    z_origin_m: float
    settings: DriftSettings

    @property
    def drift(self) -> PressureDrift:
        """The drift as factors on the simulation's acoustic forces, relative to the mean pressure scale."""
        s_mean = float(np.mean(np.concatenate([p**2 for _, p, _ in self.nodes.values()])))
        return PressureDrift({n: (t, p**2 / s_mean) for n, (t, p, _) in self.nodes.items()})

    def to_dict(self) -> dict:
        """The diagnosis.json form (``calibration.drift``): flat lists ``times_s``, ``pressure_amplitude_pa``
        (and ``std_error_pa``), one entry per node, with the run of each node in ``run``."""
        names = [n for n in self.nodes for _ in self.nodes[n][0]]
        out = {"detected": self.detected, "tested": self.tested, "relative_amplitude": self.relative_amplitude,
               "time_scale_s": self.time_scale_s, "p_value": self.p_value, "f_statistic": self.f_statistic,
               "dof": list(self.dof), "window_s": self.settings.window_s, "alpha": self.settings.alpha,
               "min_relative_amplitude": self.settings.min_relative_amplitude,
               "test": "F-test of one pressure per data set against a cubic-spline pressure per run "
                       "(nodes window_s apart), both on the vertical equation in its integral form",
               "times_s": [], "pressure_amplitude_pa": [], "std_error_pa": [], "run": []}
        if self.tested:
            out["times_s"] = np.concatenate([t for t, _, _ in self.nodes.values()]).tolist()
            out["pressure_amplitude_pa"] = np.concatenate([p for _, p, _ in self.nodes.values()]).tolist()
            out["std_error_pa"] = np.concatenate([e for _, _, e in self.nodes.values()]).tolist()
            out["run"] = names
        return out


def _node_times(t0: float, t1: float, window_s: float, max_nodes: int = 270, name: str = "a run") -> NDArray[np.float64]:
    k = max(2, int(round((t1 - t0) / window_s)) + 1)
    if k > max_nodes:
        raise ValueError(f"{name}: a time span of {t1 - t0:.4g} s needs {k} pressure-drift windows of {window_s:g} s "
                         f"(at most {max_nodes}); a free oscillation after a field drop lasts seconds: is t in "
                         f"seconds? (docs/conventions.md)")
    return np.linspace(t0, t1, k)


def drift_basis(t: NDArray, nodes: NDArray) -> NDArray[np.float64]:
    """(n, K) weights of the node values at times ``t`` [s]: the not-a-knot cubic spline through the K nodes
    (a parabola through 3, the straight line through 2), constant beyond the end nodes.  Rows sum to 1.

    A spline rather than straight lines between the nodes: through the values of a sinusoidal drift of period T
    at nodes 0.3 s apart, straight lines miss it by an rms 9.8 % of its amplitude at T = 1.5 s and 1.4 % at 4 s
    (error ~h^2), the spline by 1.6 % and 0.03 % (~h^4; tests/validation/diagnosis/test_drift.py).  The energy
    balance integrates that error along the path, where it competes with a weak damping's work
    (docs/fullwave.md).
    """
    from scipy.interpolate import CubicSpline

    nodes = np.asarray(nodes, float)
    tc = np.clip(np.asarray(t, float), nodes[0], nodes[-1])
    # scipy's not-a-knot spline is the parabola through 3 points and the line through 2
    return CubicSpline(nodes, np.eye(nodes.size), bc_type="not-a-knot", axis=0)(tc)


def _fixed_parts(problem: DiagnosisProblem, window_s: float,
                 max_nodes: int = 270) -> list[tuple[NDArray, NDArray, NDArray]]:
    """Per run, what :func:`_designs` needs that does not depend on the origin z0: (the node times, the drift basis at
    the integral form's times (rows, K), the target P y - P K[-g] (rows,)).  Made once per test, not once per z0 the
    search tries."""
    g = problem.model.gravity
    out = []
    for r in problem.runs:
        pi = r.integral
        t = pi.times
        nodes = _node_times(t[0], t[-1], window_s, max_nodes, r.name)
        out.append((nodes, drift_basis(t, nodes), pi.target(0) - pi.columns(0, np.full(t.shape, -g))))
    return out


def _designs(problem: DiagnosisProblem, z0: float,
             fixed: list[tuple[NDArray, NDArray, NDArray]]) -> list[tuple[NDArray, NDArray, NDArray]]:
    """Per run: (columns P K[phi_k F_Z/M] (rows, K), target P y - P K[-g] (rows,), node times); ``fixed``: the
    runs' :func:`_fixed_parts`."""
    model = problem.model
    mass = model.dimer.total_mass
    out = []
    for r, (nodes, basis, b) in zip(problem.runs, fixed):
        pi = r.integral
        st = model.integrals_at_height(pi.state[:, 2], z0 + pi.state[:, 0], problem.orientation_sums(pi))
        out.append((pi.columns(0, (st.force_z / mass)[:, None] * basis), b, nodes))
    return out


def _lstsq(x: NDArray, b: NDArray) -> tuple[NDArray, float, NDArray]:
    """Column-scaled least squares: (solution, residual sum of squares, diag((X^T X)^-1))."""
    scale = np.maximum(np.sqrt(np.sum(x * x, axis=0)), 1e-300)
    xs = x / scale
    sol, *_ = np.linalg.lstsq(xs, b, rcond=None)
    r = b - xs @ sol
    return sol / scale, float(r @ r), np.diag(np.linalg.pinv(xs.T @ xs)) / scale**2


def _rss(designs, per_node: bool) -> float:
    if per_node:
        return sum(_lstsq(x, b)[1] for x, b, _ in designs)
    x = np.concatenate([x.sum(axis=1) for x, _, _ in designs])[:, None]
    return _lstsq(x, np.concatenate([b for _, b, _ in designs]))[1]


def _amplitude_and_time_scale(nodes: dict) -> tuple[float, float]:
    amps, scales = [], []
    for t, p, _ in nodes.values():
        q = p / np.mean(p) - 1.0
        amps.append(0.5 * float(np.ptp(q)))
        rate = np.diff(q) / np.diff(t)
        rms_rate = float(np.sqrt(np.mean(rate**2)))
        scales.append(float(np.sqrt(np.mean(q**2))) / rms_rate if rms_rate > 0 else float("inf"))
    return float(np.median(amps)), float(np.median(scales))


def detect_pressure_drift(problem: DiagnosisProblem, settings: DriftSettings = DriftSettings()) -> DriftTest:
    """Calibrate the pressure per node within each run and test whether it varies (module docstring).

    Parameters
    ----------
    problem : DiagnosisProblem
        Its runs need integral-form data (else nothing is tested and ``detected`` is False).
    settings : DriftSettings

    Returns
    -------
    DriftTest
    """
    from scipy.optimize import minimize_scalar
    from scipy.stats import f as f_dist

    runs = problem.runs
    if not uses_integral_form(runs):
        return DriftTest(False, False, float("nan"), float("nan"), (0, 0), float("nan"), float("nan"), {},
                         float("nan"), settings)
    w = settings.window_s
    for r in runs:  # refused before any fit: a bounded number of columns per run
        _node_times(r.integral.times[0], r.integral.times[-1], w, settings.max_nodes_per_run, r.name)
    z_eq = problem.model.equilibrium_height
    bounds = (z_eq - settings.z0_window, min(z_eq + settings.z0_window, -1e-6))

    fixed = _fixed_parts(problem, w, settings.max_nodes_per_run)

    def search(per_node: bool) -> float:
        res = minimize_scalar(lambda z: _rss(_designs(problem, z, fixed), per_node), bounds=bounds, method="bounded",
                              options={"xatol": 1e-9, "maxiter": 200})
        return float(res.x)

    z1 = search(True)
    designs = _designs(problem, z1, fixed)
    rss1 = _rss(designs, True)
    rss0 = _rss(_designs(problem, search(False), fixed), False)
    n_rows = sum(b.size for _, b, _ in designs)
    n_win = sum(r.integral.starts(0).size for r in runs)
    p1 = sum(x.shape[1] for x, _, _ in designs) + 1
    dof1, dof2 = p1 - 2, n_rows - 2 * n_win - p1
    s2 = rss1 / max(dof2, 1)
    fstat = float(max(rss0 - rss1, 0.0) / max(dof1, 1) / max(s2, 1e-300))
    pval = float(f_dist.sf(fstat, dof1, dof2)) if dof1 > 0 and dof2 > 0 else 1.0
    p_nom = problem.model.wave.pressure_amplitude_pa
    nodes = {}
    for r, (x, b, t) in zip(runs, designs):
        sol, rss, var = _lstsq(x, b)
        s = np.maximum(sol, 1e-12)
        se_s = np.sqrt(np.clip(var * rss / max(b.size - 2 * r.integral.starts(0).size - x.shape[1], 1), 0, None))
        p = p_nom * np.sqrt(s)
        nodes[r.name] = (t, p, p_nom * se_s / (2 * np.sqrt(s)))  # dp = p_nom ds / (2 sqrt(s))
    amp, scale = _amplitude_and_time_scale(nodes)
    detected = bool(pval < settings.alpha and amp >= settings.min_relative_amplitude)
    return DriftTest(detected, True, pval, fstat, (int(dof1), int(dof2)), amp, scale, nodes, z1, settings)
