"""The unmodelled effects of docs/conventions.md section 5: names, parameters, formulas, parsing, composition."""
from dataclasses import dataclass
from typing import Callable, ClassVar

import numpy as np
import pytest

from acousim.dynamics.integrator import DimerDynamics
from acousim.dynamics.air_damping import hinge_damping_shape
from acousim.dynamics.compiled_effects import packed_effect_accelerations, registered_effect_kernels
from acousim.dynamics.effects import (EFFECT_TYPES, PACKED_PARAMETERS, AirDamping, Effect, EffectError, EffectSet,
                             LinearDamping, MirrorAsymmetry, PairScattering, QuadraticDrag, VelocityCoupling,
                             packed_parameters, parse_effect, register_effect)
from acousim.gorkov.energy_surrogate import cached_surrogate

K = 836.2315139147175  # wavenumber at 45.65 kHz, 343 m/s [1/m]
Z_EQ = -4.2888847763325813e-4  # default equilibrium height [m]

# docs/conventions.md section 5, verbatim: names and parameter names are part of the file formats
PHYSICS_TABLE = {
    "linear_damping": ("gamma_y", "gamma_theta"),
    "quadratic_drag": ("c_y", "c_theta"),
    "pair_scattering": ("kappa",),
    "mirror_asymmetry": ("beta0", "beta1"),
    "velocity_coupling": ("c5", "c6"),
    "air_damping": ("gamma_y", "gamma_theta", "sway_ratio", "wedge_ratio", "gap_ratio"),
}


def test_names_and_parameters_are_those_of_physics_md():
    assert {n: c.parameter_names() for n, c in EFFECT_TYPES.items()} == PHYSICS_TABLE
    assert [n for n, _ in PACKED_PARAMETERS] == [n for n, ps in PHYSICS_TABLE.items() for _ in ps]


def _expected(name, p, y, yd, th, thd):
    """The docs/conventions.md formulas written out independently."""
    zero = 0.0 * y
    if name == "linear_damping":
        return -p["gamma_y"] * yd, -p["gamma_theta"] * thd
    if name == "quadratic_drag":
        return -p["c_y"] * abs(yd) * yd, -p["c_theta"] * abs(thd) * thd
    if name == "pair_scattering":
        return zero, -p["kappa"] * np.cos(K * (Z_EQ + y)) ** 2 * th
    if name == "mirror_asymmetry":
        return zero, p["beta0"] + p["beta1"] * y
    if name == "velocity_coupling":
        return zero, p["c5"] * thd**2 * y + p["c6"] * thd * yd * y
    if name == "air_damping":  # the shape itself is checked against its limits in test_air_damping.py
        shape = np.vectorize(hinge_damping_shape)(th, p["gap_ratio"], p["sway_ratio"], p["wedge_ratio"])
        return -p["gamma_y"] * yd + zero, -p["gamma_theta"] * shape * thd
    raise AssertionError(name)


EXAMPLES = [
    LinearDamping(gamma_y=0.3, gamma_theta=0.8),
    QuadraticDrag(c_y=40.0, c_theta=0.05),
    PairScattering(kappa=12000.0),
    MirrorAsymmetry(beta0=60.0, beta1=1.5e6),
    VelocityCoupling(c5=5.0e3, c6=8.0e6),
    AirDamping(gamma_y=0.6, gamma_theta=1.3, sway_ratio=1.8, wedge_ratio=0.47, gap_ratio=0.03),
]
#: the effects the diagnosis fits (linear in every parameter)
CANDIDATES = [e for e in EXAMPLES if e.candidate]


@pytest.mark.parametrize("effect", EXAMPLES, ids=lambda e: e.name)
def test_effect_terms_follow_physics_md(effect):
    rng = np.random.default_rng(1)
    y, yd, th, thd = rng.uniform(-3e-4, 3e-4, 20), rng.uniform(-0.05, 0.05, 20), rng.uniform(-0.8, 0.8, 20), rng.uniform(-20, 20, 20)
    got = effect.accelerations(y, yd, th, thd, K, Z_EQ)
    exp = _expected(effect.name, effect.params(), y, yd, th, thd)
    np.testing.assert_allclose(got[0], exp[0], rtol=1e-14, atol=0)
    np.testing.assert_allclose(got[1], exp[1], rtol=1e-14, atol=0)


