"""The family's grid: the edge-graded mesh rule, the level of each gap node (tied to the measured mesh
convergence), nodes read back from their tables, and one mesh rule per family (no solve here)."""
from __future__ import annotations

import json
import shutil

import numpy as np
import pytest

from acousim.fullwave.convergence import stated_mesh_error
from acousim.fullwave.family import FAMILY_DIR, FamilyTableError, FullwaveFamily, family_accuracy, load_node
from acousim.fullwave.family_grid import (EDGE_GRADED_H_EDGE, FAMILY_GAP_RATIOS, FAMILY_KS, FAMILY_MESH_LEVELS,
                                          MESH_CONVERGENCE_FILE, FamilyNode, edge_graded_mesh_spec, family_mesh_level,
                                          family_mesh_spec, family_nodes)
from acousim.fullwave.geometry import dimer_bodies

from ...conftest import synthetic_reduced, write_synthetic_family

SIDE = 500e-6


def _edge_rows() -> dict[float, dict]:
    rows = json.loads((FAMILY_DIR / MESH_CONVERGENCE_FILE).read_text())["gap_rows"]
    return {round(r["gap_over_side"], 6): r["edge_graded"] for r in rows}


def test_levels_are_given_at_every_gap_node():
    assert [g for g, _ in FAMILY_MESH_LEVELS] == pytest.approx(sorted(FAMILY_GAP_RATIOS), rel=1e-9)
    for g, q in FAMILY_MESH_LEVELS:
        assert family_mesh_level(g) == q


def test_level_between_nodes_lies_between_theirs_and_is_held_outside():
    (g0, q0), (g1, q1) = FAMILY_MESH_LEVELS[:2]
    mid = float(np.sqrt(g0 * g1))  # halfway in log g/s
    assert family_mesh_level(mid) == pytest.approx(0.5 * (q0 + q1), rel=1e-12)
    assert family_mesh_level(0.5 * g0) == q0 and family_mesh_level(2 * FAMILY_MESH_LEVELS[-1][0]) == FAMILY_MESH_LEVELS[-1][1]


@pytest.mark.parametrize("q", [1.0, 0.7, 0.5])
def test_edge_graded_mesh_scales_every_size_and_grades_the_edges(q):
    base = family_mesh_spec(SIDE, 10e-6)
    spec = edge_graded_mesh_spec(SIDE, 10e-6, q)
    for name in ("h_hinge", "h_max", "h_along", "h_corner"):
        assert getattr(spec, name) == pytest.approx(q * getattr(base, name), rel=1e-12)
    assert spec.h_edge == pytest.approx(EDGE_GRADED_H_EDGE * q, rel=1e-12) and spec.growth == base.growth


@pytest.mark.parametrize("g,q", FAMILY_MESH_LEVELS)
def test_node_levels_are_the_measured_levels_and_state_less_than_two_percent(g, q):
    """Each node's mesh is a level of the edge-graded convergence study at its gap (same number of unknowns), and
    the stiffness measured there is within 2 % of the Richardson limit, extrapolation included."""
    edge = _edge_rows()[round(g, 6)]
    i = [round(v, 9) for v in edge["levels_q"]].index(round(q, 9))
    dofs = sum(len(b.vertices) for b in dimer_bodies(0.0, edge_graded_mesh_spec(SIDE, g * SIDE)))
    assert dofs == edge["dofs"][i]
    stated = stated_mesh_error(edge["stiffness_nm"][i], edge["levels_q"], edge["stiffness_nm"])["stated_error"]
    assert stated < 0.02


def test_default_nodes_are_edge_graded_at_their_levels():
    nodes = family_nodes()
    assert len(nodes) == len(FAMILY_KS) * len(FAMILY_GAP_RATIOS)
    assert all(n.mesh_level == family_mesh_level(n.gap_ratio) for n in nodes)
    assert all(n.mesh_level is None for n in family_nodes(edge_graded=False))
    node = nodes[0]
    assert node.expected_settings()["h_edge"] == pytest.approx(EDGE_GRADED_H_EDGE * node.mesh_level)
    assert "h_edge" not in FamilyNode(node.ks, node.gap_ratio).expected_settings()


