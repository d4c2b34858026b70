"""Static force/torque sweeps over (theta, y) and the static coefficients fitted to them.

A sweep evaluates the Gor'kov model (:class:`acousim.gorkov.forces.GorkovDimer`) at zero velocity on a
rectangular (theta, y) grid; its CSV has the docs/formats.md columns
``theta, y, potential, force_z, q_y, q_theta, yddot, thetaddot`` (J, N, N, N m, m/s^2, 1/s^2) plus
``z_com`` [m] (height above the pressure node).

Static coefficients: ordinary least squares of the swept ``yddot`` and ``thetaddot`` on the
velocity-free monomials of the library (theta and y up to degree 3, docs/formats.md term names), with
y measured from Z_eq.  The model values are deterministic, so the "residual" is the truncation
error of the cubic; the reported standard errors treat it as white noise
(``sigma^2 (X^T X)^{-1}``, sigma^2 = RSS / (n - p)) and are therefore a measure of how well the
cubic represents the sweep over the chosen box, not a measurement error.  The coefficients of a
truncated expansion depend on the box: keep the box comparable to the data's range.
"""
from __future__ import annotations

import json
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray

from cubedimer.atomic import atomic_write_text, write_json
from cubedimer.terms import library_exponents, term_name

from ..static_model import StaticModel

__all__ = [
    "SweepResult",
    "static_sweep",
    "read_sweep_csv",
    "StaticCoefficients",
    "fit_static_coefficients",
    "taylor_coefficients",
    "SWEEP_COLUMNS",
]

#: Columns written by :meth:`SweepResult.to_csv`, in order, with units.
SWEEP_COLUMNS: tuple[tuple[str, str], ...] = (
    ("theta", "1"),
    ("y", "m"),
    ("potential", "J"),
    ("force_z", "N"),
    ("q_y", "N"),
    ("q_theta", "N m"),
    ("yddot", "m/s^2"),
    ("thetaddot", "1/s^2"),
    ("z_com", "m"),
)


@dataclass(frozen=True)
class SweepResult:
    """Force-model values on a (theta, y) grid; every array has shape (n_theta, n_y).

    Attributes
    ----------
    theta_grid, y_grid : 1-D arrays (dimensionless, m)
    columns : dict of 2-D arrays, keys of :data:`SWEEP_COLUMNS`
    settings : dict of the model settings (side, pressure, mesh size, Z_eq, ...)
    """

    theta_grid: NDArray[np.float64]
    y_grid: NDArray[np.float64]
    columns: dict[str, NDArray[np.float64]]
    settings: dict = field(default_factory=dict)

    def __getitem__(self, key: str) -> NDArray[np.float64]:
        return self.columns[key]

    def to_csv(self, path: str | os.PathLike) -> None:
        """Write one row per grid point (theta-major), atomically, with a commented settings header."""
        names = [c for c, _ in SWEEP_COLUMNS]
        data = np.column_stack([self.columns[c].ravel() for c in names])
        lines = [f"# acousim static sweep; units: " + ", ".join(f"{c} [{u}]" for c, u in SWEEP_COLUMNS)]
        lines.append("# settings: " + json.dumps(self.settings, sort_keys=True))
        lines.append(",".join(names))
        body = "\n".join(",".join("" if np.isnan(v) else f"{v:.10g}" for v in row) for row in data)
        atomic_write_text(path, "\n".join(lines) + "\n" + body + "\n")


def static_sweep(
    model: StaticModel,
    theta: ArrayLike,
    y: ArrayLike,
    progress: bool = False,
    chunk: int = 64,
) -> SweepResult:
    """Evaluate a static model (:class:`acousim.static_model.StaticModel`: Gor'kov or full wave) on the grid
    ``theta x y`` (1-D arrays; theta dimensionless, y [m] above the model's own Z_eq).

    A model without a potential (``conservative = False``) leaves the ``potential`` column empty (NaN).  The
    orientation sums are computed once per theta value, vectorised over all quadrature
    nodes, and combined with every y by broadcasting (see :mod:`acousim.gorkov.forces`); ``chunk``
    theta values are processed at a time with an optional progress bar.
    """
    theta = np.atleast_1d(np.asarray(theta, float))
    y = np.atleast_1d(np.asarray(y, float))
    if theta.ndim != 1 or y.ndim != 1:
        raise ValueError("theta and y grids must be 1-D")
    if np.any(np.abs(theta) >= 1):
        raise ValueError("theta must lie in (-1, 1)")
    from tqdm.auto import tqdm

    z_eq = model.equilibrium_height
    parts = []
    starts = range(0, len(theta), chunk)
    for i0 in tqdm(starts, desc="sweep", disable=not progress or len(starts) < 2, leave=False):
        th = theta[i0 : i0 + chunk, None]
        parts.append(model.integrals_at_height(th, z_eq + y[None, :]))
    cols = {name: np.concatenate([getattr(p, name) for p in parts], axis=0) for name in parts[0]._fields}
    tt, yy = np.meshgrid(theta, y, indexing="ij")
    cols["theta"], cols["y"], cols["z_com"] = tt, yy, yy + z_eq
    if not model.conservative:  # no potential (the full-wave forces): an empty column
        cols["potential"] = np.full(tt.shape, np.nan)
    return SweepResult(theta, y, cols, model.record())


