"""What the equations of motion need from a force model (docs/conventions.md sections 3, 4 and 7).

A force model gives the generalised forces ``Q_y`` [N] and ``Q_theta`` [N m] of the dimer over
(theta, y), with ``y`` measured from the equilibrium height ``Z_eq`` (< 0, below the pressure
node).  Every acoustic model of the suite has the same exact height structure: the incident field
at ``Z = Z_eq + y`` is a combination of sin(kZ) and cos(kZ), forces are quadratic in the field, so

    Q_y     = A_y(theta)     + B_y(theta)     cos(2kZ) + C_y(theta)     sin(2kZ)  - M g
    Q_theta = A_theta(theta) + B_theta(theta) cos(2kZ) + C_theta(theta) sin(2kZ)

and a model hands the compiled equations of motion the six coefficient functions as Chebyshev
series in theta on [-1, 1] (:class:`ForceCoefficients`; gravity is kept apart).  The Gor'kov
surrogate (:class:`acousim.gorkov.energy_surrogate.ForceSurrogate`) derives them from one potential; a full-wave
model gives Q_y and Q_theta directly (they need not derive from a potential).

:class:`ForceModel` is the protocol (structural: any object with these members is one).
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Callable, Protocol, runtime_checkable

import numpy as np
from numpy.polynomial import chebyshev as cheb
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import brentq

__all__ = ["ForceCoefficients", "ForceModel", "SinusoidalInertia", "ChebyshevSurrogate", "levitation_height",
           "escape_height_below"]

_FIELDS = ("q_y_a", "q_y_b", "q_y_c", "q_theta_a", "q_theta_b", "q_theta_c")


def _trimmed(c: ArrayLike, name: str) -> NDArray[np.float64]:
    a = np.ascontiguousarray(np.asarray(c, float).ravel())
    if a.size == 0 or not np.all(np.isfinite(a)):
        raise ValueError(f"force coefficient series {name} must be non-empty and finite")
    nz = np.flatnonzero(a)
    # trailing zeros change nothing (Clenshaw adds exact zeros) but cost time in every evaluation
    return a[: int(nz[-1]) + 1 if nz.size else 1].copy()


@dataclass(frozen=True, eq=False)
class ForceCoefficients:
    """Chebyshev-in-theta coefficients of the acoustic generalised forces' height structure.

    ``Q_y + M g = A_y + B_y cos(2kZ) + C_y sin(2kZ)`` [N] and
    ``Q_theta = A_theta + B_theta cos(2kZ) + C_theta sin(2kZ)`` [N m], ``Z = Z_eq + y`` [m]; each of
    A, B, C is ``sum_j c_j T_j(theta)``.  Arrays may differ in length; trailing zeros are dropped.

    Attributes
    ----------
    q_y_a, q_y_b, q_y_c : ndarray
        Series of A_y, B_y, C_y [N].
    q_theta_a, q_theta_b, q_theta_c : ndarray
        Series of A_theta, B_theta, C_theta [N m].
    """

    q_y_a: NDArray[np.float64]
    q_y_b: NDArray[np.float64]
    q_y_c: NDArray[np.float64]
    q_theta_a: NDArray[np.float64]
    q_theta_b: NDArray[np.float64]
    q_theta_c: NDArray[np.float64]

    def __post_init__(self) -> None:
        for name in _FIELDS:
            object.__setattr__(self, name, _trimmed(getattr(self, name), name))

    def as_tuple(self) -> tuple[NDArray[np.float64], ...]:
        """(A_y, B_y, C_y, A_theta, B_theta, C_theta): the order the compiled kernel reads."""
        return tuple(getattr(self, name) for name in _FIELDS)

    def evaluate(self, theta: ArrayLike, z: ArrayLike, two_k: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """(Q_y + M g [N], Q_theta [N m]) at bend ``theta`` and height ``z`` above the node [m]; ``two_k`` [1/m]."""
        theta, z = np.asarray(theta, float), np.asarray(z, float)
        c, s = np.cos(two_k * z), np.sin(two_k * z)
        a_y, b_y, c_y, a_t, b_t, c_t = (cheb.chebval(theta, x) for x in self.as_tuple())
        return a_y + b_y * c + c_y * s, a_t + b_t * c + c_t * s


@runtime_checkable
class ForceModel(Protocol):
    """What the equations of motion (:mod:`acousim.dynamics.equations`) need from a force model.

    Attributes
    ----------
    z_eq : float
        Equilibrium height Z_eq [m] of the theta = 0 dimer (below the node, < 0); y is Z_com - Z_eq.
    mass : float
        Total mass M [kg].
    gravity : float
        g [m/s^2].
    wavenumber : float
        k [1/m].
    two_k : float
        2k [1/m], the argument scale of the height structure.
    inertia_const, inertia_sin2 : float
        ``I(theta) = inertia_const + inertia_sin2 sin^2(pi theta / 4)`` [kg m^2] (docs/conventions.md section 4).
    pressure_amplitude_pa : float
        p0 [Pa] the forces belong to.
    settings : dict
        The model's settings (side, material, mesh or solver parameters) for bookkeeping.
    """

    z_eq: float
    mass: float
    gravity: float
    wavenumber: float
    two_k: float
    inertia_const: float
    inertia_sin2: float
    pressure_amplitude_pa: float
    settings: dict

    def generalized_forces(self, theta: ArrayLike, y: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """(Q_y [N] including -M g, Q_theta [N m]) at (theta, y)."""
        ...

    def force_coefficients(self) -> ForceCoefficients:
        """The height structure of Q_y + M g and Q_theta as Chebyshev series in theta."""
        ...

    def hinge_inertia(self, theta: ArrayLike) -> NDArray[np.float64]:
        """I(theta) [kg m^2]."""
        ...

    def hinge_inertia_derivative(self, theta: ArrayLike) -> NDArray[np.float64]:
        """dI/dtheta [kg m^2]."""
        ...

    def with_pressure(self, pressure_amplitude_pa: float) -> "ForceModel":
        """The model at another pressure amplitude [Pa] (forces scale as p0^2; Z_eq moves)."""
        ...

    def linear_frequencies(self) -> tuple[float, float]:
        """Small-oscillation frequencies (f_y, f_theta) [Hz] about (theta, y) = (0, 0)."""
        ...

    def escape_height(self) -> float:
        """y [m] of the barrier below the equilibrium (theta = 0) below which the dimer falls out."""
        ...

    def provenance(self) -> dict:
        """How the model was built (its build record and validity range), for truth.json."""
        ...


class SinusoidalInertia:
    """Methods of a force model whose inertia is ``I(theta) = inertia_const + inertia_sin2 sin^2(pi theta / 4)``
    (docs/conventions.md section 4) and whose ``generalized_forces`` give (Q_y, Q_theta): the hinge inertia, its
    derivative and the static accelerations, written once for every such model (a base of the surrogates)."""

    inertia_const: float
    inertia_sin2: float
    mass: float

    def hinge_inertia(self, theta: ArrayLike) -> NDArray[np.float64]:
        """I(theta) [kg m^2]."""
        return self.inertia_const + self.inertia_sin2 * np.sin(np.pi * np.asarray(theta, float) / 4) ** 2

    def hinge_inertia_derivative(self, theta: ArrayLike) -> NDArray[np.float64]:
        """dI/dtheta [kg m^2]."""
        return self.inertia_sin2 * (np.pi / 4) * np.sin(np.pi * np.asarray(theta, float) / 2)

    def accelerations(self, theta: ArrayLike, y: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Static accelerations (Q_y / M [m/s^2], Q_theta / I [1/s^2]) at zero velocity."""
        q_y, q_t = self.generalized_forces(theta, y)
        return q_y / self.mass, q_t / self.hinge_inertia(theta)