def test_check_points_take_the_level_of_their_gap_in_the_given_order():
    points = [(0.6, 0.0122), (0.34, 0.03), (0.5625, 0.05)]
    nodes = family_nodes(points=points)
    assert [(n.ks, n.gap_ratio) for n in nodes] == points
    assert [n.mesh_level for n in nodes] == [family_mesh_level(g) for _, g in points]
    assert 0.7 < nodes[0].mesh_level < 1.0  # 0.0122 lies between the nodes 0.01 (q 1) and 0.01495 (q 0.7)
    assert all(n.mesh_level is None for n in family_nodes(points=points, edge_graded=False))


@pytest.mark.parametrize("level", [0.0, -1.0, float("nan"), 10.0])
def test_bad_mesh_level_is_refused(level):
    with pytest.raises(ValueError, match="mesh level"):
        FamilyNode(0.4, 0.02, mesh_level=level)


def test_edge_graded_family_reads_back_its_nodes_and_interpolates(tmp_path):
    write_synthetic_family(tmp_path, edge_graded=True)
    fam = FullwaveFamily(tmp_path)
    for (k, g), sur in fam.tables.items():
        node = FamilyNode.from_table(sur)
        assert node.mesh_level == pytest.approx(family_mesh_level(g), rel=1e-9)
        load_node(tmp_path / f"{node.name}.json", node)  # its own node accepts it
    # the synthetic dependence is quadratic in ks and log g/s: the interpolant is exact (1e-9: rounding)
    np.testing.assert_allclose(fam.dimensionless(0.5, 0.02)["qt"], synthetic_reduced(0.5, 0.02)["qt"], rtol=1e-9)


def test_accuracy_skips_a_check_on_the_other_mesh_rule(tmp_path, synthetic_family_dir, caplog):
    """A check built on the other mesh rule would measure the mesh difference, not the interpolation: skipped."""
    write_synthetic_family(tmp_path, gap_nodes=FAMILY_GAP_RATIOS[:1], edge_graded=True)
    other = [load_node(p) for p in sorted(tmp_path.glob("ks*.json"))]
    hinge = FullwaveFamily(synthetic_family_dir)
    assert hinge.edge_graded is False and FullwaveFamily(tmp_path).edge_graded is True
    with caplog.at_level("WARNING"):
        acc = family_accuracy(hinge, other)
    assert acc["summary"]["n_checks"] == 0 and "edge-graded mesh rule" in caplog.text
    same = [load_node(p) for p in sorted(synthetic_family_dir.glob("ks*.json"))]
    assert family_accuracy(hinge, same)["summary"]["n_checks"] == len(same)


def test_family_mixing_mesh_rules_is_refused(tmp_path, synthetic_family_dir):
    for p in synthetic_family_dir.glob("*.json"):
        shutil.copy(p, tmp_path / p.name)
    write_synthetic_family(tmp_path, gap_nodes=FAMILY_GAP_RATIOS[:1], edge_graded=True)  # one row replaced
    with pytest.raises(FamilyTableError, match="mixed"):
        FullwaveFamily(tmp_path)


def test_the_record_rule_restates_every_shipped_row():
    """The stated error of each shipped gap row is what the record's rule (mesh_record) computes from its levels."""
    from acousim.fullwave.mesh_record import stated_row_error

    rows = json.loads((FAMILY_DIR / MESH_CONVERGENCE_FILE).read_text())["gap_rows"]
    for r in rows:
        assert stated_row_error(r) == pytest.approx(r["stated_error"], abs=1e-12)


def _study_rows(levels, limit, c, p):
    """Rows of a mesh study whose stiffness is the power law limit + c q^p (what hinge_quantities writes)."""
    return [{"level_q": q, "dofs": int(2000 / q**2), "stiffness_nm": limit + c * q**p, "f_theta_hz": 30.0,
             "f_y_hz": 24.0, "thetaddot": {"y^2*theta": 3e10}} for q in levels]