def read_sweep_csv(path: str | os.PathLike) -> SweepResult:
    """Read a sweep CSV written by :meth:`SweepResult.to_csv` (or any CSV with the docs/formats.md columns
    on a full rectangular grid).  Raises ValueError naming the file on bad input."""
    path = Path(path)
    settings: dict = {}
    try:
        with open(path) as fh:
            lines = fh.read().splitlines()
    except OSError as exc:
        raise ValueError(f"{path}: cannot read sweep CSV ({exc.strerror})") from None
    for line in lines:
        if line.startswith("# settings: "):
            try:
                settings = json.loads(line[len("# settings: ") :])
            except json.JSONDecodeError:
                settings = {}
    rows = [ln for ln in lines if ln.strip() and not ln.lstrip().startswith("#")]
    if not rows:
        raise ValueError(f"{path}: empty sweep CSV")
    names = [c.strip() for c in rows[0].split(",")]
    required = ["theta", "y", "potential", "force_z", "q_y", "q_theta", "yddot", "thetaddot"]
    missing = [c for c in required if c not in names]
    if missing:
        raise ValueError(f"{path}: missing column(s) {', '.join(missing)}")
    try:
        values = np.array([[float(v) if v.strip() else np.nan for v in r.split(",")] for r in rows[1:]],
                          float).reshape(-1, len(names))
    except ValueError:
        raise ValueError(f"{path}: non-numeric or ragged rows") from None
    data = {n: values[:, i] for i, n in enumerate(names)}
    theta_grid, y_grid = np.unique(data["theta"]), np.unique(data["y"])
    if len(theta_grid) * len(y_grid) != len(values) or len(values) == 0:
        raise ValueError(f"{path}: rows do not form a full (theta, y) grid")
    order = np.lexsort((data["y"], data["theta"]))
    cols = {n: data[n][order].reshape(len(theta_grid), len(y_grid)) for n in names}
    return SweepResult(theta_grid, y_grid, cols, settings)


def _static_exponents(degree: int) -> NDArray[np.int64]:
    e = library_exponents(degree)
    return e[(e[:, 1] == 0) & (e[:, 3] == 0)]


@dataclass(frozen=True)
class StaticCoefficients:
    """Least-squares coefficients of the swept accelerations on velocity-free monomials.

    Attributes
    ----------
    terms : list of term names (docs/formats.md), shared by both equations
    coefficients, std_errors : dict equation -> dict term -> value [SI: (1/s^2 or m/s^2) / unit^powers]
    rms_residual : dict equation -> RMS residual of the fit [equation's units]
    relative_residual : dict equation -> RMS residual / RMS of the swept values
    y_origin : str, description of the origin of y
    box : dict with the theta and y ranges of the sweep
    """

    terms: list[str]
    coefficients: dict[str, dict[str, float]]
    std_errors: dict[str, dict[str, float]]
    rms_residual: dict[str, float]
    relative_residual: dict[str, float]
    y_origin: str
    box: dict
    settings: dict
    taylor: dict | None = None

    def to_dict(self) -> dict:
        return {
            "terms": self.terms,
            "equations": self.coefficients,
            "std_errors": self.std_errors,
            "rms_residual": self.rms_residual,
            "relative_residual": self.relative_residual,
            "y_origin": self.y_origin,
            "box": self.box,
            "settings": self.settings,
            "taylor_at_equilibrium": self.taylor,
            "units": "SI",
            "note": "std_errors treat the cubic's truncation residual as white noise (OLS); "
            "they measure how well the cubic represents the sweep over this box",
        }

    def to_json(self, path: str | os.PathLike) -> None:
        """Write :meth:`to_dict` as JSON (the suite's one JSON writer, atomic)."""
        write_json(path, self.to_dict())


