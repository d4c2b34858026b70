"""The unmodelled effects of docs/conventions.md section 5 as composable, parameterised objects.

Each effect is a frozen dataclass whose class attribute ``name`` and field names are exactly those
of docs/conventions.md (they appear in files and reports); each adds terms to the accelerations
``(yddot, thetaddot)`` of the equations of motion:

=====================  ===========================  ==========================================
name                   parameters (SI)              adds to (yddot, thetaddot)
=====================  ===========================  ==========================================
``linear_damping``     gamma_y, gamma_theta [1/s]   (-gamma_y ydot, -gamma_theta thetadot)
``quadratic_drag``     c_y [1/m], c_theta [-]       (-c_y |ydot| ydot, -c_theta |thetadot| thetadot)
``pair_scattering``    kappa [1/s^2]                (0, -kappa cos^2(k Z_com) theta)
``mirror_asymmetry``   beta0 [1/s^2], beta1 [1/(m s^2)]  (0, beta0 + beta1 y)
``velocity_coupling``  c5 [1/m], c6 [1/m^2]          (0, c5 thetadot^2 y + c6 thetadot ydot y)
``air_damping``        gamma_y, gamma_theta [1/s],  (-gamma_y ydot, -gamma_theta S(theta) thetadot)
                       sway_ratio, wedge_ratio,
                       gap_ratio [-]
=====================  ===========================  ==========================================

``Z_com = Z_eq + y`` is measured from the pressure node.  An :class:`EffectSet` holds any subset
(at most one of each name); :func:`parse_effect` reads the command-line form
``NAME:param=value,param=value`` (parameters not given are 0).

One definition per effect.  Every effect is linear in its parameters, so it is defined by its
*regressor columns*: a plain function ``columns(y, ydot, theta, thetadot, wavenumber, z_eq)``
returning ``(yddot columns, thetaddot columns)``, one entry per parameter, such that the added
accelerations are ``sum_j p_j column_j``.  The same function serves

* the numpy reference (:meth:`Effect.regressors`, :meth:`Effect.accelerations`,
  :meth:`EffectSet.regressors`, :meth:`EffectSet.accelerations`), on arrays;
* the linear fits of the diagnosis (:meth:`Effect.regressors`: the design-matrix columns);
* the compiled equations of motion: numba compiles the same source for scalars, and
  :func:`acousim.dynamics.compiled_effects.packed_effect_accelerations` sums every effect over the flat parameter vector
  :meth:`EffectSet.packed` (order :func:`packed_parameters`; absent effects contribute zeros).

A new effect is a subclass with its ``columns`` function, registered with :func:`register_effect`.  Nothing else
is needed for the twin to integrate it: the compiled sum (:mod:`acousim.dynamics.compiled_effects`) calls the compiled
``columns`` of every registered effect that has no line of its own.  The effects of docs/conventions.md have their own
lines (:data:`COMPILED_EFFECTS`), so that the equations of motion with them are compiled once and cached on disk; a
new effect that is used often earns such a line too (the tests compare the compiled sum with the numpy one for
every effect type).

With the acoustic field off only the air's effects (``acts_without_field``: ``linear_damping``,
``quadratic_drag``, ``air_damping``) act; :meth:`EffectSet.acting` selects them.

``air_damping`` is the air's drag computed from the dimer's geometry and the air (:mod:`acousim.dynamics.air_damping`,
docs/damping.md), with the hinge's theta-dependence ``S(theta)`` of
:func:`acousim.dynamics.air_damping.hinge_damping_shape`.  It is not linear in ``gap_ratio`` and is not a candidate of
the diagnosis (``candidate = False``; its fitted counterparts are ``linear_damping`` and ``quadratic_drag``):
it has no :meth:`Effect.regressors`, and its compiled term is its own line of
:func:`acousim.dynamics.compiled_effects.packed_effect_accelerations`.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import Callable, ClassVar, Iterable, Mapping

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .air_damping import air_damping_rates, hinge_damping_shape

__all__ = [
    "Effect",
    "LinearDamping",
    "QuadraticDrag",
    "PairScattering",
    "MirrorAsymmetry",
    "VelocityCoupling",
    "AirDamping",
    "EffectSet",
    "EFFECT_TYPES",
    "COMPILED_EFFECTS",
    "register_effect",
    "packed_parameters",
    "air_damping_for",
    "PACKED_PARAMETERS",
    "parse_effect",
    "EffectError",
]


class EffectError(ValueError):
    """A bad effect specification; ``str(err)`` is one line."""


# ---------------------------------------------------------------------- the definitions
# Each returns (yddot columns, thetaddot columns), one entry per parameter in the order of the
# effect's fields; scalars in and out under numba, arrays (or broadcastable scalars) under numpy.
def _linear_damping_columns(y, ydot, theta, thetadot, wavenumber, z_eq):
    return (-ydot, 0.0), (0.0, -thetadot)


def _quadratic_drag_columns(y, ydot, theta, thetadot, wavenumber, z_eq):
    return (-abs(ydot) * ydot, 0.0), (0.0, -abs(thetadot) * thetadot)


def _pair_scattering_columns(y, ydot, theta, thetadot, wavenumber, z_eq):
    c = np.cos(wavenumber * (z_eq + y))
    return (0.0,), (-c * c * theta,)


def _mirror_asymmetry_columns(y, ydot, theta, thetadot, wavenumber, z_eq):
    return (0.0, 0.0), (1.0, y)


def _velocity_coupling_columns(y, ydot, theta, thetadot, wavenumber, z_eq):
    return (0.0, 0.0), (thetadot * thetadot * y, thetadot * ydot * y)


def _state_arrays(*values) -> tuple[list[NDArray[np.float64]], tuple[int, ...]]:
    """The values as float arrays and their broadcast shape."""
    arrays = [np.asarray(v, float) for v in values]
    return arrays, np.broadcast_shapes(*(a.shape for a in arrays))


@dataclass(frozen=True)
class Effect:
    """Base class: an unmodelled effect adding to the accelerations (see the module table).

    Subclasses set ``name``, their parameters as float fields, and ``columns`` (the one definition
    of the effect, see the module docstring).
    """

    name: ClassVar[str] = ""
    #: parameters that must be >= 0 (dissipation and stiffening)
    _non_negative: ClassVar[tuple[str, ...]] = ()
    #: True for effects of the air, which act with the acoustic field off too
    acts_without_field: ClassVar[bool] = False
    #: True when the columns depend on the height above the node itself (through ``wavenumber * (z_eq + y)``),
    #: not only on the state
    depends_on_node_height: ClassVar[bool] = False
    #: True for effects the diagnosis fits as candidates (linear in every parameter, with regressors)
    candidate: ClassVar[bool] = True
    #: regressor columns ``(y, ydot, theta, thetadot, wavenumber, z_eq) -> (yddot cols, thetaddot cols)``
    columns: ClassVar[Callable]

    def __post_init__(self) -> None:
        for f in fields(self):
            v = getattr(self, f.name)
            try:
                v = float(v)
            except (TypeError, ValueError):
                raise EffectError(f"{self.name}: parameter {f.name} must be a number, got {v!r}") from None
            if not math.isfinite(v):
                raise EffectError(f"{self.name}: parameter {f.name} must be finite, got {v!r}")
            if f.name in self._non_negative and v < 0:
                raise EffectError(f"{self.name}: parameter {f.name} must be >= 0, got {v!r}")
            object.__setattr__(self, f.name, v)

    @classmethod
    def parameter_names(cls) -> tuple[str, ...]:
        """The docs/conventions.md parameter names, in order."""
        return tuple(f.name for f in fields(cls))

    def params(self) -> dict[str, float]:
        """{parameter name: value} (SI)."""
        return {f.name: float(getattr(self, f.name)) for f in fields(self)}

    def parameter_vector(self) -> NDArray[np.float64]:
        """Parameter values in the order of :meth:`parameter_names`."""
        return np.array([getattr(self, p) for p in self.parameter_names()], float)

    @classmethod
    def regressors(cls, y: ArrayLike, ydot: ArrayLike, theta: ArrayLike, thetadot: ArrayLike,
                   wavenumber: float, z_eq: float) -> NDArray[np.float64]:
        """d(accelerations)/d(parameters): array (..., 2, n_params) over the broadcast state shape.

        Row 0 is the yddot equation [m/s^2 per unit parameter], row 1 thetaddot [1/s^2 per unit
        parameter]; columns follow :meth:`parameter_names`.  State in SI, ``wavenumber`` k [1/m],
        ``z_eq`` [m] the equilibrium height below the node (the effects' y is Z_com - Z_eq; a scalar
        or an array broadcasting with the state).
        """
        args, shape = _state_arrays(y, ydot, theta, thetadot, z_eq)
        cy, ct = cls.columns(*args[:4], float(wavenumber), args[4])
        rows = [np.stack([np.broadcast_to(np.asarray(c, float), shape) for c in cols], axis=-1) for cols in (cy, ct)]
        return np.stack(rows, axis=-2)

    def accelerations(self, y: ArrayLike, ydot: ArrayLike, theta: ArrayLike, thetadot: ArrayLike,
                      wavenumber: float, z_eq: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Terms added to (yddot [m/s^2], thetaddot [1/s^2]): ``sum_j p_j column_j`` (numpy, arrays in SI)."""
        args, shape = _state_arrays(y, ydot, theta, thetadot, z_eq)
        cy, ct = self.columns(*args[:4], float(wavenumber), args[4])
        p = self.parameter_vector()
        ay = sum((pj * np.asarray(c, float) for pj, c in zip(p, cy)), np.zeros(shape))
        at = sum((pj * np.asarray(c, float) for pj, c in zip(p, ct)), np.zeros(shape))
        return ay, at