@dataclass(frozen=True, kw_only=True)
class ChebyshevSurrogate(SinusoidalInertia):
    """Base of the frozen-dataclass surrogates whose coefficient functions are Chebyshev series in theta and whose
    forces scale exactly as p0^2: the Gor'kov :class:`acousim.gorkov.energy_surrogate.ForceSurrogate` and the full-wave
    :class:`acousim.fullwave.table.FullwaveSurrogate`.  It holds the fields they share (keyword-only, after each
    surrogate's own coefficients); the change of pressure (:meth:`with_pressure`) and the escape height
    (:meth:`escape_height`) are written here once; a surrogate gives its vertical force at theta = 0
    (:meth:`_theta0_vertical_force`) and the fields its coefficients scale (:meth:`_scaled_fields`).

    Attributes
    ----------
    two_k, wavenumber : float
        2k and k [1/m] (k is used by ``pair_scattering``).
    z_eq : float
        Equilibrium height Z_eq [m] of the theta = 0 dimer, where its vertical force equals M g (below the node, < 0).
    mass : float
        Total mass M [kg].
    gravity : float
        g [m/s^2].
    inertia_const, inertia_sin2 : float
        ``I(theta) = inertia_const + inertia_sin2 sin^2(phi)`` [kg m^2], phi = pi theta / 4.
    pressure_amplitude_pa : float
        p0 [Pa] the forces belong to.
    settings : dict
        The model's settings (geometry, material, mesh, medium, build) for bookkeeping.
    build_accuracy : dict
        The build's record (errors against the direct model, timings, degrees of freedom).
    """

    two_k: float
    wavenumber: float
    z_eq: float
    mass: float
    gravity: float
    inertia_const: float
    inertia_sin2: float
    pressure_amplitude_pa: float
    settings: dict = field(default_factory=dict, compare=False, hash=False)
    build_accuracy: dict = field(default_factory=dict, compare=False, hash=False)

    def _theta0_vertical_force(self, scale: float = 1.0) -> Callable[[float], float]:
        """F_Z(theta = 0, Z) [N] as a function of the absolute height Z [m], for the coefficients times ``scale``."""
        raise NotImplementedError

    def _scaled_fields(self, scale: float) -> dict:
        """The dataclass fields that hold the forces' coefficients, times ``scale`` (for :func:`dataclasses.replace`)."""
        raise NotImplementedError

    def with_pressure(self, pressure_amplitude_pa: float):
        """The surrogate at another pressure amplitude p [Pa].

        Every force scales exactly as p0^2 (E_ac = p0^2 / (4 rho0 c0^2)), so the coefficients are multiplied by
        (p / p0)^2 and the new equilibrium height is solved for (:func:`levitation_height`; y is then measured from
        the new Z_eq).  Exact, no new solve or sweep.
        """
        p = float(pressure_amplitude_pa)
        if not np.isfinite(p) or p <= 0:
            raise ValueError(f"pressure amplitude must be positive and finite, got {pressure_amplitude_pa!r} Pa")
        r = (p / self.pressure_amplitude_pa) ** 2
        z_eq = levitation_height(self._theta0_vertical_force(r), self.mass * self.gravity, self.two_k)
        settings = dict(self.settings, pressure_amplitude_pa=p, equilibrium_height_m=z_eq)
        return replace(self, **self._scaled_fields(r), pressure_amplitude_pa=p, z_eq=z_eq, settings=settings)

    def escape_height(self) -> float:
        """y [m] of the barrier below the equilibrium at theta = 0: below it the dimer falls out
        (:func:`escape_height_below`)."""
        return escape_height_below(self._theta0_vertical_force(), self.mass * self.gravity, self.two_k, self.z_eq)


