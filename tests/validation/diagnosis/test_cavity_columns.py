"""The cavity candidate's columns from the force model's height structure (validation.diagnosis.prepare.cavity_lag
.CavityColumns) and the calibration's exact expansion of them in the origin height: the same numbers as evaluating the
model's forces directly, at a fraction of the cost."""
import numpy as np
import pytest

from acousim import CavityMode, Medium, cached_surrogate

from validation.diagnosis.prepare.cavity_lag import HEIGHT_DEGREE, CavityColumns, cavity_lag_columns

FREQUENCY = Medium().frequency_hz


@pytest.fixture(scope="module")
def surrogate():
    return cached_surrogate()


@pytest.fixture(scope="module")
def states():
    """Random states over a drop's range: |y| <= 200 um, |theta| <= 0.5 (n, 4)."""
    rng = np.random.default_rng(1)
    n = 400
    return np.column_stack([rng.uniform(-2e-4, 2e-4, n), rng.uniform(-0.03, 0.03, n), rng.uniform(-0.5, 0.5, n),
                            rng.uniform(-3.0, 3.0, n)])


def _columns_from_forces(fm, state, rest_y, reference):
    """The columns written with the model's own ``generalized_forces`` and central differences for the forces'
    gradients: the independent evaluation the height-structure one must reproduce."""
    from acousim.dynamics.resonator import mode_energy, potential_series

    from validation.diagnosis.prepare.cavity_lag import second_order_ratios

    y, yd, th, thd = state.T
    pot = potential_series(fm)
    shift = 2 * np.pi * FREQUENCY / mode_energy(fm.pressure_amplitude_pa, np.pi * 0.01**2, Medium())
    q_y, q_t = fm.generalized_forces(th, y)
    m, g = fm.mass, fm.gravity
    f_z, inertia = q_y + m * g, fm.hinge_inertia(th)
    delta = shift * (pot(th, y) - pot(0.0, rest_y))
    rate = -shift * (f_z * yd + q_t * thd)
    accel = np.stack([f_z / m, q_t / inertia], axis=1)
    a2, r2, b2, r3 = second_order_ratios(reference, FREQUENCY)
    hy, ht = 1e-7, 1e-4  # [m], [rad]: truncation (2k hy)^2 ~ 1e-8, round-off ~1e-9 of the gradients
    grad = {}
    for name, (dth, dy) in {"y": (0.0, hy), "t": (ht, 0.0)}.items():
        up, dn = fm.generalized_forces(th + dth, y + dy), fm.generalized_forces(th - dth, y - dy)
        grad[name] = [(u - d) / (2 * (hy if name == "y" else ht)) for u, d in zip(up, dn)]
    f_rest = float(fm.generalized_forces(0.0, rest_y)[0]) + m * g
    omega2 = -g * (float(fm.generalized_forces(0.0, rest_y + hy)[0]) - float(fm.generalized_forces(0.0, rest_y - hy)[0])) \
        / (2 * hy) / f_rest
    f_dot = grad["y"][0] * yd + grad["t"][0] * thd
    q_dot = grad["y"][1] * yd + grad["t"][1] * thd
    curvature = -shift * (f_z * g * (f_z / f_rest - 1) + q_t * g * m * q_t / (f_rest * inertia) + f_dot * yd + q_dot * thd)
    static = delta + a2 * delta**2 + r2 * curvature
    lag = rate * (1 + b2 * delta - r3 * omega2)
    return np.stack([accel * static[:, None], accel * lag[:, None]], axis=2)


@pytest.mark.parametrize("reference", [None, CavityMode(250.0, 1.2), CavityMode(180.0, 2.5)])
@pytest.mark.parametrize("rest_y", [0.0, 3e-5])
def test_columns_are_the_forces_columns(surrogate, states, reference, rest_y):
    """The height-structure columns equal those written with the model's generalized_forces: to round-off at first
    order; with the second-order terms to 1e-9 of each column (the central differences' truncation, (2k h)^2 ~ 1e-8 on
    the curvature, which enters multiplied by r2 delta'' ~ 1e-2 of the column)."""
    got = cavity_lag_columns(surrogate, states, rest_y=rest_y, reference=reference)
    want = _columns_from_forces(surrogate, states, rest_y, reference)
    scale = np.abs(want).max(axis=0)
    assert np.all(np.abs(got - want).max(axis=0) <= (1e-12 if reference is None else 1e-9) * scale)


