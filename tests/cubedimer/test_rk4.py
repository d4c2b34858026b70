"""The one compiled RK4 (cubedimer.rk4): accuracy against DOP853, the box and its status codes,
batching, and on-disk caching of the entry points that bind an acceleration."""
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numba as nb
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from cubedimer.rk4 import STATUS_NONFINITE, STATUS_OK, box_status, describe_status, rk4, rk4_batch

W_Y, W_T = 2 * np.pi * 22.0, 2 * np.pi * 9.0


@nb.njit(cache=True)
def _coupled(t, y, yd, th, thd, args):
    """A damped, anharmonic, coupled pair (cubic in y, y-theta coupling): no closed form."""
    (p,) = args
    return (-p[0] * y - p[1] * yd + p[2] * y * y,
            -p[3] * th - p[4] * thd + p[5] * y - p[6] * th * y * y)


PARAMS = np.array([W_Y**2, 0.3, 9.5e6, W_T**2, 0.8, 1.5e6, 2e10])


def _coupled_rhs(_t, x):
    ay, at = _coupled.py_func(_t, x[0], x[1], x[2], x[3], (PARAMS,))
    return [x[1], ay, x[3], at]


@nb.njit(cache=True)
def _integrate_coupled(args, x0, h, substeps, n_out, lower, upper, out):
    return rk4(_coupled, args, x0, h, substeps, n_out, lower, upper, out)


@nb.njit(cache=True)
def _integrate_coupled_batch(args, x0s, h, substeps, n_out, lower, upper, out, n_valid, status):
    rk4_batch(_coupled, args, x0s, h, substeps, n_out, lower, upper, out, n_valid, status)


NO_BOX = (np.full(4, -np.inf), np.full(4, np.inf))


def test_matches_dop853():
    x0 = np.array([1.2e-4, 0.0, 0.3, 0.0])
    n, dt = 4500, 1 / 1500
    out = np.empty((n, 4))
    nv, status = _integrate_coupled((PARAMS,), x0, dt / 2, 2, n, *NO_BOX, out)
    assert (nv, status) == (n, STATUS_OK)
    t = np.arange(n) * dt
    ref = solve_ivp(_coupled_rhs, (0, t[-1]), x0, t_eval=t, rtol=1e-11, atol=1e-15, method="DOP853").y.T
    # RK4 at h omega_y = 0.046: phase error ~(h w)^5 / 120 per step ~ 1.7e-9, x 9000 steps ~ 1.5e-5 rad;
    # 1e-4 of each component's range leaves a margin of ~5
    scale = np.abs(ref).max(axis=0)
    np.testing.assert_allclose(out / scale, ref / scale, rtol=0, atol=1e-4)
    # and the check can fail: one step per frame is visibly worse than two
    out1 = np.empty((n, 4))
    _integrate_coupled((PARAMS,), x0, dt, 1, n, *NO_BOX, out1)
    assert np.max(np.abs(out1 - ref) / scale) > 4 * np.max(np.abs(out - ref) / scale)


def test_fourth_order_convergence():
    x0 = np.array([1e-4, 0.0, 0.2, 0.0])
    ends = []
    for sub in (1, 2, 4):
        out = np.empty((301, 4))
        _integrate_coupled((PARAMS,), x0, 1e-3 / sub, sub, 301, *NO_BOX, out)
        ends.append(out[-1])
    e1, e2 = np.abs(ends[0] - ends[2]), np.abs(ends[1] - ends[2])
    # halving h divides the error by 2^4 = 16 (by ~15 measured against h/4 instead of the exact solution)
    assert np.all(e1 / e2 > 12)


@pytest.mark.parametrize("component, upper", [(0, False), (0, True), (2, False), (2, True), (3, True)])
def test_box_exits_report_the_component_and_side(component, upper):
    x0 = np.array([1e-4, 0.0, 0.2, 0.0])
    lower, upp = (b.copy() for b in NO_BOX)
    amp = {0: 1e-4, 2: 0.2, 3: 0.2 * W_T}[component]
    if upper:
        upp[component] = 0.5 * amp
    else:
        lower[component] = -0.5 * amp
    out = np.full((2000, 4), np.nan)
    nv, status = _integrate_coupled((PARAMS,), x0, 5e-4, 1, 2000, lower, upp, out)
    assert status == box_status(component, upper) and 1 <= nv < 2000
    # the samples after x0 up to the exit are inside the box, the rest untouched
    assert np.all(out[1:nv, component] >= lower[component]) and np.all(out[1:nv, component] <= upp[component])
    assert np.all(np.isnan(out[nv:]))
    assert ("above" if upper else "below") in describe_status(status)


def test_non_finite_state_stops():
    blow = np.array([1e12, 0, 0, 0, 0, 0, 0.0])  # yddot = -1e12 y + ... grows without bound at h = 1 ms
    out = np.empty((5000, 4))
    nv, status = _integrate_coupled((-blow,), np.array([1e-3, 0, 0, 0]), 1e-3, 1, 5000, *NO_BOX, out)
    assert status == STATUS_NONFINITE and nv < 5000 and np.all(np.isfinite(out[:nv]))
    assert describe_status(status) == "the state became non-finite"