def levitation_height(force_z: Callable[[float], float], weight: float, two_k: float) -> float:
    """Z_eq [m]: the height in (-lambda/8, 0) below the pressure node where the vertical acoustic force at
    theta = 0 equals the weight (the one root-finding of every force model).

    Parameters
    ----------
    force_z : callable
        Vertical acoustic force [N] at theta = 0 and absolute height Z [m].
    weight : float
        M g [N].
    two_k : float
        2k [1/m] of the standing wave (lambda/8 = pi / (2 two_k)).

    Raises
    ------
    ValueError
        The force at -lambda/8 is below the weight: the field cannot levitate the dimer.
    """
    f = lambda z: force_z(z) - weight  # noqa: E731
    lo = -np.pi / (2 * two_k)
    if f(lo) < 0:
        raise ValueError("the field cannot levitate the dimer at this pressure amplitude")
    return float(brentq(f, lo, 0.0, xtol=1e-15, rtol=1e-14))


def escape_height_below(force_z: Callable[[float], float], weight: float, two_k: float, z_eq: float) -> float:
    """y [m] (from ``z_eq``) of the potential barrier below the equilibrium at theta = 0: below it the dimer falls out.

    The upward net force ``force_z - weight`` is positive from Z_eq down past the force maximum near -lambda/8;
    the barrier is its next zero, within the half period [-3 lambda/8, -lambda/8] where sin(2kZ) is monotonic.
    Returns -inf when there is no sign change there (no barrier within the model's reach).
    """
    f = lambda z: force_z(z) - weight  # noqa: E731
    quarter = np.pi / two_k  # lambda / 4
    lo, hi = -1.5 * quarter, -0.5 * quarter
    if f(lo) * f(hi) >= 0:
        return float("-inf")
    return float(brentq(f, lo, hi, xtol=1e-15)) - z_eq