@pytest.mark.parametrize("effect", EXAMPLES, ids=lambda e: e.name)
def test_compiled_rhs_adds_exactly_the_effect(effect):
    """The compiled integrator's right-hand side differs from the bare model by the effect's terms."""
    sur = cached_surrogate()
    bare = DimerDynamics(sur)
    dyn = DimerDynamics(sur, EffectSet((effect,)))
    rng = np.random.default_rng(2)
    for _ in range(10):
        x = np.array([rng.uniform(-3e-4, 3e-4), rng.uniform(-0.05, 0.05), rng.uniform(-0.8, 0.8), rng.uniform(-20, 20)])
        d = dyn.rhs(0.0, x) - bare.rhs(0.0, x)
        ey, et = _expected(effect.name, effect.params(), *x)
        # the difference of two accelerations of size ~|Q/M| ~ 20 m/s^2 loses ~1e-15 of them
        assert d[1] == pytest.approx(ey, abs=1e-12)
        assert d[3] == pytest.approx(et, rel=1e-9, abs=1e-9)
        assert d[0] == 0.0 and d[2] == 0.0  # dy/dt = ydot, dtheta/dt = thetadot untouched


def _states(seed, n=20):
    rng = np.random.default_rng(seed)
    return rng.uniform(-3e-4, 3e-4, n), rng.uniform(-0.05, 0.05, n), rng.uniform(-0.8, 0.8, n), rng.uniform(-20, 20, n)


def test_every_effect_type_has_an_example():
    assert sorted(e.name for e in EXAMPLES) == sorted(EFFECT_TYPES)


@pytest.mark.parametrize("effect", CANDIDATES, ids=lambda e: e.name)
def test_regressors_are_the_linear_form_of_the_accelerations(effect):
    """accelerations == regressors @ parameters: the columns the diagnosis fits are the effect itself."""
    x = _states(5)
    reg = type(effect).regressors(*x, K, Z_EQ)
    assert reg.shape == (20, 2, len(effect.parameter_names()))
    ay, at = effect.accelerations(*x, K, Z_EQ)
    pred = reg @ effect.parameter_vector()
    np.testing.assert_allclose(pred[:, 0], ay, rtol=1e-14, atol=0)
    np.testing.assert_allclose(pred[:, 1], at, rtol=1e-14, atol=0)
    # column j is the effect with parameter j at 1 and the others at 0, checked against docs/conventions.md
    for j, p in enumerate(effect.parameter_names()):
        unit = {q: float(q == p) for q in effect.parameter_names()}
        ey, et = _expected(effect.name, unit, *x)
        np.testing.assert_allclose(reg[:, 0, j], ey + 0 * x[0], rtol=1e-14, atol=0)
        np.testing.assert_allclose(reg[:, 1, j], et + 0 * x[0], rtol=1e-14, atol=0)


def test_the_equilibrium_height_may_vary_per_state():
    """The diagnosis passes Z_eq per sample (its lab origin minus the data's y)."""
    x = _states(8)
    z_eq = Z_EQ + np.linspace(-1e-5, 1e-5, 20)
    reg = PairScattering.regressors(*x, K, z_eq)
    np.testing.assert_allclose(reg[:, 1, 0], -np.cos(K * (z_eq + x[0])) ** 2 * x[2], rtol=1e-14)
    ay, at = EffectSet((PairScattering(kappa=2.0),)).accelerations(*x, K, z_eq)
    np.testing.assert_allclose(at, 2.0 * reg[:, 1, 0], rtol=1e-14)


def test_set_regressors_stack_the_effects():
    s = EffectSet(tuple(CANDIDATES))
    x = _states(6)
    reg = s.regressors(*x, K, Z_EQ)
    candidate_parameters = tuple(q for q in PACKED_PARAMETERS if EFFECT_TYPES[q[0]].candidate)
    assert reg.shape == (20, 2, len(candidate_parameters))
    assert s.parameter_names() == candidate_parameters
    np.testing.assert_array_equal(s.parameter_vector(), s.packed()[:len(candidate_parameters)])
    ay, at = s.accelerations(*x, K, Z_EQ)
    pred = reg @ s.parameter_vector()
    np.testing.assert_allclose(pred[:, 0], ay, rtol=1e-13, atol=1e-300)
    np.testing.assert_allclose(pred[:, 1], at, rtol=1e-13, atol=1e-300)
    assert EffectSet().regressors(*x, K, Z_EQ).shape == (20, 2, 0)


