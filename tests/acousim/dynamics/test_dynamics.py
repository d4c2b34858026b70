"""Equations of motion (docs/conventions.md section 4), the force-model protocol and the physics checks of the twin."""
import numpy as np
import pytest
from scipy.optimize import fsolve

from acousim.dynamics.integrator import DimerDynamics
from acousim.dynamics.effects import EffectSet
from acousim.dynamics.equations import accelerations
from acousim.force_model import ForceCoefficients, ForceModel
from acousim.gorkov.energy_surrogate import build_surrogate
from acousim.statics.sweep import taylor_coefficients

G = 9.81


@pytest.fixture(scope="module")
def surrogate(default_model):
    return build_surrogate(default_model)


@pytest.fixture(scope="module")
def bare(surrogate):
    return DimerDynamics(surrogate)


@pytest.fixture(scope="module")
def swept(default_model):
    """Linear stiffnesses from a static sweep of the mesh model (not from the surrogate)."""
    t = taylor_coefficients(default_model)
    return {"w2_y": -t["yddot"]["y"], "w2_theta": -t["thetaddot"]["theta"]}


def _frequency(t, x):
    """Mean frequency [Hz] from upward zero crossings of x - mean, linearly interpolated."""
    x = x - x.mean()
    k = np.flatnonzero((x[:-1] < 0) & (x[1:] >= 0))
    tc = t[k] - x[k] * (t[k + 1] - t[k]) / (x[k + 1] - x[k])
    return (len(tc) - 1) / (tc[-1] - tc[0])


class TabulatedForces:
    """A force model given only by its coefficient series (no potential), as a full-wave model is."""

    def __init__(self, sur):
        self._sur = sur
        self._coefs = sur.force_coefficients()
        for name in ("z_eq", "mass", "gravity", "wavenumber", "two_k", "inertia_const", "inertia_sin2",
                     "pressure_amplitude_pa", "settings"):
            setattr(self, name, getattr(sur, name))

    def force_coefficients(self):
        return self._coefs

    def generalized_forces(self, theta, y):
        q_y, q_t = self._coefs.evaluate(theta, np.asarray(y, float) + self.z_eq, self.two_k)
        return q_y - self.mass * self.gravity, q_t

    def hinge_inertia(self, theta):
        return self._sur.hinge_inertia(theta)

    def hinge_inertia_derivative(self, theta):
        return self._sur.hinge_inertia_derivative(theta)

    def with_pressure(self, p):
        return TabulatedForces(self._sur.with_pressure(p))

    def linear_frequencies(self):
        return self._sur.linear_frequencies()

    def escape_height(self):
        return self._sur.escape_height()

    def provenance(self):
        return {"source": "tabulated for the test"}


# ---------------------------------------------------------------------- the force-model protocol
def test_the_gorkov_surrogate_is_a_force_model(surrogate):
    assert isinstance(surrogate, ForceModel)
    assert not isinstance(object(), ForceModel)
    with pytest.raises(TypeError, match="not a ForceModel"):
        DimerDynamics(object())


def test_force_coefficients_reproduce_the_generalized_forces(surrogate):
    """Q = A + B cos 2kZ + C sin 2kZ (- M g for Q_y) from the Chebyshev series, over the whole box."""
    c = surrogate.force_coefficients()
    assert isinstance(c, ForceCoefficients) and len(c.as_tuple()) == 6
    assert c.q_y_a.tolist() == [0.0]  # a potential's Q_y + M g has no height-independent part
    tt, yy = np.meshgrid(np.linspace(-0.95, 0.95, 15), np.linspace(-1e-3, 8e-4, 13), indexing="ij")
    q_y, q_t = surrogate.generalized_forces(tt, yy)
    fy, ft = c.evaluate(tt, yy + surrogate.z_eq, surrogate.two_k)
    # the same sums with the factor 2k and the sign folded into the coefficients: round-off of max |Q|
    np.testing.assert_allclose(fy - surrogate.mass * surrogate.gravity, q_y, rtol=0, atol=1e-13 * np.abs(q_y).max())
    np.testing.assert_allclose(ft, q_t, rtol=0, atol=1e-13 * np.abs(q_t).max())


