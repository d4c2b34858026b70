"""Static sweeps and the static coefficients fitted to them."""
import json

import numpy as np
import pytest

from acousim import analytic
from acousim.statics.sweep import SweepResult, fit_static_coefficients, read_sweep_csv, static_sweep, taylor_coefficients

from tests.acousim.gorkov.test_forces import vertical_stiffness


def _synthetic_sweep(coefs_yddot, coefs_thetaddot):
    theta, y = np.linspace(-0.5, 0.5, 15), np.linspace(-1e-4, 1e-4, 13)
    tt, yy = np.meshgrid(theta, y, indexing="ij")
    from cubedimer.terms import parse_term

    def poly(c):
        out = np.zeros_like(tt)
        for name, v in c.items():
            e = parse_term(name)
            out += v * yy ** e[0] * tt ** e[2]
        return out

    cols = {"theta": tt, "y": yy, "yddot": poly(coefs_yddot), "thetaddot": poly(coefs_thetaddot)}
    return SweepResult(theta, y, cols, {})


def test_static_fit_recovers_known_polynomial():
    truth_y = {"1": 0.1, "y": -1.9e4, "y^2": -1.4e7, "y^3": 8e9, "y*theta^2": 4.0}
    truth_t = {"theta": -111.0, "y*theta": -1.6e5, "y^2*theta": 1.56e8, "theta^3": 390.0}
    c = fit_static_coefficients(_synthetic_sweep(truth_y, truth_t))
    assert len(c.terms) == 10  # velocity-free monomials of degree <= 3 in (y, theta)
    for eq, truth in (("yddot", truth_y), ("thetaddot", truth_t)):
        for term in c.terms:
            expected = truth.get(term, 0.0)
            scale = max(abs(v) for v in truth.values()) * 1e-9
            # exact data: recovered to round-off of the scaled least squares
            np.testing.assert_allclose(c.coefficients[eq][term], expected, rtol=1e-7, atol=scale * 1e-3 ** -0)
        assert c.relative_residual[eq] < 1e-10


def test_sweep_csv_round_trip(default_model, tmp_path):
    sw = static_sweep(default_model, np.linspace(-0.5, 0.5, 5), np.linspace(-1e-4, 1e-4, 4))
    path = tmp_path / "sweep.csv"
    sw.to_csv(path)
    back = read_sweep_csv(path)
    for col in ("theta", "y", "potential", "force_z", "q_y", "q_theta", "yddot", "thetaddot"):
        np.testing.assert_allclose(back[col], sw[col], rtol=1e-9)  # written with 10 significant digits
    assert back.settings["pressure_amplitude_pa"] == 3000.0


def test_read_sweep_rejects_missing_column(tmp_path):
    path = tmp_path / "bad.csv"
    path.write_text("theta,y,force_z\n0,0,1\n")
    with pytest.raises(ValueError, match="bad.csv.*missing column"):
        read_sweep_csv(path)


def test_sweep_columns_are_consistent(default_model):
    sw = static_sweep(default_model, np.linspace(-0.9, 0.9, 7), np.linspace(-2e-4, 2e-4, 5))
    m = default_model.dimer.total_mass
    np.testing.assert_allclose(sw["q_y"], sw["force_z"] - m * 9.81, rtol=1e-12)
    np.testing.assert_allclose(sw["yddot"], sw["q_y"] / m, rtol=1e-12)
    np.testing.assert_allclose(sw["thetaddot"], sw["q_theta"] / default_model.dimer.hinge_inertia(sw["theta"]), rtol=1e-12)


def test_taylor_coefficients_match_closed_form(default_model):
    """Local coefficients at equilibrium against derivatives of the closed form:
    thetaddot = Q_theta/I with Q_theta ~ cos(2k(Z_eq + y)) so b[y^2*theta] / b[theta] = -2k^2."""
    t = taylor_coefficients(default_model)
    k = default_model.wave.wavenumber
    z = default_model.equilibrium_height
    h = 1e-4
    _, _, qp = analytic.dimer_generalized_forces(500e-6, h, z, default_model.wave)
    _, _, qm = analytic.dimer_generalized_forces(500e-6, -h, z, default_model.wave)
    b_theta = (qp - qm) / (2 * h) / default_model.dimer.hinge_inertia(0.0)
    np.testing.assert_allclose(t["thetaddot"]["theta"], b_theta, rtol=1e-3)  # mesh error 1.3e-4
    np.testing.assert_allclose(t["thetaddot"]["y^2*theta"] / t["thetaddot"]["theta"], -2 * k**2, rtol=1e-3)
    np.testing.assert_allclose(t["thetaddot"]["y*theta"] / t["thetaddot"]["theta"], -2 * k * np.tan(2 * k * z), rtol=1e-3)
    np.testing.assert_allclose(t["yddot"]["y"], -vertical_stiffness(default_model) / default_model.dimer.total_mass, rtol=1e-6)


def test_theta_y2_coupling_at_defaults(default_model):
    """Acceptance: at the defaults the theta*y^2 term comes out with its sign, size and uncertainty."""
    from acousim.cli.sweep_command import DEFAULT_THETA, DEFAULT_Y, parse_range

    sw = static_sweep(default_model, parse_range(DEFAULT_THETA, "theta"), parse_range(DEFAULT_Y, "y"))
    c = fit_static_coefficients(sw, theta_max=0.3, y_max=150e-6, taylor=taylor_coefficients(default_model))
    b, e = c.coefficients["thetaddot"]["y^2*theta"], c.std_errors["thetaddot"]["y^2*theta"]
    taylor = c.taylor["thetaddot"]["y^2*theta"]
    assert b > 0 and b / e > 10  # positive: the hinge stiffens as |y| grows... towards the node
    # the box fit absorbs part of the coupling into theta^3 and higher orders: within 25 % of the local value
    np.testing.assert_allclose(b, taylor, rtol=0.25)
    # forbidden terms vanish (mirror symmetry: thetaddot odd, yddot even in theta)
    for term in ("1", "y", "y^2", "y^3", "theta^2", "y*theta^2"):
        assert abs(c.coefficients["thetaddot"][term]) < 1e-6 * abs(c.coefficients["thetaddot"]["theta"]) * (1e4 if "y" in term else 1)
    d = c.to_dict()
    assert d["equations"]["thetaddot"]["y^2*theta"] == b and "y_origin" in d
    json.dumps(d)
