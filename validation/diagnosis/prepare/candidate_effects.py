"""The candidate effects of docs/conventions.md section 5 as linear regressors of the accelerations.

Every candidate effect is linear in its parameters, so its added accelerations at given states are
``effect_regressors(...) @ params`` and every fit of the diagnosis is a linear least-squares problem at
the measured states.  The columns are those of :meth:`acousim.dynamics.effects.Effect.regressors` (the one definition of each
effect); this module only chooses the effects' y (measured from the calibrated equilibrium).
"""
from __future__ import annotations

from typing import Iterator, Mapping, Sequence

import numpy as np
from numpy.typing import NDArray

from acousim.dynamics.effects import EFFECT_TYPES

from .cavity_lag import CAVITY_LAG_PARAMETERS, height_expansion as _cavity_height_expansion, problem_columns

__all__ = ["CANDIDATE_EFFECTS", "MODEL_CANDIDATES", "default_candidates", "LIBRARY_EQUIVALENTS", "LEADING_LIBRARY_TERMS", "own_library_columns", "effect_regressors", "HEIGHT_EXPANSIONS", "height_expansion", "ALIAS_CANDIDATES", "alias_partners", "parameter_slots", "acting_components", "parameter_vector"]


def _is_candidate(cls: type) -> bool:
    """Whether the diagnosis fits the effect class (linear in every parameter; an effect computed from physics
    sets ``candidate = False``)."""
    return bool(getattr(cls, "candidate", True))


#: Candidates whose columns need the force model, not the state alone: name -> (parameters, equations it acts in).
#: ``cavity_lag``: the levitator's cavity responding to the dimer with a lag
#: (:mod:`validation.diagnosis.prepare.cavity_lag`, from acousim's resonator equations).
MODEL_CANDIDATES: dict[str, tuple[tuple[str, ...], tuple[int, ...]]] = {
    "cavity_lag": (CAVITY_LAG_PARAMETERS, (0, 1)),
}
#: Candidates whose columns depend on the origin height through a few fixed blocks of columns
#: (:func:`height_expansion`): name -> ``(problem, runs, q) -> HeightExpansion | None``.
HEIGHT_EXPANSIONS = {"cavity_lag": _cavity_height_expansion}


class _RegisteredEffects(Mapping[str, tuple[str, ...]]):
    """Effect name -> its parameter names, read from :data:`acousim.dynamics.effects.EFFECT_TYPES` on every access: the one
    registry of effects, so that an effect registered there is a candidate of the diagnosis without a copy here."""

    def __getitem__(self, name: str) -> tuple[str, ...]:
        if name in MODEL_CANDIDATES:
            return MODEL_CANDIDATES[name][0]
        cls = EFFECT_TYPES[name]
        if not _is_candidate(cls):
            raise KeyError(name)
        return cls.parameter_names()

    def __iter__(self) -> Iterator[str]:
        return iter([n for n, cls in EFFECT_TYPES.items() if _is_candidate(cls)] + list(MODEL_CANDIDATES))

    def __len__(self) -> int:
        return sum(_is_candidate(cls) for cls in EFFECT_TYPES.values()) + len(MODEL_CANDIDATES)

    def __repr__(self) -> str:
        return repr(dict(self))


#: Candidate effects and their parameters (docs/conventions.md section 5): every effect registered in
#: :data:`acousim.dynamics.effects.EFFECT_TYPES` that the diagnosis can fit (``candidate``, True unless the effect says not).
CANDIDATE_EFFECTS: Mapping[str, tuple[str, ...]] = _RegisteredEffects()


def default_candidates() -> tuple[str, ...]:
    """The candidates a diagnosis tries unless told: every registered effect; the cavity's lag
    (:data:`MODEL_CANDIDATES`) only when asked for, until the blind check has measured its false alarms."""
    return tuple(n for n in CANDIDATE_EFFECTS if n not in MODEL_CANDIDATES)


#: Library terms (per equation) whose columns are a candidate's own, up to the sign: linear damping's
#: ``-gamma_y ydot`` and ``-gamma_theta thetadot``.  A candidate is not judged against its own copy.
LIBRARY_EQUIVALENTS: dict[str, dict[str, tuple[str, ...]]] = {
    "linear_damping": {"yddot": ("ydot",), "thetaddot": ("thetadot",)},
}

#: Library terms (per equation) that a candidate's columns reduce to near the levitation height, beyond the exact
#: copies above: pair scattering's ``-kappa cos^2(k Z_com) theta`` is ``theta`` times a constant up to terms in
#: ``y theta``; mirror asymmetry's ``beta0 + beta1 y`` and velocity coupling's ``y thetadot^2`` and
#: ``y ydot thetadot`` (y from the calibrated levitation height, so ``1`` takes the origin's difference).  A
#: discovered term that is one of them, beside the identified effect, splits the effect's parameter: the final joint
#: model folds it into the effect (:func:`~validation.diagnosis.discover.joint_model.joint_estimates`).
LEADING_LIBRARY_TERMS: dict[str, dict[str, tuple[str, ...]]] = {
    "pair_scattering": {"thetaddot": ("theta",)},
    "mirror_asymmetry": {"thetaddot": ("1", "y")},
    "velocity_coupling": {"thetaddot": ("y*thetadot^2", "y*ydot*thetadot")},
}


#: Candidates that can stand for one another on a data set, so that the one the greedy rounds did not choose is checked
#: beside the chosen one (:func:`alias_partners`): the cavity's lag damps y with a rate that varies over a cycle as
#: F_Z^2, which runs at one amplitude do not resolve from linear damping's constant rate (measured on twin data with
#: linear damping of y alone at one drop amplitude: the greedy rounds chose the cavity, and nothing was named).
ALIAS_CANDIDATES: dict[str, tuple[str, ...]] = {"cavity_lag": ("linear_damping",), "linear_damping": ("cavity_lag",)}


