"""The full-wave dimer as a static simulation model at absolute heights: the counterpart of :class:`acousim.GorkovDimer`.

The sim-to-real diagnosis evaluates its simulation model at the measured states of every frame, at lab
heights ``Z = z0 + y`` of a calibrated origin ``z0`` and at a calibrated pressure.  :class:`FullwaveDimer`
gives the full-wave surrogate (:class:`~acousim.fullwave.force_surrogate.FullwaveSurrogate`) the members the
diagnosis reads from :class:`~acousim.gorkov.forces.GorkovDimer`: :meth:`~FullwaveDimer.integrals_at_height`,
:meth:`~FullwaveDimer.orientation_sums`, :attr:`~FullwaveDimer.equilibrium_height`,
:meth:`~FullwaveDimer.with_pressure`, ``dimer`` (mass and hinge inertia), ``wave`` and ``gravity``.

Potential.  The full-wave forces need not derive from a potential (``conservative = False``).  Where a
diagnosis needs an acoustic energy (the oscillation energy that normalises the energy balance), it uses
the *path potential*: the work against the forces from (theta, Z) = (0, 0) up to (0, Z) and then
across to (theta, Z)::

    U(theta, Z) = C_F(0) cos(2kZ) / (2k) - int_0^theta Q_theta(theta', Z) dtheta'

(A_F and B_F vanish at theta = 0 by the bend parity).  It is the potential when the forces have one.
The torque is its exact theta-derivative, Q_theta = -dU/dtheta, so only the vertical force can differ from
-dU/dZ; the diagnosis's energy balance takes U at the states plus the work of that remainder along the measured
path (:class:`validation.diagnosis.prepare.simulation_terms.SimulationTerms`).
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
from numpy.polynomial import chebyshev as cheb
from numpy.typing import ArrayLike, NDArray
from cubedimer.meta import DEFAULT_PARTICLE_DENSITY, DEFAULT_PRESSURE_AMPLITUDE_PA

from ..field import StandingWave
from ..force_model import SinusoidalInertia
from ..static_model import StaticForces
from ..medium import ParticleMaterial
from .force_surrogate import FullwaveSurrogate, default_fullwave_surrogate

__all__ = ["FullwaveDimer", "FullwaveInertia", "default_fullwave_dimer", "TableMismatch"]


class TableMismatch(ValueError):
    """The experiment differs from what the full-wave table was built for (side, frequency, bend range...)."""


@dataclass(frozen=True)
class FullwaveInertia(SinusoidalInertia):
    """Mass and hinge inertia of the full-wave table's dimer (hinge arm d + g/2; docs/conventions.md section 4).

    Attributes
    ----------
    inertia_const, inertia_sin2 : float
        ``I(theta) = inertia_const + inertia_sin2 sin^2(pi theta / 4)`` [kg m^2].
    mass : float
        Total mass M [kg].
    """

    inertia_const: float
    inertia_sin2: float
    mass: float

    @property
    def total_mass(self) -> float:
        """M [kg] (the name :class:`acousim.CubeDimer` uses)."""
        return self.mass


#: The full-wave model's name in the force-model registry (:mod:`acousim.models`).
MODEL_NAME = "fullwave"


class FullwaveDimer:
    """The full-wave surrogate evaluated at absolute heights above the node (see the module docstring).

    Parameters
    ----------
    surrogate : FullwaveSurrogate
        The table at the nominal pressure of the experiment.
    """

    #: registry name (:mod:`acousim.models`)
    name = MODEL_NAME
    #: the forces need not derive from a potential: energy balances use the work along the path
    conservative = False

    def __init__(self, surrogate: FullwaveSurrogate):
        self.surrogate = surrogate
        st = surrogate.settings
        material = ParticleMaterial(density_kg_m3=float(st.get("particle_density_kg_m3", DEFAULT_PARTICLE_DENSITY)))
        self.wave = StandingWave(surrogate.pressure_amplitude_pa, surrogate.medium, material)
        self.gravity = float(surrogate.gravity)
        self.dimer = FullwaveInertia(surrogate.inertia_const, surrogate.inertia_sin2, surrogate.mass)
        tm = surrogate.theta_max
        # the bend-only factors: (A, B, C) of F_Z and Q_theta, and the theta-integral of Q_theta's (A, B, C)
        self._series = [tuple(np.asarray(c, float) for c in surrogate.coefficients[k]) for k in ("fz", "qt")]
        self._series.append(tuple(cheb.chebint(np.asarray(c, float), lbnd=0.0) * tm
                                  for c in surrogate.coefficients["qt"]))

    @property
    def settings(self) -> dict:
        """The table's settings (geometry, mesh, medium, pressure)."""
        return dict(self.surrogate.settings)

    def record(self) -> dict:
        """The table's settings (geometry, mesh or family, medium, pressure, accuracy source) and Z_eq."""
        return {"model": self.name, **self.surrogate.settings, "equilibrium_height_m": self.surrogate.z_eq}

    @property
    def theta_max(self) -> float:
        """Half-width of the bend range the table covers."""
        return float(self.surrogate.theta_max)

    @cached_property
    def equilibrium_height(self) -> float:
        """Z_eq [m] (< 0) of the theta = 0 dimer at this pressure."""
        return float(self.surrogate.z_eq)

    def with_pressure(self, pressure_amplitude_pa: float) -> "FullwaveDimer":
        """The model at another pressure amplitude [Pa] (forces scale exactly as p0^2)."""
        return FullwaveDimer(self.surrogate.with_pressure(pressure_amplitude_pa))

    def interpolated(self) -> "FullwaveDimer":
        """Itself: the table is already a series in theta (the Gor'kov model's fast variant has this name)."""
        return self

    def as_force_model(self) -> FullwaveSurrogate:
        """The :class:`~acousim.force_model.ForceModel` for the equations of motion (the surrogate itself)."""
        return self.surrogate

    def orientation_sums(self, theta: ArrayLike) -> tuple[NDArray[np.float64], ...]:
        """The bend-only factors at ``theta``: (A, B, C) of F_Z [N], of Q_theta [N m] and of the path
        potential's theta-integral [J], each of shape ``theta.shape + (3,)``.

        Raises
        ------
        TableMismatch
            When some |theta| exceeds the table's range.
        """
        th = np.asarray(theta, float)
        if th.size and float(np.max(np.abs(th))) > self.theta_max:
            raise TableMismatch(f"the bend reaches |theta| = {float(np.max(np.abs(th))):.3g}, beyond the full-wave "
                                f"table's range |theta| <= {self.theta_max:g}")
        t = th / self.theta_max
        return tuple(np.stack([cheb.chebval(t, c) for c in series], -1) for series in self._series)

    def integrals_at_height(self, theta: ArrayLike, z_com: ArrayLike, orientation_sums: tuple | None = None) -> StaticForces:
        """Static forces at bend ``theta`` and lab height ``z_com`` of the centre of mass [m above the node].

        ``potential`` is the path potential of the module docstring [J]; ``orientation_sums`` (from
        :meth:`orientation_sums` for the same ``theta``) skips the series evaluation.
        """
        theta = np.asarray(theta, float)
        z = np.asarray(z_com, float)
        fz_abc, qt_abc, iq_abc = orientation_sums if orientation_sums is not None else self.orientation_sums(theta)
        two_k = self.surrogate.two_k
        c, s = np.cos(two_k * z), np.sin(two_k * z)

        def at(abc: NDArray) -> NDArray:
            return abc[..., 0] + abc[..., 1] * c + abc[..., 2] * s

        force_z, q_theta = at(fz_abc), at(qt_abc)
        c_f0 = float(cheb.chebval(0.0, self._series[0][2]))
        potential = c_f0 * c / two_k - at(iq_abc)
        m = self.dimer.total_mass
        q_y = force_z - m * self.gravity
        theta_b = np.broadcast_to(theta, np.shape(force_z))
        return StaticForces(potential=potential, force_z=force_z, q_y=q_y, q_theta=q_theta, yddot=q_y / m,
                            thetaddot=q_theta / self.dimer.hinge_inertia(theta_b))


def default_fullwave_dimer(pressure_amplitude_pa: float = DEFAULT_PRESSURE_AMPLITUDE_PA) -> FullwaveDimer:
    """The shipped default dimer's table (:func:`default_fullwave_surrogate`) as a static model at p0 [Pa]."""
    return FullwaveDimer(default_fullwave_surrogate(pressure_amplitude_pa))
