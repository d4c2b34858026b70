"""Coefficient comparison: origin shifts, ensemble statistics, agreement flags, CLI errors."""
import json
import subprocess
import sys

import numpy as np
import pytest

from cubedimer.terms import evaluate_library, library_terms
from validation.coefficients import (compare_coefficients, fitted_equilibrium_offset, origin_sensitivity,
                                     shift_origin)


def _poly(coefs, y, theta):
    terms = library_terms()
    state = np.column_stack([y, np.zeros_like(y), theta, np.zeros_like(y)])
    lib = evaluate_library(state)
    return lib @ np.array([coefs.get(t, 0.0) for t in terms])


def test_shift_origin_is_the_same_polynomial(rng):
    coefs = {"1": 0.3, "y": -1.9e4, "y^2": -1.4e7, "y^3": 8.7e9, "theta": -111.0, "y*theta": -1.6e5,
             "y^2*theta": 1.56e8, "theta^3": 390.0, "y*theta^2": 4.0}
    delta = 12e-6
    shifted = shift_origin(coefs, delta)
    y_new = rng.uniform(-2e-4, 2e-4, 50)
    theta = rng.uniform(-0.5, 0.5, 50)
    # p_old(y_new + delta) == p_new(y_new) for every point: exact algebra, round-off only
    np.testing.assert_allclose(_poly(shifted, y_new, theta), _poly(coefs, y_new + delta, theta), rtol=1e-9, atol=1e-9)
    # highest orders are unchanged, lower ones move by the first-order sensitivity
    assert shifted["y^3"] == coefs["y^3"] and shifted["y^2*theta"] == coefs["y^2*theta"]
    sens = origin_sensitivity(coefs)
    # theta picks up b[y*theta] delta (first order, = sensitivity) + b[y^2*theta] delta^2, exactly
    np.testing.assert_allclose(shifted["theta"] - coefs["theta"], sens["theta"] * delta + coefs["y^2*theta"] * delta**2, rtol=1e-9)


def test_fitted_equilibrium_offset():
    # yddot = -w^2 (y - y0) - a (y - y0)^2 has its root at y0 = -delta
    w2, a, y0 = 1.9e4, 1.4e7, -7e-6
    coefs = {"1": w2 * y0 - a * y0**2, "y": -w2 + 2 * a * y0, "y^2": -a}
    np.testing.assert_allclose(fitted_equilibrium_offset(coefs), -y0, rtol=1e-9)
    assert fitted_equilibrium_offset({"ydot": -1.0}) == 0.0  # no static part: origins taken to coincide


def _fake_model(static, delta, spread, rng, n_runs=12, flip=None):
    true = {eq: shift_origin(static[eq], delta) for eq in static}
    keep = {"yddot": ("1", "y", "y^2"), "thetaddot": ("theta", "y*theta", "y^2*theta")}
    runs = []
    for i in range(n_runs):
        eqs = {eq: {t: true[eq][t] * (1 + spread * rng.standard_normal()) for t in keep[eq]} for eq in keep}
        eqs["yddot"]["ydot"] = -1.0
        eqs["thetaddot"]["y*ydot*thetadot"] = 3e3
        runs.append({"file": f"run{i:02d}.csv", "equations": eqs})
    eqs = {eq: {t: true[eq][t] for t in keep[eq]} for eq in keep}
    if flip:
        eqs[flip[0]][flip[1]] *= -1
        for r in runs:
            r["equations"][flip[0]][flip[1]] *= -1
    eqs["yddot"]["ydot"] = -1.0
    eqs["thetaddot"]["y*ydot*thetadot"] = 3e3
    return {"equations": eqs, "per_run": runs}


@pytest.fixture(scope="module")
def static(default_model):
    from acousim import fit_static_coefficients, static_sweep

    sw = static_sweep(default_model, np.linspace(-0.3, 0.3, 31), np.linspace(-1.5e-4, 1.5e-4, 31))
    return fit_static_coefficients(sw)


