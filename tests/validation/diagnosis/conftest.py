"""Synthetic runs of the calibrated simulation (plus effects) with known truth, shared by the diagnosis tests, and
twin-like data sets with causes outside the candidates (a drifting pressure, a cubic hinge term)."""
import json
from pathlib import Path

import numpy as np
import pytest

from validation.diagnosis import Calibration, DiagnosisProblem, RunAccelerations, predicted_accelerations


@pytest.fixture(scope="module")
def fast_model():
    from acousim import GorkovDimer

    return GorkovDimer().interpolated()


def _calibrated_runs(cal: Calibration, effects: dict, x0, t, substeps: int = 2):
    """Integrate the calibrated simulation model (+ effects) from each run's initial state with the suite's
    equations of motion and compiled RK4 (:class:`acousim.DimerDynamics`): the synthetic trajectories of
    these tests.

    The force model is the default dimer's surrogate at the calibrated pressure, whose y is measured from
    its own equilibrium Z_eq; the data's y is measured from ``cal.z_origin_m``, so states are shifted by
    Z_eq - z0.  ``x0`` (n_runs, 4) in the data's y; ``t`` (n,) uniform times [s].  Returns states
    (n_runs, n, 4) and the number of valid samples per run.
    """
    from acousim import DimerDynamics, EffectSet, cached_surrogate

    sur = cached_surrogate().with_pressure(cal.pressure_amplitude_pa)
    dyn = DimerDynamics(sur, EffectSet.from_dict(effects))
    shift = np.array([sur.z_eq - cal.z_origin_m, 0.0, 0.0, 0.0])
    dt = float(t[1] - t[0])
    out = np.full((len(x0), len(t), 4), np.nan)
    n_valid = np.zeros(len(x0), dtype=np.int64)
    for i, x in enumerate(np.asarray(x0, float)):
        traj = dyn.integrate(x - shift, duration=dt * (len(t) - 1), dt_out=dt, max_step=dt / substeps)
        out[i, : len(traj.t)] = traj.state + shift
        n_valid[i] = len(traj.t)
    return out, n_valid


def _synthetic_runs(model, cal, effects, n_runs=8, duration=1.6, fps=500, noise=(0.05, 50.0), seed=0, known_noise=False):
    """Trajectories of the calibrated model + effects from random starts (|y| <= 150 um, |theta| <= 0.4);
    exact accelerations plus noise of the size Savitzky-Golay differentiation leaves on realistic
    tracking (0.05 m/s^2 and 50 1/s^2).  ``known_noise``: the runs carry the noise variances, as
    :func:`validation.diagnosis.prepare_diagnosis_runs` gives them, so that the gaps are in excess of the noise."""
    rng = np.random.default_rng(seed)
    x0 = np.column_stack([rng.uniform(-1.5e-4, 1.5e-4, n_runs), rng.uniform(-0.01, 0.01, n_runs),
                          rng.uniform(-0.4, 0.4, n_runs), rng.uniform(-5, 5, n_runs)])
    t = np.arange(int(duration * fps)) / fps
    states, n_valid = _calibrated_runs(cal, effects, x0, t)
    assert np.all(n_valid == len(t))
    runs = [RunAccelerations(f"run{i:02d}.csv", t, states[i], np.zeros((len(t), 2))) for i in range(n_runs)]
    pred = predicted_accelerations(DiagnosisProblem(model, runs), cal, effects)
    nv = np.array([noise[0] ** 2, noise[1] ** 2, 0.0, 0.0]) if known_noise else None
    return [RunAccelerations(r.name, r.t, r.state, p + rng.normal(0, noise, p.shape), nv) for r, p in zip(runs, pred)]


@pytest.fixture
def synthetic_runs():
    """:func:`_synthetic_runs`: (model, calibration, effects, ...) -> noisy runs of known truth."""
    return _synthetic_runs


