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
