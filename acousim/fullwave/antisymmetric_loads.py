"""The antisymmetric loads of the full-wave dimer: its sideways force and rocking torque, and their stiffness.

The suite's equations of motion keep the mirror-symmetric coordinates (y, theta).  The two antisymmetric rigid
motions in the camera's plane are left out:

* **sideways**: the whole dimer translated along X by ``x`` [m];
* **rocking**: the whole dimer turned about the Y axis (the hinge line's direction, the camera's axis) through its
  centre of mass by ``psi`` [rad], positive in the right-handed sense about +Y (``(X, Z) -> (X cos psi + Z sin psi,
  -X sin psi + Z cos psi)``: cube B, at X > 0, goes down for psi > 0).

Their generalised forces are the total force ``Q_x = F_X`` [N] and the total torque about the centre of mass
``Q_psi = tau_Y`` [N m] on both cubes; gravity adds nothing to either (it acts at the centre of mass, whose height
neither motion changes).  Both vanish on the mirror-symmetric dimer (x = psi = 0) and are odd in (x, psi): the dimer
posed at -psi is the exact mirror image in X = 0 of the dimer at +psi (the meshes of
:func:`~acousim.fullwave.geometry.dimer_bodies` are mirror symmetric), so a central difference needs one solve::

    K_psipsi = -dQ_psi/dpsi = -Q_psi(delta) / delta,   K_xpsi = -dQ_x/dpsi = -Q_x(delta) / delta.

The incident plane standing wave ``p0 sin(kZ)`` does not depend on X, and the boundary integral equation does not
depend on where the bodies sit, so a translation along X changes nothing: ``K_xx = K_psix = 0`` exactly (the
surface pressure of a translated dimer is the same to rounding, :func:`rocked_dimer_bodies`).  The linearised
antisymmetric loads are therefore::

    Q_x   = -K_xpsi(theta, Z) psi,      Q_psi = -K_psipsi(theta, Z) psi.

A conservative (Gor'kov-like) force would give a symmetric stiffness matrix, here K_xpsi = K_psix = 0; the measured
K_xpsi says how far the full-wave loads are from that.

Each solve gives the loads at every height (:class:`~acousim.fullwave.solver.HeightStructure`): the stiffnesses are
``A + B cos 2kZ + C sin 2kZ`` in the lab height ``Z = Z_com`` of the centre of mass.  The loads are integrated as
the momentum flux through a sphere around the whole dimer (:func:`~acousim.fullwave.flux.enclosing_sphere_surface`;
accurate at the cubes' sharp edges), and by the surface tractions as a check.

Parity in theta.  Mirroring a posed dimer in Z (about the node, where ``sin kZ`` is odd and the time-averaged loads
even in p) maps (theta, psi, Z) to (-theta, -psi, -Z), F_X to F_X and tau_Y to -tau_Y, so
``K_psipsi(-theta, -Z) = K_psipsi(theta, Z)`` (A, B even in theta, C odd) and ``K_xpsi(-theta, -Z) =
-K_xpsi(theta, Z)`` (A, B odd, C even).  :class:`RockingStiffness` fills the negative bends by these relations.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .flux import ExteriorField, enclosing_sphere_surface, flux_height_structure
from .geometry import DimerMeshSpec, dimer_bodies
from .solver import Body, ScatteringSolution

__all__ = ["rocking_rotation", "rocked_dimer_bodies", "total_loads", "pose_stiffness", "RockingStiffness"]


def rocking_rotation(psi: float) -> NDArray[np.float64]:
    """The rotation matrix (3, 3) by ``psi`` [rad] about +Y (right-handed)."""
    c, s = np.cos(psi), np.sin(psi)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def rocked_dimer_bodies(theta: float, psi: float = 0.0, x: float = 0.0, spec: DimerMeshSpec | None = None) -> list[Body]:
    """The dimer of :func:`~acousim.fullwave.geometry.dimer_bodies` at bend ``theta``, turned by ``psi`` [rad] about
    +Y through its centre of mass and moved by ``x`` [m] along X; coordinates relative to the unmoved centre of
    mass (z' = 0 is the lab height Z_com).  Each body's ``centre`` (its cube centre) moves with it."""
    bodies = dimer_bodies(theta) if spec is None else dimer_bodies(theta, spec)
    rot = rocking_rotation(psi)
    shift = np.array([float(x), 0.0, 0.0])
    return [Body(b.vertices @ rot.T + shift, b.faces, rot @ b.centre + shift) for b in bodies]


def total_loads(solution: ScatteringSolution, pressure_amplitude_pa: float, centre: ArrayLike = (0.0, 0.0, 0.0),
                method: str = "flux", n_polar: int = 24) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """(A, B, C) of the total force [N] and of the total torque about ``centre`` [N m] on all bodies.

    Parameters
    ----------
    solution : ScatteringSolution
    pressure_amplitude_pa : float
        p0 [Pa].
    centre : array_like (3,)
        The torque's reference point [m] in the solution's local coordinates (the centre of mass).
    method : {"flux", "surface"}
        The momentum flux through a sphere of 1.6 times the farthest vertex's distance from ``centre`` (Y-folded:
        F_X, F_Z and tau_Y only, valid for a field mirror symmetric in Y = 0), or the surface tractions.
    n_polar : int
        Gauss points in the sphere's polar angle (flux only).

    Returns
    -------
    force, torque : ndarray (3, 3)
        Rows A, B, C (``A + B cos 2kZ + C sin 2kZ``), columns X, Y, Z.
    """
    c = np.asarray(centre, float).reshape(3)
    if method == "flux":
        med = solution.medium
        radius = 1.6 * float(np.max(np.linalg.norm(solution.vertices - c, axis=1)))
        surface = enclosing_sphere_surface(radius, n_polar)
        surface = type(surface)(surface.points + c, surface.normals, surface.weights, surface.y_folded)
        return flux_height_structure(ExteriorField(solution), surface, c, med.density_kg_m3, med.sound_speed_m_s,
                                     2 * np.pi * med.frequency_hz, pressure_amplitude_pa)
    if method != "surface":
        raise ValueError(f"method must be 'flux' or 'surface', got {method!r}")
    hs = solution.height_structure(pressure_amplitude_pa)
    lever = hs.centres - c
    force = np.array([f.sum(0) for f in (hs.force_a, hs.force_b, hs.force_c)])
    torque = np.array([(t + np.cross(lever, f)).sum(0)
                       for t, f in ((hs.torque_a, hs.force_a), (hs.torque_b, hs.force_b), (hs.torque_c, hs.force_c))])
    return force, torque


def pose_stiffness(force: ArrayLike, torque: ArrayLike, step: float) -> dict[str, NDArray[np.float64]]:
    """(A, B, C) of ``K_psipsi`` [N m/rad], ``K_xpsi`` [N/rad] and of the symmetric ``F_Z`` [N] from the total loads
    of one solve at psi = ``step`` [rad] (the central difference of the module docstring; F_Z is even in psi, so
    it equals the symmetric dimer's to O(step^2))."""
    f, t = np.asarray(force, float), np.asarray(torque, float)
    if not step > 0:
        raise ValueError(f"the rocking step must be positive, got {step!r}")
    return {"k_psipsi": -t[:, 1] / step, "k_xpsi": -f[:, 0] / step, "fz": f[:, 2].copy()}


@dataclass(frozen=True)
class RockingStiffness:
    """The rocking stiffnesses over the bend and the height, from poses at bends theta >= 0.

    Parameters
    ----------
    theta : ndarray (n,)
        The measured bends, all >= 0, increasing [-].
    k_psipsi, k_xpsi : ndarray (n, 3)
        (A, B, C) of K_psipsi [N m/rad] and K_xpsi [N/rad] at each bend.
    two_k : float
        2k [1/m].
    pressure_amplitude_pa : float
        p0 [Pa] of the coefficients (they scale as p0^2).
    degree : int
        Degree of the least-squares polynomial in theta through the measured bends and their mirror images.

    Notes
    -----
    The negative bends are filled by the parity of the module docstring; each coefficient is then fitted by a
    polynomial of ``degree`` in theta over [-theta_n, theta_n] (with an exactly even or odd basis for each).
    """

    theta: NDArray[np.float64]
    k_psipsi: NDArray[np.float64]
    k_xpsi: NDArray[np.float64]
    two_k: float
    pressure_amplitude_pa: float
    degree: int = 4

    def __post_init__(self) -> None:
        th = np.asarray(self.theta, float)
        if th.ndim != 1 or th.size < 2 or np.any(th < 0) or np.any(np.diff(th) <= 0):
            raise ValueError("the rocking poses need at least two increasing bends theta >= 0")
        for name in ("k_psipsi", "k_xpsi"):
            v = np.asarray(getattr(self, name), float)
            if v.shape != (th.size, 3):
                raise ValueError(f"{name} must have shape ({th.size}, 3), got {v.shape}")
            object.__setattr__(self, name, v)
        object.__setattr__(self, "theta", th)

    @property
    def theta_max(self) -> float:
        """The largest measured |theta|; beyond it the fit is extrapolated."""
        return float(self.theta[-1])

    def _fit(self, values: NDArray, even: bool) -> NDArray[np.float64]:
        """Monomial coefficients (lowest first) of the parity-constrained least-squares fit of one coefficient."""
        powers = [p for p in range(self.degree + 1) if (p % 2 == 0) == even]
        basis = np.stack([self.theta**p for p in powers], 1)
        sol, *_ = np.linalg.lstsq(basis, values, rcond=None)
        out = np.zeros(self.degree + 1)
        out[powers] = sol
        return out

    def polynomials(self) -> dict[str, NDArray[np.float64]]:
        """``{"k_psipsi": (3, degree + 1), "k_xpsi": (3, degree + 1)}``: monomial coefficients in theta (lowest
        first) of A, B and C."""
        parity = {"k_psipsi": (True, True, False), "k_xpsi": (False, False, True)}
        return {name: np.stack([self._fit(getattr(self, name)[:, j], even) for j, even in enumerate(par)])
                for name, par in parity.items()}

    def at(self, theta: ArrayLike, z: ArrayLike, pressure_amplitude_pa: float | None = None) -> tuple[NDArray, NDArray]:
        """(K_psipsi [N m/rad], K_xpsi [N/rad]) at bend ``theta`` and lab height ``z`` [m] of the centre of mass."""
        th, zz = np.asarray(theta, float), np.asarray(z, float)
        scale = 1.0 if pressure_amplitude_pa is None else (float(pressure_amplitude_pa) / self.pressure_amplitude_pa) ** 2
        c, s = np.cos(self.two_k * zz), np.sin(self.two_k * zz)
        out = []
        for coef in self.polynomials().values():
            a, b, cc = (np.polynomial.polynomial.polyval(th, coef[j]) for j in range(3))
            out.append(scale * (a + b * c + cc * s))
        return out[0], out[1]