def write_twin_like_dataset(path, runs=8, duration=3.0, fps=2000, seed=0, drift=0.0, drift_period=(1.5, 4.0),
                            cubic_hinge=0.0, pressure_error=0.03, noise=(1e-6, 0.005)) -> dict:
    """Runs of the surrogate's equations of motion (PHYSICS.md section 4) with a pressure
    ``p(t) = p_true (1 + drift sin(2 pi t / T + phase))`` (T and phase drawn per run) and ``-cubic_hinge theta^3``
    [1/s^2] added to thetaddot, written as FORMATS.md CSVs with tracking noise (y [m], theta) and meta.json
    at the nominal pressure; y is measured from the nominal equilibrium height.

    Classical RK4 at the frame interval (omega_y dt = 0.07 at 2000 fps), batched over runs.  The drops start
    at |y| of 80-150 um, so that each run's oscillation dominates its y spectrum (a drift of a few per cent
    moves the equilibrium by tens of micrometres).  Returns the truth: the pressure, the drift's periods
    and phases, and per run the relative half range of p(t) over the recorded frames."""
    from numpy.polynomial import chebyshev as cheb

    from acousim import cached_surrogate
    from acousim.equations import hinge_acceleration

    path = Path(path)
    path.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(seed)
    sur = cached_surrogate()
    p_nom = sur.pressure_amplitude_pa
    p_true = p_nom * (1 + rng.uniform(-pressure_error, pressure_error))
    m, g, two_k, z_eq = sur.mass, sur.gravity, sur.two_k, sur.z_eq
    _, b, gm, da, db, dg = sur.coefficient_arrays()
    coef = np.stack([b, gm, da, db, dg], axis=1)  # Chebyshev series in theta, one column per function
    n = int(round(duration * fps))
    h = 1.0 / fps
    phase = rng.uniform(0, 2 * np.pi, runs)
    period = rng.uniform(*drift_period, runs)
    x = np.column_stack([rng.choice([-1, 1], runs) * rng.uniform(0.8e-4, 1.5e-4, runs), np.zeros(runs),
                         rng.uniform(-0.3, 0.3, runs), rng.uniform(-2, 2, runs)])

    def pressure(t):
        return p_true * (1 + drift * np.sin(2 * np.pi * t / period + phase))

    def rhs(t, s):
        scale = (pressure(t) / p_nom) ** 2  # Gor'kov forces scale with p0^2 at fixed lab height
        th = s[:, 2]
        bv, gv, dav, dbv, dgv = cheb.chebval(th, coef)
        c, sn = np.cos(two_k * (s[:, 0] + z_eq)), np.sin(two_k * (s[:, 0] + z_eq))
        ay = scale * two_k * (bv * sn - gv * c) / m - g
        at = hinge_acceleration(-scale * (dav + dbv * c + dgv * sn), sur.hinge_inertia(th), sur.hinge_inertia_derivative(th),
                                s[:, 3]) - cubic_hinge * th**3
        return np.column_stack([s[:, 1], ay, s[:, 3], at])

    out = np.empty((n, runs, 4))
    out[0] = x
    for i in range(1, n):
        t = (i - 1) * h
        k1 = rhs(t, x)
        k2 = rhs(t + h / 2, x + h / 2 * k1)
        k3 = rhs(t + h / 2, x + h / 2 * k2)
        k4 = rhs(t + h, x + h * k3)
        x = x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        out[i] = x
    assert np.all(np.isfinite(out)) and np.all(np.abs(out[:, :, 2]) < 1), "a run left the trap"
    t = np.arange(n) / fps
    for r in range(runs):
        y = out[:, r, 0] + rng.normal(0, noise[0], n)
        th = out[:, r, 2] + rng.normal(0, noise[1], n)
        np.savetxt(path / f"run{r:02d}.csv", np.column_stack([t, y, th]), delimiter=",", header="t,y,theta", comments="")
    (path / "meta.json").write_text(json.dumps({"pressure_amplitude_pa": p_nom}))
    p_t = np.array([pressure(tt) for tt in t])  # (n, runs)
    return {"pressure_amplitude_pa": p_true, "period_s": period.tolist(), "phase": phase.tolist(),
            "relative_half_range": (0.5 * np.ptp(p_t, axis=0) / p_t.mean(axis=0)).tolist(), "cubic_hinge": cubic_hinge}


#: the cubic hinge term of the discovery tests [1/s^2]: -CUBIC_HINGE theta^3 in thetaddot (on the soft hinge, 1.7 Hz,
#: about 35 % of the Gor'kov restoring acceleration at theta = 0.3)
CUBIC_HINGE = 2.4e4
#: relative pressure amplitude of the drift tests
DRIFT = 0.04


@pytest.fixture(scope="session")
def drift_dataset(tmp_path_factory):
    """(data directory, truth): 8 runs of 3 s with the pressure drifting by DRIFT (periods 1.5-4 s)."""
    path = tmp_path_factory.mktemp("twin_like") / "drift"
    return path, write_twin_like_dataset(path, seed=2, drift=DRIFT)


@pytest.fixture(scope="session")
def cubic_dataset(tmp_path_factory):
    """(data directory, truth): 8 runs of 3 s with -CUBIC_HINGE theta^3 added to thetaddot."""
    path = tmp_path_factory.mktemp("twin_like") / "cubic"
    return path, write_twin_like_dataset(path, seed=3, cubic_hinge=CUBIC_HINGE)


@pytest.fixture(scope="session")
def clean_dataset(tmp_path_factory):
    """(data directory, truth): 8 runs of 3 s of the surrogate alone (a constant pressure off nominal)."""
    path = tmp_path_factory.mktemp("twin_like") / "clean"
    return path, write_twin_like_dataset(path, seed=1)
