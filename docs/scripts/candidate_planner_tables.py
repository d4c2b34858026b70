"""The candidates' run planner's tables of docs/diagnosis.md ("Planning runs for the candidates").

``c6``: for the velocity coupling's fixed-set draws (``velocity_coupling_fixed_set.draw``: the blind strengths, a
pressure error within +-10 %, the twin's seed), the planner's oracle standard error of c6 on each case's own 10 runs
of 3 s (the twin's exact states of the data set the diagnosis was given; the air's damping, linear damping fitted
beside the coupling) and the runs for c6 within 20 % at 95 % (oracle z 9.8, 1/sqrt(n) from the case's runs).  With
``--records DIR`` (the output folder of ``velocity_coupling_information.py`` or of
``velocity_coupling_fixed_set.py --effects velocity_coupling`` for the same seed) it prints the trajectory test's
measured c6, standard error and error beside it, and the ratio of the two standard errors.

    python docs/scripts/candidate_planner_tables.py c6 --seed 16100 --cases 16
    python docs/scripts/velocity_coupling_information.py --out /tmp/vc19301 --seed 19301 --cases 2
    python docs/scripts/candidate_planner_tables.py c6 --seed 19301 --cases 2 --records /tmp/vc19301
    python docs/scripts/velocity_coupling_fixed_set.py --out /tmp/fs19302 --effects velocity_coupling --cases 2 \
        --seed 19302
    python docs/scripts/candidate_planner_tables.py c6 --seed 19302 --cases 2 --records /tmp/fs19302

``heights``: the alias z of the cavity's lag against linear damping (and back) for runs dropped from one height or
from several, on the twin with a resonator (Q 250, detuning 1.5 half-widths) and on one with linear damping of y
alone (1 1/s), both without the air's damping (the pair's twin case of docs/diagnosis.md), and with the air's
damping beside the resonator.

    python docs/scripts/candidate_planner_tables.py heights --runs 8 --duration 2

``integral-mc`` and ``trajectory-mc``: the two oracles against Monte-Carlos of their estimators (docs/diagnosis.md,
"Validation").

    python docs/scripts/candidate_planner_tables.py integral-mc --draws 2000
    python docs/scripts/candidate_planner_tables.py trajectory-mc --draws 400
"""
from __future__ import annotations

import argparse
import json
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from velocity_coupling_fixed_set import draw  # noqa: E402

from acousim.dynamics.effects import EffectSet  # noqa: E402
from acousim.models import ExperimentConditions  # noqa: E402
from acousim.twin import TwinConfig  # noqa: E402
from fitting.uncertainty.oracle import NoiseLevels  # noqa: E402
from validation.blind.candidates import NOMINAL_PRESSURE_PA  # noqa: E402
from validation.planner import CandidatePlanConfig, RunDesign, plan_candidates, reference_runs  # noqa: E402
from validation.planner.candidate_plan import target_z  # noqa: E402

NOISE = NoiseLevels(1e-6, 0.005, source="the twin camera's default")


def _case_folder(records: Path | None, i: int) -> Path | None:
    """Case i's folder in ``records``: ``vc_i`` (velocity_coupling_information.py) or ``velocity_coupling_i``
    (velocity_coupling_fixed_set.py, a whole diagnosis); None without one."""
    for name in (f"vc_{i}", f"velocity_coupling_{i}"):
        if records is not None and (records / name / "truth.json").exists():
            return records / name
    return None


def _measured(folder: Path | None) -> dict | None:
    """The trajectory test's c6 and standard errors of a case: ``record.json``, or a diagnosis's
    ``result_current.json`` (its trajectory-test record)."""
    if folder is None:
        return None
    if (folder / "record.json").exists():
        return json.loads((folder / "record.json").read_text())
    if (folder / "result_current.json").exists():
        return json.loads((folder / "result_current.json").read_text()).get("output_error")
    return None