def test_a_force_model_without_a_potential_plugs_in(bare, surrogate):
    """The equations of motion and the compiled kernel need only the protocol."""
    tab = TabulatedForces(surrogate)
    assert isinstance(tab, ForceModel)
    effects = EffectSet.parse(["pair_scattering:kappa=12000", "linear_damping:gamma_y=0.3"])
    dyn, ref = DimerDynamics(tab, effects), bare.with_effects(effects)
    x0 = [-1.5e-4, -0.02, 0.2, 1.0]
    a, b = dyn.integrate(x0, 0.5, 1e-3), ref.integrate(x0, 0.5, 1e-3)
    np.testing.assert_array_equal(a.state, b.state)  # the same coefficients, the same kernel
    x = np.array([1.2e-4, 0.01, 0.6, 7.0])
    np.testing.assert_allclose(accelerations(tab, effects, x), ref.accelerations(x), rtol=1e-12)
    with pytest.raises(TypeError, match="no potential"):
        dyn.energy(x)


# ---------------------------------------------------------------------- the equations themselves
def test_numpy_and_compiled_right_hand_sides_agree(bare):
    rng = np.random.default_rng(0)
    dyn = bare.with_effects(EffectSet.parse(["pair_scattering:kappa=12000", "mirror_asymmetry:beta0=5,beta1=1e5",
                                             "velocity_coupling:c5=100,c6=1e5", "quadratic_drag:c_y=10,c_theta=0.1",
                                             "linear_damping:gamma_y=0.3,gamma_theta=0.8"]))
    for field_on in (True, False):
        for _ in range(20):
            x = np.array([rng.uniform(-8e-4, 6e-4), rng.uniform(-0.1, 0.1), rng.uniform(-0.9, 0.9), rng.uniform(-30, 30)])
            ay, at = dyn.accelerations(x, field_on)
            np.testing.assert_allclose(dyn.rhs(0, x, field_on), [x[1], ay, x[3], at], rtol=1e-12, atol=1e-15)


def test_lagrange_equations_with_theta_dependent_inertia(bare, surrogate, default_model):
    """thetaddot = [Q_theta - I'/2 thetadot^2] / I with the mesh model's Q and CubeDimer's I(theta)."""
    x = np.array([1.2e-4, 0.01, 0.6, 7.0])
    q = default_model.static_forces(x[2], x[0])
    dimer = default_model.dimer
    i, di = dimer.hinge_inertia(x[2]), dimer.hinge_inertia_derivative(x[2])
    ay, at = bare.accelerations(x)
    assert ay == pytest.approx(q.q_y / dimer.total_mass, rel=1e-10)
    # Q_theta ~ 1e-13 N m; the surrogate agrees with the mesh model to ~1e-9 of it
    assert at == pytest.approx((q.q_theta - 0.5 * di * x[3] ** 2) / i, rel=1e-7)
    np.testing.assert_allclose(surrogate.hinge_inertia(x[2]), i, rtol=1e-14)
    np.testing.assert_allclose(surrogate.hinge_inertia_derivative(x[2]), di, rtol=1e-12)


def test_free_fall_with_free_hinge(bare):
    t_off = 5e-3
    tr = bare.integrate([0.0, 0.0, 0.3, 4.0], t_off, t_off / 10, field_on=False)
    # RK4 is exact for y = -g t^2 / 2 (a polynomial of degree 2)
    np.testing.assert_allclose(tr.y, -0.5 * G * tr.t**2, rtol=1e-12, atol=1e-18)
    np.testing.assert_allclose(tr.state[:, 1], -G * tr.t, rtol=1e-12, atol=1e-18)
    # no torque: the hinge's kinetic energy I(theta) thetadot^2 / 2 is conserved (RK4 error ~ (h w)^5)
    kin = bare.force_model.hinge_inertia(tr.theta) * tr.state[:, 3] ** 2
    assert np.ptp(kin) / kin[0] < 1e-10


