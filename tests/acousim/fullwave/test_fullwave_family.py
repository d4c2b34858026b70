"""The full-wave table family: scaling, interpolation, coverage, refusals and the resumable build (no solve here;
the scaling against direct solves is in test_fullwave_surrogate.py)."""
from __future__ import annotations

import json
import shutil
import subprocess
import sys

import numpy as np
import pytest

from acousim.fullwave import default_fullwave_surrogate
from acousim.fullwave.family import (FAMILY_GAP_RATIOS, FAMILY_KS, FamilyNode, FamilyRangeError, FamilyTableError,
                                     FullwaveFamily, build_family, dimensionless_coefficients, family_mesh_spec,
                                     family_nodes, load_node, node_path, scaled_surrogate)
from acousim.fullwave.geometry import hinge_refined_spec
from acousim.fullwave.mesh_rules import TABLE_SPEC, edge_graded_mesh_spec
from acousim.medium import Medium
from acousim.models import ConditionError, ExperimentConditions, dynamic_model, static_model

from ...conftest import synthetic_reduced, write_synthetic_family


def test_shipped_table_meshes_are_the_family_rule_at_the_default_gap():
    """The default dimer's table is on the family's edge-graded mesh at g/s = 0.01 (q = 1); the hinge-graded
    rule there is the hinge-refined mesh."""
    assert TABLE_SPEC == edge_graded_mesh_spec(500e-6, 5e-6, 1.0)
    assert family_mesh_spec(500e-6, 5e-6) == hinge_refined_spec()


def test_family_mesh_keeps_the_hinge_aspect_ratio():
    """Elements g/2 across and 3 g along the hinge at every gap node (up to the caps)."""
    for g in FAMILY_GAP_RATIOS:
        spec = family_mesh_spec(500e-6, g * 500e-6)
        assert spec.h_hinge == pytest.approx(min(max(0.5 * g, 0.0025), 0.02))
        assert spec.h_along == pytest.approx(min(3 * g, 0.125))


@pytest.mark.parametrize("q", [1.4, 0.7])
def test_uniformly_refined_family_mesh_scales_every_size(q):
    """The convergence study's family-uniform sequence: faces and hinge sizes all times q; the hinge-only
    sequence keeps the faces."""
    base = family_mesh_spec(500e-6, 10e-6)
    every = family_mesh_spec(500e-6, 10e-6, refine=q, refine_faces=True)
    hinge = family_mesh_spec(500e-6, 10e-6, refine=q)
    for name in ("h_hinge", "h_max", "h_along", "h_corner"):
        assert getattr(every, name) == pytest.approx(q * getattr(base, name))
    assert hinge.h_max == base.h_max and hinge.h_hinge == pytest.approx(q * base.h_hinge)


#: The lab range's corners: sides 400-700 um at 40-50 kHz in air at 343 m/s, ks = 2 pi f s / c0.
LAB_KS = tuple(2 * np.pi * f * s / 343.0 for f, s in ((40e3, 400e-6), (50e3, 700e-6)))


def test_nodes_span_the_lab_range():
    ks_lab = LAB_KS
    np.testing.assert_allclose(ks_lab, [0.2931, 0.6411], atol=1e-4)
    assert FAMILY_KS[0] == 0.28 < ks_lab[0] and ks_lab[1] < FAMILY_KS[-1] == 0.65 and len(FAMILY_KS) == 3
    assert FAMILY_GAP_RATIOS[0] == 0.01 and FAMILY_GAP_RATIOS[-1] == 0.05
    # the cheapest (largest gap) nodes are built first
    order = [n.gap_ratio for n in family_nodes()]
    assert order == sorted(order, reverse=True)


def test_scaling_round_trip_is_exact():
    """dimensionless -> physical at the table's own settings gives the table back (forces, Z_eq, inertia)."""
    sur = default_fullwave_surrogate()
    st = sur.settings
    back = scaled_surrogate(dimensionless_coefficients(sur), sur.theta_max, st["side_m"], st["gap_m"], sur.medium,
                            st["particle_density_kg_m3"], sur.pressure_amplitude_pa)
    for comp in ("fz", "qt"):
        np.testing.assert_allclose(np.array(back.coefficients[comp]), np.array(sur.coefficients[comp]), rtol=1e-13,
                                   atol=0)
    assert back.z_eq == pytest.approx(sur.z_eq, rel=1e-12)
    assert back.inertia_const == pytest.approx(sur.inertia_const, rel=1e-12)
    assert back.inertia_sin2 == pytest.approx(sur.inertia_sin2, rel=1e-12)
    assert back.mass == pytest.approx(sur.mass, rel=1e-12)