@dataclass(frozen=True)
class LinearDamping(Effect):
    """Viscous drag of air: (-gamma_y ydot, -gamma_theta thetadot); gamma in 1/s."""

    name: ClassVar[str] = "linear_damping"
    _non_negative: ClassVar[tuple[str, ...]] = ("gamma_y", "gamma_theta")
    acts_without_field: ClassVar[bool] = True
    columns: ClassVar[Callable] = staticmethod(_linear_damping_columns)
    gamma_y: float = 0.0
    gamma_theta: float = 0.0


@dataclass(frozen=True)
class QuadraticDrag(Effect):
    """Form drag: (-c_y |ydot| ydot, -c_theta |thetadot| thetadot); c_y in 1/m, c_theta dimensionless."""

    name: ClassVar[str] = "quadratic_drag"
    _non_negative: ClassVar[tuple[str, ...]] = ("c_y", "c_theta")
    acts_without_field: ClassVar[bool] = True
    columns: ClassVar[Callable] = staticmethod(_quadratic_drag_columns)
    c_y: float = 0.0
    c_theta: float = 0.0


@dataclass(frozen=True)
class PairScattering(Effect):
    """Secondary scattering stiffens the hinge: thetaddot += -kappa cos^2(k Z_com) theta; kappa in 1/s^2."""

    name: ClassVar[str] = "pair_scattering"
    _non_negative: ClassVar[tuple[str, ...]] = ("kappa",)
    depends_on_node_height: ClassVar[bool] = True
    columns: ClassVar[Callable] = staticmethod(_pair_scattering_columns)
    kappa: float = 0.0