def test_compiled_rk4_matches_scipy_dop853(bare):
    dyn = bare.with_effects(EffectSet.parse(["pair_scattering:kappa=12000", "linear_damping:gamma_y=0.3,gamma_theta=0.3"]))
    x0 = [-1.5e-4, -0.02, 0.2, 1.0]
    tr = dyn.integrate(x0, 2.0, 1e-3)
    ref = dyn.integrate_scipy(x0, tr.t)
    # RK4 at 20 kHz: global error ~ (h w)^4 w t ~ 1e-9 relative over 40 periods
    np.testing.assert_allclose(tr.y, ref.y, rtol=0, atol=1e-8 * 1.5e-4 * 100)
    np.testing.assert_allclose(tr.theta, ref.theta, rtol=0, atol=1e-6 * 0.2)


# ---------------------------------------------------------------------- energy and damping
@pytest.mark.parametrize(
    "x0",
    [[3e-4, 0.0, 0.0, 0.0], [-2e-4, 0.01, 0.3, 0.5], [1e-4, 0.0, 0.85, 0.0], [-6e-4, 0.0, -0.5, 3.0]],
    ids=["y-only", "mixed", "large-theta", "large-y"],
)
def test_energy_is_conserved_without_effects(bare, x0):
    f_y = bare.force_model.linear_frequencies()[0]
    tr = bare.integrate(x0, 100 / f_y, 1e-3)
    assert tr.ok
    e = bare.energy(tr.state)
    # V = 0 at the equilibrium, so e[0] is the oscillation energy: the requirement is 1e-6
    # relative over 100 periods; RK4 at 20 kHz (h w_y = 0.007) drifts ~1e-10
    assert np.max(np.abs(e - e[0])) / e[0] < 1e-6
    assert np.max(np.abs(e - e[0])) / e[0] < 1e-8


def test_energy_check_detects_a_wrong_force(bare):
    """A 1 % error in the hinge force breaks T + V conservation visibly: the check can fail."""
    import dataclasses

    s = bare.force_model
    wrong = dataclasses.replace(s, beta=tuple(np.asarray(s.beta) * np.r_[1.0, np.full(len(s.beta) - 1, 1.01)]))
    # integrate the wrong dynamics, evaluate the energy of the right one
    x0 = [-2e-4, 0.0, 0.5, 0.0]
    tr = DimerDynamics(wrong).integrate(x0, 20.0, 1e-3)
    e = bare.energy(tr.state)
    assert np.max(np.abs(e - e[0])) / e[0] > 1e-6


@pytest.mark.parametrize("gamma_y", [0.3, 1.0])
def test_linear_damping_decay_rate_y(bare, gamma_y):
    dyn = bare.with_effects(EffectSet.parse([f"linear_damping:gamma_y={gamma_y}"]))
    tr = dyn.integrate([2e-5, 0.0, 0.0, 0.0], 4.0 / gamma_y, 1e-3)
    e = dyn.energy(tr.state)
    # dE/dt = -gamma_y M ydot^2, whose average over a period is -gamma_y E: E ~ exp(-gamma_y t)
    # with a ripple at 2 f_y that the straight-line fit over 87 periods averages to ~0.3 %
    slope = np.polyfit(tr.t, np.log(e), 1)[0]
    assert -slope == pytest.approx(gamma_y, rel=0.01)


@pytest.mark.parametrize("gamma_theta", [0.2, 0.5])
def test_linear_damping_decay_rate_theta(bare, gamma_theta):
    dyn = bare.with_effects(EffectSet.parse([f"linear_damping:gamma_theta={gamma_theta}",
                                             "pair_scattering:kappa=5000"]))
    tr = dyn.integrate([0.0, 0.0, 0.02, 0.0], 4.0 / gamma_theta, 1e-3)
    # small theta oscillation: its energy I thetadot^2/2 + I w^2 theta^2/2 decays at gamma_theta;
    # measured on the envelope of theta^2 + (thetadot / w)^2 (w from the run), which is ripple-free
    # to O(amplitude^2) for a linear oscillator
    w = 2 * np.pi * _frequency(tr.t, tr.theta)
    amp2 = tr.theta**2 + (tr.state[:, 3] / w) ** 2
    slope = np.polyfit(tr.t, np.log(amp2), 1)[0]
    assert -slope == pytest.approx(gamma_theta, rel=0.01)