@pytest.mark.parametrize("name", list(EFFECT_TYPES))
def test_compiled_sum_uses_every_effect_definition(name):
    """The compiled packed sum adds exactly the numpy terms of each effect type, at its packed slot."""
    effect = next(e for e in EXAMPLES if e.name == name)
    packed = EffectSet((effect,)).packed()
    for y, yd, th, thd in zip(*_states(7, 10)):
        got = packed_effect_accelerations(y, yd, th, thd, K, Z_EQ, packed, ())
        exp = effect.accelerations(y, yd, th, thd, K, Z_EQ)
        # same columns, same products; only the order of the additions of zeros may differ
        np.testing.assert_allclose(got, [float(exp[0]), float(exp[1])], rtol=1e-14, atol=1e-300)


def test_only_the_air_acts_without_the_field():
    s = EffectSet(tuple(EXAMPLES))
    assert s.acting(field_on=False).names == ("linear_damping", "quadratic_drag", "air_damping")
    assert s.acting(field_on=True) == s


def test_any_subset_composes_additively():
    rng = np.random.default_rng(4)
    x = (rng.uniform(-3e-4, 3e-4, 8), rng.uniform(-0.05, 0.05, 8), rng.uniform(-0.8, 0.8, 8), rng.uniform(-20, 20, 8))
    for mask in range(1 << len(EXAMPLES)):
        subset = tuple(e for i, e in enumerate(EXAMPLES) if mask >> i & 1)
        total = EffectSet(subset).accelerations(*x, K, Z_EQ)
        parts = [e.accelerations(*x, K, Z_EQ) for e in subset]
        for j in (0, 1):
            np.testing.assert_allclose(total[j], sum((p[j] for p in parts), np.zeros(8)), rtol=1e-13, atol=1e-300)


def test_parse_round_trip_and_order():
    s = EffectSet.parse(["velocity_coupling:c6=8e6", "pair_scattering:kappa=12000",
                         "linear_damping:gamma_y=0.3,gamma_theta=0.8"])
    # stored in docs/conventions.md order; missing parameters are 0
    assert s.names == ("linear_damping", "pair_scattering", "velocity_coupling")
    assert s.to_dict() == {"linear_damping": {"gamma_y": 0.3, "gamma_theta": 0.8},
                           "pair_scattering": {"kappa": 12000.0},
                           "velocity_coupling": {"c5": 0.0, "c6": 8e6}}
    assert EffectSet.from_dict(s.to_dict()) == s
    assert s.packed().tolist() == [0.3, 0.8, 0, 0, 12000.0, 0, 0, 0.0, 8e6, 0, 0, 0, 0, 0]
    assert EffectSet().packed().tolist() == [0.0] * 14
    assert "pair_scattering" in s and s["pair_scattering"].kappa == 12000.0


def test_merge_replaces_same_name():
    a = EffectSet.parse(["pair_scattering:kappa=1", "linear_damping:gamma_y=1"])
    b = EffectSet.parse(["pair_scattering:kappa=2"])
    assert a.merged(b).to_dict() == {"linear_damping": {"gamma_y": 1.0, "gamma_theta": 0.0},
                                     "pair_scattering": {"kappa": 2.0}}


@pytest.mark.parametrize(
    "spec, fragment",
    [
        ("pair_scatering:kappa=1", "unknown effect 'pair_scatering'"),
        ("pair_scattering:k=1", "unknown parameter 'k'"),
        ("linear_damping:gamma_y=fast", "must be a number"),
        ("linear_damping:gamma_y", "expected param=value"),
        ("linear_damping:gamma_y=-0.1", "must be >= 0"),
        ("quadratic_drag:c_y=nan", "must be finite"),
        ("mirror_asymmetry:beta0=1,beta0=2", "given twice"),
    ],
)
def test_bad_specs_give_one_line_errors(spec, fragment):
    with pytest.raises(EffectError) as err:
        parse_effect(spec)
    assert fragment in str(err.value) and "\n" not in str(err.value)


def test_duplicate_effect_in_a_set_is_rejected():
    with pytest.raises(EffectError, match="more than once"):
        EffectSet.parse(["pair_scattering:kappa=1", "pair_scattering:kappa=2"])


def test_effects_are_frozen_and_hashable():
    e = PairScattering(kappa=1.0)
    with pytest.raises(Exception):
        e.kappa = 2.0
    assert hash(EffectSet((e,))) == hash(EffectSet((PairScattering(kappa=1.0),)))


