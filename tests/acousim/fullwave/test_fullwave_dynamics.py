"""The equations of motion on the full-wave surrogate (the shipped default table; no boundary-element solve)."""
from __future__ import annotations

import json

import numpy as np
import pytest

from acousim.dynamics.integrator import DimerDynamics
from acousim.force_model import ForceModel
from acousim.fullwave.force_surrogate import default_fullwave_surrogate


@pytest.fixture(scope="module")
def surrogate():
    return default_fullwave_surrogate()


def test_is_a_force_model(surrogate):
    assert isinstance(surrogate, ForceModel)


def test_force_coefficients_reproduce_the_surrogate(surrogate):
    """The re-expansion of the table's series (in theta / theta_max) as series in theta is the same
    polynomial: equal to round-off, also beyond the interpolation box."""
    th, y = np.meshgrid(np.linspace(-0.98, 0.98, 9), np.linspace(-0.4e-3, 0.3e-3, 7), indexing="ij")
    q_y, q_t = surrogate.generalized_forces(th, y)
    a, b = surrogate.force_coefficients().evaluate(th, y + surrogate.z_eq, surrogate.two_k)
    mg = surrogate.mass * surrogate.gravity
    np.testing.assert_allclose(a - mg, q_y, rtol=0, atol=1e-12 * np.max(np.abs(q_y)))
    np.testing.assert_allclose(b, q_t, rtol=0, atol=1e-12 * np.max(np.abs(q_t)))


def _peak_frequency(signal: np.ndarray, dt: float, band: tuple[float, float]) -> float:
    """Frequency [Hz] of the largest Hann-windowed spectral peak in ``band``, refined by a parabola
    through the log-magnitudes of the peak bin and its neighbours."""
    x = (signal - signal.mean()) * np.hanning(signal.size)
    spec = np.abs(np.fft.rfft(x))
    f = np.fft.rfftfreq(signal.size, dt)
    idx = np.flatnonzero((f >= band[0]) & (f <= band[1]))
    i = idx[np.argmax(spec[idx])]
    la, lb, lc = np.log(spec[i - 1: i + 2])
    return float(f[i] + 0.5 * (la - lc) / (la - 2 * lb + lc) * (f[1] - f[0]))


def test_twin_small_oscillations_match_linear_frequencies(surrogate):
    """The twin's equations of motion on the full-wave model, started 0.2 um and 2e-4 rad off the
    equilibrium, oscillate at the surrogate's linear_frequencies() (f_y ~ 24 Hz, f_theta ~ 31 Hz).

    Tolerance 0.1 %: over 4 s the spectral bin is 0.25 Hz and the parabolic refinement of a Hann
    peak is good to a few hundredths of a bin, i.e. < 0.05 % at 23 Hz; the amplitude-dependent
    (nonlinear) shift at these amplitudes is below 1e-4 relative.  A wrong stiffness, inertia or
    coefficient re-expansion moves a frequency by far more."""
    dyn = DimerDynamics(force_model=surrogate)
    theta_eq, y_eq = surrogate.equilibrium()
    f_y, f_theta = surrogate.linear_frequencies()
    dt = 1.0 / 4000
    traj = dyn.integrate([y_eq + 0.2e-6, 0.0, theta_eq + 2e-4, 0.0], duration=4.0, dt_out=dt, max_step=2.5e-5)
    y, theta = traj.state[:, 0], traj.state[:, 2]
    assert np.all(np.isfinite(traj.state))
    # each coordinate is dominated by its own mode: look for it on its side of the geometric mean
    split = np.sqrt(f_y * f_theta)
    assert abs(_peak_frequency(y, dt, (5.0, split)) / f_y - 1) < 1e-3
    assert abs(_peak_frequency(theta, dt, (split, 400.0)) / f_theta - 1) < 1e-3


def test_simulate_on_the_fullwave_model(tmp_path, capsys, surrogate):
    """``python -m acousim simulate --model fullwave`` writes a loadable data set whose truth names the
    model and its frequencies; the pressure error rescales the table exactly as p0^2."""
    from acousim.cli import main
    from cubedimer.dataset import load_dataset

    out = tmp_path / "d"
    rc = main(["simulate", "--model", "fullwave", "--runs", "2", "--seed", "3", "--pressure-error", "0.05",
               "--workers", "1", "--no-progress", "--duration", "0.5", "--fps", "1000", "--out", str(out)])
    assert rc == 0, capsys.readouterr().err
    ds = load_dataset(out, strict=True)
    assert len(ds.runs) == 2
    truth = json.loads((out / "truth.json").read_text())
    assert truth["force_model"] == "fullwave" and truth["model"]["model"] == "fullwave"
    p = truth["pressure_amplitude_pa"]
    assert p != 3000.0
    rescaled = surrogate.with_pressure(p)
    assert np.isclose(truth["equilibrium_height_m"], rescaled.z_eq, rtol=1e-12)
    f_y, f_theta = rescaled.linear_frequencies()
    assert truth["fullwave_linear_frequencies_hz"] == {"y": f_y, "theta": f_theta}
    # the straight trapped dimer stays trapped: every sample finite, y well inside the trap
    for run in ds.runs:
        assert np.all(np.abs(run.y[np.isfinite(run.y)]) < 0.5e-3)


@pytest.mark.parametrize("extra, fragment", [
    (["--side", "1e-3"], "outside the full-wave family"),  # ks = 0.84
    (["--mesh-size", "1e-4"], "--mesh-size applies to --model gorkov only"),
    (["--gap", "0"], "--gap = 0.0 must be positive"),
    (["--model", "bem"], "invalid choice"),
])
def test_simulate_fullwave_refusals_are_one_line(tmp_path, capsys, extra, fragment):
    from acousim.cli import main

    args = ["simulate", "--model", "fullwave", "--out", str(tmp_path / "d"), "--runs", "1", *extra]
    try:
        rc = main(args)
    except SystemExit as exc:  # argparse choices
        rc = exc.code
    err = capsys.readouterr().err
    assert rc == 2 and fragment in err and len(err.strip().splitlines()) == 1, err
    assert not (tmp_path / "d").exists()


def test_gorkov_remains_the_default_and_is_not_recorded():
    """The Gor'kov model stays the twin's default force model, and truth.json names the model only when it is another."""
    from acousim.models import ConditionError, ModelSpec
    from acousim.twin import TwinConfig, TwinError

    assert TwinConfig().force_model == "gorkov" and TwinConfig().model_spec == ModelSpec()
    assert "force_model" not in TwinConfig().to_dict()
    assert TwinConfig(model_spec=ModelSpec("fullwave")).to_dict()["force_model"] == "fullwave"
    with pytest.raises(ConditionError):
        ModelSpec("bem")
    with pytest.raises(TwinError, match="model_spec"):
        TwinConfig(model_spec="fullwave")  # a name is not a spec
