"""The digital twin: field-drop protocol, camera, data sets (docs/formats.md) and their truth files."""
import json
from dataclasses import replace

import numpy as np
import pytest

from acousim.dynamics.effects import EffectSet
from acousim.models import ExperimentConditions, ModelSpec
from acousim.twin import (PAPER_LIKE, Camera, DropProtocol, TwinConfig, TwinError, simulate_dataset,
                          simulate_field_drop_runs, simulate_run, true_pressure, twin_dynamics)
from cubedimer.attractors import classify_trajectory
from cubedimer.dataset import load_dataset, load_run
from cubedimer.meta import META_KEYS
from cubedimer.executor import ExecutorConfig

SERIAL = ExecutorConfig(workers=1)
G = 9.81


def _small(**kw):
    base = dict(runs=3, duration=1.0, seed=5, camera=Camera(fps=500.0), effects=EffectSet.parse(
        ["pair_scattering:kappa=12000", "linear_damping:gamma_y=0.3,gamma_theta=0.8"]))
    base.update(kw)
    return TwinConfig(**base)


@pytest.fixture(scope="module")
def dataset(tmp_path_factory):
    out = tmp_path_factory.mktemp("twin") / "data"
    cfg = _small(pressure_error=0.1)
    truth = simulate_dataset(cfg, out, SERIAL, progress=False)
    return out, cfg, truth


def test_dataset_loads_under_formats_rules(dataset):
    out, cfg, _ = dataset
    ds = load_dataset(out, strict=True)
    assert [r.name for r in ds.runs] == ["run01.csv", "run02.csv", "run03.csv"]
    for r in ds.runs:
        assert r.t[0] == 0.0 and r.dt == pytest.approx(1 / 500.0, rel=1e-9)
        assert r.t.size == 500 and r.n_filled == cfg.camera.missing_frames
    assert set(META_KEYS) <= set(ds.meta)


def test_meta_holds_the_nominal_and_truth_the_true_pressure(dataset):
    out, cfg, truth = dataset
    meta = json.loads((out / "meta.json").read_text())
    assert meta["pressure_amplitude_pa"] == 3000.0
    p = truth["pressure_amplitude_pa"]
    assert p != 3000.0 and abs(p / 3000.0 - 1) <= 0.1
    assert p == true_pressure(3000.0, 0.1, cfg.seed)


def test_truth_reproduces_the_settings(dataset):
    out, cfg, _ = dataset
    truth = json.loads((out / "truth.json").read_text())
    assert truth["seed"] == cfg.seed and truth["runs"] == cfg.runs
    # the default twin has the air's computed damping: recorded as a setting and with its parameters among the
    # effects, computed at the true pressure's frequencies (docs/damping.md)
    dyn, _ = twin_dynamics(cfg)
    assert truth["air_damping"] is True
    assert truth["effects"] == {"linear_damping": {"gamma_y": 0.3, "gamma_theta": 0.8},
                                "pair_scattering": {"kappa": 12000.0},
                                "air_damping": dyn.effects["air_damping"].params()}
    rebuilt = TwinConfig(
        runs=truth["runs"], duration=truth["duration_s"], seed=truth["seed"],
        experiment=ExperimentConditions(side_length_m=truth["side_length_m"],
                                        pressure_amplitude_pa=truth["nominal_pressure_amplitude_pa"]),
        model_spec=ModelSpec(options={"mesh_size_m": truth["mesh_size_m"]}), pressure_error=truth["pressure_error"],
        effects=EffectSet.from_dict(truth["effects"]),
        protocol=DropProtocol(**truth["protocol"]),
        camera=Camera(fps=truth["camera"]["fps"], noise_y=truth["camera"]["noise_y_m"],
                      noise_theta=truth["camera"]["noise_theta"], missing_frames=truth["camera"]["missing_frames"]),
        max_step=truth["max_step_s"], air_damping=truth["air_damping"],
    )
    # the recorded effects hold the computed air damping, which the rebuilt twin keeps instead of computing it again
    assert rebuilt == replace(cfg, effects=EffectSet.from_dict(truth["effects"]))
    # and re-simulating from the truth file reproduces the data exactly
    runs, _, _ = simulate_field_drop_runs(rebuilt, SERIAL, progress=False)
    states = np.load(out / "truth_states.npz")
    for i, r in enumerate(runs, 1):
        np.testing.assert_array_equal(r.state, states[f"run{i:02d}"])
        d = truth["runs_detail"][i - 1]
        assert d["t_off_s"] == r.drop["t_off_s"] and d["missing_frames"] == r.missing.tolist()


def test_same_seed_gives_identical_files_and_another_seed_does_not(tmp_path):
    cfg = _small(runs=2, duration=0.5)
    a, b, c = tmp_path / "a", tmp_path / "b", tmp_path / "c"
    simulate_dataset(cfg, a, SERIAL, progress=False)
    simulate_dataset(cfg, b, SERIAL, progress=False)
    simulate_dataset(_small(runs=2, duration=0.5, seed=6), c, SERIAL, progress=False)
    names = sorted(p.name for p in a.iterdir())
    assert names == sorted(p.name for p in b.iterdir())
    for n in names:
        assert (a / n).read_bytes() == (b / n).read_bytes(), n
    assert (a / "run01.csv").read_bytes() != (c / "run01.csv").read_bytes()


