"""Gor'kov force, torque and generalised forces on the meshed cube dimer (docs/conventions.md sections 3-4).

Every quantity is a volume integral over the tetrahedra of the two posed cube meshes, evaluated
with a tetrahedral quadrature rule (:mod:`acousim.gorkov.quadrature`).  Quadrature nodes are computed
once in each cube's body frame; posing is a rigid transform of those nodes (never a re-mesh).

Fast path.  The potential density depends on the lab height only, ``u(Z) = A0 - A2 cos(2kZ)``,
and a node of cube i sits at ``Z = Z_i + zeta_q(theta)`` where ``zeta_q`` depends on the bend only.
Hence for every integrand the quadrature sum factorises exactly::

    sum_q w_q cos(2k(Z_i + zeta_q)) = Re[ exp(2ik Z_i) * C_i(theta) ],  C_i = sum_q w_q exp(2ik zeta_q)

so an (N_theta x N_y) sweep costs N_theta x N_nodes complex exponentials plus N_theta x N_y
products, instead of N_theta x N_y x N_nodes.  This is the same sum in another order, not an
approximation; :meth:`GorkovDimer.direct_integrals` evaluates it node by node for checking.
"""
from __future__ import annotations

import hashlib
import threading
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import brentq

from ..dimer import CubeDimer, bend_angle
from ..field import StandingWave, gorkov_potential_density, gorkov_potential_gradient
from ..medium import GRAVITY
from ..static_model import StaticForces
from .mesh import grid_arrays, tetrahedralize_cube
from .quadrature import tetrahedral_quadrature

__all__ = [
    "GorkovDimer",
    "DEFAULT_MESH_FRACTION",
    "DEFAULT_QUADRATURE_DEGREE",
    "acoustic_potential_energy",
    "acoustic_force",
    "acoustic_torque",
]

#: The model's registry name (:mod:`acousim.models`), for modules that name it.
GORKOV = "gorkov"
#: Default target tetrahedron edge length as a fraction of the cube side (see docs in README).
DEFAULT_MESH_FRACTION = 0.2
#: Default quadrature degree per tetrahedron.
DEFAULT_QUADRATURE_DEGREE = 2
#: Chebyshev interpolants of the orientation sums by what they depend on (GorkovDimer._interpolant_key): a
#: diagnosis, a sweep or a study that builds the same model again reuses them (1.5 s each at the default mesh).
_INTERPOLANTS: dict = {}
_INTERPOLANTS_KEPT = 8
_INTERPOLANTS_LOCK = threading.Lock()  # threaded executors (dask workers) share the cache


@dataclass(frozen=True)
class _CubeNodes:
    nodes: NDArray[np.float64]  # body-frame quadrature nodes (n, 3) [m]
    weights: NDArray[np.float64]  # (n,) [m^3]
    n_tetrahedra: int


def acoustic_potential_energy(nodes: ArrayLike, weights: ArrayLike, wave: StandingWave) -> float:
    """U_ac = integral of u dV [J] from quadrature nodes (n, 3) [m] (lab frame) and weights (n,) [m^3]."""
    nodes, weights = np.asarray(nodes, float), np.asarray(weights, float)
    return float(weights @ gorkov_potential_density(nodes[:, 2], wave))


def acoustic_force(nodes: ArrayLike, weights: ArrayLike, wave: StandingWave) -> NDArray[np.float64]:
    """F = -integral of grad u dV [N], a 3-vector (only the Z component is non-zero)."""
    nodes, weights = np.asarray(nodes, float), np.asarray(weights, float)
    return np.array([0.0, 0.0, -float(weights @ gorkov_potential_gradient(nodes[:, 2], wave))])


