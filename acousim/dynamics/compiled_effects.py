"""The compiled sum of the effects (:mod:`acousim.dynamics.effects`) that the equations of motion integrate.

:func:`packed_effect_accelerations` adds the terms of every effect of one state for the flat parameter vector
:meth:`acousim.dynamics.effects.EffectSet.packed`.  The effects of docs/conventions.md section 5
(:data:`acousim.dynamics.effects.COMPILED_EFFECTS`) have a line of their own here: numba compiles their ``columns`` for
scalars, and the equations of motion built on them are compiled once and cached on disk.  Every other registered
effect (:func:`acousim.dynamics.effects.register_effect`) is added through :func:`registered_effect_kernels`, its compiled
``columns`` passed to the sum as a first-class function, with no code here.
"""
from __future__ import annotations

from typing import Callable

import numba as nb
from numba.extending import overload

from .effects import (COMPILED_EFFECTS, EFFECT_TYPES, _air_damping_terms, _linear_damping_columns,
                      _mirror_asymmetry_columns, _pair_scattering_columns, _quadratic_drag_columns,
                      _velocity_coupling_columns)

__all__ = ["packed_effect_accelerations", "registered_effect_kernels"]

_REGISTERED_KERNELS: dict[type, Callable] = {}


def registered_effect_kernels() -> tuple:
    """The compiled ``columns`` of every registered effect without a line in :func:`packed_effect_accelerations`,
    in registry order (the last argument of that function; empty for the effects of docs/conventions.md).

    Each is compiled once per process.  A kernel passed this way is called through numba's first-class functions,
    so the equations of motion that take it compile anew in each process; a line in
    :func:`packed_effect_accelerations` (and the name in :data:`acousim.dynamics.effects.COMPILED_EFFECTS`) makes an effect
    as fast as the built-in ones.
    """
    out = []
    for name, cls in EFFECT_TYPES.items():
        if name in COMPILED_EFFECTS:
            continue
        if cls not in _REGISTERED_KERNELS:
            _REGISTERED_KERNELS[cls] = nb.njit(cls.columns)
        out.append(_REGISTERED_KERNELS[cls])
    return tuple(out)


# ---------------------------------------------------------------------- the compiled sum
_linear_damping_kernel = nb.njit(cache=True)(_linear_damping_columns)
_quadratic_drag_kernel = nb.njit(cache=True)(_quadratic_drag_columns)
_pair_scattering_kernel = nb.njit(cache=True)(_pair_scattering_columns)
_mirror_asymmetry_kernel = nb.njit(cache=True)(_mirror_asymmetry_columns)
_velocity_coupling_kernel = nb.njit(cache=True)(_velocity_coupling_columns)
_air_damping_kernel = nb.njit(cache=True)(_air_damping_terms)


@nb.njit(cache=True)
def _add_columns(ay, at, cy, ct, p, i0):
    """(ay + sum_j p[i0 + j] cy[j], at + sum_j p[i0 + j] ct[j], i0 + number of columns)."""
    for j in range(len(cy)):
        ay += p[i0 + j] * cy[j]
        at += p[i0 + j] * ct[j]
    return ay, at, i0 + len(cy)


def _registered_effects_sum(kernels, y, ydot, theta, thetadot, wavenumber, z_eq, packed, i0):
    """Compiled only (its implementation is the overload below): the summed terms of the registered effects'
    ``kernels`` from slot ``i0`` of ``packed``."""
    raise NotImplementedError("compiled only")


@overload(_registered_effects_sum)
def _registered_effects_sum_impl(kernels, y, ydot, theta, thetadot, wavenumber, z_eq, packed, i0):
    # one specialisation per tuple type: the first kernel, then the rest (recursion on the tuple's type)
    if len(kernels) == 0:
        def impl(kernels, y, ydot, theta, thetadot, wavenumber, z_eq, packed, i0):
            return 0.0, 0.0
        return impl

    def impl(kernels, y, ydot, theta, thetadot, wavenumber, z_eq, packed, i0):
        cy, ct = kernels[0](y, ydot, theta, thetadot, wavenumber, z_eq)
        ay, at, i1 = _add_columns(0.0, 0.0, cy, ct, packed, i0)
        by, bt = _registered_effects_sum(kernels[1:], y, ydot, theta, thetadot, wavenumber, z_eq, packed, i1)
        return ay + by, at + bt
    return impl


@nb.njit(cache=True)
def packed_effect_accelerations(y, ydot, theta, thetadot, wavenumber, z_eq, packed, registered):
    """Compiled: the summed effect terms (yddot, thetaddot) of one state for the parameter vector
    ``packed`` (:meth:`acousim.dynamics.effects.EffectSet.packed`, order :func:`acousim.dynamics.effects.packed_parameters`) and the kernels of the registered
    effects without a line here (:func:`registered_effect_kernels`; ``()`` when there are none)."""
    ay = 0.0
    at = 0.0
    i0 = 0
    cy, ct = _linear_damping_kernel(y, ydot, theta, thetadot, wavenumber, z_eq)
    ay, at, i0 = _add_columns(ay, at, cy, ct, packed, i0)
    cy, ct = _quadratic_drag_kernel(y, ydot, theta, thetadot, wavenumber, z_eq)
    ay, at, i0 = _add_columns(ay, at, cy, ct, packed, i0)
    cy, ct = _pair_scattering_kernel(y, ydot, theta, thetadot, wavenumber, z_eq)
    ay, at, i0 = _add_columns(ay, at, cy, ct, packed, i0)
    cy, ct = _mirror_asymmetry_kernel(y, ydot, theta, thetadot, wavenumber, z_eq)
    ay, at, i0 = _add_columns(ay, at, cy, ct, packed, i0)
    cy, ct = _velocity_coupling_kernel(y, ydot, theta, thetadot, wavenumber, z_eq)
    ay, at, i0 = _add_columns(ay, at, cy, ct, packed, i0)
    a, b = _air_damping_kernel(ydot, theta, thetadot, packed[i0], packed[i0 + 1], packed[i0 + 2], packed[i0 + 3],
                               packed[i0 + 4])
    ry, rt = _registered_effects_sum(registered, y, ydot, theta, thetadot, wavenumber, z_eq, packed, i0 + 5)
    return ay + a + ry, at + b + rt