def c6_table(seed: int, cases: int, records: Path | None) -> None:
    """One line per case: c6, the planner's SE on the case's runs, the runs for 20 % (and the measured SE)."""
    ratios, rel, ratios_t, rel_t, z_t = [], [], [], [], []
    for i in range(cases):
        case = draw("velocity_coupling", i, seed)
        folder = _case_folder(records, i)
        truth = json.loads((folder / "truth.json").read_text()) if folder is not None else None
        p = truth["pressure_amplitude_pa"] if truth else NOMINAL_PRESSURE_PA * (1 + case["pressure_error"])
        twin_seed = truth["seed"] if truth else case["twin_seed"]
        twin = TwinConfig(runs=10, duration=3.0, seed=twin_seed, experiment=ExperimentConditions(pressure_amplitude_pa=p),
                          effects=EffectSet.from_dict(case["effects"]), air_damping=True)
        cpu = time.process_time()
        fitted = ("velocity_coupling", "linear_damping")
        ref = reference_runs(twin, RunDesign(duration=3.0, n_reference=10, seed=twin_seed), fitted, NOISE)
        plan = plan_candidates(ref, NOISE, CandidatePlanConfig(fitted, pairs=(("velocity_coupling", "linear_damping"),),
                                                               run_counts=(10,), n_draws=1))
        c6 = next(q for q in plan.parameters if q.label == "velocity_coupling.c6")
        se = c6.std_error_reference
        tr = next(q for q in plan.parameters if q.label == "trajectory test: c6")
        se_t = tr.std_error_reference
        need_t = int(np.ceil(10 * (target_z(0.2, 0.95) * se_t / abs(c6.coefficient)) ** 2))
        rel_t.append(se_t / abs(c6.coefficient))
        need = int(np.ceil(10 * (target_z(0.2, 0.95) * se / abs(c6.coefficient)) ** 2))
        rel.append(se / abs(c6.coefficient))
        line = (f"{i}: c5 {case['effects']['velocity_coupling']['c5']:.0f}, c6 {c6.coefficient:.3g}; planner SE "
                f"{se:.3g} (relative {se / abs(c6.coefficient):.2f}); runs for c6 within 20 % at 95 %: {need}; "
                f"alias z of the coupling by linear damping {plan.pairs[0].alias_z_reference:.1f}; trajectory test's "
                f"oracle SE {se_t:.3g} (relative {se_t / abs(c6.coefficient):.2f}), runs for 20 %: {need_t}; "
                f"{time.process_time() - cpu:.1f} CPU-s")
        r = _measured(folder)
        if r is not None:
            m_se = r["std_errors"]["c6"]
            err = r["params"]["c6"] / c6.coefficient - 1
            ratios.append(se / m_se)
            ratios_t.append(se_t / m_se)
            z_t.append((r["params"]["c6"] - c6.coefficient) / se_t)
            line += (f"; trajectory test: c6 error {err:+.0%}, SE {m_se:.3g} (relative {m_se / abs(c6.coefficient):.2f}), "
                     f"integral form / measured SE {se / m_se:.2f}, trajectory oracle / measured SE {se_t / m_se:.2f}, "
                     f"error in oracle SEs {z_t[-1]:+.2f}")
        print(line, flush=True)
    print(f"median relative SE of c6 over {len(rel)} cases: integral form {np.median(rel):.2f}, trajectory test's oracle "
          f"{np.median(rel_t):.2f}", flush=True)
    if ratios:
        print(f"integral form / measured SE: median {np.median(ratios):.2f}, range {min(ratios):.2f}-{max(ratios):.2f}; "
              f"trajectory oracle / measured SE: median {np.median(ratios_t):.2f}, range {min(ratios_t):.2f}-"
              f"{max(ratios_t):.2f}; measured errors in oracle SEs: rms {np.sqrt(np.mean(np.square(z_t))):.2f}")


def _designs() -> list[tuple[str, tuple[float, ...]]]:
    return [("one amplitude, 20 um", (20e-6,)), ("one amplitude, 50 um", (50e-6,)), ("one amplitude, 100 um", (100e-6,)),
            ("one amplitude, 150 um", (150e-6,)), ("four amplitudes, 20-150 um", (20e-6, 50e-6, 100e-6, 150e-6))]


