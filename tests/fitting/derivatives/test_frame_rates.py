"""Any frame rate: the default fit finds the same model from 23 to 2300 frames per period of the y oscillation
(500-50,000 frames/s at 22 Hz), and the Savitzky-Golay smoothing is correct for windows of any length."""
import importlib.util
from pathlib import Path

import numpy as np
import pytest

from cubedimer.dataset import DatasetError, Run
from fitting.config import DiscoveryMethodConfig, FitConfig
from fitting.derivatives.decimation import block_average, decimation_factor
from fitting.derivatives.savitzky_golay import LONG_WINDOW, SmoothingConfig, differentiate, noise_gain, run_derivatives
from fitting.model import TERMS
from fitting.fit import fit_dataset, prepare_runs
from fitting.refinement.long_time import RefineConfig
from fitting.synthetic import SyntheticConfig, generate_runs

# the truth and CSV writer of test_default_fit.py (pytest's importlib mode: load it by path)
_spec = importlib.util.spec_from_file_location(
    "_fitting_test_default_fit", Path(__file__).parents[1] / "methods" / "test_default_fit.py")
_default = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(_default)
TRUTH, _write = _default.TRUTH, _default._write

FRAME_RATES = (500.0, 2000.0, 20000.0, 50000.0)


@pytest.mark.parametrize("window", [51, LONG_WINDOW + 2, 835, 5001])
def test_savgol_derivatives_follow_a_sinusoid_at_any_window(window):
    # 0.75 periods per window, order 5: the filter's own attenuation of the k-th derivative of a sinusoid is
    # ~3e-3 (docs/fitting.md: 3.3 % on the second derivative at 0.75 periods), the same at every window length
    # (it depends on the window in periods only); scipy's weights returned ~0 at 835 frames and more
    fpp = window / 0.75
    dt = 1e-4
    w = 2 * np.pi / (fpp * dt)
    t = np.arange(8 * window) * dt
    x = np.sin(w * t)
    s, d1, d2 = differentiate(x, dt, window, 5)
    inner = slice(window, -window)
    np.testing.assert_allclose(s[inner], x[inner], atol=5e-3)
    np.testing.assert_allclose(d1[inner] / w, np.cos(w * t)[inner], atol=1e-2)
    np.testing.assert_allclose(d2[inner] / w**2, -x[inner], atol=5e-2)
    # white-noise gain of the smoothed value: sqrt of the centre weight's share, ~ sqrt(3.7 / window) at order 5
    assert 0.5 < noise_gain(window, 5, 0, dt) * np.sqrt(window / 3.7) < 2.0


def test_a_window_that_loses_the_signal_names_the_smoothing():
    # 3 periods per window remove the oscillation: the error says so instead of a later "model blows up"
    t = np.arange(4000) * 1e-4
    y = 1e-4 * np.sin(2 * np.pi * 22 * t)
    with pytest.raises(ValueError, match="Savitzky-Golay smoothing over 1365 frames .* removed"):
        run_derivatives(t, y, 0.1 * np.cos(2 * np.pi * 9 * t), 22.0, SmoothingConfig(window_periods=3.0))
    run = Run(name="r.csv", t=t, y=y, theta=0.1 * np.cos(2 * np.pi * 9 * t))
    with pytest.raises(DatasetError, match="^r.csv: the Savitzky-Golay smoothing"):
        prepare_runs([run, run], FitConfig(smoothing=SmoothingConfig(window_periods=3.0, max_frames_per_period=None)))


