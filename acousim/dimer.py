"""Geometry and inertia of the hinged cube dimer (docs/conventions.md sections 2 and 4).

Conventions (lab frame: Z up, X horizontal in the image, Y along the hinge, camera looking along +Y):

* ``phi = pi theta / 4``.  Cube B (X > 0) is the "diamond" (face diagonals horizontal and vertical)
  rotated by phi about its own centre, clockwise as the camera sees it; cube A is its mirror image
  in X = 0.  In the (X, Z) plane cube B's body axes are turned counter-clockwise by
  ``psi_B = pi/4 - phi`` from the lab axes and cube A's by ``psi_A = -(pi/4 - phi)`` (mirrored).
* Equal cubes: centres at X = +-d cos(phi), both at Z_com; hinge at Z_com + d sin(phi),
  d = s / sqrt(2).
* Unequal cubes (side_a != side_b, an extension): the hinge is the shared edge, each cube still
  turns by +-phi, the centres are at X = -d_A cos(phi), +d_B cos(phi) and
  Z_i = Z_hinge - d_i sin(phi); Z_com is the mass-weighted centre.  The horizontal centre of mass
  is put at X = 0.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from cubedimer.meta import DEFAULT_SIDE_LENGTH_M

from .medium import ParticleMaterial

__all__ = ["CubeDimer", "bend_angle"]


def bend_angle(theta: ArrayLike) -> NDArray[np.float64]:
    """phi = pi theta / 4 [rad], each cube's rotation from the diamond pose."""
    return np.pi * np.asarray(theta, dtype=float) / 4.0


