"""Synthetic runs of the calibrated simulation (plus effects) with known truth, shared by the diagnosis tests, and
twin-like data sets with causes outside the candidates (a drifting pressure, a cubic hinge term)."""
from dataclasses import dataclass
from typing import Callable, ClassVar

import numpy as np
import pytest

from acousim.dynamics.effects import EFFECT_TYPES, Effect

from validation.diagnosis import Calibration, DiagnosisProblem
from validation.diagnosis.calibrate.gap_model import predicted_accelerations
from validation.diagnosis.prepare.runs import RunAccelerations


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


def write_twin_like_dataset(path, **settings) -> dict:
    """:func:`validation.blind.twin_like.write_twin_like_dataset` (the surrogate's equations of motion with a
    drifting pressure or a cubic hinge term), with the true mean pressure within 3 % of nominal by default."""
    from validation.blind.twin_like import TwinLikeConfig, write_twin_like_dataset as write

    return write(path, TwinLikeConfig(**{"pressure_error": 0.03, **settings}))


def cached_twin_like_dataset(cache, **settings):
    """(data directory, truth) of :func:`write_twin_like_dataset` with ``settings``, made once per version of the
    sources in the pipeline cache (tests/conftest.py), so that the files reading the same data set share one build:
    read it, never write into it.  The truth is kept beside the data set (truth.json), out of the diagnosis's view."""
    import json

    from validation.blind.twin_like import TwinLikeConfig

    def build(folder):
        truth = write_twin_like_dataset(folder / "data", **settings)
        (folder / "truth.json").write_text(json.dumps(truth))

    folder = cache.folder("twin-like", repr(TwinLikeConfig(**{"pressure_error": 0.03, **settings})), build)
    return folder / "data", json.loads((folder / "truth.json").read_text())


#: the cubic hinge term of the discovery tests [1/s^2]: -CUBIC_HINGE theta^3 in thetaddot (on the soft hinge, 1.7 Hz,
#: about 35 % of the Gor'kov restoring acceleration at theta = 0.3)
CUBIC_HINGE = 2.4e4
#: relative pressure amplitude of the drift tests
DRIFT = 0.04
#: the y-dependent damping of the energy-balance discovery tests [1/(m^2 s)]: -Y_DAMPING y^2 ydot in yddot
#: (Y_DAMPING (100 um)^2 = 6 1/s; y from the true equilibrium)
Y_DAMPING = 6.0e8


@pytest.fixture(scope="session")
def drift_dataset(pipeline_cache):
    """(data directory, truth): 8 runs of 3 s with the pressure drifting by DRIFT (periods 1.5-4 s)."""
    return cached_twin_like_dataset(pipeline_cache, seed=2, drift=DRIFT)


@pytest.fixture(scope="session")
def cubic_dataset(pipeline_cache):
    """(data directory, truth): 8 runs of 3 s with -CUBIC_HINGE theta^3 added to thetaddot."""
    return cached_twin_like_dataset(pipeline_cache, seed=3, cubic_hinge=CUBIC_HINGE)


@pytest.fixture(scope="session")
def y_damping_dataset(pipeline_cache):
    """(data directory, truth): 8 runs of 3 s with -Y_DAMPING y^2 ydot added to yddot, y from the true equilibrium,
    which lies 77 um above the nominal one (the data's y origin: a true pressure 7.5 % above nominal)."""
    return cached_twin_like_dataset(pipeline_cache, seed=4, y_damping=Y_DAMPING, pressure_error=0.1)


@pytest.fixture(scope="session")
def centred_y_damping_dataset(pipeline_cache):
    """(data directory, truth): as y_damping_dataset, with the true equilibrium near the data's origin (the true
    pressure within 3 % of nominal)."""
    return cached_twin_like_dataset(pipeline_cache, seed=4, y_damping=Y_DAMPING)


@pytest.fixture(scope="session")
def clean_dataset(pipeline_cache):
    """(data directory, truth): 8 runs of 3 s of the surrogate alone (a constant pressure off nominal)."""
    return cached_twin_like_dataset(pipeline_cache, seed=1)


# ---- a dummy effect, registered for one test (the effect registry's promise) ----------------------------------

def _constant_push_columns(y, ydot, theta, thetadot, wavenumber, z_eq):
    """thetaddot += push (a constant torque per inertia); nothing in yddot."""
    return (0.0,), (1.0,)


@dataclass(frozen=True)
class ConstantPush(Effect):
    """A dummy effect: a constant hinge torque, thetaddot += push [1/s^2]."""

    name: ClassVar[str] = "constant_push"
    columns: ClassVar[Callable] = staticmethod(_constant_push_columns)
    push: float = 0.0


@pytest.fixture
def registered_push(monkeypatch):
    monkeypatch.setitem(EFFECT_TYPES, ConstantPush.name, ConstantPush)
    return ConstantPush