def test_air_damping_is_computed_not_fitted():
    """air_damping has no regressors (the diagnosis fits linear_damping) and needs its gap for the wedge term."""
    with pytest.raises(EffectError, match="computed, not fitted"):
        AirDamping.regressors(*_states(1), K, Z_EQ)
    with pytest.raises(EffectError, match="gap_ratio"):
        AirDamping(gamma_theta=1.0, wedge_ratio=0.5, gap_ratio=0.0)
    assert AirDamping.acts_without_field and not AirDamping.candidate
    # without the wedge term it is plain linear damping, also from the command-line form
    e = parse_effect("air_damping:gamma_y=0.5,gamma_theta=1.0")
    ay, at = e.accelerations(0.0, 0.1, 0.0, 2.0, K, Z_EQ)
    assert (float(ay), float(at)) == (-0.05, -2.0)


# ---- a new effect through the registry alone --------------------------------------------------------------------

def _hardening_columns(y, ydot, theta, thetadot, wavenumber, z_eq):
    """A cubic stiffening of the trap and of the hinge: (-a y^3, -b theta^3)."""
    return (-y * y * y, 0.0), (0.0, -theta * theta * theta)


@dataclass(frozen=True)
class CubicHardening(Effect):
    """A test effect that is not in docs/conventions.md: yddot += -a y^3, thetaddot += -b theta^3."""

    name: ClassVar[str] = "cubic_hardening"
    columns: ClassVar[Callable] = staticmethod(_hardening_columns)
    a: float = 0.0
    b: float = 0.0


@pytest.fixture
def registered_hardening():
    register_effect(CubicHardening)
    yield CubicHardening
    EFFECT_TYPES.pop(CubicHardening.name)


def test_register_effect_refuses_what_it_cannot_integrate(registered_hardening):
    with pytest.raises(EffectError, match="registered already"):
        register_effect(CubicHardening)
    with pytest.raises(EffectError, match="not an Effect subclass"):
        register_effect(dict)
    assert parse_effect("cubic_hardening:b=2").params() == {"a": 0.0, "b": 2.0}


def test_a_registered_effect_gets_the_slots_after_the_compiled_ones(registered_hardening):
    assert packed_parameters() == PACKED_PARAMETERS + (("cubic_hardening", "a"), ("cubic_hardening", "b"))
    s = EffectSet((PairScattering(kappa=3.0), CubicHardening(a=1e9, b=40.0)))
    assert s.packed().tolist()[-2:] == [1e9, 40.0]
    assert s.packed()[PACKED_PARAMETERS.index(("pair_scattering", "kappa"))] == 3.0
    assert len(registered_effect_kernels()) == 1


def test_a_registered_effect_is_integrated_by_the_equations_of_motion(registered_hardening):
    """No line of code beyond the class and its registration: the compiled equations of motion (the twin's) add
    the new effect exactly as its numpy definition does, beside a compiled one."""
    effect = CubicHardening(a=3e9, b=4e4)
    effects = EffectSet((LinearDamping(gamma_y=0.3, gamma_theta=0.8), effect))
    packed, kernels = effects.packed(), registered_effect_kernels()
    for y, yd, th, thd in zip(*_states(8, 11)):
        got = packed_effect_accelerations(y, yd, th, thd, K, Z_EQ, packed, kernels)
        exp = effects.accelerations(y, yd, th, thd, K, Z_EQ)
        # the same products summed in another order: round-off only
        np.testing.assert_allclose(got, [float(exp[0]), float(exp[1])], rtol=1e-13, atol=1e-300)
    dyn = DimerDynamics(cached_surrogate(), effects)
    bare = DimerDynamics(cached_surrogate(), EffectSet((LinearDamping(gamma_y=0.3, gamma_theta=0.8),)))
    x = np.array([1e-4, 0.01, 0.4, 3.0])
    d_new, d_bare = dyn.rhs(0.0, x), bare.rhs(0.0, x)
    # the difference of the two right-hand sides is exactly the new effect's term (-a y^3, -b theta^3)
    np.testing.assert_allclose(d_new[[1, 3]] - d_bare[[1, 3]], [-3e9 * 1e-12, -4e4 * 0.064], rtol=1e-9)
    # and the twin's integrator runs it: the hardened hinge, started at rest at theta = 0.4, keeps its energy
    # bounded and swings back through theta = 0 within a period
    traj = dyn.integrate([0.0, 0.0, 0.4, 0.0], 0.2, 1e-4)
    assert traj.ok and traj.state[:, 2].min() < 0.0
