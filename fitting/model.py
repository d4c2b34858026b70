"""Polynomial acceleration models over the cubic library and their model.json form.

A :class:`PolynomialModel` is frozen: coefficients in SI for every term of the canonical
35-term library (zeros for absent terms), one row per equation [yddot, thetaddot].
:class:`Scales` converts states and coefficients between SI and the dimensionless variables
used inside regression and refinement (y / L_y, theta / L_theta, t / T).
"""
from __future__ import annotations

import json
from dataclasses import dataclass, field
from typing import Mapping

import numpy as np
from numpy.typing import ArrayLike, NDArray

from cubedimer.terms import EQUATION_NAMES, STATE_NAMES, evaluate_library, library_exponents, library_terms, parse_term
from .integrate import integrate

__all__ = ["PolynomialModel", "Scales", "TERMS", "EXPONENTS", "DAMPING_TERMS", "damping_mask"]

TERMS: tuple[str, ...] = tuple(library_terms(3))
EXPONENTS: NDArray[np.int64] = library_exponents(3)
EXPONENTS.setflags(write=False)
#: The viscous damping term of each equation (always kept in the minimal model).
DAMPING_TERMS: dict[str, str] = {"yddot": "ydot", "thetaddot": "thetadot"}


def damping_mask() -> NDArray[np.bool_]:
    """Boolean mask (2, n_terms) that is True at the linear damping term of each equation
    (``ydot`` in yddot, ``thetadot`` in thetaddot): the terms every selection rule keeps."""
    m = np.zeros((len(EQUATION_NAMES), len(TERMS)), bool)
    for q, eq in enumerate(EQUATION_NAMES):
        m[q, TERMS.index(DAMPING_TERMS[eq])] = True
    return m


@dataclass(frozen=True)
class Scales:
    """Characteristic scales for conditioning.

    Parameters
    ----------
    length_y : float
        Length scale of y [m] (e.g. the median over runs of max|y|).
    length_theta : float
        Scale of theta [-].
    time : float
        Time scale [s]; ``1 / (2 pi f_y)`` makes the scaled y frequency ~1.
    """

    length_y: float
    length_theta: float
    time: float

    @property
    def state(self) -> NDArray[np.float64]:
        """Scale of each state component [m, m/s, -, 1/s]."""
        return np.array([self.length_y, self.length_y / self.time,
                         self.length_theta, self.length_theta / self.time])

    @property
    def accel(self) -> NDArray[np.float64]:
        """Scale of [yddot, thetaddot] [m/s^2, 1/s^2]."""
        return np.array([self.length_y, self.length_theta]) / self.time**2

    def coef_factor(self, exps: NDArray[np.int64] = EXPONENTS) -> NDArray[np.float64]:
        """Factor f (2, n_terms) with ``c_scaled = c_SI * f``."""
        mono = np.prod(self.state[None, :] ** exps, axis=1)
        return mono[None, :] / self.accel[:, None]

    def to_scaled(self, coef_si: ArrayLike, exps: NDArray[np.int64] = EXPONENTS) -> NDArray[np.float64]:
        return np.asarray(coef_si, dtype=float) * self.coef_factor(exps)

    def to_si(self, coef_scaled: ArrayLike, exps: NDArray[np.int64] = EXPONENTS) -> NDArray[np.float64]:
        return np.asarray(coef_scaled, dtype=float) / self.coef_factor(exps)

    def to_dict(self) -> dict[str, float]:
        return {"length_y_m": self.length_y, "length_theta": self.length_theta, "time_s": self.time}


def _frozen(a: ArrayLike) -> NDArray[np.float64]:
    a = np.array(a, dtype=float)
    a.setflags(write=False)
    return a


