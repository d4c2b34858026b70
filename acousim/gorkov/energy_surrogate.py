"""A smooth, energy-consistent surrogate of the Gor'kov generalised forces (docs/conventions.md sections 3-4).

Evaluating the mesh integral at every right-hand-side call of the equations of motion is far too
slow, so the dynamics use a surrogate built from **one static sweep** of the mesh model
(:func:`acousim.statics.sweep.static_sweep`).

Structure.  The Gor'kov density is ``u(Z) = A0 - A2 cos(2kZ)`` and every quadrature node of a cube
sits at ``Z = Z_com + (offset depending on theta only)``, so for any mesh the acoustic potential
energy is *exactly* of the form::

    U_ac(theta, Z) = alpha(theta) + beta(theta) cos(2kZ) + gamma(theta) sin(2kZ),   Z = Z_eq + y

with coefficient functions that are analytic in theta (sums of complex exponentials of
trigonometric functions of phi = pi theta / 4).  The surrogate:

1. sweeps the mesh model on ``n_theta`` Chebyshev points of the first kind in (-1, 1) times an
   ``n_y`` grid in y;
2. at each theta, fits (alpha, beta, gamma) to the swept potential by least squares on the basis
   ``[1, cos 2kZ, sin 2kZ]`` (the residual, reported as ``separable_residual``, is round-off: the
   form is exact, not an approximation);
3. interpolates the three coefficient functions in theta with Chebyshev series.

The total potential is ``V = U_ac + M g Z`` (gravity; referred to its value at the equilibrium) and
the generalised forces are its *analytic* derivatives,
``Q_y = -dV/dy = -dU_ac/dZ - M g`` and ``Q_theta = -dV/dtheta``, so the surrogate forces are exactly
the gradient of the surrogate potential and the continuous dynamics conserve T + V exactly.

Accuracy is measured against the direct model (:meth:`ForceSurrogate.accuracy`) and recorded at
build time against the swept ``q_y`` and ``q_theta`` columns (which the fit never sees): typically
1e-10 of max|Q| over the box, far inside the required 0.5 %.

Mirror symmetry.  For equal cubes U_ac is even in theta; the symmetrised quadrature of
:class:`~acousim.gorkov.forces.GorkovDimer` makes the swept potential even to round-off, and the surrogate
then keeps only the even Chebyshev terms so that theta = 0 is an exactly invariant set.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass
from functools import lru_cache

import numpy as np
from numpy.polynomial import chebyshev as cheb
from numpy.typing import ArrayLike, NDArray

from cubedimer.meta import DEFAULT_PRESSURE_AMPLITUDE_PA, DEFAULT_SIDE_LENGTH_M

from ..dimer import CubeDimer
from ..field import StandingWave
from ..force_model import ChebyshevSurrogate, ForceCoefficients
from .forces import GorkovDimer
from ..medium import GRAVITY

__all__ = [
    "SurrogateBox",
    "ForceSurrogate",
    "build_surrogate",
    "cached_surrogate",
    "DEFAULT_BOX",
]


@dataclass(frozen=True)
class SurrogateBox:
    """The (theta, y) box a surrogate is swept and checked on.

    Parameters
    ----------
    theta_max : float
        Accuracy is stated for |theta| <= theta_max (dimensionless); the Chebyshev interpolant
        itself covers the whole of [-1, 1].
    y_min, y_max : float
        Height range [m] above the equilibrium height.  The default, [-1.0, +0.8] mm, spans the
        trap from just above the escape height (~ -1.02 mm at the defaults: below it the
        dimer falls out) to well above the pressure node (+0.43 mm).
    n_theta : int
        Chebyshev points of the sweep in theta.
    n_y : int
        Grid points of the sweep in y.
    """

    theta_max: float = 0.95
    y_min: float = -1.0e-3
    y_max: float = 0.8e-3
    n_theta: int = 40
    n_y: int = 41

    def __post_init__(self) -> None:
        if not 0 < self.theta_max < 1:
            raise ValueError(f"theta_max must lie in (0, 1), got {self.theta_max!r}")
        if not self.y_min < self.y_max:
            raise ValueError(f"need y_min < y_max, got [{self.y_min!r}, {self.y_max!r}] m")
        if self.n_theta < 8 or self.n_y < 4:
            raise ValueError("the sweep needs n_theta >= 8 and n_y >= 4")


#: The box of the default surrogate.
DEFAULT_BOX = SurrogateBox()


def _as_tuple(a: ArrayLike) -> tuple[float, ...]:
    return tuple(float(v) for v in np.asarray(a, float).ravel())


@dataclass(frozen=True)
class ForceSurrogate(ChebyshevSurrogate):
    """Chebyshev-in-theta x harmonic-in-Z representation of the Gor'kov potential and forces.

    Build with :func:`build_surrogate`; all arrays are small and the object is picklable (it is
    sent to worker processes as is).

    Attributes
    ----------
    alpha, beta, gamma : tuple of float
        Chebyshev coefficients (argument theta on [-1, 1]) of the coefficient functions of
        ``U_ac = alpha + beta cos(2kZ) + gamma sin(2kZ)`` [J].
    box : SurrogateBox
    two_k, wavenumber, z_eq, mass, gravity, inertia_const, inertia_sin2, pressure_amplitude_pa, settings, build_accuracy
        The fields every surrogate has (:class:`acousim.force_model.ChebyshevSurrogate`); ``settings`` are the mesh
        model's (side, material, mesh size, ...), ``build_accuracy`` the errors at build time (module docstring).
    """

    alpha: tuple[float, ...]
    beta: tuple[float, ...]
    gamma: tuple[float, ...]
    box: SurrogateBox = DEFAULT_BOX

    # ------------------------------------------------------------------ coefficient arrays
    def coefficient_arrays(self) -> tuple[NDArray, NDArray, NDArray, NDArray, NDArray, NDArray]:
        """(alpha, beta, gamma, alpha', beta', gamma') Chebyshev coefficient arrays [J], padded to one length."""
        a, b, g = (np.asarray(c, float) for c in (self.alpha, self.beta, self.gamma))
        n = max(a.size, b.size, g.size)
        pad = lambda c: np.pad(c, (0, n - c.size))
        da, db, dg = (pad(cheb.chebder(c)) if c.size > 1 else np.zeros(n) for c in (a, b, g))
        return pad(a), pad(b), pad(g), da, db, dg

    def force_coefficients(self) -> ForceCoefficients:
        """The :class:`~acousim.force_model.ForceModel` height structure of the forces.

        ``Q_y + M g = -dU_ac/dZ = 2k (beta sin 2kZ - gamma cos 2kZ)``, so A_y = 0, B_y = -2k gamma,
        C_y = 2k beta [N]; ``Q_theta = -dU_ac/dtheta``, so (A, B, C)_theta = -(alpha', beta', gamma') [N m].
        """
        _, b, g, da, db, dg = self.coefficient_arrays()
        return ForceCoefficients(q_y_a=np.zeros(1), q_y_b=-self.two_k * g, q_y_c=self.two_k * b,
                                 q_theta_a=-da, q_theta_b=-db, q_theta_c=-dg)

    # ------------------------------------------------------------------ physics
    def acoustic_potential(self, theta: ArrayLike, y: ArrayLike) -> NDArray[np.float64]:
        """U_ac(theta, y) [J] (gravity excluded, absolute Gor'kov value)."""
        theta, z = np.asarray(theta, float), np.asarray(y, float) + self.z_eq
        a, b, g = (cheb.chebval(theta, np.asarray(c)) for c in (self.alpha, self.beta, self.gamma))
        return a + b * np.cos(self.two_k * z) + g * np.sin(self.two_k * z)

    @property
    def potential_offset(self) -> float:
        """V_0 = U_ac + M g Z at the equilibrium (theta = 0, y = 0) [J]; :meth:`potential` subtracts it."""
        return float(self.acoustic_potential(0.0, 0.0) + self.mass * self.gravity * self.z_eq)

    def potential(self, theta: ArrayLike, y: ArrayLike) -> NDArray[np.float64]:
        """Total potential V = U_ac + M g Z_com - V_0 [J], zero at the equilibrium."""
        z = np.asarray(y, float) + self.z_eq
        return self.acoustic_potential(theta, y) + self.mass * self.gravity * z - self.potential_offset

    def generalized_forces(self, theta: ArrayLike, y: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """(Q_y [N], Q_theta [N m]) = (-dV/dy, -dV/dtheta), the analytic derivatives of the surrogate."""
        theta, z = np.asarray(theta, float), np.asarray(y, float) + self.z_eq
        _, b, g, da, db, dg = self.coefficient_arrays()
        bv, gv = cheb.chebval(theta, b), cheb.chebval(theta, g)
        c, s = np.cos(self.two_k * z), np.sin(self.two_k * z)
        q_y = self.two_k * (bv * s - gv * c) - self.mass * self.gravity
        q_theta = -(cheb.chebval(theta, da) + cheb.chebval(theta, db) * c + cheb.chebval(theta, dg) * s)
        return q_y, q_theta

    def _theta0_vertical_force(self, scale: float = 1.0):
        """The theta = 0 acoustic force two_k (b0 sin 2kZ - g0 cos 2kZ) [N] as a function of the height Z [m], with
        b0, g0 the values of beta and gamma at theta = 0 times ``scale``."""
        b0 = scale * float(cheb.chebval(0.0, np.asarray(self.beta)))
        g0 = scale * float(cheb.chebval(0.0, np.asarray(self.gamma)))
        two_k = self.two_k
        return lambda z: two_k * (b0 * np.sin(two_k * z) - g0 * np.cos(two_k * z))

    def _scaled_fields(self, scale: float) -> dict:
        return dict(alpha=tuple(scale * np.asarray(self.alpha)), beta=tuple(scale * np.asarray(self.beta)),
                    gamma=tuple(scale * np.asarray(self.gamma)), build_accuracy=dict(self.build_accuracy))

    # ------------------------------------------------------------------ linearisation
    def linear_frequencies(self) -> tuple[float, float]:
        """Small-oscillation frequencies (f_y, f_theta) [Hz] about (theta, y) = (0, 0), from the
        analytic second derivatives of V (NaN for an unstable direction)."""
        _, b, g, _, db, dg = self.coefficient_arrays()
        z = self.z_eq
        c, s = np.cos(self.two_k * z), np.sin(self.two_k * z)
        k_y = -self.two_k**2 * (cheb.chebval(0.0, b) * c + cheb.chebval(0.0, g) * s)
        d2a, d2b, d2g = (cheb.chebder(np.asarray(x), 2) if len(x) > 2 else np.zeros(1) for x in (self.alpha, self.beta, self.gamma))
        k_t = cheb.chebval(0.0, d2a) + cheb.chebval(0.0, d2b) * c + cheb.chebval(0.0, d2g) * s
        w2 = np.array([k_y / self.mass, k_t / self.inertia_const])
        return tuple(float(np.sqrt(v) / (2 * np.pi)) if v > 0 else float("nan") for v in w2)

    def provenance(self) -> dict:
        """The build record (accuracy against the mesh model) and the interpolation box."""
        return {"build_accuracy": self.build_accuracy, "box": asdict(self.box)}

    # ------------------------------------------------------------------ checks
    def accuracy(self, model: GorkovDimer, n_theta: int = 23, n_y: int = 19, seed: int = 0) -> dict:
        """Errors against the direct mesh model on a random (seeded) grid inside the box.

        Returns
        -------
        dict with ``q_y`` and ``q_theta``: max |surrogate - direct| / max |direct| over the grid,
        and ``potential``: max |Delta U_ac| / max |U_ac - U_ac(0, 0)|.
        """
        rng = np.random.default_rng(seed)
        bx = self.box
        th = np.sort(rng.uniform(-bx.theta_max, bx.theta_max, n_theta))
        yy = np.sort(rng.uniform(bx.y_min, bx.y_max, n_y))
        tt, ygrid = np.meshgrid(th, yy, indexing="ij")
        direct = model.integrals_at_height(tt, ygrid + self.z_eq)
        q_y, q_t = self.generalized_forces(tt, ygrid)
        u = self.acoustic_potential(tt, ygrid)
        du = direct.potential - float(model.integrals_at_height(0.0, self.z_eq).potential)
        return {
            "q_y": float(np.max(np.abs(q_y - direct.q_y)) / np.max(np.abs(direct.q_y))),
            "q_theta": float(np.max(np.abs(q_t - direct.q_theta)) / np.max(np.abs(direct.q_theta))),
            "potential": float(np.max(np.abs(u - direct.potential)) / np.max(np.abs(du))),
        }


def build_surrogate(model: GorkovDimer, box: SurrogateBox = DEFAULT_BOX, symmetric: bool | None = None) -> ForceSurrogate:
    """Build the surrogate of ``model`` from one static sweep (see the module docstring).

    Parameters
    ----------
    model : GorkovDimer
        The mesh model (any side, pressure, mesh size).
    box : SurrogateBox
        Sweep grid and the box the accuracy is stated on.
    symmetric : bool, optional
        Keep only the even Chebyshev terms in theta.  Default: when the dimer has equal cubes and
        the swept potential is even in theta to 1e-9 of its theta-variation.

    Returns
    -------
    ForceSurrogate
        With ``build_accuracy`` holding the errors of Q_y and Q_theta against the swept columns
        (relative to their max over the sweep) and the separable-fit residual.
    """
    from ..statics.sweep import static_sweep

    n = box.n_theta
    nodes = np.cos(np.pi * (np.arange(n) + 0.5) / n)[::-1]  # Chebyshev points of the first kind, increasing
    y = np.linspace(box.y_min, box.y_max, box.n_y)
    sw = static_sweep(model, nodes, y)
    z_eq = model.equilibrium_height
    two_k = 2.0 * model.wave.wavenumber
    z = y + z_eq
    basis = np.column_stack([np.ones_like(z), np.cos(two_k * z), np.sin(two_k * z)])
    u = sw["potential"]  # (n_theta, n_y)
    coef, *_ = np.linalg.lstsq(basis, u.T, rcond=None)  # (3, n_theta)
    resid = u - (basis @ coef).T
    separable_residual = float(np.max(np.abs(resid)) / np.max(np.abs(u)))
    series = [cheb.chebfit(nodes, c, n - 1) for c in coef]
    theta_variation = max(np.ptp(c) for c in coef) or 1.0
    odd = max(np.max(np.abs(s[1::2])) for s in series)
    even_part = odd / theta_variation
    if symmetric is None:
        symmetric = model.dimer.is_symmetric and even_part < 1e-9
    if symmetric:
        for s in series:
            s[1::2] = 0.0
    # drop coefficients at the round-off floor of the swept potential (~1e-16 |U|; they are noise,
    # and fewer terms make every right-hand-side call cheaper)
    floor = 1e3 * np.finfo(float).eps * max(np.max(np.abs(s)) for s in series)
    for s in series:
        s[np.abs(s) < floor] = 0.0
    last = max(int(np.max(np.flatnonzero(s), initial=0)) for s in series)
    series = [s[: last + 1] for s in series]
    dimer = model.dimer
    i0 = float(dimer.hinge_inertia(0.0))
    i_sin2 = float(dimer.hinge_inertia(2.0)) - i0  # phi = pi/2: sin^2 = 1
    sur = ForceSurrogate(
        alpha=_as_tuple(series[0]), beta=_as_tuple(series[1]), gamma=_as_tuple(series[2]),
        two_k=two_k, wavenumber=float(model.wave.wavenumber), z_eq=float(z_eq), mass=dimer.total_mass,
        gravity=model.gravity, inertia_const=i0, inertia_sin2=i_sin2,
        pressure_amplitude_pa=float(model.wave.pressure_amplitude_pa), settings=model.record(),
        box=box,
    )
    tt, yy = np.meshgrid(nodes, y, indexing="ij")
    q_y, q_t = sur.generalized_forces(tt, yy)
    acc = {
        "q_y_vs_sweep": float(np.max(np.abs(q_y - sw["q_y"])) / np.max(np.abs(sw["q_y"]))),
        "q_theta_vs_sweep": float(np.max(np.abs(q_t - sw["q_theta"])) / np.max(np.abs(sw["q_theta"]))),
        "separable_residual": separable_residual,
        "odd_part": float(even_part),
        "symmetric": bool(symmetric),
        "chebyshev_terms": int(last + 1),
    }
    object.__setattr__(sur, "build_accuracy", acc)
    return sur


@lru_cache(maxsize=16)
def cached_surrogate(
    side: float = DEFAULT_SIDE_LENGTH_M,
    pressure_amplitude_pa: float = DEFAULT_PRESSURE_AMPLITUDE_PA,
    mesh_size: float | None = None,
    quadrature_degree: int = 2,
    box: SurrogateBox = DEFAULT_BOX,
) -> ForceSurrogate:
    """The surrogate of the default-material dimer of side ``side`` [m] at ``pressure_amplitude_pa``
    [Pa] on a mesh of edge ``mesh_size`` [m] (default: the model's default), cached per arguments
    in this process (meshes are cached on disk by :func:`acousim.gorkov.mesh.tetrahedralize_cube`)."""
    dimer = CubeDimer(side)
    model = GorkovDimer(dimer, StandingWave(pressure_amplitude_pa, material=dimer.material), mesh_size=mesh_size,
                        quadrature_degree=quadrature_degree, gravity=GRAVITY)
    return build_surrogate(model, box)