def fit_static_coefficients(
    sweep: SweepResult,
    degree: int = 3,
    theta_max: float | None = None,
    y_max: float | None = None,
    taylor: dict | None = None,
) -> StaticCoefficients:
    """Fit ``yddot`` and ``thetaddot`` of a sweep on the velocity-free monomials up to ``degree``.

    Parameters
    ----------
    sweep : SweepResult
    degree : int
        Highest total degree in (y, theta).
    theta_max, y_max : float, optional
        Fit only grid points with |theta| <= theta_max and |y| <= y_max [m] (the fitting box).
        A cubic represents Q_theta ~ sin(4 phi) well only for |theta| <~ 0.3; keep the box
        comparable to the range the data explore.
    taylor : dict, optional
        Local Taylor coefficients (:func:`taylor_coefficients`) stored alongside.

    Variables are scaled to [-1, 1] for conditioning (y by max|y|, theta by max|theta|) and the
    coefficients converted back to SI.
    """
    exps = _static_exponents(degree)
    terms = [term_name(e) for e in exps]
    th = sweep["theta"].ravel()
    yy = sweep["y"].ravel()
    keep = np.ones(th.shape, bool)
    if theta_max is not None:
        keep &= np.abs(th) <= theta_max * (1 + 1e-12)
    if y_max is not None:
        keep &= np.abs(yy) <= y_max * (1 + 1e-12)
    th, yy = th[keep], yy[keep]
    ys, ts = np.max(np.abs(yy)) or 1.0, np.max(np.abs(th)) or 1.0
    x = np.column_stack([(yy / ys) ** e[0] * (th / ts) ** e[2] for e in exps])
    scale = np.array([ys ** e[0] * ts ** e[2] for e in exps], float)
    n, p = x.shape
    if n <= p:
        raise ValueError(f"a static fit of {p} terms needs more than {p} grid points, got {n}")
    xtx_inv = np.linalg.pinv(x.T @ x)
    coefs, ses, rms, rel = {}, {}, {}, {}
    for eq in ("yddot", "thetaddot"):
        target = sweep[eq].ravel()[keep]
        beta, *_ = np.linalg.lstsq(x, target, rcond=None)
        resid = target - x @ beta
        sigma2 = resid @ resid / (n - p)
        se = np.sqrt(np.clip(np.diag(xtx_inv) * sigma2, 0, None))
        coefs[eq] = {t: float(b / s) for t, b, s in zip(terms, beta, scale)}
        ses[eq] = {t: float(e / s) for t, e, s in zip(terms, se, scale)}
        rms[eq] = float(np.sqrt(np.mean(resid**2)))
        rel[eq] = float(rms[eq] / (np.sqrt(np.mean(target**2)) or 1.0))
    box = {
        "theta": [float(th.min()), float(th.max())],
        "y_m": [float(yy.min()), float(yy.max())],
    }
    origin = (
        "y = Z_com - Z_eq: height of the centre of mass above the simulated equilibrium height "
        f"Z_eq = {sweep.settings.get('equilibrium_height_m', float('nan')):.6g} m (below the node)"
    )
    return StaticCoefficients(terms, coefs, ses, rms, rel, origin, box, dict(sweep.settings), taylor)


def taylor_coefficients(model: StaticModel, degree: int = 3, theta_half_width: float = 0.05,
                        y_half_width: float = 20e-6) -> dict[str, dict[str, float]]:
    """Local Taylor coefficients of yddot and thetaddot at (theta, y) = (0, 0) [SI].

    Obtained by an exact-interpolation-quality least-squares fit of degree ``degree + 2`` on a
    17 x 17 Chebyshev grid in a small box around the equilibrium (the extra degrees absorb the
    higher-order terms), keeping the monomials up to ``degree``.  These are the coefficients the
    model predicts in the small-amplitude limit, independent of any fitting box.
    """
    n = 17
    cheb = np.cos(np.pi * (np.arange(n) + 0.5) / n)
    sweep = static_sweep(model, theta_half_width * cheb, y_half_width * cheb)
    full = fit_static_coefficients(sweep, degree=degree + 2)
    keep = {term_name(e) for e in _static_exponents(degree)}
    return {eq: {t: v for t, v in c.items() if t in keep} for eq, c in full.coefficients.items()}
