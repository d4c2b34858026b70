"""The held-y attractor map (acousim.atlas.held_y, python -m acousim held-y): Floquet multipliers against the Mathieu
stability chart, a cell against a hand-integrated one, the command's contract."""
import json
import math

import numba as nb
import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from acousim.atlas.field_drops import AtlasDimer, atlas_dynamics, settled_outcome
from acousim.cli import main
from acousim.dynamics.effects import EffectSet
from acousim.dynamics.equations import accelerations
from acousim.atlas.held_y import CLOSED, HeldYConfig, cell_summary, floquet_multipliers, held_y_arguments, held_y_cell
from cubedimer.rk4 import rk4


@nb.njit
def _mathieu(t, y, ydot, theta, thetadot, args):
    """y'' = -y (so y = cos t from (1, 0)); theta'' + gamma theta' + (delta + eps y) theta = 0."""
    delta, eps, gamma = args
    return -y, -(delta + eps * y) * theta - gamma * thetadot


@nb.njit
def _integrate_mathieu(args, x0, h, substeps, n_out, lower, upper, out):
    return rk4(_mathieu, args, x0, h, substeps, n_out, lower, upper, out)


def _mathieu_multipliers(delta, eps, gamma=0.0):
    # 4000 RK4 steps over 2 pi: h = 1.6e-3, the monodromy's error ~h^4 ~ 1e-11
    return floquet_multipliers(_integrate_mathieu, (delta, eps, gamma), [1.0, 0.0, 0.0, 0.0], 2 * np.pi, 4000)


def test_floquet_multipliers_give_the_mathieu_stability_chart():
    """theta'' + (delta + eps cos t) theta = 0: the first instability tongue (period doubling, tr M = -2) is bounded
    by delta = 1/4 +- eps/2 - eps^2/8 + O(eps^3) (the eps^3 term is -+eps^3/32 = 3e-5 at eps = 0.1)."""
    eps = 0.1
    trace = lambda d: float(np.real(np.sum(_mathieu_multipliers(d, eps))))
    upper = brentq(lambda d: trace(d) + 2.0, 0.25, 0.25 + eps, xtol=1e-10)
    lower = brentq(lambda d: trace(d) + 2.0, 0.25 - eps, 0.25, xtol=1e-10)
    assert upper == pytest.approx(0.25 + eps / 2 - eps ** 2 / 8, abs=1e-4)
    assert lower == pytest.approx(0.25 - eps / 2 - eps ** 2 / 8, abs=1e-4)
    # inside the tongue the orbit theta = 0 is unstable: mu = -exp(2 pi sigma) with, at its centre, sigma = the
    # half-width eps/2 over 2 omega = 1 (averaging), to O(eps^2)
    mu = _mathieu_multipliers(0.25 - eps ** 2 / 8, eps)
    sigma = math.log(np.max(np.abs(mu))) / (2 * np.pi)
    assert np.all(np.real(mu) < 0) and sigma == pytest.approx(eps / 2, rel=0.03)
    # outside, both multipliers lie on the unit circle; without damping their product is 1 (Liouville)
    mu = _mathieu_multipliers(0.4, eps)
    np.testing.assert_allclose(np.abs(mu), 1.0, atol=1e-8)
    assert np.prod(mu).real == pytest.approx(1.0, abs=1e-8)


def test_floquet_multipliers_of_a_damped_hinge_multiply_to_the_damping():
    """det M = exp(-gamma T) for theta'' + gamma theta' + ...: 1e-8 is the central difference's O(eps^2) error."""
    mu = _mathieu_multipliers(0.4, 0.1, gamma=0.05)
    assert abs(np.prod(mu)) == pytest.approx(math.exp(-0.05 * 2 * np.pi), rel=1e-8)


TINY = dict(settle_periods=20, analysed_periods=16, samples_per_period=40, max_step=1e-4)


@pytest.fixture(scope="module")
def cell():
    config = HeldYConfig(dimers=(AtlasDimer(500e-6, 0.02),), pressures_pa=(3000.0,), amplitudes_m=(100e-6,),
                         theta_starts=(0.15,), thetadot_starts=(0.0,), **TINY)
    return held_y_cell(config.dimers[0], 3000.0, 100e-6, config), config