@dataclass(frozen=True, eq=False)
class PolynomialModel:
    """Accelerations ``[yddot, thetaddot] = coef @ library(x)`` in SI.

    Parameters
    ----------
    coef : ndarray, shape (2, 35)
        SI coefficients for the canonical library terms (:data:`TERMS`); rows yddot, thetaddot.
        Units: [m/s^2] / [unit of the monomial] and [1/s^2] / [unit of the monomial].
    """

    coef: NDArray[np.float64] = field(default_factory=lambda: np.zeros((2, len(TERMS))))

    def __post_init__(self) -> None:
        c = np.asarray(self.coef, dtype=float)
        if c.shape != (2, len(TERMS)):
            raise ValueError(f"coef must have shape (2, {len(TERMS)}), got {c.shape}")
        if not np.all(np.isfinite(c)):
            raise ValueError("model coefficients must be finite")
        object.__setattr__(self, "coef", _frozen(c))

    # ---- construction / serialisation -------------------------------------------------
    @classmethod
    def from_equations(cls, equations: Mapping[str, Mapping[str, float]]) -> "PolynomialModel":
        """From ``{"yddot": {"y": a1, ...}, "thetaddot": {...}}`` (any term spelling order)."""
        coef = np.zeros((2, len(TERMS)))
        index = {tuple(e): j for j, e in enumerate(EXPONENTS)}
        for q, eq in enumerate(EQUATION_NAMES):
            for name, val in equations.get(eq, {}).items():
                e = tuple(parse_term(name))
                if e not in index:
                    raise ValueError(f"term {name!r} is not in the cubic library")
                coef[q, index[e]] += float(val)
        unknown = set(equations) - set(EQUATION_NAMES)
        if unknown:
            raise ValueError(f"unknown equations {sorted(unknown)}; expected {EQUATION_NAMES}")
        return cls(coef)

    def equations(self, include_zeros: bool = False) -> dict[str, dict[str, float]]:
        """Coefficients keyed by equation and canonical term name (non-zero terms only by default)."""
        return {eq: {t: float(c) for t, c in zip(TERMS, self.coef[q]) if include_zeros or c != 0.0}
                for q, eq in enumerate(EQUATION_NAMES)}

    def to_json(self) -> dict:
        """The docs/formats.md model fragment: ``{"state": [...], "equations": {...}, "units": "SI"}``."""
        return {"state": list(STATE_NAMES), "equations": self.equations(), "units": "SI"}

    @classmethod
    def from_json(cls, data: Mapping | str) -> "PolynomialModel":
        """From a dict or a JSON string of the docs/formats.md model (files: :func:`fitting.output.model_file.read_model_json`)."""
        if isinstance(data, str):
            data = json.loads(data)
        if "units" in data and data["units"] != "SI":
            raise ValueError(f"only SI models are supported, got units={data['units']!r}")
        if "system" in data:  # a generic two-coordinate system (cubedimer.system): its declared names
            from cubedimer.system import read_system
            spec = read_system({"system": data["system"]}, "model.json")
            if spec.generic:
                if "state" in data and list(data["state"]) != list(spec.state_names):
                    raise ValueError(f"state must be {list(spec.state_names)}, got {data['state']}")
                return cls.from_equations(spec.internal_equations(data["equations"]))
        if "state" in data and list(data["state"]) != list(STATE_NAMES):
            raise ValueError(f"state must be {list(STATE_NAMES)}, got {data['state']}")
        return cls.from_equations(data["equations"])

    # ---- queries ----------------------------------------------------------------------
    @property
    def support(self) -> NDArray[np.bool_]:
        """Boolean mask (2, 35) of non-zero terms."""
        return self.coef != 0.0

    def with_mask(self, mask: ArrayLike) -> "PolynomialModel":
        """Copy with the terms outside ``mask`` (2, 35) set to zero."""
        return PolynomialModel(np.where(np.asarray(mask, bool), self.coef, 0.0))

    def predict(self, states: ArrayLike) -> NDArray[np.float64]:
        """Accelerations (n, 2) [m/s^2, 1/s^2] at states (n, 4) [m, m/s, -, 1/s]."""
        return evaluate_library(states) @ self.coef.T

    def simulate(self, x0: ArrayLike, t: ArrayLike, substeps: int | None = None,
                 bound: float | ArrayLike | None = None) -> tuple[NDArray[np.float64], int]:
        """Integrate from ``x0`` and sample at the uniform times ``t`` (RK4, compiled).

        Parameters
        ----------
        x0 : array (4,)
            Initial state [m, m/s, -, 1/s].
        t : array (n,)
            Uniform sample times [s]; ``t[0]`` is the time of ``x0``.
        substeps : int, optional
            RK4 steps per sample; default makes ``h * omega_max <= 0.05`` from the model's
            linear stiffness (at least 1).
        bound : float or array (4,), optional
            Blow-up bound per component (SI).

        Returns
        -------
        states : ndarray (n, 4), NaN after a blow-up
        n_valid : int
        """
        t = np.asarray(t, dtype=float)
        dt = float(t[1] - t[0]) if t.size > 1 else 1.0
        if substeps is None:
            substeps = self.default_substeps(dt)
        return integrate(self.coef, EXPONENTS, np.asarray(x0, float), dt, t.size, substeps, bound)

    def default_substeps(self, dt: float, h_omega: float = 0.05) -> int:
        """RK4 steps per ``dt`` [s] so that ``h * omega <= h_omega``, omega from the linear terms."""
        k_y = -self.coef[0, TERMS.index("y")]
        k_t = -self.coef[1, TERMS.index("theta")]
        om = np.sqrt(max(k_y, k_t, 1e-300))
        return max(1, int(np.ceil(dt * om / h_omega)))

    def __repr__(self) -> str:
        eqs = self.equations()
        body = "; ".join(f"{eq}: " + ", ".join(f"{v:.4g} {k}" for k, v in terms.items())
                         for eq, terms in eqs.items())
        return f"PolynomialModel({body})"