def test_merging_an_edge_graded_study_states_the_family_levels_error(tmp_path):
    """A new record for an edge-graded family: the row's error is |k(q_f)/k_inf - 1| plus the extrapolation's
    size, on a known power law (the fit recovers the limit exactly)."""
    from acousim.fullwave.mesh_record import merge_edge_graded_study

    limit, c, p = -5.0e-10, 2.0e-11, 1.5
    target = tmp_path / "mesh_convergence.json"
    row = merge_edge_graded_study(target, 0.02, _study_rows([0.5, 1.0, 0.7], limit, c, p), family_level_q=1.0)
    assert row["edge_graded"]["levels_q"] == [1.0, 0.7, 0.5]  # coarse to fine whatever the study's order
    np.testing.assert_allclose(row["edge_graded"]["richardson"]["limit"], limit, rtol=1e-9)
    expected = abs(c / limit) + abs(c * 0.5**p / limit)
    assert expected <= row["stated_error"] < expected + 1e-4  # rounded up to 1e-4
    on_disk = json.loads(target.read_text())["gap_rows"][0]
    assert on_disk["family_mesh_rule"] == "family-edges" and on_disk["stated_error"] == row["stated_error"]


def test_merging_into_a_hinge_graded_row_keeps_its_family_level(tmp_path):
    from acousim.fullwave.mesh_record import merge_edge_graded_study, stated_row_error

    target = tmp_path / "mesh_convergence.json"
    record = json.loads((FAMILY_DIR / MESH_CONVERGENCE_FILE).read_text())
    for r in record["gap_rows"]:  # as a family on the hinge-graded rule records them: its level of the uniform study
        del r["family_mesh_rule"]
        r["family_level_q"] = 1.0
        r["stated_error"] = stated_row_error(r)
    target.write_text(json.dumps(record))
    before = {r["gap_over_side"]: r for r in record["gap_rows"]}
    edge = before[0.05]["edge_graded"]
    rows = [{"level_q": q, "dofs": d, "stiffness_nm": k, "f_theta_hz": f, "f_y_hz": fy, "thetaddot": {"y^2*theta": y}}
            for q, d, k, f, fy, y in zip(edge["levels_q"], edge["dofs"], edge["stiffness_nm"], edge["f_theta_hz"],
                                         edge["f_y_hz"], edge["y2_theta"])]
    row = merge_edge_graded_study(target, 0.05, rows)
    assert row["family_level_q"] == before[0.05]["family_level_q"] and "family_mesh_rule" not in row
    assert row["stated_error"] == before[0.05]["stated_error"]
    with pytest.raises(ValueError, match="no gap row"):
        merge_edge_graded_study(target, 0.02, rows)


def test_shipped_family_record_states_below_two_percent_at_every_gap_node():
    """The shipped (edge-graded) family's mesh record: one row per gap node, at the node's level, each stating less than
    2 % (the target for the hinge stiffness), restated by the record's rule from its levels."""
    from acousim.fullwave.mesh_record import stated_row_error

    rows = json.loads((FAMILY_DIR / MESH_CONVERGENCE_FILE).read_text())["gap_rows"]
    assert [r["gap_over_side"] for r in rows] == pytest.approx(sorted(FAMILY_GAP_RATIOS), rel=1e-9)
    for r in rows:
        assert r["family_mesh_rule"] == "family-edges"
        assert r["family_level_q"] == family_mesh_level(r["gap_over_side"])
        assert r["stated_error"] == pytest.approx(stated_row_error(r), abs=1e-12) and r["stated_error"] < 0.02


@pytest.mark.parametrize("gap_ratio", [0.0, -0.01, float("nan"), float("inf")])
def test_mesh_level_refuses_a_gap_that_is_not_positive(gap_ratio):
    with pytest.raises(ValueError, match="g/s must be positive"):
        family_mesh_level(gap_ratio)