@pytest.mark.slow
def test_results_do_not_depend_on_the_number_of_workers(tmp_path):
    cfg = _small(runs=4, duration=0.5)
    simulate_dataset(cfg, tmp_path / "one", SERIAL, progress=False)
    simulate_dataset(cfg, tmp_path / "two", ExecutorConfig(workers=2), progress=False)
    for n in ("run01.csv", "run04.csv", "truth.json"):
        assert (tmp_path / "one" / n).read_bytes() == (tmp_path / "two" / n).read_bytes()


def test_zero_noise_gives_exact_samples(tmp_path):
    cfg = _small(runs=1, camera=Camera(fps=500.0, noise_y=0.0, noise_theta=0.0, missing_frames=0))
    simulate_dataset(cfg, tmp_path / "d", SERIAL, progress=False)
    run = load_run(tmp_path / "d" / "run01.csv")
    state = np.load(tmp_path / "d" / "truth_states.npz")["run01"]
    # written with 11 significant digits (y) and 10 decimals (theta)
    assert run.n_filled == 0
    np.testing.assert_allclose(run.y, state[:, 0], rtol=1e-10, atol=1e-18)
    np.testing.assert_allclose(run.theta, state[:, 2], rtol=0, atol=1e-10)
    np.testing.assert_allclose(run.t, np.arange(500) / 500.0, rtol=0, atol=1e-12)


# ---------------------------------------------------------------------- protocol and camera
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_field_drop_protocol_start_state(seed):
    # no air damping: the drop is then an exact free fall with a free hinge (the air's drag acts during the drop)
    dyn, _ = twin_dynamics(_small(effects=EffectSet(), air_damping=False))
    proto = DropProtocol(t_off=(2e-3, 5e-3), theta_drop=(-0.4, 0.4), thetadot_drop=(-5, 5))
    run = simulate_run(dyn, proto, Camera(fps=1000.0, noise_y=0, noise_theta=0, missing_frames=0), 0.2, seed)
    t_off = run.drop["t_off_s"]
    assert 2e-3 <= t_off <= 5e-3 and abs(run.drop["theta_drop"]) <= 0.4
    y, yd, th, thd = run.state_at_field_on
    # free fall from rest at the equilibrium height, field off: exact for RK4
    assert y == pytest.approx(-0.5 * G * t_off**2, rel=1e-12)
    assert yd == pytest.approx(-G * t_off, rel=1e-12)
    # free hinge: I(theta) thetadot^2 is conserved during the drop
    s = dyn.force_model
    assert s.hinge_inertia(th) * thd**2 == pytest.approx(
        s.hinge_inertia(run.drop["theta_drop"]) * run.drop["thetadot_drop"] ** 2, rel=1e-9)
    # the recording starts at t = 0 with the field back on
    assert run.t[0] == 0 and run.t.size == 200


def test_drops_cover_several_initial_conditions(dataset):
    _, _, truth = dataset
    d = truth["runs_detail"]
    for key in ("t_off_s", "theta_drop", "thetadot_drop"):
        assert len({r[key] for r in d}) == len(d)


def test_camera_noise_and_missing_frames():
    cam = Camera(fps=1000.0, noise_y=2e-6, noise_theta=0.01, missing_frames=5)
    state = np.zeros((4000, 4))
    state[:, 2] = 0.3
    y, th, idx = cam.record(state, np.random.default_rng(9))
    # 4000 samples: the sample std is within ~2.3 % (2 sigma) of the true one; 6 % is ~5 sigma
    assert np.nanstd(y) == pytest.approx(2e-6, rel=0.06)
    assert np.nanstd(th) == pytest.approx(0.01, rel=0.06)
    assert np.nanmean(th) == pytest.approx(0.3, abs=5 * 0.01 / np.sqrt(4000))
    assert idx.size == 5 and np.all(np.diff(idx) > 1) and idx.min() > 0 and idx.max() < 3999
    assert np.all(np.isnan(y[idx])) and np.all(np.isnan(th[idx])) and np.isnan(y).sum() == 5


def test_noisy_theta_never_leaves_the_physical_range():
    cam = Camera(noise_theta=0.05, missing_frames=0)
    state = np.zeros((1000, 4))
    state[:, 2] = 0.99
    _, th, _ = cam.record(state, np.random.default_rng(0))
    assert np.all(np.abs(th) < 1)