# ---------------------------------------------------------------------- small oscillations
@pytest.mark.parametrize("kappa", [0.0, 12000.0])
def test_small_oscillation_frequencies_match_swept_stiffnesses(bare, swept, kappa):
    dyn = bare.with_effects(EffectSet.parse([f"pair_scattering:kappa={kappa}"]))
    k, z_eq = bare.force_model.wavenumber, bare.force_model.z_eq
    f_y_exp = np.sqrt(swept["w2_y"]) / (2 * np.pi)
    # pair_scattering adds kappa cos^2(k Z_eq) to the hinge's w^2 at the equilibrium
    f_t_exp = np.sqrt(swept["w2_theta"] + kappa * np.cos(k * z_eq) ** 2) / (2 * np.pi)
    ty = dyn.integrate([1e-6, 0.0, 0.0, 0.0], 5.0, 2e-4)
    tt = dyn.integrate([0.0, 0.0, 0.005, 0.0], 30.0 if kappa == 0 else 5.0, 2e-4)
    # amplitudes 1 um and theta 0.005: anharmonic shifts ~(k y)^2 ~ 1e-6 and ~theta^2 ~ 3e-5;
    # the zero-crossing estimate over >= 50 periods is good to ~1e-6
    assert _frequency(ty.t, ty.y) == pytest.approx(f_y_exp, rel=2e-4)
    assert _frequency(tt.t, tt.theta) == pytest.approx(f_t_exp, rel=2e-4)
    # and the check can fail: the pure Gor'kov hinge is ~13 x slower than with kappa = 12000
    if kappa:
        assert abs(f_t_exp / (np.sqrt(swept["w2_theta"]) / (2 * np.pi)) - 1) > 1.0


# ---------------------------------------------------------------------- symmetry
SYMMETRIC_EFFECTS = ["pair_scattering:kappa=12000", "linear_damping:gamma_y=0.3,gamma_theta=0.8",
                     "quadratic_drag:c_y=30,c_theta=0.05", "velocity_coupling:c5=5e3,c6=8e6"]


@pytest.mark.parametrize("effects", [[], SYMMETRIC_EFFECTS], ids=["bare", "symmetric-effects"])
def test_symmetric_start_stays_symmetric(bare, effects):
    dyn = bare.with_effects(EffectSet.parse(effects))
    tr = dyn.integrate([-3e-4, 0.02, 0.0, 0.0], 4.0, 5e-4)
    assert tr.ok and np.ptp(tr.y) > 1e-4
    # every theta term vanishes at theta = thetadot = 0 (the surrogate keeps only even terms in
    # theta), so the symmetric state is invariant exactly, not just to round-off
    assert np.all(tr.theta == 0.0) and np.all(tr.state[:, 3] == 0.0)


def test_mirror_asymmetry_breaks_the_symmetry(bare):
    dyn = bare.with_effects(EffectSet.parse(["mirror_asymmetry:beta1=1e5"]))
    tr = dyn.integrate([-3e-4, 0.0, 0.0, 0.0], 1.0, 5e-4)
    assert np.max(np.abs(tr.theta)) > 1e-3


@pytest.mark.parametrize(
    "effects",
    [
        ["mirror_asymmetry:beta0=10"],
        ["mirror_asymmetry:beta0=-10,beta1=3e5"],
        ["mirror_asymmetry:beta0=400,beta1=-1e6", "pair_scattering:kappa=5000"],
    ],
    ids=["beta0", "beta0-beta1", "with-pair-scattering"],
)
def test_mirror_asymmetry_equilibrium_is_the_static_balance(bare, default_model, effects):
    strong = ["linear_damping:gamma_y=40,gamma_theta=40"]
    dyn = bare.with_effects(EffectSet.parse(effects + strong))
    tr = dyn.integrate([0.0, 0.0, 0.0, 0.0], 8.0, 1e-3)
    y_end, th_end = tr.y[-1], tr.theta[-1]
    # static balance on the direct mesh model: yddot = 0 and thetaddot + effects = 0 at rest
    eff = EffectSet.parse(effects)
    k, z_eq = default_model.wave.wavenumber, default_model.equilibrium_height

    def balance(v):
        th, y = v[0], v[1] * 1e-6
        s = default_model.static_forces(th, y)
        _, et = eff.accelerations(y, 0.0, th, 0.0, k, z_eq)
        return [float(s.thetaddot + et), float(s.yddot)]

    th_s, y_s = fsolve(balance, [0.5 * th_end, 0.0], xtol=1e-12)
    y_s *= 1e-6
    assert abs(th_s) > 0.02  # the asymmetry really moves the hinge
    # settled: damping e^{-20 t} over 8 s leaves nothing; the surrogate's Q_theta is within ~1e-9
    assert th_end == pytest.approx(th_s, rel=1e-6)
    assert y_end == pytest.approx(y_s, rel=1e-4, abs=1e-12)
    # the surrogate's own equilibrium finder agrees
    eq = dyn.equilibrium(theta_guess=th_end)
    assert eq[2] == pytest.approx(th_s, rel=1e-6)


