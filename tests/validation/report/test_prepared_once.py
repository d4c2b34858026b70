"""``validation report`` prepares the data set once and passes the one preparation to the fit and the diagnosis
(fitting.derivatives.preparation): the fit and the diagnosis read the same arrays, and the checks run once.

The long steps (the fit's method, the diagnosis's steps, the report's pages) are replaced by recorders: what is
tested is the data flow through build_report (the loading's trap-frequency check and the model's construction are
real: a few seconds)."""
from types import SimpleNamespace

import numpy as np


def test_a_report_prepares_once_and_the_fit_and_the_diagnosis_read_the_same_arrays(small_oscillating_dataset, tmp_path,
                                                                                  monkeypatch):
    import fitting.derivatives.preparation as preparation
    import fitting.fit
    import fitting.output.model_file
    import validation.diagnosis.steps as steps
    import validation.report.build as build
    import validation.report.context as context
    import validation.simulation
    from validation.diagnosis.prepare.runs import prepare_diagnosis_runs

    calls = {"prepare_run": 0, "check_enough_runs": 0, "conditions_from_meta": 0}
    seen = {}

    def counted(name, module):
        real = getattr(module, name)

        def wrapper(*args, **kwargs):
            calls[name] += 1
            return real(*args, **kwargs)

        monkeypatch.setattr(module, name, wrapper)

    counted("prepare_run", preparation)
    counted("check_enough_runs", steps)
    counted("conditions_from_meta", validation.simulation)

    def fit_runs(prepared, scales, config, executor=None, cache_dir=None, progress=True, noise=None):
        seen["fit"] = prepared
        return SimpleNamespace(runs=list(prepared))

    def diagnose_steps(start, config, progress):
        seen["diagnosis"] = prepare_diagnosis_runs(start.prepared)
        return SimpleNamespace(to_json=lambda: {})

    monkeypatch.setattr(fitting.fit, "fit_runs", fit_runs)
    monkeypatch.setattr(fitting.output.model_file, "write_fit", lambda res, out: None)
    monkeypatch.setattr(fitting.output.model_file, "model_json", lambda res: {})
    monkeypatch.setattr(context, "variant_comparison", lambda res, fit_dir, joint: None)
    monkeypatch.setattr(context, "fit_description", lambda record, res: None)
    monkeypatch.setattr(steps, "_diagnose", diagnose_steps)
    monkeypatch.setattr(build, "with_simulations", lambda diag, meta, spec, res, figs: diag)
    monkeypatch.setattr(build, "render_report", lambda out, **kw: out / "report.html")
    monkeypatch.setattr(fitting.fit, "replace", lambda res, **kw: res)

    build.build_report(small_oscillating_dataset, tmp_path / "report", progress=False)

    n_runs = len(seen["fit"])
    assert n_runs == 3 and calls["prepare_run"] == n_runs  # each run prepared once, the orientation check included
    assert calls["check_enough_runs"] == 1 and calls["conditions_from_meta"] == 1
    for fit, diag in zip(seen["fit"], seen["diagnosis"]):
        d = fit.derivs
        inner = slice(d.trim, len(d.t) - d.trim)
        assert diag.name == fit.run.name
        np.testing.assert_array_equal(diag.state, d.state[inner])
        np.testing.assert_array_equal(diag.accel, d.accel[inner])
        p = fit.preparation
        edge = slice(p.column_edge, len(p.run.t) - p.column_edge)
        np.testing.assert_array_equal(diag.integral.state, p.columns[edge])
        assert diag.integral.windows == p.windows and diag.smoothing == (d.window * fit.run.dt, d.polyorder)