def heights_table(runs: int, duration: float, n_reference: int) -> None:
    """Alias z of the cavity's lag and linear damping against each other, per design."""
    twins = [("resonator Q 250, x 1.5, no air", TwinConfig(air_damping=False, transducer_q=250.0, cavity_detuning=1.5),
              ("cavity_lag", "linear_damping")),
             ("linear damping of y 1 1/s, no air", TwinConfig(
                 air_damping=False, effects=EffectSet.from_dict({"linear_damping": {"gamma_y": 1.0, "gamma_theta": 0.0}})),
              ("linear_damping", "cavity_lag")),
             ("resonator Q 250, x 1.5, with the air", TwinConfig(transducer_q=250.0, cavity_detuning=1.5),
              ("cavity_lag", "linear_damping"))]
    fitted = ("cavity_lag", "linear_damping")
    for label, twin, pair in twins:
        for name, heights in _designs():
            cpu = time.process_time()
            ref = reference_runs(twin, RunDesign(duration=duration, n_reference=n_reference, amplitudes=heights,
                                                 theta_drop=(-0.05, 0.05), seed=1), fitted)
            plan = plan_candidates(ref, NOISE, CandidatePlanConfig(fitted, pairs=(pair,), run_counts=(runs,), n_draws=100))
            a = plan.pairs[0]
            amp = plan.amplitude_m
            line = (f"{label} | {name}: |y| {amp[0] * 1e6:.0f}-{amp[2] * 1e6:.0f} um; {pair[0]} by {pair[1]}: alias z "
                    f"{a.table[0][1]:.2f} at {runs} runs (10 %: {a.table[0][2]:.2f}), {a.alias_z_reference:.2f} on "
                    f"{len(ref)}; runs for alias z 4: {a.runs_needed}")
            if pair[0] == "cavity_lag":  # the lag's part alone: the static gain's contribution left out of the truth
                lag = replace(ref, truth={**ref.truth, "cavity_lag.static_gain": 0.0})
                alone = plan_candidates(lag, NOISE, CandidatePlanConfig(fitted, pairs=(pair,), run_counts=(runs,),
                                                                        n_draws=100)).pairs[0]
                line += f"; the lag alone: alias z {alone.table[0][1]:.2f}, runs for 4: {alone.runs_needed}"
            print(line + f"; {time.process_time() - cpu:.1f} CPU-s", flush=True)


