"""The field's switching (acousim.dynamics.switching): ring time, forces scaling exactly with p(t)^2, the drop's motion."""
import math

import numpy as np
import pytest

from acousim.atlas.field_drops import atlas_dynamics
from acousim.dynamics.integrator import DimerDynamics
from acousim.dynamics.switching import (DEFAULT_TRANSDUCER_Q, field_drop, pressure_ratio, ring_time,
                               switching_acceleration)

P0 = 3000.0


@pytest.fixture(scope="module")
def dyn():
    """The family's 500 um, g/s 0.02 dimer at 3 kPa with the air's computed damping."""
    return atlas_dynamics(500e-6, 0.02, P0, 45_650.0)


def test_ring_time_and_envelope():
    # tau = Q / (pi f): 1.74 ms for the stated Q = 250 at 45.65 kHz; the range Q 150-400 gives 1.0-2.8 ms
    assert ring_time(DEFAULT_TRANSDUCER_Q, 45_650.0) == pytest.approx(250 / (math.pi * 45_650.0), rel=1e-15)
    assert 1.0e-3 < ring_time(150, 45_650.0) < ring_time(400, 45_650.0) < 2.8e-3
    assert ring_time(0, 45_650.0) == 0.0
    t = np.array([0.0, 1e-3, 5e-3])
    np.testing.assert_allclose(pressure_ratio(t, 1e-3, 1.0, 0.0), np.exp(-t / 1e-3), rtol=1e-15)
    np.testing.assert_allclose(pressure_ratio(t, 1e-3, 0.2, 1.0), 1 - 0.8 * np.exp(-t / 1e-3), rtol=1e-15)
    with pytest.raises(ValueError):
        ring_time(-1, 45_650.0)


def test_forces_scale_exactly_with_the_pressure_squared(dyn):
    """The switching accelerations at s = (p/p0)^2 equal the accelerations of the same dimer built at pressure p
    (its forces scale as p^2 by construction, and its equilibrium height moves: compared at the same absolute
    height), and at s = 0 those with the field off.  Sums of the same floating-point terms up to the p^2
    scaling: equal to ~1e-12 of the trap's accelerations (9.81 m/s^2, ~1e4 1/s^2)."""
    fm = dyn.force_model
    rng = np.random.default_rng(3)
    for s in (0.0, 0.6, 0.81, 1.0):   # below ~0.5 the field no longer holds the dimer: no model at that pressure
        for _ in range(4):
            y, yd, th, thd = rng.uniform(-3e-4, 3e-4), rng.uniform(-0.05, 0.05), rng.uniform(-0.6, 0.6), \
                rng.uniform(-30, 30)
            got = np.array(switching_acceleration(y, yd, th, thd, s, dyn._args_on, dyn._args_off))
            if s == 0:  # no field: gravity, the free hinge and the air
                ref = np.array(dyn.accelerations(np.array([y, yd, th, thd]), field_on=False), float)
            else:
                at_p = DimerDynamics(fm.with_pressure(P0 * math.sqrt(s)), dyn.effects)
                y_p = y + fm.z_eq - at_p.force_model.z_eq
                ref = np.array(at_p.accelerations(np.array([y_p, yd, th, thd]), field_on=True), float)
            assert np.all(np.abs(got - ref) <= 1e-12 * np.array([fm.gravity, 1e4])), (s, got, ref)
    # and linearly in s between the two ends, so the acoustic part is exactly s times the full field's
    x = (1e-4, 0.01, 0.2, 5.0)
    on, off = (np.array(switching_acceleration(*x, s, dyn._args_on, dyn._args_off)) for s in (1.0, 0.0))
    half = np.array(switching_acceleration(*x, 0.25, dyn._args_on, dyn._args_off))
    np.testing.assert_allclose(half, off + 0.25 * (on - off), rtol=1e-14)