@pytest.mark.parametrize("factor", [0.8, 1.3])
def test_scaling_in_side_and_frequency_at_fixed_ks(factor):
    """Same ks, side times f: forces times f^2 (p0, rho0, c0 fixed), torques times f^3, mass times f^3; the
    equilibrium sits at the same k Z_eq only where gravity is rescaled too, so compare the coefficients."""
    sur = default_fullwave_surrogate()
    st = sur.settings
    d = dimensionless_coefficients(sur)
    med = Medium(frequency_hz=sur.medium.frequency_hz / factor)
    big = scaled_surrogate(d, sur.theta_max, st["side_m"] * factor, st["gap_m"] * factor, med)
    np.testing.assert_allclose(np.array(big.coefficients["fz"]), factor**2 * np.array(sur.coefficients["fz"]),
                               rtol=1e-12, atol=0)
    np.testing.assert_allclose(np.array(big.coefficients["qt"]), factor**3 * np.array(sur.coefficients["qt"]),
                               rtol=1e-12, atol=0)
    assert big.mass == pytest.approx(factor**3 * sur.mass, rel=1e-12)
    assert big.two_k == pytest.approx(sur.two_k / factor, rel=1e-12)


def test_interpolation_reproduces_the_dependence_exactly(synthetic_family_dir):
    """The synthetic family is quadratic in ks and log g/s: the 3 x 4 Lagrange interpolant is exact between nodes."""
    fam = FullwaveFamily(synthetic_family_dir)
    assert fam.ks_nodes == FAMILY_KS and fam.gap_nodes == FAMILY_GAP_RATIOS
    for ks, g in ((0.33, 0.012), (0.418, 0.0224), (0.6, 0.041), (0.65, 0.05)):
        got = fam.dimensionless(ks, g)
        want = synthetic_reduced(ks, g)
        for comp in ("fz", "qt"):
            np.testing.assert_allclose(got[comp], want[comp], rtol=1e-11, atol=1e-13 * np.abs(want[comp]).max())


def test_family_surrogate_of_a_lab_dimer(synthetic_family_dir):
    """A 600 um dimer at 42 kHz: the physical surrogate is the scaled interpolant, with its accuracy record."""
    fam = FullwaveFamily(synthetic_family_dir)
    med = Medium(frequency_hz=42_000.0)
    sur = fam.surrogate(600e-6, 12e-6, med)
    ks = med.wavenumber * 600e-6
    want = synthetic_reduced(ks, 0.02)
    unit = 3000.0**2 * 600e-6**2 / (med.density_kg_m3 * med.sound_speed_m_s**2)
    np.testing.assert_allclose(np.array(sur.coefficients["fz"]), unit * want["fz"], rtol=1e-11,
                               atol=1e-13 * unit * np.abs(want["fz"]).max())
    assert sur.build_accuracy["source"] == "family interpolation"
    assert sur.settings["gap_m"] == 12e-6 and sur.settings["ks"] == pytest.approx(ks)
    f_y, f_t = sur.linear_frequencies()
    assert 5 < f_y < 200 and np.isfinite(f_t)


def test_interpolated_model_states_the_mesh_error_of_its_gap_rows(tmp_path, synthetic_family_dir):
    """mesh_convergence.json's stated error per gap row reaches the model's settings: the larger of the two rows
    around the gap, the row's own on a node, and None when a row has no study."""
    for p in synthetic_family_dir.glob("*.json"):
        shutil.copy(p, tmp_path / p.name)
    g = FAMILY_GAP_RATIOS
    rows = [{"gap_over_side": g[0], "stated_error": 0.016}, {"gap_over_side": g[1], "stated_error": 0.03},
            {"gap_over_side": g[2], "stated_error": 0.027}]
    (tmp_path / "mesh_convergence.json").write_text(json.dumps({"gap_rows": rows}))
    fam = FullwaveFamily(tmp_path)
    med = Medium()
    side = 0.45 / med.wavenumber
    assert fam.surrogate(side, 0.012 * side, med).settings["mesh_error_hinge_stiffness"] == 0.03
    assert fam.mesh_error(g[2]) == 0.027  # on a node: that row's
    assert fam.mesh_error(0.04) is None  # the g/s = 0.05 row has no study here
    (tmp_path / "mesh_convergence.json").write_text("{")
    with pytest.raises(FamilyTableError, match="mesh_convergence.json"):
        FullwaveFamily(tmp_path)