@dataclass(frozen=True)
class MirrorAsymmetry(Effect):
    """Broken mirror symmetry: thetaddot += beta0 + beta1 y; beta0 in 1/s^2, beta1 in 1/(m s^2)."""

    name: ClassVar[str] = "mirror_asymmetry"
    columns: ClassVar[Callable] = staticmethod(_mirror_asymmetry_columns)
    beta0: float = 0.0
    beta1: float = 0.0


@dataclass(frozen=True)
class VelocityCoupling(Effect):
    """Velocity-dependent acoustic forces: thetaddot += c5 thetadot^2 y + c6 thetadot ydot y; c5 in 1/m, c6 in 1/m^2."""

    name: ClassVar[str] = "velocity_coupling"
    columns: ClassVar[Callable] = staticmethod(_velocity_coupling_columns)
    c5: float = 0.0
    c6: float = 0.0


def _air_damping_terms(ydot, theta, thetadot, gamma_y, gamma_theta, sway_ratio, wedge_ratio, gap_ratio):
    """(yddot, thetaddot) terms of the air's computed drag (scalars; numba compiles the same source)."""
    at = 0.0
    if gamma_theta != 0.0:
        at = -gamma_theta * hinge_damping_shape(theta, gap_ratio, sway_ratio, wedge_ratio) * thetadot
    return -gamma_y * ydot, at