def test_the_compiled_ring_up_matches_scipy(dyn):
    """field_drop's envelope RK4 (20 kHz internal steps) against solve_ivp (DOP853, rtol 1e-11) on the same
    time-dependent right-hand side: RK4's global error at h omega ~ 0.02 is ~1e-8 of the amplitude."""
    from scipy.integrate import solve_ivp

    tau, t_off = 1.5e-3, 3e-3
    motion = field_drop(dyn, [0, 0, 0.1, 0], t_off, 0.05, 1e-3, tau=tau)
    assert motion.ok and motion.pressure_at_field_on == pytest.approx(math.exp(-t_off / tau), rel=1e-15)

    def rhs(a_start, a_end):
        def f(t, x):
            s = pressure_ratio(t, tau, a_start, a_end) ** 2
            ay, at = switching_acceleration(x[0], x[1], x[2], x[3], float(s), dyn._args_on, dyn._args_off)
            return [x[1], ay, x[3], at]
        return f

    tol = dict(method="DOP853", rtol=1e-11, atol=[1e-14, 1e-12, 1e-12, 1e-10])
    fall = solve_ivp(rhs(1.0, 0.0), (0, t_off), [0, 0, 0.1, 0], **tol)
    np.testing.assert_allclose(motion.state_at_field_on, fall.y[:, -1], rtol=1e-8, atol=1e-12)
    on = solve_ivp(rhs(math.exp(-t_off / tau), 1.0), (0, 0.05), fall.y[:, -1], t_eval=motion.trajectory.t, **tol)
    err = np.abs(on.y.T - motion.trajectory.state) / np.max(np.abs(on.y.T), axis=0)
    assert err.max() < 1e-7


def test_a_short_ring_is_an_impulse(dyn):
    """A ring much shorter than the motion's time scales adds the impulse of the field's tail: while the drive is
    off the field still acts for int_0^inf exp(-2 t / tau) dt = tau / 2, so at field-on the velocities differ
    from the instant switch's by (tau / 2) (xddot_on - xddot_off) at the drop's state, to O(tau^2)."""
    tau, x0 = 1e-5, np.array([0.0, 0.0, 0.1, 0.0])
    a = field_drop(dyn, x0, 1e-3, 1e-3, 1e-3, tau=0.0, max_step=1e-7)
    b = field_drop(dyn, x0, 1e-3, 1e-3, 1e-3, tau=tau, max_step=1e-7)
    on = np.array(switching_acceleration(*x0, 1.0, dyn._args_on, dyn._args_off))
    off = np.array(switching_acceleration(*x0, 0.0, dyn._args_on, dyn._args_off))
    kick = b.state_at_field_on[[1, 3]] - a.state_at_field_on[[1, 3]]
    # O(tau / t_off) = 1 %: the accelerations change along the 1 ms fall
    np.testing.assert_allclose(kick, 0.5 * tau * (on - off), rtol=0.02)


def test_the_ring_lengthens_the_fall(dyn):
    """The ring-down holds the dimer for ~tau/2 of the drop, but the ring-up leaves it short of its support for
    ~3 tau/2 after the drive is back (the integral of 1 - (1 - e^{-t/tau})^2): the net fall is longer."""
    instant = field_drop(dyn, [0, 0, 0.05, 0], 3e-3, 0.2, 1e-3, tau=0.0)
    ringing = field_drop(dyn, [0, 0, 0.05, 0], 3e-3, 0.2, 1e-3, tau=ring_time(DEFAULT_TRANSDUCER_Q, 45_650.0))
    assert instant.ok
    assert ringing.trajectory.state[:, 0].min() < 1.3 * instant.trajectory.state[:, 0].min()


def test_a_fold_stops_the_motion_and_says_when(dyn):
    """A 7 ms instant drop of this dimer folds its hinge (theta = +-1) after the field is back."""
    m = field_drop(dyn, [0, 0, 0.05, 0], 7e-3, 1.0, 1e-3)
    assert m.status == 2 and 0 < m.t_stop < 1.0 and np.all(np.abs(m.trajectory.state[:, 2]) < 1)
    assert m.t_stop == pytest.approx(m.trajectory.t[-1])
