"""The air's damping of the levitated dimer, computed from its geometry and the air (docs/damping.md).

No free parameter: given the cube side ``s``, the particle density, the hinge gap ``g``, the air's viscosity
and density and the frequencies of the two modes, the air's drag on the dimer is fixed.  Three mechanisms:

* **vertical** (y): the in-phase drag of a body oscillating at a frequency whose viscous (Stokes) layer
  ``delta = sqrt(2 nu / omega)`` (about 0.45 mm at 20-30 Hz) is as thick as the cube.  The oscillating
  sphere (Stokes 1851; Landau & Lifshitz, *Fluid Mechanics*, section 24) has the in-phase drag
  ``6 pi mu a (1 + a / delta) U``; the dimer takes it with two equivalent radii, the steady (Stokes) one
  for the ``1`` and the wetted-area one for the Stokes-layer term ``a / delta``
  (:func:`oscillating_translation_drag`);
* **hinge, each cube** (theta): each cube turns about its own centre at ``phi_dot = pi thetadot / 4``
  (rotary oscillation of a sphere, the same reference) and its centre moves sideways at
  ``d sin(phi) phi_dot`` (the translation drag above) (:func:`oscillating_rotation_drag`);
* **hinge, squeeze flow in the wedges** (theta): the facing faces of the two cubes close one wedge and open
  the other as theta changes; lubrication theory of the wedge with the gap at the hinge, corrected at wide
  openings by the exact Stokes flow of hinged plates (:func:`wedge_squeeze_torque`).

The twin takes them as the effect ``air_damping`` (:class:`acousim.dynamics.effects.AirDamping`, built by
:func:`air_damping_parameters`): ``yddot += -gamma_y ydot`` and ``thetaddot += -gamma_theta(theta) thetadot``
with ``gamma_theta(theta)`` from :func:`hinge_damping_shape`.  :func:`air_damping_rates` reports the rates.

Pure functions, SI units throughout.  :func:`hinge_damping_shape` is compiled by numba for the equations of
motion and callable from Python on scalars.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numba as nb
import numpy as np
from numpy.typing import ArrayLike, NDArray
from cubedimer.meta import DEFAULT_AIR_DENSITY_KG_M3, DEFAULT_PARTICLE_DENSITY

__all__ = [
    "AIR_DYNAMIC_VISCOSITY_PA_S",
    "CUBE_STOKES_RADIUS",
    "stokes_layer_thickness",
    "oscillating_translation_drag",
    "oscillating_rotation_drag",
    "wedge_squeeze_torque",
    "wedge_gap_factor",
    "stokes_corner_factor",
    "hinge_damping_shape",
    "DimerDragRadii",
    "dimer_drag_radii",
    "AirDampingRates",
    "air_damping_rates",
    "air_damping_parameters",
]

#: Dynamic viscosity of air at 20-25 C [Pa s].
AIR_DYNAMIC_VISCOSITY_PA_S = 1.81e-5
#: Steady Stokes-drag radius of a cube over its side: a cube of side s drags like a sphere of 0.661 s
#: (boundary-integral and capacitance estimates agree within 0.2 %).
CUBE_STOKES_RADIUS = 0.661
_VOLUME_RADIUS = (3.0 / (4.0 * math.pi)) ** (1.0 / 3.0)  # radius of the sphere of volume s^3, over s


def stokes_layer_thickness(kinematic_viscosity: float, frequency_hz: float) -> float:
    """Depth of the oscillating viscous layer ``delta = sqrt(2 nu / omega)`` [m].

    Parameters
    ----------
    kinematic_viscosity : float
        nu = mu / rho_air [m^2/s].
    frequency_hz : float
        Oscillation frequency [Hz] (> 0).
    """
    if frequency_hz <= 0:
        raise ValueError(f"frequency must be positive, got {frequency_hz!r} Hz")
    return math.sqrt(2.0 * kinematic_viscosity / (2.0 * math.pi * frequency_hz))


def oscillating_translation_drag(viscosity: float, stokes_radius: float, area_radius: float, delta: float) -> float:
    """In-phase drag coefficient of a body oscillating along a line: F = -c U, c [kg/s].

    ``c = 6 pi mu (a_S + a_A^2 / delta)``: for a sphere (``a_S = a_A = a``) the exact in-phase part of the
    oscillating-sphere drag, ``6 pi mu a (1 + a / delta)``; the rest of that force (added mass and the Basset
    history term, in quadrature with U) shifts the frequency by rho_air / rho_p ~ 1e-3 and is left out.  For
    another body ``a_S`` is its steady Stokes radius (exact as delta -> infinity) and ``a_A`` the radius of
    the sphere of equal wetted area (the thin-layer drag is mu U / delta times a shape factor times the area).

    Parameters
    ----------
    viscosity : float
        Dynamic viscosity mu [Pa s].
    stokes_radius, area_radius : float
        a_S, a_A [m].
    delta : float
        Stokes-layer depth [m] (``math.inf``: steady Stokes drag).
    """
    return 6.0 * math.pi * viscosity * (stokes_radius + area_radius ** 2 / delta)


def oscillating_rotation_drag(viscosity: float, radius: float, delta: float) -> float:
    """In-phase torque coefficient of a sphere in rotary oscillation about a diameter: M = -c Omega, c [kg m^2/s].

    ``c = (8 pi / 3) mu a^3 (3 + 6x + 6x^2 + 2x^3) / (1 + 2x + 2x^2)``, ``x = a / delta``: the real part of
    the exact solution (Landau & Lifshitz, section 24, problem 5).  It tends to the steady ``8 pi mu a^3``
    as x -> 0 and to the thin-layer ``(8 pi / 3) mu a^4 / delta`` as x -> infinity.

    Parameters
    ----------
    viscosity : float
        Dynamic viscosity mu [Pa s].
    radius : float
        Sphere radius a [m].
    delta : float
        Stokes-layer depth [m] (``math.inf``: steady rotation).
    """
    x = radius / delta
    return (8.0 * math.pi / 3.0) * viscosity * radius ** 3 * (3 + 6 * x + 6 * x * x + 2 * x ** 3) / (1 + 2 * x + 2 * x * x)


@nb.njit(cache=True)
def _gap_moments(lam):
    """(J0, J2, J4) with J_n = integral_0^lam w^n / (1 + w)^3 dw (series below lam = 0.05, where the closed
    forms cancel)."""
    if lam < 0.05:
        l2 = lam * lam
        j0 = lam - 1.5 * l2 + 2.0 * l2 * lam - 2.5 * l2 * l2
        j2 = lam ** 3 / 3.0 - 0.75 * l2 * l2 + 1.2 * l2 * l2 * lam - (10.0 / 6.0) * l2 ** 3
        j4 = lam ** 5 / 5.0 - 0.5 * lam ** 6 + (6.0 / 7.0) * lam ** 7 - 1.25 * lam ** 8
        return j0, j2, j4
    v = 1.0 + lam
    lg = np.log(v)
    j0 = 0.5 * (1.0 - 1.0 / (v * v))
    j2 = lg + 2.0 * (1.0 / v - 1.0) - 0.5 * (1.0 / (v * v) - 1.0)
    j4 = 0.5 * (v * v - 1.0) - 4.0 * lam + 6.0 * lg + 4.0 * (1.0 / v - 1.0) - 0.5 * (1.0 / (v * v) - 1.0)
    return j0, j2, j4


@nb.njit(cache=True)
def wedge_gap_factor(opening_over_gap):
    """The gap's factor on the wedge's squeeze torque: 1 for a closed hinge, ``(8 / 45) lam^3`` for nearly parallel faces.

    ``F(lam) = 2 (J4 - J2^2 / J0) / lam^2`` with ``lam = beta s / h0`` (the wedge's opening at the outer edge
    over the gap at the hinge) and ``J_n`` the moments of :func:`_gap_moments`.  F = 1 - 6 / lam +
    O((ln lam)^2 / lam^2) as lam -> infinity (the squared logarithm is the gap's cut-off of the hinge pressure
    ``-(6 mu beta_dot / beta^3) ln(s beta / h0)``, which diverges for a closed hinge while the torque does not) and
    F -> 8 lam^3 / 45 as lam -> 0 (parallel faces at the gap h0).  Scalar in, scalar out (numba-compatible).
    """
    lam = opening_over_gap
    if lam <= 0.0:
        return 0.0
    j0, j2, j4 = _gap_moments(lam)
    return 2.0 * (j4 - j2 * j2 / j0) / (lam * lam)


@nb.njit(cache=True)
def stokes_corner_factor(opening):
    """Wide-angle factor of the wedge's squeeze pressure: ``beta^3 cos(beta) / (3 (sin beta - beta cos beta))``.

    The hinged-plates corner flow ``psi = r^2 (B sin 2 phi + C phi)`` is an exact Stokes flow for any opening
    beta; its pressure ``2 mu beta_dot cos(beta) / (sin beta - beta cos beta) ln(s / r)`` is the lubrication one
    times this factor (1 as beta -> 0, 0.75 at pi/4, 0 at pi/2).  At openings of pi/2 and more the corner
    carries no squeeze pressure (0 returned) and its drag is part of each cube's own.  Scalar (numba-compatible).
    """
    b = opening
    if b >= 0.5 * math.pi:
        return 0.0
    if b < 1e-3:
        return 1.0 - 0.4 * b * b
    return b ** 3 * np.cos(b) / (3.0 * (np.sin(b) - b * np.cos(b)))


def wedge_squeeze_torque(viscosity: float, side: float, gap: float, opening: float) -> float:
    """Squeeze-flow torque coefficient of one wedge between the cubes' facing faces: T = -c beta_dot, c [kg m^2/s].

    Lubrication (Reynolds) theory of the film between two faces of length ``s`` (radially) and ``s`` (along
    the hinge) at opening ``beta``, turning about the hinge edge, the film's thickness ``h0 + x beta`` from the
    gap ``h0`` at the hinge, open to the air at both ends:
    ``c = (3/2) mu s^3 / beta^3 * F(beta s / h0) * K(beta)`` with :func:`wedge_gap_factor` F and
    :func:`stokes_corner_factor` K.  Closed hinge: ``(3/2) mu s^3 / beta^3``; parallel faces:
    ``(4/15) mu s^6 / h0^3`` (per unit hinge length: ``mu s^2`` times the cube of s over the gap or the opening).

    Parameters
    ----------
    viscosity : float
        mu [Pa s].
    side : float
        Cube side s [m] (face length and hinge length).
    gap : float
        Film thickness at the hinge h0 [m] (> 0).
    opening : float
        Wedge opening beta [rad], in (0, pi).
    """
    if gap <= 0:
        raise ValueError(f"the gap at the hinge must be positive, got {gap!r} m")
    if opening <= 0:
        return (4.0 / 15.0) * viscosity * side ** 6 / gap ** 3
    return 1.5 * viscosity * side ** 3 / opening ** 3 * wedge_gap_factor(opening * side / gap) * stokes_corner_factor(opening)


@nb.njit(cache=True)
def hinge_damping_shape(theta, gap_ratio, sway_ratio, wedge_ratio):
    """theta-dependence of the hinge's air damping: ``gamma_theta(theta) / gamma_theta(0)`` [-].

    ``[1 + sway_ratio sin^2(phi) + wedge_ratio sum over both wedges of w(beta)] / (1 + 3 sin^2 phi)`` with
    ``phi = pi theta / 4``: the cubes' own rotation (1), their centres' sideways motion (``sway_ratio``, the
    translation drag times ``d^2`` over the rotation drag), and the squeeze flow in the two wedges of opening
    ``alpha = pi (1 + theta) / 2`` and ``beta = pi (1 - theta) / 2`` (``w = F K / beta^3`` with the gap at the
    hinge ``h0 = g cos(phi)``), over the hinge inertia ``I(theta) / I(0) = 1 + 3 sin^2 phi``.

    Parameters
    ----------
    theta : float
        Bending angle [-], |theta| < 1.
    gap_ratio : float
        g / s [-] (> 0).
    sway_ratio, wedge_ratio : float
        The sideways-translation and wedge coefficients over the rotation one [-] (:class:`AirDampingRates`).

    Scalar in, scalar out (compiled with numba: the equations of motion call it).
    """
    phi = 0.25 * math.pi * theta
    s2 = np.sin(phi) ** 2
    h0 = gap_ratio * np.cos(phi)
    wedges = 0.0
    if wedge_ratio > 0.0 and h0 > 0.0:  # no wedge term without one (or without a gap to cut it off)
        for opening in (0.5 * math.pi * (1.0 + theta), 0.5 * math.pi * (1.0 - theta)):
            if opening > 0.0:  # |theta| < 1: both wedges are open
                wedges += wedge_gap_factor(opening / h0) * stokes_corner_factor(opening) / opening ** 3
    return (1.0 + sway_ratio * s2 + wedge_ratio * wedges) / (1.0 + 3.0 * s2)


@dataclass(frozen=True)
class DimerDragRadii:
    """Equivalent-sphere radii of the dimer and of one cube [m] (docs/damping.md states the choice).

    Attributes
    ----------
    dimer_stokes, dimer_area : float
        Steady-drag and wetted-area radii of the dimer (vertical motion).
    cube_stokes, cube_area : float
        The same for one cube (its centre's sideways motion in the hinge mode).
    cube_rotation : float
        Radius of the sphere of the cube's volume (rotation of a cube about its centre).
    """

    dimer_stokes: float
    dimer_area: float
    cube_stokes: float
    cube_area: float
    cube_rotation: float


def dimer_drag_radii(side: float) -> DimerDragRadii:
    """Equivalent radii of a dimer of cubes of side ``side`` [m].

    Steady drag: the volume-equivalent radius times the cube's Stokes-to-volume radius ratio
    (0.661 / 0.620 = 1.066; for the dimer this assumes its shape factor is the cube's); wetted area: the sphere
    of the same area (6 s^2 per cube, 12 s^2 for the dimer, the touching edge being a line); rotation: the
    volume-equivalent sphere of one cube.
    """
    shape = CUBE_STOKES_RADIUS / _VOLUME_RADIUS
    return DimerDragRadii(
        dimer_stokes=shape * _VOLUME_RADIUS * 2.0 ** (1.0 / 3.0) * side,
        dimer_area=math.sqrt(12.0 / (4.0 * math.pi)) * side,
        cube_stokes=CUBE_STOKES_RADIUS * side,
        cube_area=math.sqrt(6.0 / (4.0 * math.pi)) * side,
        cube_rotation=_VOLUME_RADIUS * side,
    )


@dataclass(frozen=True)
class AirDampingRates:
    """The air's damping rates of the two modes (what :func:`air_damping_rates` reports).

    Attributes
    ----------
    gamma_y : float
        Vertical rate [1/s]: ``yddot += -gamma_y ydot`` (the energy of y decays at gamma_y).
    gamma_theta : float
        Hinge rate at theta = 0 [1/s] (``thetaddot += -gamma_theta * shape(theta) * thetadot``).
    sway_ratio, wedge_ratio : float
        Coefficients of :func:`hinge_damping_shape` [-].
    gap_ratio : float
        g / s [-].
    delta_y, delta_theta : float
        Stokes-layer depths at the two frequencies [m].
    frequency_y, frequency_theta : float
        The frequencies the rates are evaluated at [Hz].
    """

    gamma_y: float
    gamma_theta: float
    sway_ratio: float
    wedge_ratio: float
    gap_ratio: float
    delta_y: float
    delta_theta: float
    frequency_y: float
    frequency_theta: float

    def hinge_rate(self, theta: ArrayLike) -> NDArray[np.float64]:
        """gamma_theta(theta) [1/s] over any array of bending angles."""
        th = np.asarray(theta, float)
        out = np.array([hinge_damping_shape(float(t), self.gap_ratio, self.sway_ratio, self.wedge_ratio)
                        for t in th.ravel()]).reshape(th.shape)
        return self.gamma_theta * out


def air_damping_rates(side: float, gap: float, frequency_y: float, frequency_theta: float,
                      particle_density: float = DEFAULT_PARTICLE_DENSITY, air_density: float = DEFAULT_AIR_DENSITY_KG_M3,
                      viscosity: float = AIR_DYNAMIC_VISCOSITY_PA_S) -> AirDampingRates:
    """The air's damping of a dimer, per mode, from its geometry and the air (no free parameter).

    Parameters
    ----------
    side : float
        Cube side s [m].
    gap : float
        Hinge gap g [m] (> 0; the full-wave model's, 0.01 s by default there).
    frequency_y, frequency_theta : float
        Frequencies of the vertical and hinge motion [Hz]: each mode's drag is evaluated at its own (the
        Stokes layer depends on it).
    particle_density, air_density : float
        [kg/m^3].
    viscosity : float
        Dynamic viscosity of the air [Pa s].

    Returns
    -------
    AirDampingRates
    """
    for name, v in (("side", side), ("gap", gap), ("frequency_y", frequency_y), ("frequency_theta", frequency_theta),
                    ("particle_density", particle_density), ("air_density", air_density), ("viscosity", viscosity)):
        if not (math.isfinite(v) and v > 0):
            raise ValueError(f"air damping: {name} must be positive and finite, got {v!r}")
    nu = viscosity / air_density
    d_y = stokes_layer_thickness(nu, frequency_y)
    d_t = stokes_layer_thickness(nu, frequency_theta)
    r = dimer_drag_radii(side)
    m = particle_density * side ** 3
    gamma_y = oscillating_translation_drag(viscosity, r.dimer_stokes, r.dimer_area, d_y) / (2.0 * m)
    c_rot = oscillating_rotation_drag(viscosity, r.cube_rotation, d_t)
    c_sway = oscillating_translation_drag(viscosity, r.cube_stokes, r.cube_area, d_t) * side ** 2 / 2.0  # d^2 = s^2/2
    # Q_theta = -(pi/4)^2 2 [c_rot + c_sway sin^2 phi] thetadot - (pi/2)^2 sum_wedges c_wedge thetadot,
    # I(0) = (pi/4)^2 m s^2 / 3
    inertia0 = (math.pi / 4.0) ** 2 * m * side ** 2 / 3.0
    rot_rate = (math.pi / 4.0) ** 2 * 2.0 * c_rot / inertia0
    wedge_lead = 1.5 * viscosity * side ** 3  # c_wedge = wedge_lead * F K / beta^3
    wedge_rate = (math.pi / 2.0) ** 2 * wedge_lead / inertia0
    return AirDampingRates(gamma_y=gamma_y, gamma_theta=rot_rate, sway_ratio=c_sway / c_rot,
                           wedge_ratio=wedge_rate / rot_rate, gap_ratio=gap / side, delta_y=d_y, delta_theta=d_t,
                           frequency_y=frequency_y, frequency_theta=frequency_theta)


def air_damping_parameters(rates: AirDampingRates) -> dict[str, float]:
    """The ``air_damping`` effect's parameters (docs/conventions.md section 5) of computed rates."""
    return {"gamma_y": rates.gamma_y, "gamma_theta": rates.gamma_theta, "sway_ratio": rates.sway_ratio,
            "wedge_ratio": rates.wedge_ratio, "gap_ratio": rates.gap_ratio}
