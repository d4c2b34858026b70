"""Glitch detection (cubedimer.glitches): injected outlier frames are found, clean noise is never flagged."""
import numpy as np
import pytest

from cubedimer.glitches import GlitchConfig, find_glitches

FPS, F_Y, SIGMA = 2000.0, 22.0, 1e-6


def _signal(rng, n=6000, amp=2e-4):
    t = np.arange(n) / FPS
    # a decaying y oscillation with a 2 f_y component, as after a field drop
    x = amp * np.exp(-0.3 * t) * (np.cos(2 * np.pi * F_Y * t) + 0.2 * np.cos(4 * np.pi * F_Y * t + 1.0))
    return x + SIGMA * rng.standard_normal(n)


@pytest.mark.parametrize("seed", range(5))
# a glitch of size h leaves h (1 - c0) in the residual against the threshold 7 sigma sqrt(1 - c0) (c0 ~ 0.42):
# detection is certain from ~14 sigma on; smaller ones are near the noise and harmless
@pytest.mark.parametrize("size", [20.0, 30.0, 100.0])
def test_injected_glitches_are_found_exactly(seed, size):
    rng = np.random.default_rng(seed)
    x = _signal(rng)
    idx = np.sort(rng.choice(np.arange(3, x.size - 3), 6, replace=False))
    x[idx] += size * SIGMA * rng.choice([-1.0, 1.0], idx.size)
    found = find_glitches(x, FPS / F_Y)
    np.testing.assert_array_equal(np.flatnonzero(found), idx)


def test_two_frame_glitch_and_missing_frames():
    rng = np.random.default_rng(7)
    x = _signal(rng)
    x[1000:1002] += 80 * SIGMA
    x[2000:2003] = np.nan  # missing frames are never flagged
    found = find_glitches(x, FPS / F_Y)
    np.testing.assert_array_equal(np.flatnonzero(found), [1000, 1001])


def test_clean_noise_is_never_flagged():
    # 40 runs x 6000 frames of Gaussian noise on a smooth signal: at 7 robust standard deviations the
    # expected number of false alarms is ~1e-6, so any flag is a defect of the method
    rng = np.random.default_rng(11)
    flagged = sum(int(find_glitches(_signal(rng, amp=float(a)), FPS / F_Y).sum())
                  for a in rng.uniform(2e-5, 5e-4, 40))
    assert flagged == 0


def test_too_many_outliers_is_not_a_glitch_pattern():
    rng = np.random.default_rng(3)
    x = _signal(rng)
    x[::20] += 100 * SIGMA  # 5 % of the frames: broken tracking, not glitches
    assert not find_glitches(x, FPS / F_Y, GlitchConfig(max_fraction=0.02)).any()


def test_config_validates_itself():
    with pytest.raises(ValueError):
        GlitchConfig(threshold=2.0)


@pytest.mark.parametrize("noise", [0.03e-6, 0.1e-6])
def test_the_onset_of_a_fall_is_not_a_glitch(drop_heights, noise):
    # 20 field drops (rest, a free fall of 2-4.5 ms, the field back): the acceleration jumps by g twice, which a
    # smoothing residual shows over several frames; the mask before the acceleration check took 11-16 frames of
    # 10 of these runs at 0.03 um (120 frames); it now takes at most one frame in all 20
    rng = np.random.default_rng(5)
    flagged = []
    for _ in range(20):
        t, y, _ = drop_heights(3000, FPS, 60 - rng.uniform(0, 1), rng.uniform(2e-3, 4.5e-3))
        flagged.append(int(find_glitches(y + noise * rng.standard_normal(t.size), FPS / F_Y).sum()))
    assert sum(flagged) <= 1
