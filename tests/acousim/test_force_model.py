"""The surrogates' common base (acousim.force_model.ChebyshevSurrogate): the Gor'kov and the full-wave surrogate hold
the same shared fields, declared once, and differ only in their own coefficients."""
from __future__ import annotations

from dataclasses import fields, replace

import pytest

from acousim.force_model import ChebyshevSurrogate
from acousim.fullwave.table import FullwaveSurrogate
from acousim.gorkov.energy_surrogate import ForceSurrogate
from acousim.models import ExperimentConditions, dynamic_model

SHARED = ("two_k", "wavenumber", "z_eq", "mass", "gravity", "inertia_const", "inertia_sin2", "pressure_amplitude_pa",
          "settings", "build_accuracy")
OWN = {ForceSurrogate: {"alpha", "beta", "gamma", "box"}, FullwaveSurrogate: {"coefficients", "theta_max", "nodes"}}


@pytest.mark.parametrize("surrogate", list(OWN))
def test_the_shared_fields_are_the_bases_and_keyword_only(surrogate):
    base = {f.name: f for f in fields(ChebyshevSurrogate)}
    assert tuple(base) == SHARED
    mine = {f.name: f for f in fields(surrogate)}
    assert set(mine) == set(SHARED) | OWN[surrogate]
    for name in SHARED:  # the very field objects of the base: same type, default, comparison and keyword-only
        assert mine[name] is base[name] and mine[name].kw_only
    assert not any(mine[name].kw_only for name in OWN[surrogate])  # the own coefficients stay positional


@pytest.mark.parametrize("name", ["gorkov", "fullwave"])
def test_both_models_answer_the_shared_fields_alike(name):
    """The same experiment gives both surrogates the same k, mass and gravity (the hinge inertia differs: the
    full-wave dimer's arm is d + g/2); the bookkeeping dicts take no part in equality."""
    model = dynamic_model(name, ExperimentConditions())
    sur = getattr(model, "surrogate", model)
    assert isinstance(sur, ChebyshevSurrogate)
    gorkov = dynamic_model("gorkov", ExperimentConditions())
    assert sur.two_k == 2 * sur.wavenumber == gorkov.two_k
    assert sur.mass == pytest.approx(gorkov.mass, rel=1e-12) and sur.gravity == gorkov.gravity  # same cubes, same g
    assert sur.z_eq < 0 and sur.pressure_amplitude_pa == ExperimentConditions().pressure_amplitude_pa
    assert replace(sur, settings={"other": 1}, build_accuracy={}) == sur