# ---------------------------------------------------------------------- leaving the trap
def test_falling_out_of_the_trap_is_reported(bare):
    tr = bare.integrate([0.0, -0.2, 0.0, 0.0], 1.0, 1e-3)
    assert tr.status == 1 and "fell out" in tr.message
    assert np.all(np.isfinite(tr.state)) and tr.y[-1] > bare.force_model.escape_height()


def test_hinge_closing_is_reported(bare):
    tr = bare.integrate([0.0, 0.0, 0.9, 40.0], 1.0, 1e-3)
    assert tr.status == 2 and np.all(np.abs(tr.theta) < 1)


def test_batch_equals_single_runs(bare):
    dyn = bare.with_effects(EffectSet.parse(["pair_scattering:kappa=12000", "linear_damping:gamma_y=0.3"]))
    x0s = np.array([[-1.5e-4, -0.02, 0.2, 1.0], [0.0, -0.2, 0.0, 0.0], [1e-4, 0.0, -0.3, 0.0]])
    states, n_valid, status = dyn.integrate_batch(x0s, 1.0, 1e-3)
    for i, x0 in enumerate(x0s):
        tr = dyn.integrate(x0, 1.0, 1e-3)
        assert n_valid[i] == len(tr.t) and status[i] == tr.status
        np.testing.assert_array_equal(states[i, : n_valid[i]], tr.state)  # identical arithmetic
    assert status.tolist() == [0, 1, 0]  # the second falls out of the trap
    assert np.all(np.isnan(states[1, n_valid[1]:]))
    # an extra bound on |y| stops the first run too
    _, nv, st = dyn.integrate_batch(x0s[:1], 1.0, 1e-3, y_bound=1e-4)
    assert nv[0] < 1001 and st[0] == 1


@pytest.mark.slow
def test_compiled_entry_points_are_cached_on_disk(tmp_path):
    """Worker processes load the compiled equations of motion from numba's cache."""
    from tests.cubedimer.test_rk4 import cache_hits_in_fresh_processes

    code = """
        import numpy as np
        import acousim.dynamics.integrator as d
        from acousim.dynamics.effects import EffectSet
        from acousim.gorkov.energy_surrogate import cached_surrogate
        dyn = d.DimerDynamics(cached_surrogate(), EffectSet.parse(["linear_damping:gamma_y=0.3"]))
        dyn.integrate([1e-4, 0, 0.1, 0], 0.01, 1e-3)
        dyn.integrate([1e-4, 0, 0.1, 0], 0.01, 1e-3, field_on=False)
        dyn.integrate_batch([[1e-4, 0, 0.1, 0]], 0.01, 1e-3)
        dyn.rhs(0.0, [1e-4, 0, 0.1, 0])
    """
    entries = "[d._integrate_field_on, d._integrate_field_off, d._integrate_field_on_batch, d.state_derivative]"
    first, second = cache_hits_in_fresh_processes(code, entries, tmp_path)
    assert first == 0 and second >= 4


def test_bad_arguments(bare):
    with pytest.raises(ValueError):
        bare.integrate([0, 0, 1.0, 0], 1.0, 1e-3)
    with pytest.raises(ValueError):
        bare.integrate([0, 0, 0, 0], 1.0, 0.0)
