"""Synthetic runs of the calibrated simulation (plus effects) with known truth, shared by the diagnosis tests."""
import numpy as np
import pytest

from validation.diagnosis import (CANDIDATE_EFFECTS, Calibration, DiagnosisProblem, RunAccelerations,
                                  effect_regressors, predicted_accelerations)


@pytest.fixture(scope="module")
def fast_model():
    from acousim import GorkovDimer

    return GorkovDimer().interpolated()


def _rk4_calibrated_runs(model, cal: Calibration, effects: dict, x0, t, substeps: int = 2, bound: float = 2e-3):
    """Integrate the calibrated simulation model (+ effects) from each run's initial state: the
    synthetic trajectories of these tests.

    Classical RK4 with step ``dt / substeps`` on a uniform output grid ``t``, batched over runs (all
    runs advance together; the model is evaluated once per stage for the whole batch).  A run whose
    |y| exceeds ``bound`` [m] (it left the trap) or turns non-finite is frozen and reported through
    ``n_valid``.  ``model``: an interpolated acousim.GorkovDimer at nominal pressure; ``x0`` (n_runs, 4);
    ``t`` (n,) uniform times [s].  Returns states (n_runs, n, 4) and n_valid (n_runs,).
    """
    x = np.array(x0, float)
    n_runs, n = x.shape[0], len(t)
    h = float(t[1] - t[0]) / substeps
    out = np.empty((n_runs, n, 4))
    out[:, 0] = x
    n_valid = np.full(n_runs, n, dtype=np.int64)
    alive = np.ones(n_runs, bool)
    dimer, g, k = model.dimer, model.gravity, model.wave.wavenumber
    mass = dimer.total_mass
    names = list(effects)
    pvec = [np.array([effects[e][p] for p in CANDIDATE_EFFECTS[e]]) for e in names]

    def rhs(s):
        th = np.clip(s[:, 2], -1.0, 1.0)
        z = cal.z_origin_m + s[:, 0]
        st = model.integrals_at_height(th, z)
        inertia = dimer.hinge_inertia(th)
        a = np.column_stack([cal.pressure_scale * st.force_z / mass - g,
                             (cal.pressure_scale * st.q_theta - 0.5 * dimer.hinge_inertia_derivative(th) * s[:, 3] ** 2) / inertia])
        for e, pv in zip(names, pvec):
            a = a + effect_regressors(e, s, z, k, cal.equilibrium_height_m) @ pv
        return np.column_stack([s[:, 1], a[:, 0], s[:, 3], a[:, 1]])

    for i in range(1, n):
        for _ in range(substeps):
            k1 = rhs(x)
            k2 = rhs(x + 0.5 * h * k1)
            k3 = rhs(x + 0.5 * h * k2)
            k4 = rhs(x + h * k3)
            x = np.where(alive[:, None], x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4), x)
        bad = alive & (~np.all(np.isfinite(x), axis=1) | (np.abs(x[:, 0]) > bound) | (np.abs(x[:, 2]) >= 1.0))
        if np.any(bad):
            n_valid[bad] = i
            alive &= ~bad
            x[bad] = out[bad, i - 1]
        out[:, i] = x
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
    states, n_valid = _rk4_calibrated_runs(model, cal, effects, x0, t)
    assert np.all(n_valid == len(t))
    runs = [RunAccelerations(f"run{i:02d}.csv", t, states[i], np.zeros((len(t), 2))) for i in range(n_runs)]
    pred = predicted_accelerations(DiagnosisProblem(model, runs), cal, effects)
    nv = np.array([noise[0] ** 2, noise[1] ** 2, 0.0, 0.0]) if known_noise else None
    return [RunAccelerations(r.name, r.t, r.state, p + rng.normal(0, noise, p.shape), nv) for r, p in zip(runs, pred)]


@pytest.fixture
def synthetic_runs():
    """:func:`_synthetic_runs`: (model, calibration, effects, ...) -> noisy runs of known truth."""
    return _synthetic_runs