def test_comparison_agrees_with_consistent_model(static, rng):
    model = _fake_model(static.coefficients, 10e-6, 0.05, rng)
    c = compare_coefficients(model, static.coefficients, static.std_errors)
    np.testing.assert_allclose(c.delta_m, 10e-6, rtol=1e-3)  # recovered from the fitted yddot's root
    first = c.rows[0]
    assert (first.equation, first.term) == ("thetaddot", "y^2*theta")
    for r in c.rows:
        if r.in_minimal_model and r.kind == "static":
            assert r.signs_agree and r.within_uncertainty, r
            np.testing.assert_allclose(r.ratio, 1.0, atol=0.1)  # 5 % spread over 12 runs
    dyn = [r for r in c.rows if r.kind != "static"]
    assert {r.term for r in dyn} == {"ydot", "y*ydot*thetadot"}
    assert all("dynamic only" in r.kind for r in dyn)


def test_comparison_flags_a_wrong_sign(static, rng):
    model = _fake_model(static.coefficients, 0.0, 0.05, rng, flip=("thetaddot", "y^2*theta"))
    c = compare_coefficients(model, static.coefficients, static.std_errors)
    lead = c.rows[0]
    assert lead.term == "y^2*theta" and lead.signs_agree is False and lead.within_uncertainty is False


def test_verdict_uses_the_integral_form_where_it_selected_the_term(static, rng):
    """A pooled integral-form estimate decides the verdict for the terms in its support; the others keep the ensemble."""
    model = _fake_model(static.coefficients, 0.0, 0.05, rng, flip=("thetaddot", "y^2*theta"))  # ensemble: wrong sign
    s_lead = static.coefficients["thetaddot"]["y^2*theta"]
    se = 0.2 * abs(s_lead)
    model["integral_form"] = {"method": "test", "thetaddot": {"terms": {
        "y^2*theta": {"value": 0.9 * s_lead, "std_error": se, "z": 0.9 * s_lead / se}}}}
    c = compare_coefficients(model, static.coefficients, static.std_errors, origin_offset=0.0)
    lead = c.rows[0]
    assert lead.term == "y^2*theta" and lead.verdict_from == "integral form"
    assert lead.integral == 0.9 * s_lead and lead.integral_std_error == se
    assert lead.signs_agree is True and lead.within_uncertainty is True
    np.testing.assert_allclose(lead.ratio, 0.9, rtol=1e-12)
    other = next(r for r in c.rows if r.term == "y*theta" and r.equation == "thetaddot")
    assert other.verdict_from == "ensemble" and np.isnan(other.integral)
    # 3 combined sigma away (SE dominates the static std): not within 2 sigma, same sign
    model["integral_form"]["thetaddot"]["terms"]["y^2*theta"]["value"] = s_lead + 3.0 * np.hypot(se, static.std_errors["thetaddot"]["y^2*theta"])
    lead = compare_coefficients(model, static.coefficients, static.std_errors, origin_offset=0.0).rows[0]
    assert lead.signs_agree is True and lead.within_uncertainty is False
    assert "integral form" in c.table().splitlines()[2]


def test_compare_cli(static, rng, tmp_path, default_model):
    from acousim import static_sweep

    model = _fake_model(static.coefficients, 5e-6, 0.05, rng)
    (tmp_path / "model.json").write_text(json.dumps(model))
    sw = static_sweep(default_model, np.linspace(-0.3, 0.3, 21), np.linspace(-1.5e-4, 1.5e-4, 21))
    sw.to_csv(tmp_path / "sweep.csv")
    r = subprocess.run([sys.executable, "-m", "validation", "compare", "--model", str(tmp_path / "model.json"),
                        "--sweep", str(tmp_path / "sweep.csv"), "--out", str(tmp_path / "out")], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    out = json.loads((tmp_path / "out" / "comparison.json").read_text())
    assert out["terms"][0]["term"] == "y^2*theta" and out["terms"][0]["signs_agree"] is True
    assert (tmp_path / "out" / "comparison.md").read_text().count("dynamic only") == 2


@pytest.mark.parametrize("content,message", [("{", "not valid JSON"), ('{"a": 1}', "no 'equations'"),
                                             ('{"equations": {"yddot": {"zz": 1}}}', "bad term")])
def test_compare_cli_bad_model(tmp_path, content, message, capsys):
    """The command's entry point in this process (``python -m validation compare`` itself runs in test_compare_cli):
    exit 2, one line naming model.json and the problem, nothing written."""
    from validation.cli import main

    (tmp_path / "model.json").write_text(content)
    assert main(["compare", "--model", str(tmp_path / "model.json"), "--data", str(tmp_path),
                 "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and message in err and "model.json" in err
    assert not (tmp_path / "out").exists()