def test_batch_equals_single():
    x0s = np.array([[1e-4, 0, 0.1, 0], [-8e-5, 1e-3, -0.2, 1.0], [5e-5, 0, 0.0, 0.0]])
    n_out = np.array([500, 300, 400])
    h = np.array([5e-4, 5e-4, 2.5e-4])
    b = len(x0s)
    out = np.full((b, 500, 4), np.nan)
    n_valid, status = np.zeros(b, np.int64), np.zeros(b, np.int64)
    _integrate_coupled_batch((PARAMS,), x0s, h, 2, n_out, np.tile(NO_BOX[0], (b, 1)), np.tile(NO_BOX[1], (b, 1)),
                             out, n_valid, status)
    for i in range(b):
        single = np.empty((n_out[i], 4))
        _integrate_coupled((PARAMS,), x0s[i], h[i], 2, n_out[i], *NO_BOX, single)
        np.testing.assert_array_equal(out[i, :n_out[i]], single)  # identical arithmetic
    assert n_valid.tolist() == n_out.tolist() and status.tolist() == [0, 0, 0]


def test_direct_call_from_python_with_a_function_argument():
    x0 = np.array([1e-4, 0.0, 0.2, 0.0])
    a, b = np.empty((50, 4)), np.empty((50, 4))
    rk4(_coupled, (PARAMS,), x0, 5e-4, 2, 50, *NO_BOX, a)
    _integrate_coupled((PARAMS,), x0, 5e-4, 2, 50, *NO_BOX, b)
    np.testing.assert_array_equal(a, b)


# ---------------------------------------------------------------------- caching
def cache_hits_in_fresh_processes(code: str, dispatchers: str, tmp_path: Path, runs: int = 2) -> list[int]:
    """Run ``code`` in ``runs`` fresh interpreters sharing an empty numba cache directory; return
    the number of cache hits of ``dispatchers`` (an expression giving a list of dispatchers) in each."""
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "numba-cache"))
    root = Path(__file__).resolve().parents[2]
    env["PYTHONPATH"] = os.pathsep.join([str(root), env.get("PYTHONPATH", "")])
    script = textwrap.dedent(code) + f"\nprint(sum(sum(d.stats.cache_hits.values()) for d in {dispatchers}))\n"
    hits = []
    for _ in range(runs):
        res = subprocess.run([sys.executable, "-W", "error::numba.NumbaWarning", "-c", script], env=env, cwd=root,
                             capture_output=True, text=True, timeout=600)
        assert res.returncode == 0, res.stderr[-2000:]
        hits.append(int(res.stdout.strip().splitlines()[-1]))
    return hits


@pytest.mark.slow
def test_entry_points_binding_an_acceleration_are_cached_on_disk(tmp_path):
    code = """
        import numpy as np
        from tests.cubedimer.test_rk4 import PARAMS, NO_BOX, _integrate_coupled
        _integrate_coupled((PARAMS,), np.array([1e-4, 0, 0.1, 0]), 1e-3, 1, 10, *NO_BOX, np.empty((10, 4)))
    """
    # a NumbaWarning ("cannot cache ...") is an error in the child; the second process loads from disk
    first, second = cache_hits_in_fresh_processes(code, "[_integrate_coupled]", tmp_path)
    assert first == 0 and second >= 1


@nb.njit(cache=True)
def _driven(t, y, yd, th, thd, args):
    """Undamped oscillators driven at Omega: y'' = -w^2 y + F cos(Omega t), and theta'' = F sin(Omega t)."""
    w2, force, omega = args
    return -w2 * y + force * np.cos(omega * t), force * np.sin(omega * t)


@nb.njit(cache=True)
def _integrate_driven(args, x0, h, substeps, n_out, lower, upper, out):
    return rk4(_driven, args, x0, h, substeps, n_out, lower, upper, out)


def test_a_driven_oscillator_sees_the_stage_times():
    """The time argument: the stages at t, t + h/2 and t + h.  From rest, y = F (cos Omega t - cos w t) / (w^2 -
    Omega^2) and theta = F (t / Omega - sin(Omega t) / Omega^2); with the drive evaluated at the right times the
    error is fourth order (halving h divides it by 16; any stage at a wrong time leaves a first-order error)."""
    w, omega, force = 2 * np.pi * 20.0, 2 * np.pi * 13.0, 50.0
    t = np.arange(401) * 1e-3
    exact_y = force * (np.cos(omega * t) - np.cos(w * t)) / (w**2 - omega**2)
    exact_th = force * (t / omega - np.sin(omega * t) / omega**2)
    errors = []
    for sub in (4, 8):
        out = np.empty((401, 4))
        nv, status = _integrate_driven((w**2, force, omega), np.zeros(4), 1e-3 / sub, sub, 401, *NO_BOX, out)
        assert (nv, status) == (401, STATUS_OK)
        errors.append((np.max(np.abs(out[:, 0] - exact_y)), np.max(np.abs(out[:, 2] - exact_th))))
    (ey1, et1), (ey2, et2) = errors
    assert ey1 < 1e-6 * np.max(np.abs(exact_y)) and et1 < 1e-7 * np.max(np.abs(exact_th))
    # fourth order: 16x per halving (13-19: the leading term's constant moves a little between the two steps)
    assert 13 < ey1 / ey2 < 19 and 13 < et1 / et2 < 19