def test_flux_disc_quadrature_is_a_keyed_build_setting(tmp_path, synthetic_family_dir):
    """The flux disc's Gauss points per panel key a table only when they differ from 6, so tables built with 6
    keep their keys (and cache names) and read as 6; new nodes default to the converged 12 and refuse a 6-point
    table by name (``build`` then rebuilds it), and a family mixing quadratures is refused."""
    from acousim.fullwave.flux import FLUX_DISC_POINTS, UNKEYED_FLUX_DISC_POINTS
    from acousim.fullwave.force_surrogate import build_settings, build_settings_of

    assert (FLUX_DISC_POINTS, UNKEYED_FLUX_DISC_POINTS) == (12, 6)
    n_half = default_fullwave_surrogate().settings["n_half"]  # as the synthetic family's tables
    node12 = FamilyNode(FAMILY_KS[0], FAMILY_GAP_RATIOS[0], n_half, 0.9)
    node6 = FamilyNode(FAMILY_KS[0], FAMILY_GAP_RATIOS[0], n_half, 0.9, flux_disc_points=6)
    assert node12.flux_disc_points == 12
    assert node12.expected_settings()["flux_disc_points"] == 12
    assert "flux_disc_points" not in node6.expected_settings()
    assert "flux_disc_points" not in build_settings(TABLE_SPEC, Medium(), 2160.0, 6, 0.9, "surface", 12)
    with pytest.raises(ValueError, match="flux disc points"):
        FamilyNode(0.3, 0.02, flux_disc_points=1)
    for p in synthetic_family_dir.glob("*.json"):
        shutil.copy(p, tmp_path / p.name)
    path = node_path(tmp_path, node12)
    assert build_settings_of(load_node(path, node12))["flux_disc_points"] == 12
    with pytest.raises(FamilyTableError, match="built with other settings"):
        load_node(path, node6)
    table = json.loads(path.read_text())
    del table["settings"]["flux_disc_points"]  # a table from before the setting: 6 points
    path.write_text(json.dumps(table))
    assert build_settings_of(load_node(path, node6)).get("flux_disc_points") is None
    with pytest.raises(FamilyTableError, match="built with other settings"):
        load_node(path, node12)
    with pytest.raises(FamilyTableError, match="different flux quadratures"):
        FullwaveFamily(tmp_path)


def test_shipped_family_covers_the_lab_range_within_its_accuracy_targets():
    """The shipped nodes form the full grid, cover a 400-um dimer at 40 kHz (ks 0.293) and a 700-um one at 50 kHz
    (ks 0.641), and their recorded interpolation errors against the check tables between them (the 0.3 row among
    them) meet the targets: 0.5 % of max |Q_y|, 2 % of max |Q_theta|."""
    from acousim.fullwave.family import shipped_family

    fam = shipped_family()
    assert fam.ks_nodes == FAMILY_KS and fam.gap_nodes == FAMILY_GAP_RATIOS
    for ks in LAB_KS:
        for g in FAMILY_GAP_RATIOS:
            fam.check_covers(ks, g)  # raises FamilyRangeError when outside
    checks = json.loads((fam.directory / "accuracy.json").read_text())["checks"]
    assert sorted(round(c["gap_over_side"], 4) for c in checks if abs(c["ks"] - 0.3) < 1e-6) == [0.01, 0.015, 0.0334,
                                                                                                0.05]
    assert all(c["q_y"] < 0.005 and c["q_theta"] < 0.02 for c in checks)


def test_shipped_mesh_errors_are_no_smaller_than_the_measured_discrepancy():
    """The error each shipped gap row states is at least the distance of the family's mesh level from the finest
    level measured there (uniformly refined rows), and, where the edge-graded sequence has a Richardson limit, the
    family's distance from that limit plus the extrapolation (``stated_mesh_error``); a row called converged has its
    finest two levels within 2 %.  Every gap node of the shipped family has a study."""
    from acousim.fullwave.convergence import stated_mesh_error
    from acousim.fullwave.family import MESH_CONVERGENCE_FILE, shipped_family
    from acousim.fullwave.mesh_record import family_value

    fam = shipped_family()
    rows = json.loads((fam.directory / MESH_CONVERGENCE_FILE).read_text())["gap_rows"]
    assert sorted(r["gap_over_side"] for r in rows) == pytest.approx(sorted(fam.gap_nodes), rel=1e-3)
    for r in rows:
        family = family_value(r)  # the stiffness on the family's own mesh
        assert family < 0  # a restoring hinge
        if r.get("levels_q"):  # a uniformly refined sequence of the family's mesh
            k = np.asarray(r["stiffness_nm"])
            assert np.all(k < 0)
            assert r["stated_error"] >= abs(1 - family / k[-1]) - 5e-5  # 5e-5: the stated error is rounded to 1e-4
            if r["converged"]:
                assert abs(1 - k[-2] / k[-1]) <= 0.02
        edge = r.get("edge_graded")
        if edge is None:
            continue
        assert np.all(np.asarray(edge["stiffness_nm"]) < 0)  # no less than its distance from the finest:
        assert r["stated_error"] >= abs(1 - family / edge["stiffness_nm"][-1]) - 5e-5
        if edge.get("richardson") is not None:  # the edge-graded sequence's limit, recomputed
            restated = stated_mesh_error(family, edge["levels_q"], edge["stiffness_nm"])
            np.testing.assert_allclose(edge["richardson"]["limit"], restated["limit"], rtol=1e-9)
            assert r["stated_error"] >= restated["stated_error"] - 5e-5
            assert np.all(np.diff(np.abs(edge["stiffness_nm"][-3:])) > 0)  # the fit's levels stiffen monotonically