def acoustic_torque(nodes: ArrayLike, weights: ArrayLike, wave: StandingWave, about: ArrayLike) -> NDArray[np.float64]:
    """T = integral of (r - P) x (-grad u) dV [N m] about the lab point ``about`` (3,) [m]."""
    nodes, weights = np.asarray(nodes, float), np.asarray(weights, float)
    force = np.zeros_like(nodes)
    force[:, 2] = -gorkov_potential_gradient(nodes[:, 2], wave) * weights
    return np.cross(nodes - np.asarray(about, float), force).sum(axis=0)


def _symmetrize_nodes(x: NDArray[np.float64], w: NDArray[np.float64]) -> tuple[NDArray, NDArray]:
    """Images of the nodes under the 16 cube symmetries fixing the body Y axis, weights / 16."""
    images = []
    for swap in (False, True):
        xs = x[:, [2, 1, 0]] if swap else x
        for sx in (1.0, -1.0):
            for sy in (1.0, -1.0):
                for sz in (1.0, -1.0):
                    images.append(xs * np.array([sx, sy, sz]))
    return np.concatenate(images), np.tile(w, len(images)) / len(images)


def _chebyshev_sums(t: NDArray[np.float64], coefs: tuple[NDArray, ...]) -> tuple[NDArray, ...]:
    """The interpolated orientation sums at bends ``t`` (|t| <= 1 rad), each of shape ``t.shape + (2,)``: the
    Chebyshev Vandermonde ``T_k(t) = cos(k arccos t)`` times the coefficients, one matrix product per sum."""
    vander = np.cos(np.arccos(t.ravel())[:, None] * np.arange(coefs[0].shape[0])[None, :])
    return tuple((vander @ c).reshape(t.shape + (2,)) for c in coefs)


