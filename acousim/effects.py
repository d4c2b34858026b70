"""The unmodelled effects of PHYSICS.md section 5 as composable, parameterised objects.

Each effect is a frozen dataclass whose class attribute ``name`` and field names are exactly those
of PHYSICS.md (they appear in files and reports); each adds terms to the accelerations
``(yddot, thetaddot)`` of the Gor'kov equations of motion:

=====================  ===========================  ==========================================
name                   parameters (SI)              adds to (yddot, thetaddot)
=====================  ===========================  ==========================================
``linear_damping``     gamma_y, gamma_theta [1/s]   (-gamma_y ydot, -gamma_theta thetadot)
``quadratic_drag``     c_y [1/m], c_theta [-]       (-c_y |ydot| ydot, -c_theta |thetadot| thetadot)
``pair_scattering``    kappa [1/s^2]                (0, -kappa cos^2(k Z_com) theta)
``mirror_asymmetry``   beta0 [1/s^2], beta1 [1/(m s^2)]  (0, beta0 + beta1 y)
``velocity_coupling``  c5, c6 [1/m]                 (0, c5 thetadot^2 y + c6 thetadot ydot y)
=====================  ===========================  ==========================================

``Z_com = Z_eq + y`` is measured from the pressure node.  An :class:`EffectSet` holds any subset
(at most one of each name); :func:`parse_effect` reads the command-line form
``NAME:param=value,param=value`` (parameters not given are 0).

The compiled integrator (:mod:`acousim.dynamics`) reads the set as one flat parameter vector
(:meth:`EffectSet.packed`, order :data:`PACKED_PARAMETERS`); absent effects contribute zeros,
which is the same as switching them off.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import ClassVar, Iterable, Mapping

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "Effect",
    "LinearDamping",
    "QuadraticDrag",
    "PairScattering",
    "MirrorAsymmetry",
    "VelocityCoupling",
    "EffectSet",
    "EFFECT_TYPES",
    "PACKED_PARAMETERS",
    "parse_effect",
    "EffectError",
]


class EffectError(ValueError):
    """A bad effect specification; ``str(err)`` is one line."""


@dataclass(frozen=True)
class Effect:
    """Base class: an unmodelled effect adding to the accelerations (see the module table)."""

    name: ClassVar[str] = ""
    #: parameters that must be >= 0 (dissipation and stiffening)
    _non_negative: ClassVar[tuple[str, ...]] = ()

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
        """The PHYSICS.md parameter names, in order."""
        return tuple(f.name for f in fields(cls))

    def params(self) -> dict[str, float]:
        """{parameter name: value} (SI)."""
        return {f.name: float(getattr(self, f.name)) for f in fields(self)}

    def accelerations(self, y: ArrayLike, ydot: ArrayLike, theta: ArrayLike, thetadot: ArrayLike,
                      wavenumber: float, z_eq: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Terms added to (yddot [m/s^2], thetaddot [1/s^2]); state in SI, ``wavenumber`` k [1/m],
        ``z_eq`` [m] the equilibrium height below the node.  Reference (numpy) implementation."""
        raise NotImplementedError


@dataclass(frozen=True)
class LinearDamping(Effect):
    """Viscous drag of air: (-gamma_y ydot, -gamma_theta thetadot); gamma in 1/s."""

    name: ClassVar[str] = "linear_damping"
    _non_negative: ClassVar[tuple[str, ...]] = ("gamma_y", "gamma_theta")
    gamma_y: float = 0.0
    gamma_theta: float = 0.0

    def accelerations(self, y, ydot, theta, thetadot, wavenumber, z_eq):
        return -self.gamma_y * np.asarray(ydot, float), -self.gamma_theta * np.asarray(thetadot, float)


@dataclass(frozen=True)
class QuadraticDrag(Effect):
    """Form drag: (-c_y |ydot| ydot, -c_theta |thetadot| thetadot); c_y in 1/m, c_theta dimensionless."""

    name: ClassVar[str] = "quadratic_drag"
    _non_negative: ClassVar[tuple[str, ...]] = ("c_y", "c_theta")
    c_y: float = 0.0
    c_theta: float = 0.0

    def accelerations(self, y, ydot, theta, thetadot, wavenumber, z_eq):
        yd, td = np.asarray(ydot, float), np.asarray(thetadot, float)
        return -self.c_y * np.abs(yd) * yd, -self.c_theta * np.abs(td) * td


@dataclass(frozen=True)
class PairScattering(Effect):
    """Secondary scattering stiffens the hinge: thetaddot += -kappa cos^2(k Z_com) theta; kappa in 1/s^2."""

    name: ClassVar[str] = "pair_scattering"
    _non_negative: ClassVar[tuple[str, ...]] = ("kappa",)
    kappa: float = 0.0

    def accelerations(self, y, ydot, theta, thetadot, wavenumber, z_eq):
        z = z_eq + np.asarray(y, float)
        return np.zeros_like(z), -self.kappa * np.cos(wavenumber * z) ** 2 * np.asarray(theta, float)


@dataclass(frozen=True)
class MirrorAsymmetry(Effect):
    """Broken mirror symmetry: thetaddot += beta0 + beta1 y; beta0 in 1/s^2, beta1 in 1/(m s^2)."""

    name: ClassVar[str] = "mirror_asymmetry"
    beta0: float = 0.0
    beta1: float = 0.0

    def accelerations(self, y, ydot, theta, thetadot, wavenumber, z_eq):
        y = np.asarray(y, float)
        return np.zeros_like(y), self.beta0 + self.beta1 * y


@dataclass(frozen=True)
class VelocityCoupling(Effect):
    """Velocity-dependent acoustic forces: thetaddot += c5 thetadot^2 y + c6 thetadot ydot y; c5, c6 in 1/m."""

    name: ClassVar[str] = "velocity_coupling"
    c5: float = 0.0
    c6: float = 0.0

    def accelerations(self, y, ydot, theta, thetadot, wavenumber, z_eq):
        y, yd, td = (np.asarray(v, float) for v in (y, ydot, thetadot))
        return np.zeros_like(y), self.c5 * td**2 * y + self.c6 * td * yd * y


#: name -> effect class, in PHYSICS.md order.
EFFECT_TYPES: dict[str, type[Effect]] = {
    cls.name: cls for cls in (LinearDamping, QuadraticDrag, PairScattering, MirrorAsymmetry, VelocityCoupling)
}

#: (effect name, parameter name) of each entry of :meth:`EffectSet.packed`.
PACKED_PARAMETERS: tuple[tuple[str, str], ...] = tuple(
    (name, p) for name, cls in EFFECT_TYPES.items() for p in cls.parameter_names()
)


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
        Stored in PHYSICS.md order whatever the order given.
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
        """``{name: {param: value}}`` in PHYSICS.md order (the truth.json form)."""
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

    def packed(self) -> NDArray[np.float64]:
        """Flat parameter vector in the order of :data:`PACKED_PARAMETERS` (absent effects: 0)."""
        d = self.to_dict()
        return np.array([d.get(name, {}).get(p, 0.0) for name, p in PACKED_PARAMETERS], float)

    def accelerations(self, y: ArrayLike, ydot: ArrayLike, theta: ArrayLike, thetadot: ArrayLike,
                      wavenumber: float, z_eq: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Sum of every effect's terms (yddot [m/s^2], thetaddot [1/s^2]), numpy reference implementation."""
        shape = np.broadcast(*(np.asarray(v) for v in (y, ydot, theta, thetadot))).shape
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