@pytest.mark.parametrize("ks,g", [(0.25, 0.02), (0.7, 0.02), (0.4, 0.005), (0.4, 0.08)])
def test_outside_the_family_is_refused_never_extrapolated(synthetic_family_dir, ks, g):
    fam = FullwaveFamily(synthetic_family_dir)
    with pytest.raises(FamilyRangeError) as err:
        fam.dimensionless(ks, g)
    msg = str(err.value)
    assert "ks 0.28-0.65 and g/s 0.01-0.05" in msg and "python -m acousim family build" in msg
    assert "\n" not in msg


def test_partial_family_covers_its_complete_rows(tmp_path):
    """Two complete gap rows and one incomplete one: the covered range is the complete rows' rectangle."""
    write_synthetic_family(tmp_path, gap_nodes=FAMILY_GAP_RATIOS[2:])
    write_synthetic_family(tmp_path, ks_nodes=FAMILY_KS[:2], gap_nodes=FAMILY_GAP_RATIOS[1:2])
    fam = FullwaveFamily(tmp_path)
    assert fam.gap_nodes == FAMILY_GAP_RATIOS[2:]
    got = fam.dimensionless(0.5, 0.04)["qt"]
    # two gap nodes: linear in log g, so not exact for the synthetic quadratic (but close)
    np.testing.assert_allclose(got, synthetic_reduced(0.5, 0.04)["qt"], rtol=2e-3)
    with pytest.raises(FamilyRangeError):
        fam.dimensionless(0.5, 0.02)


def test_corrupt_table_is_refused_by_name(tmp_path, synthetic_family_dir):
    for p in synthetic_family_dir.glob("*.json"):
        shutil.copy(p, tmp_path / p.name)
    bad = sorted(tmp_path.glob("*.json"))[3]
    bad.write_text(bad.read_text()[:500])
    with pytest.raises(FamilyTableError) as err:
        FullwaveFamily(tmp_path)
    assert bad.name in str(err.value) and "\n" not in str(err.value)


def test_table_built_with_other_settings_is_refused(tmp_path, synthetic_family_dir):
    for p in synthetic_family_dir.glob("*.json"):
        shutil.copy(p, tmp_path / p.name)
    victim = sorted(tmp_path.glob("*.json"))[0]
    d = json.loads(victim.read_text())
    d["settings"]["h_along"] = 0.2  # another mesh rule
    victim.write_text(json.dumps(d))
    with pytest.raises(FamilyTableError, match="settings do not match"):
        FullwaveFamily(tmp_path)


def test_build_resumes_from_the_nodes_on_disk(tmp_path):
    """Every node already there (with the right settings) is kept: nothing is solved."""
    write_synthetic_family(tmp_path, ks_nodes=FAMILY_KS[:2], gap_nodes=FAMILY_GAP_RATIOS[-1:])
    nodes = [FamilyNode(k, FAMILY_GAP_RATIOS[-1], n_half=7) for k in FAMILY_KS[:2]]
    before = {p.name: p.stat().st_mtime_ns for p in tmp_path.glob("*.json")}
    summary = build_family(tmp_path, nodes, progress=False)
    assert [s["built"] for s in summary] == [False, False]
    assert {p.name: p.stat().st_mtime_ns for p in tmp_path.glob("*.json")} == before


def test_registry_gives_the_family_dimer(use_synthetic_family):
    c = ExperimentConditions(side_length_m=600e-6, frequency_hz=42_000.0, gap_m=10e-6)
    fw = static_model("fullwave", c)
    assert fw.name == "fullwave" and not fw.conservative
    assert fw.record()["gap_m"] == 10e-6
    dyn = dynamic_model("fullwave", c)
    np.testing.assert_allclose(dyn.coefficients["qt"], fw.surrogate.coefficients["qt"], rtol=0)