def test_columns_reuse_the_angles(surrogate, states):
    """The angles' factors evaluated once serve any heights: the columns at shifted heights with the kept factors equal
    the columns evaluated afresh (exactly: the same arithmetic)."""
    cavity = CavityColumns(surrogate)
    angles = cavity.angle_factors(states[:, 2])
    shifted = states + np.array([4e-5, 0.0, 0.0, 0.0])
    reference = CavityMode(250.0, 1.2)
    np.testing.assert_array_equal(cavity.columns(shifted, 1e-5, reference, angles),
                                  cavity.columns(shifted, 1e-5, reference))


@pytest.mark.parametrize("reference", [None, CavityMode(250.0, 1.2)])
def test_parts_are_trigonometric_polynomials_in_the_origin_height(surrogate, states, reference):
    """With the data's origin at z0 (rest there too), each part of the columns is a trigonometric polynomial of degree
    HEIGHT_DEGREE in 2k z0: its values at 2 HEIGHT_DEGREE + 1 phases give it at any z0 through the Dirichlet kernel,
    to round-off (1e-12 of the part), the property the calibration's height search rests on."""
    cavity = CavityColumns(surrogate)
    angles = cavity.angle_factors(states[:, 2])
    two_k, z_eq = float(surrogate.two_k), float(surrogate.z_eq)
    n = 2 * HEIGHT_DEGREE + 1
    phases = 2 * np.pi * np.arange(n) / n

    def parts(z0):
        st = states.copy()
        st[:, 0] = z0 + states[:, 0] - z_eq
        regular, over, _ = cavity.column_parts(st, z0 - z_eq, reference, angles)
        return np.stack([regular, over])

    nodes = np.stack([parts(p / two_k) for p in phases])
    for z0 in (-8e-4, -4.3e-4, -1e-4):
        kernel = (1 + 2 * np.cos(np.outer(two_k * z0 - phases, np.arange(1, HEIGHT_DEGREE + 1))).sum(axis=1)) / n
        want = parts(z0)
        got = np.tensordot(kernel, nodes, axes=1)
        assert np.max(np.abs(got - want)) <= 1e-12 * np.max(np.abs(want))


def test_the_calibration_with_the_cavity_is_the_direct_one(clean_dataset, monkeypatch):
    """The calibration's height search on the cavity's exact expansion gives the pressure and origin of the search that
    evaluates the cavity's columns at every trial height (to 1e-10 relative and 1e-12 m: the two minimise the same
    function, evaluated to round-off)."""
    from validation.diagnosis import DiagnoseConfig
    from validation.diagnosis.calibrate import calibration as module
    from validation.diagnosis.calibrate.calibration_step import calibration_step
    from validation.diagnosis.calibrate.gap_model import fit_cavity_reference
    from validation.diagnosis.prepare.simulation_terms import SimulationTerms
    from validation.diagnosis.steps import load_for_diagnosis, start_diagnosis

    start = start_diagnosis(load_for_diagnosis(clean_dataset[0], progress=False))
    problem = calibration_step(start.prepared, start.conditions, start.model, start.spec, DiagnoseConfig(),
                               lambda *a: None).problem
    fit_cavity_reference(problem)
    sub = problem.subset(range(len(problem) - 1))
    effects = ["linear_damping", "cavity_lag"]
    fast = module.calibrate(SimulationTerms(sub), effects)
    monkeypatch.setattr(module, "height_expansion", lambda *a: None)
    direct = module.calibrate(SimulationTerms(sub), effects)
    assert fast.pressure_scale == pytest.approx(direct.pressure_scale, rel=1e-10)
    assert fast.z_origin_m == pytest.approx(direct.z_origin_m, abs=1e-12)
