"""What no candidate explains, named as library terms: a cubic hinge term is discovered and not forced onto a
candidate; nothing is discovered on clean data."""
import numpy as np
import pytest

from validation.diagnosis import DiagnoseConfig, DiagnosisProblem, Discovery, diagnose_dataset
from validation.diagnosis.discover.library_terms import DiscoveredTerm, discover_terms, discovered_equations
from validation.diagnosis.calibrate.gap_model import fit_gap_model
from validation.diagnosis.discover.joint_model import judge_candidates
from validation.diagnosis.prepare.runs import prepare_diagnosis_runs
from validation.diagnosis.discover.library_terms import _Normal

# the velocity coupling's trajectory test (on by default) is not what this module checks: it is checked in
# test_velocity_output_error.py and, end to end, in test_pipeline_twin.py, and costs 10-15 CPU-s per diagnosis
FAST = DiagnoseConfig(long_time=False, trajectory_test=False)


def test_discovered_equation_text():
    d = Discovery()
    assert discovered_equations(d) == {} and d.empty
    d.terms["thetaddot"] = [DiscoveredTerm("theta^3", -2.42e4, 9.6, 1.0, 0.004, 0.5),
                            DiscoveredTerm("theta", 343.0, 0.3, 0.1, 0.004, 0.3)]
    assert discovered_equations(d) == {
        "thetaddot": "thetaddot = simulation + identified effects + [discovered: -2.42e+04 theta^3 + 343 theta]"}
    assert d.to_dict()["yddot"] == [] and d.to_dict()["thetaddot"][0]["term"] == "theta^3"


