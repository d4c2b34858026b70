"""The simulation's terms at the data states: their exact height structure (three evaluations give every
origin height), and the calibration's reduced height search against the plain least squares."""
import numpy as np
import pytest

from validation.diagnosis import DiagnosisProblem
from validation.diagnosis.preparation import prepare_diagnosis_runs
from validation.diagnosis.calibration import calibrate, vertical_system
from validation.diagnosis.drift import PressureDrift
from validation.diagnosis.simulation_model import SimulationTerms


@pytest.fixture(scope="module")
def problem(clean_dataset):
    from cubedimer.dataset import load_dataset
    from cubedimer.meta import read_meta

    from validation.simulation import model_from_meta

    data, _ = clean_dataset
    model = model_from_meta(read_meta(data)).interpolated()
    return DiagnosisProblem.from_recorded(model, prepare_diagnosis_runs(load_dataset(data)), 1500)


def _direct(terms: SimulationTerms, z0: float):
    """The terms at z0 evaluated from the model's forces, not from the height harmonics."""
    return ([terms._static_run(r, z0) for r in terms.runs],
            [[terms._integral_run(r, z0, q) for r in terms.runs] for q in (0, 1)])


@pytest.mark.parametrize("drifting", [False, True])
@pytest.mark.parametrize("dz0", [-3.1e-4, 2.7e-5, 1.9e-4])
def test_height_harmonics_reproduce_direct_evaluation(problem, drifting, dz0):
    if drifting:  # a drifting pressure multiplies the acoustic terms by f(t): the structure in z0 is kept
        problem = problem.with_drift(PressureDrift({r.name: (np.array([0.0, 3.0]), np.array([0.97, 1.03]))
                                                    for r in problem.runs}))
    terms = SimulationTerms(problem)
    z0 = problem.model.equilibrium_height + dz0
    static, integral = _direct(terms, z0)
    for got, want in zip(terms._static(z0), static):
        for g, w in zip(got, want):
            # the reconstruction A + B cos + C sin differs from the direct sum by round-off of |B|, |C|
            np.testing.assert_allclose(g, w, rtol=0, atol=1e-11 * np.max(np.abs(w)))
    for q in (0, 1):
        for got, want in zip(terms.integral_known(z0, q), integral[q]):
            np.testing.assert_allclose(got[0], want[0], rtol=0, atol=1e-11 * np.max(np.abs(want[0])))
            np.testing.assert_array_equal(got[1], want[1])  # the non-acoustic part does not depend on z0


@pytest.mark.parametrize("effects", [(), ("linear_damping",), ("quadratic_drag", "pair_scattering")])
def test_reduced_height_search_matches_the_plain_least_squares(problem, effects):
    """The calibration solves its height search on the R factor of the stacked rows; the plain least squares
    on every row, minimised over z0 on a fine grid, gives the same origin and pressure."""
    terms = SimulationTerms(problem)
    cal = calibrate(terms, effects)
    z_eq = problem.model.equilibrium_height
    from validation.diagnosis.candidates import parameter_slots

    y_effects = [n for n in effects if parameter_slots([n], 0)]
    cols = [0] + [c for _, _, c in parameter_slots(y_effects, 0)]

    def rss(z0):
        x, b = vertical_system(terms, z0, y_effects)
        sol, *_ = np.linalg.lstsq(x[:, cols], b, rcond=None)
        r = b - x[:, cols] @ sol
        return float(r @ r), sol[0]

    grid = cal.z_origin_m + np.linspace(-2e-7, 2e-7, 9)
    values = [rss(z) for z in grid]
    best = int(np.argmin([v[0] for v in values]))
    assert 0 < best < len(grid) - 1  # the calibrated origin is the plain least squares' minimum to 0.05 um
    # the pressure scale at the same origin, by the two routes: round-off only
    np.testing.assert_allclose(rss(cal.z_origin_m)[1], cal.pressure_scale, rtol=1e-9)
    assert abs(cal.z_origin_m - z_eq) < 4e-4


def test_energy_balance_closes_on_a_fullwave_path_with_damping():
    """A model without a potential (the full wave): on exact, noise-free states at the thinned diagnosis frames
    (2 ms, omega_y dt ~ 0.3) the change of the mechanical energy plus the acoustic energy's change equals the
    work of the true linear damping per window to quadrature tolerance, on the hinge as on y.  The acoustic
    energy's change taken as the trapezoid of the forces' power missed it by 10-40 % of the damping's work."""
    from acousim import DimerDynamics, EffectSet
    from acousim.models import ExperimentConditions, static_model

    from validation.diagnosis.preparation import RunAccelerations

    model = static_model("fullwave", ExperimentConditions())
    assert not model.conservative
    sur = model.as_force_model()
    gamma = {"gamma_y": 0.5, "gamma_theta": 2.0}
    dyn = DimerDynamics(sur, EffectSet.from_dict({"linear_damping": gamma}))
    dt = 2e-3
    runs = []
    for i, x0 in enumerate([[1.2e-4, 0.0, 0.25, 1.5], [-0.9e-4, 0.0, -0.2, -2.0]]):
        tr = dyn.integrate(np.array(x0), duration=1.2, dt_out=dt, max_step=dt / 8)
        runs.append(RunAccelerations(f"run{i}", tr.t, tr.state, np.zeros((len(tr.t), 2))))  # y from Z_eq
    terms = SimulationTerms(DiagnosisProblem(model.interpolated(), runs))
    for e in terms.energy_terms(sur.z_eq, ["linear_damping"]):
        work = e["work"] @ np.array([gamma["gamma_y"], gamma["gamma_theta"]])
        assert np.all(e["work"][:, 1] * gamma["gamma_theta"] / work > 0.15)  # the hinge takes its share
        np.testing.assert_allclose(e["dk"] + e["du"], work, rtol=2e-3)