def alias_partners(chosen: Sequence[str], candidates: Sequence[str]) -> list[str]:
    """The candidates (among ``candidates``) that the greedy rounds did not choose but that can stand for a chosen
    effect (:data:`ALIAS_CANDIDATES`): the backward check tests them beside it, so that the two are one
    indistinguishable verdict where the data cannot tell them apart, and the better one is named where they can."""
    out: list[str] = []
    for name in chosen:
        out += [c for c in ALIAS_CANDIDATES.get(name, ()) if c in candidates and c not in chosen and c not in out]
    return out


def own_library_columns(effects: Sequence[str]) -> dict[str, list[str]]:
    """Per equation, the library terms that stand for the columns of ``effects`` (:data:`LIBRARY_EQUIVALENTS` and
    :data:`LEADING_LIBRARY_TERMS`)."""
    out: dict[str, list[str]] = {"yddot": [], "thetaddot": []}
    for name in effects:
        for table in (LIBRARY_EQUIVALENTS, LEADING_LIBRARY_TERMS):
            for eq, terms in table.get(name, {}).items():
                out[eq] += [t for t in terms if t not in out[eq]]
    return out


def effect_regressors(name: str, state: NDArray, z_com: NDArray, wavenumber: float,
                      z_eq: float | None = None, problem=None) -> NDArray[np.float64]:
    """d(accelerations)/d(parameters) of one effect: array (n, 2, n_params).

    :meth:`acousim.dynamics.effects.Effect.regressors` of the effect at the effects' y = Z_com - Z_eq.  Columns follow ``CANDIDATE_EFFECTS[name]``; the two rows are the yddot [m/s^2 per unit
    parameter] and thetaddot [1/s^2 per unit parameter] equations.

    Parameters
    ----------
    name : str
        A key of :data:`CANDIDATE_EFFECTS`.
    state : array (n, 4)
        [y, ydot, theta, thetadot] (SI).
    z_com : array (n,) or float
        Height of the centre of mass above the pressure node [m].
    wavenumber : float
        k of the standing wave [1/m].
    z_eq : float, optional
        Equilibrium height of the (calibrated) simulation [m]: the effects' y is ``Z_com - Z_eq`` as in
        docs/conventions.md (default: the state's own y, i.e. Z_eq = Z_com - y).
    problem : DiagnosisProblem, optional
        Needed by the candidates of :data:`MODEL_CANDIDATES`, whose columns come from the force model at nominal
        pressure (:meth:`DiagnosisProblem.surrogate`) at the absolute height ``z_com``.
    """
    if name not in CANDIDATE_EFFECTS:
        raise ValueError(f"unknown effect {name!r}; candidates are {', '.join(CANDIDATE_EFFECTS)}")
    if name in MODEL_CANDIDATES:
        if problem is None:
            raise ValueError(f"the candidate {name} needs the diagnosis problem's force model")
        # the cavity's detuning x is defined with the dimer at rest: at the calibrated equilibrium (the data's
        # origin when none is given)
        return problem_columns(problem, state, z_com, z_eq)
    y, yd, th, thd = np.asarray(state, float).T
    z_com = np.broadcast_to(np.asarray(z_com, float), y.shape)
    if z_eq is None:
        y_eff, z_ref = y, z_com - y
    else:
        y_eff, z_ref = z_com - z_eq, z_eq
    return EFFECT_TYPES[name].regressors(y_eff, yd, th, thd, wavenumber, z_ref)


def height_expansion(name: str, problem, runs, q: int):
    """The integral-form columns of coordinate q of effect ``name`` on ``runs`` at every origin height z0, the
    effects' y from the data's origin, as fixed blocks with weights in z0
    (:class:`~validation.diagnosis.prepare.cavity_lag.HeightExpansion`); None when the effect has none (its columns
    are then evaluated at each trial height)."""
    build = HEIGHT_EXPANSIONS.get(name)
    return None if build is None else build(problem, runs, q)


def parameter_slots(effects: Sequence[str], eq: int) -> list[tuple[str, str, int]]:
    """(effect, parameter, column) of the parameters of ``effects`` that act in equation ``eq`` (0: yddot,
    1: thetaddot); columns count from 1 for the y equation, whose column 0 is the pressure term."""
    out, col = [], (1 if eq == 0 else 0)
    for n in effects:
        if n in MODEL_CANDIDATES:
            probe = np.full(len(CANDIDATE_EFFECTS[n]), float(eq in MODEL_CANDIDATES[n][1]))
        else:
            probe = effect_regressors(n, np.ones((1, 4)), np.zeros(1), 1.0)[0, eq, :]
        for p_i, p in enumerate(CANDIDATE_EFFECTS[n]):
            if probe[p_i] != 0:
                out.append((n, p, col))
            col += 1
    return out


def acting_components(name: str) -> list[int]:
    """Gap components an effect acts in: y (0) and theta (1) where it has parameters, and the energy (2)."""
    return [q for q in (0, 1) if parameter_slots([name], q)] + [2]


def parameter_vector(params: dict[str, dict[str, float]], names: Sequence[str] | None = None) -> NDArray[np.float64]:
    """The parameters of ``names`` (default: every effect in ``params``), concatenated in the order of
    :data:`CANDIDATE_EFFECTS`' parameter lists."""
    names = list(params) if names is None else list(names)
    return np.array([params[n][p] for n in names for p in CANDIDATE_EFFECTS[n]], float)