class GorkovDimer:
    """The Gor'kov volume-integral model of a hinged cube dimer in a standing wave.

    Parameters
    ----------
    dimer : CubeDimer
        Geometry and material.
    wave : StandingWave
        Field (pressure amplitude, medium).  Its material must be the dimer's.
    mesh_size : float, optional
        Target tetrahedron edge length [m]; default ``DEFAULT_MESH_FRACTION`` x the smaller side.
    quadrature_degree : int
        Polynomial degree integrated exactly on each tetrahedron (>= 2 recommended).
    mesh_dir : path, optional
        Mesh cache folder.
    gravity : float
        g [m/s^2].
    symmetrize : bool
        Average the quadrature over the 16 symmetries of the cube that keep its hinge-parallel
        axis (the 8 coordinate reflections, with and without swapping the two in-plane body
        axes); each maps the cube onto itself.  An unstructured mesh has none of these
        symmetries, so without this the symmetry-forbidden parts of the result (Q_theta at
        theta = 0, the theta-odd part of F_Z) are O(mesh error) instead of round-off.
        Costs 16x the nodes; the orientation sums stay cheap.

    Examples
    --------
    >>> model = GorkovDimer(CubeDimer(500e-6), StandingWave(3000.0))      # doctest: +SKIP
    >>> model.static_forces(theta=0.2, y=0.0).q_theta                      # doctest: +SKIP
    """

    #: registry name (:mod:`acousim.models`)
    name = GORKOV
    #: the forces derive from the acoustic potential U_ac
    conservative = True
    #: the model covers every bend |theta| < 1
    theta_max = 1.0

    def __init__(
        self,
        dimer: CubeDimer | None = None,
        wave: StandingWave | None = None,
        mesh_size: float | None = None,
        quadrature_degree: int = DEFAULT_QUADRATURE_DEGREE,
        mesh_dir: Path | str | None = None,
        gravity: float = GRAVITY,
        symmetrize: bool = True,
    ) -> None:
        self.dimer = dimer if dimer is not None else CubeDimer()
        self.wave = wave if wave is not None else StandingWave(material=self.dimer.material)
        if self.wave.material != self.dimer.material:
            raise ValueError("the wave's particle material must be the dimer's material")
        self.mesh_size = float(mesh_size) if mesh_size is not None else DEFAULT_MESH_FRACTION * min(self.dimer.sides)
        self.quadrature_degree = int(quadrature_degree)
        self.gravity = float(gravity)
        self.symmetrize = bool(symmetrize)
        self._mesh_dir = mesh_dir
        meshes = {}
        nodes = []
        for side in self.dimer.sides:
            if side not in meshes:
                grid = tetrahedralize_cube(side, self.mesh_size, mesh_dir=mesh_dir)
                pts, cells = grid_arrays(grid)
                x, w = tetrahedral_quadrature(pts, cells, self.quadrature_degree)
                if symmetrize:
                    x, w = _symmetrize_nodes(x, w)
                meshes[side] = (grid, _CubeNodes(x, w, len(cells)))
            nodes.append(meshes[side][1])
        self._grids = tuple(meshes[s][0] for s in self.dimer.sides)
        self._nodes = tuple(nodes)
        self._total_weights = np.array([n.weights.sum() for n in self._nodes])

    # ------------------------------------------------------------------ bookkeeping
    def with_pressure(self, pressure_amplitude_pa: float) -> "GorkovDimer":
        """A copy at another pressure amplitude sharing the meshes (cheap)."""
        new = object.__new__(GorkovDimer)
        new.__dict__.update({k: v for k, v in self.__dict__.items() if k not in ("equilibrium_height",)})
        new.wave = self.wave.with_pressure(pressure_amplitude_pa)
        return new

    def record(self) -> dict:
        """The settings that determine the model's numbers (written into sweep CSV headers and JSON files)."""
        d, w = self.dimer, self.wave
        return {
            "model": self.name,
            "side_a_m": d.side_a,
            "side_b_m": d.side_b,
            "particle_density_kg_m3": d.material.density_kg_m3,
            "bulk_modulus_pa": d.material.bulk_modulus_pa,
            "pressure_amplitude_pa": w.pressure_amplitude_pa,
            "frequency_hz": w.medium.frequency_hz,
            "sound_speed_m_s": w.medium.sound_speed_m_s,
            "air_density_kg_m3": w.medium.density_kg_m3,
            "mesh_size_m": self.mesh_size,
            "quadrature_degree": self.quadrature_degree,
            "n_tetrahedra": self.n_tetrahedra,
            "equilibrium_height_m": self.equilibrium_height,
            "gravity_m_s2": self.gravity,
        }

    @property
    def cube_meshes(self) -> tuple:
        """The two cube meshes (pyvista UnstructuredGrid, body frame) for cubes A and B."""
        return self._grids

    @property
    def n_tetrahedra(self) -> int:
        """Total number of tetrahedra in the dimer."""
        return int(sum(n.n_tetrahedra for n in self._nodes))

    @property
    def n_quadrature_nodes(self) -> int:
        """Total number of quadrature nodes in the dimer."""
        return int(sum(len(n.weights) for n in self._nodes))

    # ------------------------------------------------------------------ orientation sums
    def interpolated(self, n_theta: int = 64) -> "GorkovDimer":
        """A copy whose orientation sums are Chebyshev interpolants in theta over [-1, 1].

        The sums C(theta), D(theta), E(theta) are analytic in theta, so ``n_theta`` Chebyshev nodes
        reproduce them to round-off (checked in the tests); the dependence on height and pressure
        stays exact.  Use it to evaluate the model at many distinct bends (e.g. every frame of a
        data set): the cost per evaluation no longer scales with the number of quadrature nodes.
        """
        from numpy.polynomial import chebyshev as cheb

        key = self._interpolant_key(n_theta)
        coefs = _INTERPOLANTS.get(key)
        if coefs is None:
            nodes = np.cos(np.pi * (np.arange(n_theta) + 0.5) / n_theta)
            sums = self._exact_orientation_sums(nodes)
            coefs = tuple(cheb.chebfit(nodes, s.reshape(n_theta, -1), n_theta - 1) for s in sums)
            for c in coefs:
                c.flags.writeable = False
            with _INTERPOLANTS_LOCK:
                _INTERPOLANTS[key] = coefs
                while len(_INTERPOLANTS) > _INTERPOLANTS_KEPT:
                    _INTERPOLANTS.pop(next(iter(_INTERPOLANTS)))
        new = object.__new__(GorkovDimer)
        new.__dict__.update(self.__dict__)
        new.__dict__.pop("equilibrium_height", None)
        new._interpolant = coefs
        return new

    def _interpolant_key(self, n_theta: int) -> tuple:
        """What the orientation sums depend on: the dimer (its hinge geometry), 2k and the quadrature nodes and
        weights themselves (by digest), so that equal models built anew share one interpolant."""
        digest = hashlib.blake2b(digest_size=16)
        for cube in self._nodes:
            digest.update(np.ascontiguousarray(cube.nodes, dtype=float).tobytes())
            digest.update(np.ascontiguousarray(cube.weights, dtype=float).tobytes())
        return (self.dimer, float(2.0 * self.wave.wavenumber), int(n_theta), digest.hexdigest())

    def _orientation_sums(self, theta: NDArray[np.float64]) -> tuple[NDArray, NDArray, NDArray]:
        coefs = self.__dict__.get("_interpolant")
        if coefs is None:
            return self._exact_orientation_sums(theta)
        t = np.asarray(theta, float)
        beyond = np.abs(t) > 1
        if np.any(beyond):  # the interpolant covers |theta| <= 1 rad; a wider bend takes the exact sums there
            sums = tuple(np.empty(t.shape + (2,), complex) for _ in coefs)
            for whole, part in zip(sums, self._exact_orientation_sums(t[beyond])):
                whole[beyond] = part
            for whole, part in zip(sums, _chebyshev_sums(t[~beyond], coefs)):
                whole[~beyond] = part
            return sums
        return _chebyshev_sums(t, coefs)

    def _exact_orientation_sums(self, theta: NDArray[np.float64]) -> tuple[NDArray, NDArray, NDArray]:
        """Per cube, the complex sums C = sum w e^{2ik zeta}, D = sum w dx e^{2ik zeta}, E = sum w dy e^{2ik zeta}.

        Shapes (theta.size, 2).  dx, dy are lab-frame node offsets from the cube centre.
        """
        k2 = 2.0 * self.wave.wavenumber
        rot = self.dimer.cube_rotations(theta.ravel())  # (n, 2, 3, 3)
        out_c = np.empty((theta.size, 2), complex)
        out_d = np.empty_like(out_c)
        out_e = np.empty_like(out_c)
        for i, cube in enumerate(self._nodes):
            if i == 1 and cube is self._nodes[0]:
                # cube A is the mirror (X -> -X) of cube B with the same nodes: zeta is
                # unchanged and dx flips sign, so reuse cube A's sums.
                out_c[:, 1], out_d[:, 1], out_e[:, 1] = out_c[:, 0], -out_d[:, 0], out_e[:, 0]
                continue
            r = rot[:, i]
            x = cube.nodes
            w = cube.weights
            zeta = r[:, 2, 0:1] * x[None, :, 0] + r[:, 2, 2:3] * x[None, :, 2]
            dx = r[:, 0, 0:1] * x[None, :, 0] + r[:, 0, 2:3] * x[None, :, 2]
            phase = np.exp(1j * k2 * zeta) * w[None, :]
            out_c[:, i] = phase.sum(axis=1)
            out_d[:, i] = np.einsum("tq,tq->t", phase, dx)
            out_e[:, i] = phase @ x[:, 1]
        shape = theta.shape + (2,)
        return out_c.reshape(shape), out_d.reshape(shape), out_e.reshape(shape)

    def orientation_sums(self, theta: ArrayLike) -> tuple[NDArray, NDArray]:
        """The bend-only factors (C, D) of every integral, shape theta.shape + (2,) (cubes A, B).

        ``C = sum_q w_q exp(2ik zeta_q)`` [m^3] and ``D = sum_q w_q dx_q exp(2ik zeta_q)`` [m^4]; pass them
        to :meth:`integrals_at_height` to evaluate many heights at fixed bends without recomputing.
        """
        theta = np.asarray(theta, float)
        c, d, _ = self._orientation_sums(theta) if "_interpolant" in self.__dict__ else self._unique_sums(theta)
        return c, d

    def _unique_sums(self, theta: NDArray):
        uniq, inv = np.unique(theta, return_inverse=True)
        c, d, e = self._orientation_sums(uniq)
        inv = inv.reshape(theta.shape)
        return c[inv], d[inv], e[inv]

    def _cube_integrals(self, theta: NDArray, z_com: NDArray, sums: tuple | None = None):
        """Potential, vertical force and Y-torque about its centre for each cube, (..., 2) arrays."""
        theta, z_com = np.broadcast_arrays(np.asarray(theta, float), np.asarray(z_com, float))
        if sums is not None:
            c, d = (np.broadcast_to(x, theta.shape + (2,)) for x in sums)
        elif "_interpolant" in self.__dict__:
            c, d, _ = self._orientation_sums(theta)
        else:
            # evaluate the (expensive) exact orientation sums once per distinct theta value
            uniq, inv = np.unique(theta, return_inverse=True)
            c, d, _ = self._orientation_sums(uniq)
            c, d = c[inv.reshape(theta.shape)], d[inv.reshape(theta.shape)]
        z_i = z_com[..., None] + self.dimer.centre_offsets(theta)[..., 2]
        a0, a2 = self.wave.harmonic_coefficients
        k2 = 2.0 * self.wave.wavenumber
        ph = np.exp(1j * k2 * z_i)
        w_tot = self._total_weights
        potential = a0 * w_tot - a2 * np.real(ph * c)
        # du/dZ = k2 * a2 * sin(k2 Z)
        force_z = -k2 * a2 * np.imag(ph * c)
        torque_y = k2 * a2 * np.imag(ph * d)
        return potential, force_z, torque_y

    # ------------------------------------------------------------------ public physics
    def integrals_at_height(self, theta: ArrayLike, z_com: ArrayLike, orientation_sums: tuple | None = None) -> StaticForces:
        """Static forces at lab height ``z_com`` of the centre of mass (metres above the node).

        ``orientation_sums`` (from :meth:`orientation_sums` for the same ``theta``) skips their
        evaluation.
        """
        theta = np.asarray(theta, float)
        z_com = np.asarray(z_com, float)
        pot, fz, ty = self._cube_integrals(theta, z_com, orientation_sums)
        theta_b = np.broadcast_to(theta, pot.shape[:-1])
        q_theta = self._bend_generalized_force(ty, fz, theta_b)
        m = self.dimer.total_mass
        force_z = fz.sum(-1)
        q_y = force_z - m * self.gravity
        return StaticForces(
            potential=pot.sum(-1),
            force_z=force_z,
            q_y=q_y,
            q_theta=q_theta,
            yddot=q_y / m,
            thetaddot=q_theta / self.dimer.hinge_inertia(theta_b),
        )

    def static_forces(self, theta: ArrayLike, y: ArrayLike) -> StaticForces:
        """Static forces at bend ``theta`` and height ``y`` [m] above the equilibrium height Z_eq."""
        return self.integrals_at_height(theta, np.asarray(y, float) + self.equilibrium_height)

    def generalized_forces(self, theta: ArrayLike, y: ArrayLike) -> tuple[NDArray, NDArray]:
        """(Q_y [N], Q_theta [N m]) at zero velocity."""
        s = self.static_forces(theta, y)
        return s.q_y, s.q_theta

    def torque(self, theta: float, y: float, about: ArrayLike) -> NDArray[np.float64]:
        """Total acoustic torque vector [N m] on the dimer about the lab point ``about`` (3,) [m].

        Lab coordinates: origin on the hinge-line axis through the centre of mass, horizontally,
        and at the pressure node vertically.
        """
        nodes, weights = self.posed_nodes(theta, y)
        return acoustic_torque(nodes, weights, self.wave, about)

    def _posed_cube_nodes(self, theta: float, y: float) -> list[tuple[NDArray, NDArray, NDArray]]:
        """Per cube: lab-frame nodes (n, 3) [m], weights (n,) [m^3] and the cube centre (3,) [m]."""
        z_com = float(y) + self.equilibrium_height
        rot = self.dimer.cube_rotations(float(theta))
        off = self.dimer.centre_offsets(float(theta))
        out = []
        for i, cube in enumerate(self._nodes):
            centre = off[i] + np.array([0.0, 0.0, z_com])
            out.append((cube.nodes @ rot[i].T + centre, cube.weights, centre))
        return out

    def posed_nodes(self, theta: float, y: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Lab-frame quadrature nodes (n, 3) [m] and weights (n,) [m^3] of the posed dimer."""
        parts = self._posed_cube_nodes(theta, y)
        return np.concatenate([p[0] for p in parts]), np.concatenate([p[1] for p in parts])

    def _bend_generalized_force(self, torque_y: NDArray, force_z: NDArray, theta: ArrayLike) -> NDArray:
        """Q_theta from each cube's Y torque about its centre and vertical force, (..., 2) arrays.

        Cube B turns about +Y and cube A about -Y as phi grows; for unequal cubes the centres also
        move vertically at fixed Z_com (zero for equal cubes).
        """
        dz = self.dimer.centre_height_derivatives(theta)
        return (np.pi / 4) * (torque_y[..., 1] - torque_y[..., 0] + force_z[..., 0] * dz[..., 0] + force_z[..., 1] * dz[..., 1])

    def direct_integrals(self, theta: float, y: float) -> tuple[float, float, float]:
        """(U_ac [J], F_Z [N], Q_theta [N m]) summed node by node on the posed mesh (slow reference path).

        Uses the generic :func:`acoustic_potential_energy`, :func:`acoustic_force` and
        :func:`acoustic_torque` on each posed cube, not the factorised sums.
        """
        parts = self._posed_cube_nodes(theta, y)
        potential = sum(acoustic_potential_energy(x, w, self.wave) for x, w, _ in parts)
        fz = np.array([acoustic_force(x, w, self.wave)[2] for x, w, _ in parts])
        ty = np.array([acoustic_torque(x, w, self.wave, c)[1] for x, w, c in parts])
        return float(potential), float(fz.sum()), float(self._bend_generalized_force(ty, fz, float(theta)))

    @cached_property
    def equilibrium_height(self) -> float:
        """Z_eq [m] (< 0): where the vertical force on the theta = 0 dimer balances gravity.

        Raises
        ------
        ValueError
            If the field cannot hold the dimer's weight at any height.
        """
        weight = self.dimer.total_mass * self.gravity
        lam4 = np.pi / (2.0 * self.wave.wavenumber)  # quarter wavelength
        flat = self.orientation_sums(0.0)  # the bend's sums, once: the root search varies the height only

        def net(z: float) -> float:
            return float(self.integrals_at_height(0.0, z, flat).force_z) - weight

        # the restoring force grows from 0 at the node to its maximum at -lambda/8
        z_max = -lam4 / 2.0
        if net(z_max) < 0:
            raise ValueError(
                f"pressure amplitude {self.wave.pressure_amplitude_pa:g} Pa cannot levitate this dimer: "
                f"maximum acoustic force {net(z_max) + weight:.3g} N < weight {weight:.3g} N"
            )
        return float(brentq(net, z_max, 0.0, xtol=1e-15, rtol=1e-13))
