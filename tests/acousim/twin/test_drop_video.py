"""The twin's camera records the whole field drop: rest, the free fall with the drive off, the field-on motion."""
import numpy as np
import pytest

from acousim.dynamics.effects import EffectSet
from acousim.twin import Camera, DropProtocol, TwinConfig, simulate_run, twin_dynamics
from acousim.twin.video import drop_protocol_motion

FPS = 2000.0


@pytest.mark.parametrize("seed", [0, 1])
def test_rest_fall_and_motion_are_continuous(seed):
    # no air damping: the drop is an exact free fall (tests/acousim/twin/test_twin.py), so every fall frame is known
    dyn, _ = twin_dynamics(TwinConfig(runs=1, duration=0.05, seed=seed, camera=Camera(fps=FPS), effects=EffectSet(),
                                      air_damping=False))
    proto = DropProtocol(t_off=(2e-3, 4.5e-3), theta_drop=(-0.3, 0.3), thetadot_drop=(0.0, 0.0))
    run = simulate_run(dyn, proto, Camera(fps=FPS, noise_y=0, noise_theta=0, missing_frames=0), 0.05, seed)
    y, theta, ph = drop_protocol_motion(dyn, run, 60)
    t_off = run.drop["t_off_s"]
    m = ph["fall_frames"]
    assert m == int(np.ceil(t_off * FPS)) - 1 and ph["field_on_frame"] == 60 + m
    assert ph["drop_frame"] == pytest.approx(60 + m - t_off * FPS)
    np.testing.assert_array_equal(y[:60], 0.0)
    np.testing.assert_array_equal(theta[:60], run.drop["theta_drop"])
    # the fall's frames: y = -g s^2 / 2, s the time since the drive stopped (RK4 is exact on a parabola)
    s = (np.arange(60, 60 + m) - ph["drop_frame"]) / FPS
    g = -run.state_at_field_on[1] / t_off  # the twin's own g, from the velocity at the field's return
    np.testing.assert_allclose(y[60:60 + m], -0.5 * g * s ** 2, rtol=1e-9, atol=1e-15)
    # then the run's own motion, from the field's return on
    np.testing.assert_array_equal(y[60 + m:], run.state[:, 0])
    assert y.size == theta.size == 60 + m + run.t.size
