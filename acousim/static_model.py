"""What every static model gives: the :class:`StaticModel` protocol and its values, :class:`StaticForces`.

A static model (the Gor'kov :class:`acousim.GorkovDimer`, the full-wave :class:`acousim.fullwave.statics.FullwaveDimer`)
evaluates the forces at zero velocity at absolute heights above the pressure node; the static sweep
(:mod:`acousim.statics.sweep`) and the diagnosis take any of them, and the registry (:mod:`acousim.models`) builds
them by name.
"""
from __future__ import annotations

from typing import NamedTuple, Protocol, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["StaticModel", "StaticForces"]


class StaticForces(NamedTuple):
    """A static model's values at zero velocity (arrays broadcast over the inputs).

    Attributes
    ----------
    potential : acoustic potential energy U_ac [J]
    force_z : vertical acoustic force F_Z [N]
    q_y : generalised force F_Z - M g [N]
    q_theta : generalised force -dU_ac/dtheta at fixed y [N m]
    yddot : Q_y / M [m/s^2]
    thetaddot : Q_theta / I(theta) [1/s^2]
    """

    potential: NDArray[np.float64]
    force_z: NDArray[np.float64]
    q_y: NDArray[np.float64]
    q_theta: NDArray[np.float64]
    yddot: NDArray[np.float64]
    thetaddot: NDArray[np.float64]


@runtime_checkable
class StaticModel(Protocol):
    """What the static sweep and the diagnosis need from a force model at absolute heights.

    Attributes
    ----------
    name : str
        The registry name (``"gorkov"``, ``"fullwave"``).
    conservative : bool
        Whether the forces derive from a potential (energy balances then use it; otherwise ``potential`` is a
        path potential whose theta-derivative is exactly -Q_theta, and energy balances add the work along the path
        of the vertical force's remainder F_Z + dU/dZ; a sweep leaves its potential column empty).
    equilibrium_height : float
        Z_eq [m] (< 0) of the theta = 0 dimer.
    dimer
        Mass and hinge inertia: ``total_mass`` [kg] and ``hinge_inertia(theta)`` [kg m^2].
    wave
        The standing wave (pressure amplitude, medium, material).
    gravity : float
        g [m/s^2].
    """

    name: str
    conservative: bool
    gravity: float

    @property
    def equilibrium_height(self) -> float: ...

    def orientation_sums(self, theta: ArrayLike) -> tuple: ...

    def integrals_at_height(self, theta: ArrayLike, z_com: ArrayLike, orientation_sums: tuple | None = None): ...

    def with_pressure(self, pressure_amplitude_pa: float) -> "StaticModel": ...

    def interpolated(self) -> "StaticModel": ...

    def record(self) -> dict:
        """The model's settings (geometry, medium, mesh or table, pressure) for files and reports."""
        ...