def test_block_average_keeps_the_signal_and_divides_white_noise_by_sqrt_q():
    rng = np.random.default_rng(5)
    dt, q = 2e-5, 10
    t = np.arange(200_000) * dt
    sig = 1e-4 * np.sin(2 * np.pi * 22 * t)
    run = Run(name="r", t=t, y=sig + 1e-6 * rng.standard_normal(t.size), theta=0 * t, glitch_frames=(3, 4))
    assert decimation_factor(dt, 22.0, 250.0) == 10  # 2273 frames per period -> 227
    assert decimation_factor(1 / 2000, 22.0, 250.0) == 1
    avg = block_average(run, q)
    assert avg.t.size == 20_000 and avg.n_glitches == 2
    np.testing.assert_allclose(np.diff(avg.t), q * dt, rtol=1e-9)
    exact = 1e-4 * np.sin(2 * np.pi * 22 * avg.t)
    # sinc attenuation (pi f q dt)^2 / 6 = 3e-5 of the amplitude: 3e-9 m, far below the averaged noise
    resid = avg.y - exact
    # white noise 1e-6 / sqrt(10); 20,000 samples give its std to 0.5 %
    np.testing.assert_allclose(np.std(resid), 1e-6 / np.sqrt(q), rtol=0.03)
    # and white: lag-1 autocorrelation ~ 0 (+- 0.007 for 20,000 samples)
    assert abs(np.corrcoef(resid[1:], resid[:-1])[0, 1]) < 0.03


@pytest.fixture(scope="module")
def fits_by_frame_rate(tmp_path_factory, leave_out_front):
    """The default fit (20 evaluations of the polish) at each frame rate, without the discovery's held-out front (a
    record the test does not read, tests/fitting/conftest.py)."""
    out = {}
    for fps in FRAME_RATES:
        raw = generate_runs(TRUTH, SyntheticConfig(n_runs=4, duration=2.0, fps=fps, noise_y=1e-6, noise_theta=0.002,
                                                   missing_frames=0, seed=31))
        data = _write(tmp_path_factory.mktemp(f"fps{int(fps)}") / "data", raw)
        config = FitConfig(method=DiscoveryMethodConfig(polish=RefineConfig(max_evals=20)))
        with leave_out_front():
            out[fps] = fit_dataset(data, config, progress=False)
    return out


@pytest.mark.slow
def test_the_same_model_at_500_to_50000_frames_per_second(fits_by_frame_rate):
    # the same 11-term support at every rate, and every coefficient within 4 of its stated (integral-form)
    # standard errors of the truth (44 comparisons: a 4-sigma miss by chance has probability 0.3 %)
    truth = TRUTH.support
    for fps, res in fits_by_frame_rate.items():
        disc = res.extras.discovery
        assert (disc.mask == truth).all(), (fps, [TERMS[j] for q, j in zip(*np.nonzero(disc.mask != truth))])
        dev = np.abs(disc.coef - TRUTH.coef)[truth] / disc.std_errors[truth]
        assert dev.max() < 4.0, (fps, dev.round(2))
        assert res.fallback is None
    q = {fps: res.runs[0].frames_averaged for fps, res in fits_by_frame_rate.items()}
    assert q == {500.0: 1, 2000.0: 1, 20000.0: 4, 50000.0: 10}
    # more frames carry more information: the y stiffness's standard error falls with the frame rate
    se = [fits_by_frame_rate[f].extras.discovery.std_errors[0, TERMS.index("y")] for f in FRAME_RATES]
    assert se[0] > se[1] > se[2] > se[3]


def test_recorded_noise_is_divided_by_sqrt_q_for_block_means():
    from types import SimpleNamespace

    from fitting.uncertainty.oracle import NoiseLevels
    from fitting.fit import _fitted_noise

    noise = NoiseLevels(1e-6, 4e-3, source="recorded")
    one = [SimpleNamespace(frames_averaged=1)] * 2
    four = [SimpleNamespace(frames_averaged=4)] * 2
    assert _fitted_noise(noise, one) is noise and _fitted_noise(None, four) is None
    n4 = _fitted_noise(noise, four)
    np.testing.assert_allclose([n4.sigma_y, n4.sigma_theta], [0.5e-6, 2e-3], rtol=1e-12)  # sqrt(4) = 2 exactly
    assert "sqrt(4)" in n4.source
    assert _fitted_noise(noise, one + four) is None  # different factors: estimated from the runs