def test_gap_model_error_is_the_stiffness_error_over_its_gap_sensitivity(tmp_path, synthetic_family_dir, monkeypatch):
    """The gap's systematic error from the family's stated hinge-stiffness error e (mesh + interpolation):
    e / |d ln k / d ln g|.  In the synthetic family k is proportional to 1 + a L + b L^2 (L = log(g / 0.01 s)), so
    the sensitivity is (a + 2 b L) / (1 + a L + b L^2) exactly; none is stated where the family has no mesh study."""
    from acousim.fullwave.family import FAMILY_ENV
    from acousim.models import force_model_type

    from ...conftest import SYNTHETIC_FAMILY

    for p in synthetic_family_dir.glob("*.json"):
        shutil.copy(p, tmp_path / p.name)
    g = FAMILY_GAP_RATIOS
    rows = [{"gap_over_side": v, "stated_error": e} for v, e in zip(g, (0.016, 0.028, 0.031, 0.0024))]
    (tmp_path / "mesh_convergence.json").write_text(json.dumps({"gap_rows": rows}))
    (tmp_path / "accuracy.json").write_text(json.dumps({"checks": [], "summary": {"stiffness": 0.011}}))
    monkeypatch.setenv(FAMILY_ENV, str(tmp_path))
    c = ExperimentConditions(side_length_m=600e-6, gap_m=0.02 * 600e-6)
    rel = force_model_type("fullwave").parameter_model_error(c)["gap_m"]
    a, b, L = SYNTHETIC_FAMILY["gap_slope"], SYNTHETIC_FAMILY["gap_curv"], np.log(2.0)
    slope = (a + 2 * b * L) / (1 + a * L + b * L**2)
    # the rows around g/s = 0.02 state 2.8 and 3.1 %: the larger; the sensitivity by central differences over
    # +-5 % in g, whose error on this smooth log-quadratic is below 1e-4 of it
    np.testing.assert_allclose(rel, (0.031 + 0.011) / abs(slope), rtol=1e-3)
    partial = tmp_path / "partial"  # another directory: the family is read anew
    partial.mkdir()
    for p in synthetic_family_dir.glob("*.json"):
        shutil.copy(p, partial / p.name)
    (partial / "mesh_convergence.json").write_text(json.dumps({"gap_rows": rows[:2]}))
    monkeypatch.setenv(FAMILY_ENV, str(partial))
    assert force_model_type("fullwave").parameter_model_error(c)["gap_m"] is None


def test_the_default_dimer_keeps_its_direct_solve_table():
    sur = dynamic_model("fullwave", ExperimentConditions())
    assert sur.build_accuracy["source"] == "direct-solve table of the default dimer"
    np.testing.assert_allclose(sur.coefficients["qt"], default_fullwave_surrogate().coefficients["qt"], rtol=0)


@pytest.mark.parametrize("kwargs,message", [
    ({"gap_m": 5e-6}, "--gap applies to --model fullwave only"),
    ({"edge_radius_m": 0.0}, "--edge-radius applies to --model fullwave only"),
])
def test_gorkov_refuses_hinge_options(kwargs, message):
    with pytest.raises(ConditionError, match=message):
        static_model("gorkov", ExperimentConditions(**kwargs))


def test_family_info_command(synthetic_family_dir):
    r = subprocess.run([sys.executable, "-m", "acousim", "family", "info", "--family", str(synthetic_family_dir)],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    assert "covers ks 0.28-0.65 and g/s 0.01-0.05" in r.stdout
    assert len([l for l in r.stdout.splitlines() if l.startswith("ks ")]) == len(FAMILY_KS) * len(FAMILY_GAP_RATIOS)


def test_the_default_dimers_direct_table_states_its_gap_rows_mesh_error():
    """The default dimer's own table is built on the family's mesh at g = 0.01 s, so it states that row's error."""
    from acousim.fullwave.family import MESH_CONVERGENCE_FILE, fullwave_surrogate, shipped_family
    from acousim.models import ExperimentConditions

    sur = fullwave_surrogate(ExperimentConditions())
    assert sur.settings["table_source"] == "direct-solve table of the default dimer"
    rows = json.loads((shipped_family().directory / MESH_CONVERGENCE_FILE).read_text())["gap_rows"]
    row = next(r for r in rows if r["gap_over_side"] == pytest.approx(0.01))
    assert sur.settings["mesh_error_hinge_stiffness"] == row["stated_error"]