@dataclass(frozen=True)
class CubeDimer:
    """Two cubes hinged along a shared edge.

    Parameters
    ----------
    side_a : float
        Side of cube A (X < 0) [m]; default 500 um.
    side_b : float, optional
        Side of cube B (X > 0) [m]; defaults to ``side_a``.
    material : ParticleMaterial
        Cube material (density enters the masses).
    """

    side_a: float = DEFAULT_SIDE_LENGTH_M
    side_b: float | None = None
    material: ParticleMaterial = field(default_factory=ParticleMaterial)

    def __post_init__(self) -> None:
        for name in ("side_a", "side_b"):
            v = getattr(self, name)
            if v is None:
                continue
            if not np.isfinite(v) or v <= 0:
                raise ValueError(f"cube side {name} must be positive, got {v!r} m")
        if self.side_b is None:
            object.__setattr__(self, "side_b", float(self.side_a))

    # ------------------------------------------------------------------ masses and lengths
    @property
    def sides(self) -> tuple[float, float]:
        """(s_A, s_B) [m]."""
        return float(self.side_a), float(self.side_b)

    @property
    def is_symmetric(self) -> bool:
        """True when both cubes are equal (the docs/conventions.md dimer)."""
        return self.side_a == self.side_b

    @property
    def cube_masses(self) -> tuple[float, float]:
        """(m_A, m_B) = rho_p s^3 [kg]."""
        rho = self.material.density_kg_m3
        return rho * self.side_a**3, rho * self.side_b**3

    @property
    def total_mass(self) -> float:
        """M = m_A + m_B [kg]."""
        return float(sum(self.cube_masses))

    @property
    def volume(self) -> float:
        """Total particle volume [m^3]."""
        return float(self.side_a**3 + self.side_b**3)

    @property
    def hinge_distances(self) -> tuple[float, float]:
        """(d_A, d_B) = s / sqrt(2): centre-to-hinge-edge distances [m]."""
        return self.side_a / np.sqrt(2.0), self.side_b / np.sqrt(2.0)

    @property
    def _dbar(self) -> float:
        (ma, mb), (da, db) = self.cube_masses, self.hinge_distances
        return (ma * da + mb * db) / (ma + mb)

    # ------------------------------------------------------------------ poses
    def cube_rotations(self, theta: ArrayLike) -> NDArray[np.float64]:
        """Orthogonal matrices (..., 2, 3, 3) mapping body to lab offsets for cubes A, B.

        Cube A's matrix is the mirror (X -> -X) of cube B's, so its determinant is -1; this is
        harmless for a cube (itself mirror symmetric) and keeps mesh quadrature errors mirror
        symmetric between the two cubes.
        """
        phi = bend_angle(theta)
        psi = np.pi / 4 - phi
        c, s = np.cos(psi), np.sin(psi)
        zero, one = np.zeros_like(c), np.ones_like(c)
        rb = np.stack(
            [np.stack([c, zero, -s], -1), np.stack([zero, one, zero], -1), np.stack([s, zero, c], -1)], -2
        )
        mirror = np.diag([-1.0, 1.0, 1.0])
        ra = mirror @ rb
        return np.stack([ra, rb], axis=-3)

    def centre_offsets(self, theta: ArrayLike) -> NDArray[np.float64]:
        """Cube centres relative to the centre of mass, (..., 2, 3) [m] for cubes A, B."""
        phi = bend_angle(theta)
        (ma, mb), (da, db) = self.cube_masses, self.hinge_distances
        dbar = self._dbar
        x_com = (mb * db - ma * da) / (ma + mb) * np.cos(phi)
        xa = -da * np.cos(phi) - x_com
        xb = db * np.cos(phi) - x_com
        za = (dbar - da) * np.sin(phi)
        zb = (dbar - db) * np.sin(phi)
        zero = np.zeros_like(phi)
        return np.stack([np.stack([xa, zero, za], -1), np.stack([xb, zero, zb], -1)], -2)

    def centre_height_derivatives(self, theta: ArrayLike) -> NDArray[np.float64]:
        """d Z_i / d phi at fixed Z_com for cubes A, B, (..., 2) [m/rad] (zero for equal cubes)."""
        phi = bend_angle(theta)
        (da, db), dbar = self.hinge_distances, self._dbar
        return np.stack([(dbar - da) * np.cos(phi), (dbar - db) * np.cos(phi)], -1)

    def hinge_height(self, theta: ArrayLike, z_com: ArrayLike) -> NDArray[np.float64]:
        """Height of the hinge edge [m]: Z_com + d sin(phi) for equal cubes."""
        return np.asarray(z_com, dtype=float) + self._dbar * np.sin(bend_angle(theta))

    # ------------------------------------------------------------------ inertia
    def hinge_inertia(self, theta: ArrayLike) -> NDArray[np.float64]:
        """Inertia I(theta) of the bending coordinate [kg m^2] (theta is dimensionless).

        For equal cubes ``I = (pi/4)^2 2 m s^2 (sin^2(phi)/2 + 1/6)`` (docs/conventions.md section 4): each
        cube's rotation about its centre (m s^2 / 6) plus the horizontal motion of the centres.
        """
        phi = bend_angle(theta)
        (ma, mb), (sa, sb) = self.cube_masses, self.sides
        (da, db), dbar = self.hinge_distances, self._dbar
        xcom = (mb * db - ma * da) / (ma + mb)
        # d/dphi of the centre offsets relative to the centre of mass
        dxa, dxb = (da + xcom) * np.sin(phi), (-db + xcom) * np.sin(phi)
        dza, dzb = (dbar - da) * np.cos(phi), (dbar - db) * np.cos(phi)
        i_phi = ma * sa**2 / 6 + mb * sb**2 / 6 + ma * (dxa**2 + dza**2) + mb * (dxb**2 + dzb**2)
        return (np.pi / 4) ** 2 * i_phi

    def hinge_inertia_derivative(self, theta: ArrayLike) -> NDArray[np.float64]:
        """dI/dtheta [kg m^2]; ``(pi/4)^3 m s^2 sin(2 phi)`` for equal cubes."""
        phi = bend_angle(theta)
        (ma, mb) = self.cube_masses
        (da, db), dbar = self.hinge_distances, self._dbar
        xcom = (mb * db - ma * da) / (ma + mb)
        # I_phi = const + sin^2(phi) * A + cos^2(phi) * B
        a = ma * (da + xcom) ** 2 + mb * (db - xcom) ** 2
        b = ma * (dbar - da) ** 2 + mb * (dbar - db) ** 2
        di_dphi = (a - b) * np.sin(2 * phi)
        return (np.pi / 4) ** 3 * di_dphi
