"""The phases of a field-drop recording (cubedimer.drop_phases): rest, free fall at g, the field's return, found
against an analytic drop; a series that does not start at rest has none."""
import numpy as np
import pytest

from cubedimer.drop_phases import STANDARD_GRAVITY, find_drop_phases, starts_at_rest

FPS = 2000.0


@pytest.mark.parametrize("seed", range(3))
@pytest.mark.parametrize("t_off", [2.0e-3, 3.3e-3, 4.5e-3])
@pytest.mark.parametrize("noise", [0.03e-6, 0.2e-6, 1.0e-6])  # 0.003-0.1 px at 10 um/px: the tracker's range
def test_the_switching_times_and_the_fall_are_found(drop_heights, seed, t_off, noise):
    rng = np.random.default_rng(seed)
    rest = 60 - rng.uniform(0, 1)
    t, y, on = drop_heights(3000, FPS, rest, t_off)
    ph = find_drop_phases(t, y + noise * rng.standard_normal(t.size))
    # the field's return to its stated error plus a frame (4 sigma; the field-on cubic can take up part of a late
    # return, which the residual's profile does not see: up to 1.5 frames over these 27 cases); the drive's stop
    # to a tenth of a frame; the run starts within a frame before the return (such a frame lies off the field-on
    # motion by less than g dt^2 / 2 = 1.2 um, continuous in height and velocity), at most 5 frames after it
    assert abs(ph.field_on_frame - on) <= 4 * ph.field_on_frame_error + 1.0
    assert abs(ph.drop_frame - rest) <= 0.15
    assert on - 1 <= ph.first_field_on_frame <= on + 5
    assert ph.rest_frames == int(np.floor(rest)) + 1 or abs(ph.rest_frames - rest) <= 1.0
    # the fall: g to 4 standard errors (and 0.5 % for the grid), a free fall
    assert abs(ph.fall_acceleration + STANDARD_GRAVITY) <= 4 * ph.fall_acceleration_error + 0.005 * STANDARD_GRAVITY
    assert ph.free_fall
    assert ph.to_dict()["field_off_s"] == pytest.approx(t_off, abs=2 / FPS)


def test_a_run_that_starts_moving_has_no_drop(drop_heights):
    t, y, _ = drop_heights(3000, FPS, 60.3, 3e-3)
    assert find_drop_phases(t[200:] - t[200], y[200:]) is None  # the field-on motion alone, noise-free
    rng = np.random.default_rng(1)
    assert find_drop_phases(t[200:] - t[200], y[200:] + 0.2e-6 * rng.standard_normal(2800)) is None


def test_y_down_gives_a_fall_at_plus_g(drop_heights):
    t, y, on = drop_heights(2000, FPS, 40.5, 3e-3)
    ph = find_drop_phases(t, -y + 0.1e-6 * np.random.default_rng(2).standard_normal(t.size))
    assert ph.fall_acceleration == pytest.approx(STANDARD_GRAVITY, rel=0.05) and ph.free_fall


def test_rest_then_a_jump_is_not_a_free_fall():
    # rest frames followed at once by the field-on motion (no fall in between): not a free fall, or no drop at all
    t = np.arange(2000) / FPS
    y = np.where(t < 0.03, 0.0, -8e-5 * np.cos(2 * np.pi * 22 * (t - 0.03)))
    y = y + 0.2e-6 * np.random.default_rng(3).standard_normal(t.size)
    assert starts_at_rest(y) is not None
    ph = find_drop_phases(t, y)
    assert ph is None or not ph.free_fall


def test_a_noise_free_drop_is_found_exactly(drop_heights):
    # no noise: the rest's scatter is round-off (floored at 1e-6 of the range); the times and g come out exact
    t, y, on = drop_heights(3000, FPS, 59.6, 3.5e-3)
    ph = find_drop_phases(t, y)
    assert ph.free_fall and ph.first_field_on_frame == int(np.ceil(on))
    assert ph.field_on_frame == pytest.approx(on, abs=0.01) and ph.drop_frame == pytest.approx(59.6, abs=0.01)
    assert ph.fall_acceleration == pytest.approx(-STANDARD_GRAVITY, rel=1e-4)