def test_a_cell_against_a_hand_integrated_one(cell):
    """The same held system written out with the numpy reference accelerations and integrated by solve_ivp
    (DOP853, rtol 1e-10): the y orbit's period to 1e-9 and the hinge's classification and amplitude."""
    result, config = cell
    dyn = atlas_dynamics(500e-6, 0.02, 3000.0, 45_650.0)
    fm = dyn.force_model
    _, eq = held_y_arguments(dyn)
    theta_star, y0 = eq[2], eq[0] - 100e-6

    def rhs(t, x):
        ay = accelerations(fm, EffectSet(), np.array([x[0], x[1], theta_star, 0.0]))[0]
        at = accelerations(fm, dyn.effects, x)[1]
        return [x[1], float(ay), x[3], float(at)]

    def bottom(t, x):
        return x[1]
    bottom.direction = 1.0
    tol = dict(method="DOP853", rtol=1e-10, atol=[1e-14, 1e-12, 1e-12, 1e-10])
    ev = solve_ivp(rhs, (0, 0.1), [y0, 0.0, theta_star, 0.0], events=bottom, **tol).t_events[0]
    assert result["period_s"] == pytest.approx(ev[ev > 1e-3][0], rel=1e-9)   # the start is a lowest point too
    n_per = config.samples_per_period
    n = (config.settle_periods + config.analysed_periods) * n_per + 1
    t = np.arange(n) * result["period_s"] / n_per
    sol = solve_ivp(rhs, (0, t[-1]), [y0, 0.0, 0.15, 0.0], t_eval=t, **tol)
    keep = 2 * config.analysed_periods * n_per
    hand = settled_outcome(t[-keep:], sol.y.T[-keep:])
    run = result["runs"][0]
    assert run["outcome"] == hand["outcome"] and run["lock_ratio"] == hand["lock_ratio"]
    # RK4 at h omega ~ 0.015 over 36 periods: the hinge's amplitude to ~1e-7, checked to 1e-5
    assert run["amp_theta"] == pytest.approx(hand["amp_theta"], rel=1e-5)
    assert run["share_2fy"] == pytest.approx(hand["share_2fy"], rel=1e-3)


def test_the_locked_orbits_are_stable_and_damped(cell):
    """The small anti-phase orbit of the damped hinge (the hinge starts 0.08 above theta* = 0.070 at y's lowest
    point): both |mu| < 1, and it repeats after a period to ~3e-3 (36 periods do not settle it completely; the map
    runs 304)."""
    result, _ = cell
    run = result["runs"][0]
    assert run["outcome"] == "locked-anti-phase" and run["closure"] < 1e-2
    assert all(0 < m < 1 for m in run["floquet"])
    # an orbit that does not repeat to CLOSED is counted as unclosed and its multipliers are not summarised
    row = cell_summary(result)
    assert row["starts"] == 1 and run["closure"] > CLOSED
    assert row["unclosed"] == 1 and np.isnan(row["max_floquet"])
    closed = {**result, "runs": [{**run, "closure": 0.1 * CLOSED}]}
    assert cell_summary(closed)["max_floquet"] == pytest.approx(max(run["floquet"])) and cell_summary(closed)["unclosed"] == 0


def test_the_command_writes_resumes_and_refuses_bad_input(tmp_path, capsys):
    out = tmp_path / "map"
    argv = ["held-y", "--out", str(out), "--dimers", "500e-6:0.02", "--pressures", "3000", "--amplitudes", "100e-6",
            "--theta-starts", "0.0,0.4", "--thetadot-starts", "0", "--settle-periods", "10", "--analysed-periods",
            "12", "--workers", "1", "--no-progress"]
    assert main(argv) == 0
    data = json.loads((out / "held_y.json").read_text())
    assert len(data["summary"]) == 1 and data["summary"][0]["starts"] == 2
    assert (out / "held_y_classes.png").stat().st_size > 0 and (out / "held_y_2fy.png").exists()
    assert (out / "held_y.csv").read_text().splitlines()[0].startswith("dimer,side_m,gap_ratio,pressure_pa")
    # resume: a finished cell is kept
    cell_file = next((out / "cells").glob("*.json"))
    kept = json.loads(cell_file.read_text())
    kept["runs"][0]["outcome"] = "theta-at-rest"
    cell_file.write_text(json.dumps(kept))
    assert main(argv) == 0
    assert json.loads((out / "held_y.json").read_text())["summary"][0]["at_rest"] == 1
    capsys.readouterr()
    for bad, fragment in ((["--amplitudes", "-1e-4"], "--amplitudes"), (["--pressures", "0"], "--pressures"),
                          (["--dimers", "500e-6:0.2"], "--dimers")):
        never = tmp_path / "never"
        assert main(["held-y", "--out", str(never), *bad, "--workers", "1", "--no-progress"]) == 2
        err = capsys.readouterr().err
        assert fragment in err and len(err.strip().splitlines()) == 1 and not never.exists()