def test_normal_equation_selection_matches_the_fitting_rule():
    """The backward elimination on the normal equations keeps the terms select_integral_form keeps."""
    from cubedimer.terms import evaluate_library, library_terms
    from fitting.derivatives.integral_form import integral_columns, select_integral_form, window_starts

    rng = np.random.default_rng(0)
    names = library_terms()
    dt, w = 1e-3, 50
    res, lib, cols = [], [], []
    for _ in range(4):
        t = np.arange(2000) * dt
        state = np.column_stack([1e-4 * np.sin(60 * t + rng.uniform(0, 6)), 6e-3 * np.cos(60 * t),
                                 0.3 * np.sin(9 * t + rng.uniform(0, 6)), 2.7 * np.cos(9 * t)])
        f = evaluate_library(state)
        c = integral_columns(f, dt, window_starts(len(t), w), w)
        cols.append(c)
        lib.append(f)
        res.append(c[:, names.index("theta^3")] * -2e4 + rng.normal(0, 5e-3, c.shape[0]))
    sel = select_integral_form(res, lib, [dt] * 4, [w] * 4, names, alpha=0.01)
    n_win = sum(c.shape[0] // w for c in cols)
    kept = _Normal(cols, res).select(names, sum(r.size for r in res) - 2 * n_win, 0.01)
    assert [names[j] for j in sorted(kept)] == list(sel.terms)
    assert "theta^3" in sel.terms


def _problem(data_dir):
    from cubedimer.dataset import load_dataset
    from cubedimer.meta import read_meta

    from validation.simulation import model_from_meta

    model = model_from_meta(read_meta(data_dir)).interpolated()
    return DiagnosisProblem.from_recorded(model, prepare_diagnosis_runs(load_dataset(data_dir)), 1500)


@pytest.mark.slow
def test_cubic_hinge_discovered_not_forced_onto_a_candidate(cubic_dataset):
    """-2.4e4 theta^3 in thetaddot: measured -24213 +- 10 (+0.9 %), shrink 1.0, nothing named (pair scattering,
    the closest candidate, p = 0.2)."""
    data, truth = cubic_dataset
    diag = diagnose_dataset(data, FAST, progress=False)
    assert diag.identified == ()
    found = diag.remaining_gap["discovered_terms"]
    assert found["yddot"] == []
    lead = found["thetaddot"][0]
    assert lead["term"] == "theta^3"
    # 5 %: the statistical error is 0.04 %; the columns are evaluated at theta smoothed over half a hinge period,
    # whose bias on the cubic is of order 1 % (measured +0.9 %)
    assert lead["coefficient"] == pytest.approx(-truth["cubic_hinge"], rel=0.05)
    assert lead["shrink"] > 0.8
    assert "[discovered: -2.42e+04 theta^3" in diag.remaining_gap["discovered_equations"]["thetaddot"]
    assert not diag.calibration["drift"]["detected"]


@pytest.mark.slow
def test_candidate_standing_in_for_the_cubic_is_not_named(cubic_dataset):
    """Pair scattering forced onto the cubic-hinge data absorbs part of it as linear stiffness; judged together with
    the discovered terms on held-out runs it no longer helps (measured p = 0.5) and is dropped."""
    data, _ = cubic_dataset
    problem = _problem(data)
    disc = discover_terms(problem, fit_gap_model(problem, ["pair_scattering"]))
    assert "theta^3" in [t.term for t in disc.terms["thetaddot"]]
    kept, pvals = judge_candidates(problem, ["pair_scattering"], disc)
    assert kept == [] and pvals["pair_scattering"] >= 0.01


@pytest.mark.slow
def test_nothing_discovered_on_clean_data(clean_dataset):
    data, _ = clean_dataset
    problem = _problem(data)
    disc = discover_terms(problem, fit_gap_model(problem, []))
    assert disc.to_dict() == {"yddot": [], "thetaddot": []}


def test_dissipative_terms_are_the_own_velocity_times_even_factors():
    """Each equation's energy-balance terms carry its own velocity once (or cubed) and nothing odd in the other
    velocity, so none of them does the same work as a term of the other equation."""
    from validation.diagnosis.discover.library_terms import dissipative_terms

    terms = dissipative_terms()
    assert terms["yddot"] == ["ydot", "y*ydot", "ydot*theta", "y^2*ydot", "y*ydot*theta", "ydot*theta^2", "ydot^3"]
    assert terms["thetaddot"] == ["thetadot", "y*thetadot", "theta*thetadot", "y^2*thetadot", "y*theta*thetadot",
                                  "theta^2*thetadot", "thetadot^3"]
    assert not set(terms["yddot"]) & set(terms["thetaddot"])


@pytest.mark.slow
def test_energy_window_work_of_a_linear_damping_matches_the_energy_terms(clean_dataset):
    """The work per energy window of the library term ydot in yddot (unit coefficient) is the linear damping's
    work column with gamma_y = 1: two routes to M int ydot^2 dt over the same windows."""
    from validation.diagnosis.discover.library_terms import _dissipation_work
    from validation.diagnosis.prepare.simulation_terms import SimulationTerms

    data, _ = clean_dataset
    problem = _problem(data)
    work = _dissipation_work(problem, {"yddot": ["ydot"], "thetaddot": ["thetadot"]})
    terms = SimulationTerms(problem)
    en = terms.energy_terms(0.0, ["linear_damping"])
    for w, e, r in zip(work, en, problem.runs):
        # linear damping's parameters are (gamma_y, gamma_theta) with accelerations -gamma ydot, -gamma thetadot
        np.testing.assert_allclose(w, -e["work"], rtol=1e-12, atol=1e-30)  # the same sums, up to round-off
        assert np.all(w[:, 0] > 0) and np.all(w[:, 1] > 0)  # M ydot^2 and I thetadot^2 integrated: positive


@pytest.mark.slow
def test_y_dependent_damping_discovered_in_the_energy_balance(y_damping_dataset):
    """-c (y - Delta)^2 ydot (c = 6e8 1/(m^2 s), Delta = 77 um the true equilibrium in the data's y) changes y within
    an integral-form window by under 1 % but removes a large share of the energy per window: it is found in the
    energy balance, and not forced onto a candidate damping.  Measured: -6.05e8 y^2*ydot and +4.67e4 y*ydot.

    Over windows of ten periods the balance sees the cycle-averaged damping rate, -c_2 <y^2> + c_1 <y> about
    the equilibrium; the truth's vanishes at y = Delta, and so must the discovered one's (c_1 = c_2 Delta, not the
    expansion's 2 c Delta: the odd part about the equilibrium does no net work)."""
    from acousim import cached_surrogate

    data, truth = y_damping_dataset
    diag = diagnose_dataset(data, FAST, progress=False)
    assert diag.identified == ()
    found = diag.remaining_gap["discovered_terms"]
    assert found["thetaddot"] == []
    lead = found["yddot"][0]
    assert (lead["term"], lead["form"]) == ("y^2*ydot", "energy")
    # 10 %: measured +0.9 % here and +0.04 % at seed 5 (Delta = 56 um); the statistical error is 1.8 %
    assert lead["coefficient"] == pytest.approx(-truth["y_damping"], rel=0.10)
    sur = cached_surrogate()
    delta = sur.with_pressure(truth["pressure_amplitude_pa"]).z_eq - sur.z_eq
    coef = {t["term"]: t["coefficient"] for t in found["yddot"]}
    rate_at_equilibrium = sum(coef.get(term, 0.0) * delta**k for k, term in enumerate(("ydot", "y*ydot", "y^2*ydot")))
    # measured 0.3 % of the truth's rate c Delta^2 at the nominal origin
    assert abs(rate_at_equilibrium) < 0.1 * truth["y_damping"] * delta**2
    assert "y^2*ydot (energy balance)" in diag.remaining_gap["discovered_equations"]["yddot"]


@pytest.mark.slow
def test_candidate_dampings_standing_in_for_a_dissipation_are_not_named(centred_y_damping_dataset):
    """With the y-dependent damping centred near the data's origin, linear damping and quadratic drag together
    reproduce its cycle-averaged energy loss, and both are identified (each still improves on top of the other:
    gamma_y = -1.16 1/s and c_y = 229 1/m).  On the calibration alone the energy balance finds only -4.64e8 y^2*ydot
    (23 % under the truth), and the two dampings still improve every held-out run on top of it (p = 0.004); beside
    either damping alone it also finds the y*ydot that the damping's centre off the data's origin adds, and judged
    together against those terms the two no longer improve held-out runs (measured p = 1): not named.  Which
    dissipative term carries the loss is at the information limit here: y^2*ydot and ydot^3 remove the same energy
    from a harmonic oscillation, so the test asks for a cubic dissipation in yddot found in the energy balance."""
    data, truth = centred_y_damping_dataset
    diag = diagnose_dataset(data, FAST, progress=False)
    assert diag.identified == ()
    assert sorted(r["name"] for r in diag.remaining_gap["replaced_by_discovered_terms"]) == [
        "linear_damping", "quadratic_drag"]
    lead = diag.remaining_gap["discovered_terms"]["yddot"][0]
    assert lead["form"] == "energy" and lead["term"] in ("y^2*ydot", "ydot^3")
    assert lead["coefficient"] < 0  # a damping


def test_library_equivalents_are_the_candidates_own_columns():
    """The library terms a candidate is not judged against are its own regressor columns (up to the sign)."""
    from cubedimer.terms import evaluate_library, library_terms
    from validation.diagnosis import effect_regressors
    from validation.diagnosis.prepare.candidate_effects import CANDIDATE_EFFECTS, LIBRARY_EQUIVALENTS

    rng = np.random.default_rng(0)
    state = rng.normal(size=(50, 4)) * np.array([1e-4, 1e-2, 0.3, 3.0])
    lib = dict(zip(library_terms(), evaluate_library(state).T))
    for name, forms in LIBRARY_EQUIVALENTS.items():
        regs = effect_regressors(name, state, 1e-3 + state[:, 0], 1.0, None)
        for q, eq in enumerate(("yddot", "thetaddot")):
            for term in forms.get(eq, ()):
                matches = [p for p in range(len(CANDIDATE_EFFECTS[name]))
                           if np.allclose(np.abs(regs[:, q, p]), np.abs(lib[term]), rtol=1e-12, atol=0)]
                assert matches, (name, eq, term)


@pytest.mark.slow
def test_forced_candidate_dampings_judged_together_are_dropped(y_damping_dataset):
    """Linear damping and quadratic drag forced onto the y-dependent damping (Delta = 77 um) and judged together
    against the dissipative terms found on the calibration alone: they improve no held-out run (measured p = 1)
    and both are dropped."""
    data, _ = y_damping_dataset
    problem = _problem(data)
    rivals = discover_terms(problem, fit_gap_model(problem, []), forms=("energy",))
    assert [t.term for t in rivals.terms["yddot"]][:1] == ["y^2*ydot"] and rivals.names("integral")["yddot"] == []
    kept, pvals = judge_candidates(problem, ["quadratic_drag", "linear_damping"], rivals,
                                   group=("linear_damping", "quadratic_drag"))
    assert kept == [] and pvals["quadratic_drag"] >= 0.01 and pvals["linear_damping"] >= 0.01