def integral_mc(draws: int) -> None:
    """The integral form's oracle against least squares on noisy copies of 10 twin runs of 3 s (c5 = -3028 1/m,
    c6 = -9.04e5 1/m^2, the air's damping): Monte-Carlo spread over planned standard error per parameter."""
    from acousim.twin import simulate_field_drop_runs, twin_dynamics
    from cubedimer.executor import ExecutorConfig
    from fitting.derivatives.integral_form import detrend_windows, window_starts
    from fitting.uncertainty.oracle import covariance_diagonal, integral_design
    from validation.planner.reference_runs import EQUATIONS, _columns

    fitted = ("velocity_coupling", "linear_damping")
    twin = TwinConfig(effects=EffectSet.from_dict({"velocity_coupling": {"c5": -3028.0, "c6": -9.04e5}}))
    runs, _, _ = simulate_field_drop_runs(replace(twin, runs=10, duration=3.0, seed=5,
                                                  camera=replace(twin.camera, missing_frames=0)),
                                          ExecutorConfig(workers=1), progress=False)
    ref = reference_runs(twin, RunDesign(duration=3.0, n_reference=10, seed=5), fitted)
    fm = twin_dynamics(twin)[0].force_model
    rng = np.random.default_rng(19303)
    for q, eq in enumerate(EQUATIONS):
        designs = [integral_design(_columns(r.state, fm, None, None, fitted)[q], r.state[:, 2 * q], 5e-4) for r in runs]
        X = np.concatenate([d[0] for d in designs])
        scale = np.linalg.norm(X, axis=0)
        Q, R = np.linalg.qr(X / scale)
        est = []
        for _ in range(max(1, draws // 100)):
            b = np.concatenate([detrend_windows(NOISE.of(eq) * rng.standard_normal((r.state.shape[0], 100)),
                                                window_starts(r.state.shape[0], w), w) for r, (_, w) in zip(runs, designs)])
            est.append(np.linalg.solve(R, Q.T @ b) / scale[:, None])
        planned = NOISE.of(eq) * np.sqrt(covariance_diagonal(ref.information[q].sum(axis=0)))
        ratio = np.concatenate(est, axis=1).std(axis=1, ddof=1) / planned
        print(eq, ", ".join(f"{lab} {r:.3f}" for lab, r in zip(ref.labels[q], ratio)), flush=True)


def trajectory_mc(draws: int) -> None:
    """The trajectory test's oracle against its Gauss-Newton fit on noisy copies of 4 twin runs of 1.5 s (fresh seeds
    19304 and 19305; c5 = -3000 1/m, c6 = 1e6 1/m^2, the air's damping)."""
    from acousim.twin import simulate_field_drop_runs, twin_dynamics
    from cubedimer.executor import ExecutorConfig
    from fitting.uncertainty.oracle import covariance_diagonal
    from validation.diagnosis.identify.output_error import RunTrajectories, fit_trajectories
    from validation.planner.trajectory_oracle import _law, trajectory_information

    twin = TwinConfig(runs=4, duration=1.5, seed=19304,
                      effects=EffectSet.from_dict({"velocity_coupling": {"c5": -3000.0, "c6": 1.0e6}}))
    dyn, p = twin_dynamics(twin)
    runs, _, _ = simulate_field_drop_runs(replace(twin, camera=replace(twin.camera, missing_frames=0)),
                                          ExecutorConfig(workers=1), progress=False)
    states = [r.state for r in runs]
    labels, info, truth = trajectory_information(twin, dyn, states, 5e-4, NOISE)
    se = np.sqrt(covariance_diagonal(info.sum(axis=0)))
    law, shape, rates = _law(dyn)
    start = {"pressure_pa": p, **rates, "c5": -3000.0, "c6": 1.0e6}
    names = ("pressure_pa", "gamma_y", "gamma_theta", "c5", "c6", "y_offset")
    rng = np.random.default_rng(19305)
    sd = np.array([NOISE.sigma_y, NOISE.sigma_theta])
    est = []
    for _ in range(draws):
        pos = [st[:, [0, 2]] + rng.standard_normal((len(st), 2)) * sd for st in states]
        data = RunTrajectories(5e-4, pos, np.tile(sd, (len(states), 1)), np.array([st[0] for st in states]))
        fit = fit_trajectories(data, dyn.force_model, law, shape, {}, start, True, iterations=4)
        est.append([fit.params[n] for n in names])
    est = np.array(est)
    true = np.array([truth[lab] for lab in labels])
    for lab, r, b in zip(labels, est.std(axis=0, ddof=1) / se, (est.mean(axis=0) - true) / se):
        print(f"{lab}: Monte-Carlo spread / oracle SE {r:.3f}, mean error {b:+.2f} oracle SEs", flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="what", required=True)
    c = sub.add_parser("c6")
    c.add_argument("--seed", type=int, default=16100)
    c.add_argument("--cases", type=int, default=16)
    c.add_argument("--records", type=Path, default=None)
    h = sub.add_parser("heights")
    h.add_argument("--runs", type=int, default=8)
    h.add_argument("--duration", type=float, default=2.0)
    h.add_argument("--reference-runs", type=int, default=16)
    for name in ("integral-mc", "trajectory-mc"):
        sub.add_parser(name).add_argument("--draws", type=int, default=400)
    args = ap.parse_args()
    if args.what == "c6":
        c6_table(args.seed, args.cases, args.records)
    elif args.what == "heights":
        heights_table(args.runs, args.duration, args.reference_runs)
    elif args.what == "integral-mc":
        integral_mc(args.draws)
    else:
        trajectory_mc(args.draws)


if __name__ == "__main__":
    main()