@pytest.fixture(scope="module")
def ringing_drops():
    """Field drops of the twin with the transducer's ring time (Q = 250 at 45.65 kHz: 1.74 ms, 3.5 frames at 2000
    frames/s; the field decays while the dimer starts to fall and rings back up at the return), recorded whole:
    60 frames at rest, the fall (2-4.5 ms), 0.3 s of motion.  {seed: (heights, the drive's stop and restart
    [frames], the ring time [frames])}."""
    from acousim.dynamics.effects import EffectSet
    from acousim.dynamics.switching import DEFAULT_TRANSDUCER_Q, ring_time
    from acousim.twin import Camera, DropProtocol, TwinConfig, simulate_run, twin_dynamics
    from acousim.twin.video import drop_protocol_motion

    tau = ring_time(DEFAULT_TRANSDUCER_Q, 45650.0)
    out = {}
    for seed in (20, 23):
        dyn, _ = twin_dynamics(TwinConfig(runs=1, duration=0.3, seed=seed, camera=Camera(fps=FPS), effects=EffectSet(),
                                          air_damping=False, transducer_q=DEFAULT_TRANSDUCER_Q))
        run = simulate_run(dyn, DropProtocol(t_off=(2e-3, 4.5e-3)),
                           Camera(fps=FPS, noise_y=0, noise_theta=0, missing_frames=0), 0.3, seed, ring_time_s=tau)
        y, _, ph = drop_protocol_motion(dyn, run, 60, ring_time_s=tau)
        out[seed] = (y, ph["drop_frame"], ph["field_on_frame"], tau * FPS)
    return out


@pytest.mark.parametrize("seed", [20, 23])
@pytest.mark.parametrize("noise", [0.03e-6, 0.2e-6, 1.0e-6])
def test_a_drop_with_a_ring_time_is_found(ringing_drops, seed, noise):
    """The early fall is slower than g while the field rings down, and the field comes back gradually: the phases are
    still found, the run never starts inside the fall, and the ring time is measured where the noise resolves it.
    Tolerances from 8 twin drops (seeds 20-27) at each noise: the restart seen -0.9 to +2 frames off (its force grows
    as (1 - exp(-t / tau))^2, so at 1 um it is seen late, within a ring time), the run's first frame 1-7 frames after
    it (within 2 ring times and a frame), the ring time within 15 % at 0.2 um and 4 % at 0.03 um."""
    y, stop, restart, tau = ringing_drops[seed]
    t = np.arange(y.size) / FPS
    ph = find_drop_phases(t, y + noise * np.random.default_rng(seed).standard_normal(y.size))
    assert ph is not None and ph.free_fall
    assert -1.0 <= ph.field_on_frame - restart <= tau
    assert restart < ph.first_field_on_frame <= restart + 2 * tau + 1  # no frame of the fall is kept
    assert abs(ph.fall_acceleration + STANDARD_GRAVITY) <= 4 * ph.fall_acceleration_error + 0.005 * STANDARD_GRAVITY
    if noise <= 0.2e-6:  # the ring time resolved: the drive's stop itself
        assert ph.ring_frames == pytest.approx(tau, rel=0.25 if noise > 0.1e-6 else 0.1)
        assert abs(ph.drop_frame - stop) <= 0.3
    else:  # 3.7 um below a delayed parabola, g tau^2 / 8, is within the noise of a few frames: unresolved, and the
        # fall starts where a free fall would have, tau / 2 after the drive stopped (measured 1.40-1.56 frames)
        assert ph.ring_frames == 0.0 or ph.ring_frames == pytest.approx(tau, rel=0.5)
        assert abs(ph.drop_frame - (stop + (0.5 * tau if ph.ring_frames == 0.0 else 0.0))) <= 0.5


def test_rest_is_recognised_whatever_the_noise_draws(drop_heights):
    # 300 draws of 0.2 um noise on the same drop: the rest's trend and curvature are judged by their standard errors
    # (the curvature's is 3.4 noise over 16 frames), so none is taken for a motion (at a bound of 6 noise on the
    # curvature, 7 % were, and their rest and fall were then fitted as field-on motion; at a spread bound of 2 noise,
    # 1 in 300)
    t, y, _ = drop_heights(600, FPS, 60.3, 3e-3)
    noise = 0.2e-6 * np.random.default_rng(5).standard_normal((300, t.size))
    assert all(starts_at_rest(y + n) is not None for n in noise)
    # while a smooth motion is never at rest: the run without its rest and fall, from any of 40 phases
    assert not any(starts_at_rest(y[k:] + n[k:]) for k, n in zip(range(80, 480, 10), noise))


@pytest.mark.parametrize("fps", [2000.0, 20000.0, 50000.0])
def test_a_turning_point_is_not_rest_at_any_frame_rate(fps):
    # a 100 um oscillation at 22 Hz from its turning point, 1 um of noise: over 16 frames at 50,000 frames/s (0.32 ms)
    # it moves by 9.6 nm, far inside the noise, so frames alone cannot tell it from rest; over MIN_REST_S (8 ms) it
    # moves by 55 um, 55 noise, so it is a motion at every rate
    from cubedimer.drop_phases import MIN_REST_S, rest_head_frames

    dt = 1.0 / fps
    t = np.arange(int(0.5 * fps)) * dt
    y = 1e-4 * np.cos(2 * np.pi * 22.0 * t) + 1e-6 * np.random.default_rng(3).standard_normal(t.size)
    assert rest_head_frames(dt) * dt >= MIN_REST_S - 1e-12
    assert starts_at_rest(y, dt=dt) is None
    if fps == 50000.0:  # the defect the time span mends: 16 frames of this motion read as rest
        assert starts_at_rest(y) is not None
