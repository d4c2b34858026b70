"""The full-wave table of one dimer, :class:`FullwaveSurrogate`: the Chebyshev series in theta of the height
structure of F_Z and Q_theta (docs/conventions.md section 7), with what a force model needs of it (forces,
equilibrium, linear frequencies, pressure rescaling) and its JSON file.

It is built by :func:`acousim.fullwave.force_surrogate.build_fullwave_surrogate` (one boundary-element solve per
Chebyshev node; the series, its symmetry and its range are described there) and read from the shipped or cached
files; this module holds only the table itself.
"""
from __future__ import annotations

import json
import os
from dataclasses import dataclass, field, replace
from typing import Callable

import numpy as np
from numpy.polynomial import chebyshev as cheb
from numpy.typing import ArrayLike, NDArray

from cubedimer.atomic import write_json

from ..force_model import ChebyshevSurrogate, ForceCoefficients, levitation_height
from ..medium import Medium
from .flux import UNKEYED_FLUX_DISC_POINTS

__all__ = ["FullwaveSurrogate"]

_COMPONENTS = ("fz", "qt")


def _tup(a: ArrayLike) -> tuple[float, ...]:
    return tuple(float(v) for v in np.asarray(a, float).ravel())


@dataclass(frozen=True)
class FullwaveSurrogate(ChebyshevSurrogate):
    """Chebyshev-in-theta representation of the full-wave F_Z and Q_theta (see the module docstring).

    Attributes
    ----------
    coefficients : dict
        ``{"fz": ((A...), (B...), (C...)), "qt": (...)}``: Chebyshev coefficients in ``t = theta / theta_max``
        of A, B, C of F_Z [N] and Q_theta [N m].
    theta_max : float
        Half-width of the interpolation interval in theta (dimensionless).
    nodes : dict
        The raw per-node data: ``theta`` (all Chebyshev nodes) and ``fz``/``qt`` values (n, 3) of (A, B, C).
    two_k, wavenumber, z_eq, mass, gravity, inertia_const, inertia_sin2, pressure_amplitude_pa, settings, build_accuracy
        The fields every surrogate has (:class:`acousim.force_model.ChebyshevSurrogate`): here the mass is the
        rounded-edge volume's when r_e > 0, the hinge inertia's arm d + g/2, ``settings`` the geometry, mesh, medium
        and build settings and ``build_accuracy`` the build's diagnostics (timings, degrees of freedom, residuals).
    """

    coefficients: dict
    theta_max: float
    nodes: dict = field(default_factory=dict, compare=False, hash=False)

    @property
    def flux_disc_points(self) -> int:
        """Gauss points per panel of the flux surface's mirror disc the table was built with (6 when its settings
        carry no ``flux_disc_points``: :data:`UNKEYED_FLUX_DISC_POINTS`)."""
        return int(self.settings.get("flux_disc_points", UNKEYED_FLUX_DISC_POINTS))

    # ------------------------------------------------------------------ coefficient functions
    def coefficient_values(self, theta: ArrayLike, component: str, derivative: int = 0) -> NDArray[np.float64]:
        """(A, B, C)(theta) of ``component`` (``"fz"`` [N] or ``"qt"`` [N m]), stacked on the last axis.

        ``derivative`` > 0 gives d^n/dtheta^n of the coefficient functions.
        """
        t = np.asarray(theta, float) / self.theta_max
        out = []
        for c in self.coefficients[component]:
            c = np.asarray(c, float)
            if derivative:
                c = cheb.chebder(c, derivative) / self.theta_max**derivative if c.size > derivative else np.zeros(1)
            out.append(cheb.chebval(t, c))
        return np.stack(out, -1)

    def _harmonic(self, theta: ArrayLike, y: ArrayLike, component: str, dtheta: int = 0, dy: int = 0) -> NDArray:
        abc = self.coefficient_values(theta, component, dtheta)
        z = np.asarray(y, float) + self.z_eq
        ph = self.two_k * z
        # d^n/dy^n of cos and sin
        c = np.cos(ph + dy * np.pi / 2) * self.two_k**dy
        s = np.sin(ph + dy * np.pi / 2) * self.two_k**dy
        const = abc[..., 0] if dy == 0 else 0.0
        return const + abc[..., 1] * c + abc[..., 2] * s

    # ------------------------------------------------------------------ physics
    def force_z(self, theta: ArrayLike, y: ArrayLike) -> NDArray[np.float64]:
        """Total vertical acoustic force F_Z [N] at bend theta and height y [m] above Z_eq."""
        return self._harmonic(theta, y, "fz")

    def generalized_forces(self, theta: ArrayLike, y: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """(Q_y [N], Q_theta [N m]): Q_y = F_Z - M g and Q_theta = (pi/4)(tau_A + tau_B)."""
        q_y = self._harmonic(theta, y, "fz") - self.mass * self.gravity
        return q_y, self._harmonic(theta, y, "qt")

    def force_coefficients(self) -> ForceCoefficients:
        """The :class:`~acousim.force_model.ForceModel` height structure: (A, B, C) of F_Z [N] and of
        Q_theta [N m] re-expanded as Chebyshev series in theta itself (the table's series are in
        ``theta / theta_max``; the re-expansion is the same polynomial, exact to round-off)."""
        conv = lambda c: cheb.Chebyshev(np.asarray(c, float), domain=[-self.theta_max, self.theta_max]).convert(
            domain=[-1.0, 1.0]).coef
        (fa, fb, fc), (qa, qb, qc) = (tuple(conv(c) for c in self.coefficients[k]) for k in _COMPONENTS)
        return ForceCoefficients(q_y_a=fa, q_y_b=fb, q_y_c=fc, q_theta_a=qa, q_theta_b=qb, q_theta_c=qc)

    @property
    def medium(self) -> Medium:
        """The air and frequency the table was built for (the :class:`Medium` defaults where not recorded)."""
        st, d = self.settings, Medium()
        return Medium(frequency_hz=float(st.get("frequency_hz", d.frequency_hz)),
                      sound_speed_m_s=float(st.get("sound_speed_m_s", d.sound_speed_m_s)),
                      density_kg_m3=float(st.get("air_density_kg_m3", d.density_kg_m3)))

    def _theta0_vertical_force(self, scale: float = 1.0) -> Callable[[float], float]:
        """F_Z(0, Z) [N] at the absolute height Z [m], of the table with its coefficients times ``scale``."""
        sur = self if scale == 1.0 else replace(self, coefficients=self._scaled_fields(scale)["coefficients"])
        return lambda z: float(sur._harmonic(0.0, z - sur.z_eq, "fz"))

    def _scaled_fields(self, scale: float) -> dict:
        coefs = {k: tuple(_tup(scale * np.asarray(c)) for c in v) for k, v in self.coefficients.items()}
        nodes = {k: (scale * np.asarray(v)).tolist() if k in _COMPONENTS else v for k, v in self.nodes.items()}
        return dict(coefficients=coefs, nodes=nodes)

    # ------------------------------------------------------------------ linearisation
    def taylor_coefficients(self) -> dict[str, dict[str, float]]:
        """Static Taylor coefficients of the accelerations about (theta, y) = (0, 0) (y from Z_eq).

        Returns
        -------
        dict
            ``{"yddot": {"1", "y", "y^2"}, "thetaddot": {"1", "y", "theta", "y*theta", "y^2*theta", "y^2"}}`` in SI
            units (docs/formats.md term names); I'(0) = 0, so thetaddot's derivatives are Q_theta's over I(0).
        """
        i0 = self.inertia_const
        m = self.mass
        d = lambda comp, dt, dy: float(self._harmonic(0.0, 0.0, comp, dt, dy))
        return {
            "yddot": {"1": (d("fz", 0, 0) - m * self.gravity) / m, "y": d("fz", 0, 1) / m, "y^2": d("fz", 0, 2) / (2 * m)},
            "thetaddot": {
                "1": d("qt", 0, 0) / i0, "y": d("qt", 0, 1) / i0, "y^2": d("qt", 0, 2) / (2 * i0),
                "theta": d("qt", 1, 0) / i0, "y*theta": d("qt", 1, 1) / i0, "y^2*theta": d("qt", 1, 2) / (2 * i0),
            },
        }

    def hinge_stiffness(self, y: float = 0.0) -> float:
        """dQ_theta/dtheta at theta = 0 and height y above Z_eq [N m] (negative: restoring)."""
        return float(self._harmonic(0.0, y, "qt", 1, 0))

    def equilibrium(self) -> tuple[float, float]:
        """(theta*, y*) where Q_y = Q_theta = 0, by Newton's method from (0, 0)."""
        x = np.zeros(2)
        for _ in range(50):
            q = np.array([float(v) for v in self.generalized_forces(x[0], x[1])])
            jac = self._jacobian(x[0], x[1])
            step = np.linalg.solve(jac, -q)
            x = x + step
            if np.all(np.abs(step) < [1e-13, 1e-15]):
                break
        return float(x[0]), float(x[1])

    def _jacobian(self, theta: float, y: float) -> NDArray[np.float64]:
        """d(Q_y, Q_theta)/d(theta, y): rows Q_y, Q_theta; columns theta, y."""
        h = self._harmonic
        return np.array([
            [float(h(theta, y, "fz", 1, 0)), float(h(theta, y, "fz", 0, 1))],
            [float(h(theta, y, "qt", 1, 0)), float(h(theta, y, "qt", 0, 1))],
        ])

    def linear_frequencies(self) -> tuple[float, float]:
        """Small-oscillation frequencies (f_y, f_theta) [Hz] about the equilibrium :meth:`equilibrium`.

        From the eigenvalues of ``-M^-1 dQ/dq`` (M = diag(M, I(theta*))); the generalised forces need not
        derive from a potential, so the stiffness matrix may be non-symmetric.  Each frequency is assigned
        to the coordinate its eigenvector is dominated by (with y scaled by 1/d); NaN for an unstable or
        oscillatory-growing (complex) mode.
        """
        th, y = self.equilibrium()
        jac = self._jacobian(th, y)  # rows (Q_y, Q_theta), cols (theta, y)
        k = -np.array([[jac[0, 1], jac[0, 0]], [jac[1, 1], jac[1, 0]]])  # order (y, theta)
        minv = np.diag([1.0 / self.mass, 1.0 / float(self.hinge_inertia(th))])
        w2, vec = np.linalg.eig(minv @ k)
        arm = float(self.settings.get("side_m", 500e-6)) / np.sqrt(2.0)
        out = [float("nan"), float("nan")]
        order = np.argsort([abs(vec[0, i]) / arm / (abs(vec[1, i]) + 1e-300) for i in range(2)])[::-1]
        for slot, i in zip((0, 1), order):
            v = w2[i]
            if abs(v.imag) <= 1e-9 * abs(v.real) and v.real > 0:
                out[slot] = float(np.sqrt(v.real) / (2 * np.pi))
        return out[0], out[1]

    def provenance(self) -> dict:
        """The build record (solves, DOFs, family interpolation source and accuracy) and the theta range."""
        return {"build_accuracy": self.build_accuracy, "theta_max": self.theta_max}

    # ------------------------------------------------------------------ files
    def to_dict(self) -> dict:
        """JSON-ready dict of everything."""
        return {
            "format": "cubedimer-fullwave-surrogate/1",
            "model": "fullwave",
            "coefficients": {k: [list(c) for c in v] for k, v in self.coefficients.items()},
            "theta_max": self.theta_max, "two_k": self.two_k, "wavenumber": self.wavenumber, "z_eq": self.z_eq,
            "mass": self.mass, "gravity": self.gravity, "inertia_const": self.inertia_const,
            "inertia_sin2": self.inertia_sin2, "pressure_amplitude_pa": self.pressure_amplitude_pa,
            "settings": self.settings, "build_accuracy": self.build_accuracy, "nodes": self.nodes,
        }

    @classmethod
    def from_dict(cls, d: dict) -> "FullwaveSurrogate":
        if d.get("format") != "cubedimer-fullwave-surrogate/1":
            raise ValueError("not a full-wave surrogate table (format key missing or unknown)")
        coefs = {k: tuple(_tup(c) for c in v) for k, v in d["coefficients"].items()}
        keys = ("theta_max", "two_k", "wavenumber", "z_eq", "mass", "gravity", "inertia_const", "inertia_sin2",
                "pressure_amplitude_pa")
        return cls(coefficients=coefs, **{k: float(d[k]) for k in keys}, settings=d.get("settings", {}),
                   build_accuracy=d.get("build_accuracy", {}), nodes=d.get("nodes", {}))

    def save(self, path: str | os.PathLike) -> None:
        """Write the table as JSON (atomically; missing folders are created)."""
        write_json(path, self.to_dict())

    @classmethod
    def load(cls, path: str | os.PathLike) -> "FullwaveSurrogate":
        with open(path) as fh:
            return cls.from_dict(json.load(fh))


def _equilibrium_height(sur: FullwaveSurrogate) -> float:
    """Z in (-lambda/8, 0) where F_Z(0, Z) = M g (:func:`acousim.force_model.levitation_height`)."""
    return levitation_height(sur._theta0_vertical_force(), sur.mass * sur.gravity, sur.two_k)