@dataclass(frozen=True)
class AirDamping(Effect):
    """The air's drag computed from the geometry (docs/damping.md): (-gamma_y ydot, -gamma_theta S(theta) thetadot).

    Build it with :meth:`from_rates` from :func:`acousim.dynamics.air_damping.air_damping_rates`; the parameters are
    gamma_y, gamma_theta [1/s] (hinge rate at theta = 0) and the dimensionless sway_ratio, wedge_ratio and
    gap_ratio (g / s) of :func:`acousim.dynamics.air_damping.hinge_damping_shape`.
    """

    name: ClassVar[str] = "air_damping"
    _non_negative: ClassVar[tuple[str, ...]] = ("gamma_y", "gamma_theta", "sway_ratio", "wedge_ratio", "gap_ratio")
    acts_without_field: ClassVar[bool] = True
    candidate: ClassVar[bool] = False
    gamma_y: float = 0.0
    gamma_theta: float = 0.0
    sway_ratio: float = 0.0
    wedge_ratio: float = 0.0
    gap_ratio: float = 0.0

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.gamma_theta > 0 and self.wedge_ratio > 0 and self.gap_ratio <= 0:
            raise EffectError("air_damping: gap_ratio must be > 0 when the wedge term is on")

    @classmethod
    def from_rates(cls, rates) -> "AirDamping":
        """The effect of :class:`acousim.dynamics.air_damping.AirDampingRates`."""
        from .air_damping import air_damping_parameters

        return cls(**air_damping_parameters(rates))

    @classmethod
    def regressors(cls, *args, **kwargs):
        raise EffectError("air_damping is computed, not fitted: it has no regressors (fit linear_damping instead)")

    def accelerations(self, y: ArrayLike, ydot: ArrayLike, theta: ArrayLike, thetadot: ArrayLike,
                      wavenumber: float, z_eq: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Terms added to (yddot [m/s^2], thetaddot [1/s^2]) (numpy reference, arrays in SI)."""
        (_, yd, th, thd, _), shape = _state_arrays(y, ydot, theta, thetadot, z_eq)
        yd, th, thd = (np.broadcast_to(a, shape).ravel() for a in (yd, th, thd))
        p = self.parameter_vector()
        out = np.array([_air_damping_terms(a, b, c, *p) for a, b, c in zip(yd, th, thd)]).reshape(shape + (2,))
        return out[..., 0], out[..., 1]


#: name -> effect class, in docs/conventions.md order.  Add an effect with :func:`register_effect`.
EFFECT_TYPES: dict[str, type[Effect]] = {
    cls.name: cls for cls in (LinearDamping, QuadraticDrag, PairScattering, MirrorAsymmetry, VelocityCoupling,
                              AirDamping)
}

#: The effects with a line of their own in :func:`acousim.dynamics.compiled_effects.packed_effect_accelerations` (compiled
#: once and cached on disk).
COMPILED_EFFECTS: tuple[str, ...] = tuple(EFFECT_TYPES)

#: (effect name, parameter name) of the compiled effects' slots, the start of every :meth:`EffectSet.packed`.
PACKED_PARAMETERS: tuple[tuple[str, str], ...] = tuple(
    (name, p) for name, cls in EFFECT_TYPES.items() for p in cls.parameter_names()
)


def register_effect(cls: type[Effect]) -> type[Effect]:
    """Add an effect class to :data:`EFFECT_TYPES` (usable as a class decorator); returns ``cls``.

    The class needs a new ``name``, float parameters as dataclass fields and a ``columns`` function that numba can
    compile (module docstring).  From then on the equations of motion and the twin integrate it (through
    :func:`acousim.dynamics.compiled_effects.registered_effect_kernels`), the diagnosis fits it when ``candidate`` is true, and ``--effect NAME:...``
    parses it.

    Raises
    ------
    EffectError
        Not an :class:`Effect` subclass, no ``name`` or ``columns``, or a name already registered.
    """
    if not (isinstance(cls, type) and issubclass(cls, Effect)):
        raise EffectError(f"not an Effect subclass: {cls!r}")
    if not cls.name or not getattr(cls, "columns", None):
        raise EffectError(f"{cls.__name__}: an effect needs a name and a columns function")
    if cls.name in EFFECT_TYPES:
        raise EffectError(f"effect {cls.name!r} is registered already")
    EFFECT_TYPES[cls.name] = cls
    return cls


def packed_parameters() -> tuple[tuple[str, str], ...]:
    """(effect name, parameter name) of each entry of :meth:`EffectSet.packed`: :data:`PACKED_PARAMETERS`, then
    the parameters of every registered effect without a compiled line, in registry order."""
    return PACKED_PARAMETERS + tuple((name, p) for name, cls in EFFECT_TYPES.items() if name not in COMPILED_EFFECTS
                                     for p in cls.parameter_names())


def parse_effect(spec: str) -> Effect:
    """Parse ``"NAME:param=value,param=value"`` (or just ``"NAME"``; missing parameters are 0).

    Raises
    ------
    EffectError
        Unknown effect or parameter name, repeated parameter, or a value that is not a finite number.
    """
    text = spec.strip()
    name, _, rest = text.partition(":")
    name = name.strip()
    if name not in EFFECT_TYPES:
        raise EffectError(f"unknown effect {name!r} in {spec!r} (known: {', '.join(EFFECT_TYPES)})")
    cls = EFFECT_TYPES[name]
    allowed = cls.parameter_names()
    params: dict[str, float] = {}
    for item in filter(None, (s.strip() for s in rest.split(","))):
        key, eq, value = item.partition("=")
        key = key.strip()
        if not eq:
            raise EffectError(f"{name}: expected param=value, got {item!r}")
        if key not in allowed:
            raise EffectError(f"{name}: unknown parameter {key!r} (parameters: {', '.join(allowed)})")
        if key in params:
            raise EffectError(f"{name}: parameter {key!r} given twice")
        try:
            params[key] = float(value)
        except ValueError:
            raise EffectError(f"{name}: parameter {key} must be a number, got {value.strip()!r}") from None
    return cls(**params)


@dataclass(frozen=True)
class EffectSet:
    """Any subset of the effects, at most one of each name; empty means the pure Gor'kov model.

    Parameters
    ----------
    effects : tuple of Effect
        Stored in docs/conventions.md order whatever the order given.
    """

    effects: tuple[Effect, ...] = ()

    def __post_init__(self) -> None:
        effs = tuple(self.effects)
        for e in effs:
            if not isinstance(e, Effect):
                raise EffectError(f"not an effect: {e!r}")
        names = [e.name for e in effs]
        dup = sorted({n for n in names if names.count(n) > 1})
        if dup:
            raise EffectError(f"effect {dup[0]!r} given more than once")
        order = list(EFFECT_TYPES)
        object.__setattr__(self, "effects", tuple(sorted(effs, key=lambda e: order.index(e.name))))

    # ------------------------------------------------------------------ construction
    @classmethod
    def parse(cls, specs: Iterable[str]) -> "EffectSet":
        """From command-line strings ``NAME:param=value,...`` (see :func:`parse_effect`)."""
        return cls(tuple(parse_effect(s) for s in specs))

    @classmethod
    def from_dict(cls, data: Mapping[str, Mapping[str, float]]) -> "EffectSet":
        """From ``{"pair_scattering": {"kappa": 12000.0}, ...}`` (the truth.json form)."""
        out = []
        for name, params in data.items():
            if name not in EFFECT_TYPES:
                raise EffectError(f"unknown effect {name!r} (known: {', '.join(EFFECT_TYPES)})")
            allowed = EFFECT_TYPES[name].parameter_names()
            bad = [k for k in params if k not in allowed]
            if bad:
                raise EffectError(f"{name}: unknown parameter {bad[0]!r} (parameters: {', '.join(allowed)})")
            out.append(EFFECT_TYPES[name](**params))
        return cls(tuple(out))

    def to_dict(self) -> dict[str, dict[str, float]]:
        """``{name: {param: value}}`` in docs/conventions.md order (the truth.json form)."""
        return {e.name: e.params() for e in self.effects}

    def merged(self, other: "EffectSet") -> "EffectSet":
        """This set with the effects of ``other`` added; an effect of ``other`` replaces one of the same name."""
        keep = {e.name: e for e in self.effects}
        keep.update({e.name: e for e in other.effects})
        return EffectSet(tuple(keep.values()))

    # ------------------------------------------------------------------ access
    @property
    def names(self) -> tuple[str, ...]:
        return tuple(e.name for e in self.effects)

    def __contains__(self, name: object) -> bool:
        return name in self.names

    def __getitem__(self, name: str) -> Effect:
        for e in self.effects:
            if e.name == name:
                return e
        raise KeyError(name)

    def __len__(self) -> int:
        return len(self.effects)

    def __iter__(self):
        return iter(self.effects)

    def acting(self, field_on: bool = True) -> "EffectSet":
        """The effects that act with the field on (all) or off (those with ``acts_without_field``)."""
        if field_on:
            return self
        return EffectSet(tuple(e for e in self.effects if e.acts_without_field))

    def parameter_names(self) -> tuple[tuple[str, str], ...]:
        """(effect name, parameter name) of each column of :meth:`regressors`."""
        return tuple((e.name, p) for e in self.effects for p in e.parameter_names())

    def parameter_vector(self) -> NDArray[np.float64]:
        """The parameters of the set's effects in the order of :meth:`parameter_names`."""
        return np.concatenate([e.parameter_vector() for e in self.effects] or [np.zeros(0)])

    def regressors(self, y: ArrayLike, ydot: ArrayLike, theta: ArrayLike, thetadot: ArrayLike,
                   wavenumber: float, z_eq: float) -> NDArray[np.float64]:
        """(Candidate effects only, :attr:`Effect.candidate`.)  Every effect's :meth:`Effect.regressors` side by side: (..., 2, total parameters); the
        set's accelerations are ``regressors @ parameter_vector()``."""
        shape = np.broadcast_shapes(*(np.shape(v) for v in (y, ydot, theta, thetadot, z_eq)))
        parts = [type(e).regressors(y, ydot, theta, thetadot, wavenumber, z_eq) for e in self.effects]
        return np.concatenate(parts, axis=-1) if parts else np.zeros(shape + (2, 0))

    def packed(self) -> NDArray[np.float64]:
        """Flat parameter vector in the order of :func:`packed_parameters` (absent effects: 0)."""
        d = self.to_dict()
        return np.array([d.get(name, {}).get(p, 0.0) for name, p in packed_parameters()], float)

    def accelerations(self, y: ArrayLike, ydot: ArrayLike, theta: ArrayLike, thetadot: ArrayLike,
                      wavenumber: float, z_eq: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Sum of every effect's terms (yddot [m/s^2], thetaddot [1/s^2]), numpy reference implementation."""
        shape = np.broadcast(*(np.asarray(v) for v in (y, ydot, theta, thetadot, z_eq))).shape
        ay, at = np.zeros(shape), np.zeros(shape)
        for e in self.effects:
            a, b = e.accelerations(y, ydot, theta, thetadot, wavenumber, z_eq)
            ay = ay + a
            at = at + b
        return ay, at

    def describe(self) -> str:
        """One line, e.g. ``pair_scattering(kappa=12000), linear_damping(gamma_y=0.3, ...)``; ``none`` if empty."""
        if not self.effects:
            return "none"
        return ", ".join(f"{e.name}(" + ", ".join(f"{k}={v:g}" for k, v in e.params().items()) + ")"
                         for e in self.effects)


def air_damping_for(force_model, conditions):
    """The ``air_damping`` effect of a dimer: :func:`acousim.dynamics.air_damping.air_damping_rates` at the force model's own small-oscillation
    frequencies (``linear_frequencies()``; a mode without one, e.g. an unstable hinge, is taken at the other's).

    Parameters
    ----------
    force_model : acousim.ForceModel
        The dimer's dynamic force model (its frequencies set the Stokes layers).
    conditions : acousim.models.ExperimentConditions
        Side, densities and the hinge gap (None: the full-wave default 0.01 side; a Gor'kov dimer has no gap of
        its own and takes the same).

    Returns
    -------
    acousim.dynamics.effects.AirDamping
    """
    f_y, f_theta = force_model.linear_frequencies()
    if not math.isfinite(f_y):
        raise ValueError("air damping: the model has no vertical trap frequency (the field does not hold the dimer)")
    if not math.isfinite(f_theta):
        f_theta = f_y
    side = conditions.side_length_m
    gap = conditions.gap_m if conditions.gap_m is not None else 0.01 * side
    rates = air_damping_rates(side, gap, f_y, f_theta, particle_density=conditions.particle_density_kg_m3,
                              air_density=conditions.air_density_kg_m3)
    return AirDamping.from_rates(rates)