# ---------------------------------------------------------------------- bad input, atomic output
def test_non_empty_output_is_refused_and_force_replaces(tmp_path):
    out = tmp_path / "d"
    out.mkdir()
    (out / "old.txt").write_text("x")
    cfg = _small(runs=1, duration=0.5)
    with pytest.raises(TwinError, match="not empty"):
        simulate_dataset(cfg, out, SERIAL, progress=False)
    simulate_dataset(cfg, out, SERIAL, force=True, progress=False)
    assert not (out / "old.txt").exists() and (out / "run01.csv").exists()


def test_a_run_leaving_the_trap_writes_nothing(tmp_path):
    cfg = _small(runs=2, protocol=DropProtocol(t_off=(0.012, 0.015)))
    with pytest.raises(TwinError, match="fell out of the trap"):
        simulate_dataset(cfg, tmp_path / "d", SERIAL, progress=False)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(
    "kwargs, fragment",
    [
        ({"runs": 0}, "runs"),
        ({"duration": -1.0}, "duration"),
        ({"pressure_error": 0.7}, "pressure error"),
        ({"experiment": ExperimentConditions(pressure_amplitude_pa=200.0)}, "cannot levitate"),
        ({"experiment": ExperimentConditions(side_length_m=3e-3)}, "side must lie in"),
        ({"experiment": ExperimentConditions(gap_m=1e-5)}, "model's own option"),
    ],
)
def test_bad_settings(tmp_path, kwargs, fragment):
    with pytest.raises(TwinError, match=fragment):
        cfg = _small(**kwargs)
        simulate_dataset(cfg, tmp_path / "d", SERIAL, progress=False)
    assert not (tmp_path / "d").exists()


@pytest.mark.parametrize("kwargs", [{"t_off": (-1e-3, 1e-3)}, {"theta_drop": (0.5, 0.2)}, {"theta_drop": (-1.0, 0.0)}])
def test_bad_protocol(kwargs):
    with pytest.raises(TwinError):
        DropProtocol(**kwargs)


def test_paper_like_preset_is_documented_and_simulates():
    cfg = TwinConfig.from_preset(PAPER_LIKE, runs=2, duration=1.0, seed=1)
    runs, dyn, p = simulate_field_drop_runs(cfg, SERIAL, progress=False)
    assert p == PAPER_LIKE.experiment.pressure_amplitude_pa and cfg.preset == "paper-like"
    assert "pair_scattering" in PAPER_LIKE.effects and PAPER_LIKE.description
    # its tuned linear damping is the total damping: the air's computed drag is not added on top
    assert not PAPER_LIKE.air_damping and not cfg.air_damping and "air_damping" not in dyn.effects
    assert dyn.effects == PAPER_LIKE.effects and "linear_damping" in dyn.effects
    assert all(np.all(np.isfinite(r.state)) for r in runs)


# ---------------------------------------------------------------------- attractor classes
@pytest.mark.slow
def test_paper_like_preset_has_in_phase_and_anti_phase_classes():
    """docs/twin.md: the preset is bistable, theta locks to y either in phase or in anti-phase."""
    cfg = TwinConfig.from_preset(PAPER_LIKE, runs=8, duration=4.0, seed=1, camera=Camera(fps=500.0))
    runs, _, _ = simulate_field_drop_runs(cfg, SERIAL, progress=False)
    labels = [classify_trajectory(r.t, r.state).label for r in runs]
    assert "locked-in-phase" in labels and "locked-anti-phase" in labels, labels


@pytest.mark.slow
def test_figures_are_written(tmp_path):
    from acousim.twin import write_twin_figures

    cfg = TwinConfig.from_preset(PAPER_LIKE, runs=3, duration=1.0, seed=1, camera=Camera(fps=500.0))
    simulate_dataset(cfg, tmp_path / "d", SERIAL, progress=False)
    paths = write_twin_figures(tmp_path / "d", tmp_path / "f")
    assert sorted(p.name for p in paths) == ["twin_phase_hist.png", "twin_phase_portraits.png",
                                             "twin_poincare.png", "twin_timeseries.png"]
    assert all(p.stat().st_size > 10_000 for p in paths)


def test_the_window_resonator_preset_sits_just_above_its_threshold():
    """The window-resonator preset: the cavity mode on (Q 250, x -2.2, a 20 mm transducer), and the lagged force
    nearly cancels the air's damping of y: the linear growth rate is +0.016 1/s (docs/twin.md), inside the
    first-order unstable band near its edge."""
    from acousim.dynamics.cavity_stability import LinearCavityCoupling
    from acousim.twin import WINDOW_RESONATOR
    from acousim.twin.simulation import twin_cavity

    config = TwinConfig.from_preset(WINDOW_RESONATOR, runs=1, duration=1.0)
    assert config.cavity_mode.quality_factor == 250.0 and config.to_dict()["resonator"]["detuning_half_widths"] == -2.2
    dyn, _ = twin_dynamics(config)
    lin = LinearCavityCoupling.from_cavity(twin_cavity(config, dyn), gamma_y=dyn.effects["air_damping"].gamma_y)
    assert 0 < lin.growth_rate() < 0.05
    low, high = lin.unstable_detunings()
    assert low < -2.2 < low + 0.2 and high < 0
