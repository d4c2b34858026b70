"""Mesh convergence: judging a refined sequence, its Richardson limit, and a family's record of both
(``mesh_convergence.json``) with the mesh error each gap row states.

One row per gap node (``gap_over_side``).  A row may hold a uniformly refined sequence of the hinge-graded mesh
(``levels_q``, ``stiffness_nm``; ``family_level_q`` is one of these levels for a family on that rule) and an
edge-graded sequence
(``edge_graded``: ``levels_q``, ``dofs``, ``stiffness_nm``, ``f_theta_hz``, ``f_y_hz``, ``y2_theta``, with its
Richardson fit and :func:`~acousim.fullwave.convergence.judge_convergence` verdict).  A family built on the
edge-graded meshes marks its rows ``family_mesh_rule = "family-edges"``, its level being one of the sequence's.

The stated error of a row (:func:`stated_row_error`) is the largest of

* the family value's distance from the Richardson limit plus the extrapolation's size
  (:func:`~acousim.fullwave.convergence.stated_mesh_error`), where the sequence has a limit;
* its distance from the finest uniformly refined level;
* its distance from the finest edge-graded level;

rounded up to 1e-4.  ``python -m acousim convergence --study mesh --mesh-rule family-edges --merge-into FILE``
merges a finished study into the record (:func:`merge_edge_graded_study`).
"""
from __future__ import annotations

import json
import math
import os
from pathlib import Path
from typing import Sequence

import numpy as np

from numpy.typing import NDArray
from scipy.optimize import brentq

from cubedimer.atomic import write_json

__all__ = ["CONVERGED_WITHIN", "mean_refinement_ratio", "judge_convergence", "richardson_limit", "stated_mesh_error",
           "edge_graded_block", "family_value", "stated_row_error", "merge_edge_graded_study"]

#: The hinge stiffness counts as converged when the two finest levels agree within this fraction.
CONVERGED_WITHIN = 0.02


def mean_refinement_ratio(levels_q) -> float:
    """The geometric mean of the ratios of successive mesh levels (coarse to fine), as :func:`judge_convergence`
    takes it."""
    q = np.asarray(levels_q, float)
    return float(np.exp(np.mean(np.log(q[:-1] / q[1:]))))


def judge_convergence(values, refinement_ratio: float) -> dict:
    """Judge a quantity computed on three or more successively refined meshes (coarse to fine).

    The required behaviour: the corrections between levels shrink monotonically, the observed order
    ``log(|d_(i)| / |d_(i+1)|) / log(refinement_ratio)`` of the last two corrections is at least 1, and the
    finest two levels agree within :data:`CONVERGED_WITHIN`.

    Returns
    -------
    dict
        ``corrections`` (relative to the finer level), ``monotone``, ``order``, ``finest_difference``
        and ``converged`` (all three criteria met).
    """
    v = np.asarray(values, float)
    if v.size < 3:
        raise ValueError("need at least three mesh levels")
    d = np.diff(v)
    monotone = bool(np.all(np.abs(d[1:]) < np.abs(d[:-1])))
    order = float(np.log(abs(d[-2]) / abs(d[-1])) / np.log(refinement_ratio)) if d[-1] != 0 else float("inf")
    finest = float(abs(d[-1] / v[-1]))
    return {"corrections": (d / v[1:]).tolist(), "monotone": monotone, "order": order, "finest_difference": finest,
            "converged": bool(monotone and order >= 1.0 and finest < CONVERGED_WITHIN)}


def richardson_limit(levels_q, values) -> dict:
    """The mesh-converged limit of a quantity on meshes with every element size times ``levels_q`` (coarse to fine).

    Fits ``v(q) = v_inf + C q^p`` exactly through the finest three levels (the ratios of the levels need not be
    equal).  The fit is only meaningful where the corrections shrink monotonically (``p > 0``); with four or more
    levels, the finest level is also predicted from the three before it, which tests the fit's premise that the
    sequence is already asymptotic.

    Returns
    -------
    dict
        ``limit`` (v_inf), ``order`` (p), ``finest_error`` (|v_finest / v_inf - 1|); with four levels or more,
        ``predicted_finest`` and ``prediction_error`` (relative to the limit) of the fit through the three coarser
        (None when their corrections do not shrink).

    Raises
    ------
    ValueError
        With fewer than three levels, or when the finest three corrections do not shrink (no positive order).
    """
    q = np.asarray(levels_q, float)
    v = np.asarray(values, float)
    if q.size < 3 or q.size != v.size:
        raise ValueError("need at least three mesh levels, one value each")

    def fit(q3: NDArray, v3: NDArray) -> tuple[float, float, float]:
        d1, d2 = v3[1] - v3[0], v3[2] - v3[1]
        ratio = d2 / d1 if d1 != 0 else np.inf

        def mismatch(p: float) -> float:
            return (q3[1] ** p - q3[2] ** p) / (q3[0] ** p - q3[1] ** p) - ratio

        lo, hi = 1e-3, 12.0
        if not 0 < ratio < np.inf or mismatch(lo) * mismatch(hi) > 0:
            raise ValueError(f"the corrections {d1:.4g}, {d2:.4g} do not shrink like a power of the mesh size")
        p = brentq(mismatch, lo, hi, xtol=1e-12)  # the mismatch falls monotonically in p
        c = d2 / (q3[2] ** p - q3[1] ** p)
        return float(v3[2] - c * q3[2] ** p), float(p), float(c)

    limit, order, _ = fit(q[-3:], v[-3:])
    out = {"limit": limit, "order": order, "finest_error": float(abs(v[-1] / limit - 1.0))}
    if q.size >= 4:
        try:
            lim3, p3, c3 = fit(q[-4:-1], v[-4:-1])
        except ValueError:  # the coarser three are not yet asymptotic: no prediction to test
            out.update(predicted_finest=None, prediction_error=None)
        else:
            pred = lim3 + c3 * q[-1] ** p3
            out.update(predicted_finest=float(pred), prediction_error=float(abs(pred - v[-1]) / abs(limit)))
    return out


def stated_mesh_error(family_value: float, levels_q, values) -> dict:
    """The mesh error to state for a value computed on a coarser mesh (``family_value``), from a refined sequence.

    The error is the value's distance from the Richardson limit of the sequence (:func:`richardson_limit`) plus
    the extrapolation's own size (the limit's distance from the finest level): a limit reached by extrapolating
    far is trusted less.

    Returns
    -------
    dict
        ``stated_error`` (relative to the limit) and the fit of :func:`richardson_limit`.
    """
    fit = richardson_limit(levels_q, values)
    limit = fit["limit"]
    error = abs(family_value / limit - 1.0) + fit["finest_error"]
    return {"stated_error": float(error), **fit}


EDGE_RULE = "family-edges"
_EDGE_RULE_TEXT = ("family-edges: the family's mesh graded towards all twelve edges of each cube from 0.02 q s, "
                   "every size times q (growth fixed)")


def edge_graded_block(rows: Sequence[dict]) -> dict:
    """The ``edge_graded`` entry of a gap row from the study's rows (one per level, any order)."""
    rows = sorted(rows, key=lambda r: -float(r["level_q"]))
    levels = [float(r["level_q"]) for r in rows]
    if len(set(levels)) != len(levels):
        raise ValueError(f"the study repeats a mesh level ({levels})")
    k = [float(r["stiffness_nm"]) for r in rows]
    block = {"mesh_rule": _EDGE_RULE_TEXT, "levels_q": levels, "dofs": [int(r["dofs"]) for r in rows],
             "stiffness_nm": k, "f_theta_hz": [float(r["f_theta_hz"]) for r in rows],
             "f_y_hz": [float(r["f_y_hz"]) for r in rows],
             "y2_theta": [float(r["thetaddot"]["y^2*theta"]) for r in rows], "richardson": None, "judgement": None}
    if len(levels) >= 3:
        try:
            block["richardson"] = richardson_limit(levels, k)
        except ValueError:
            pass
        block["judgement"] = judge_convergence(k, mean_refinement_ratio(levels))
    return block


def family_value(row: dict) -> float:
    """The hinge stiffness [N m] on the family's own mesh at this gap row."""
    if row.get("family_mesh_rule") == EDGE_RULE:
        edge = row["edge_graded"]
        return float(edge["stiffness_nm"][_index(edge["levels_q"], row["family_level_q"], row)])
    return float(row["stiffness_nm"][_index(row["levels_q"], row["family_level_q"], row)])


def _index(levels: Sequence[float], q: float, row: dict) -> int:
    for i, v in enumerate(levels):
        if math.isclose(float(v), float(q), rel_tol=1e-9):
            return i
    raise ValueError(f"gap row g/s = {row.get('gap_over_side')}: the family's level q = {q} is not among the "
                     f"measured levels {list(levels)}")


def stated_row_error(row: dict) -> float:
    """The relative mesh error of the hinge stiffness a gap row states (the module's rule), rounded up to 1e-4."""
    fam = family_value(row)
    candidates = []
    if row.get("levels_q"):
        candidates.append(abs(1 - fam / float(row["stiffness_nm"][-1])))
    edge = row.get("edge_graded")
    if edge:
        candidates.append(abs(1 - fam / float(edge["stiffness_nm"][-1])))
        if edge.get("richardson") is not None:
            candidates.append(stated_mesh_error(fam, edge["levels_q"], edge["stiffness_nm"])["stated_error"])
    if not candidates:
        raise ValueError(f"gap row g/s = {row.get('gap_over_side')}: no refined sequence to state an error from")
    return math.ceil(max(candidates) * 1e4 - 1e-9) / 1e4


def merge_edge_graded_study(target: str | os.PathLike, gap_over_side: float, rows: Sequence[dict],
                            family_level_q: float | None = None) -> dict:
    """Merge an edge-graded mesh study at one gap into the record ``target`` (created if missing), atomically.

    The gap row (matched within 1e-3 relative) gets the ``edge_graded`` block and its restated error.  A new
    row, or ``family_level_q`` given, marks the family as built on the edge-graded mesh at that level (which the
    study must contain); an existing hinge-graded row keeps its family level.  Returns the merged row.
    """
    target = Path(target)
    data = json.loads(target.read_text()) if target.exists() else {
        "description": "hinge stiffness against mesh refinement at each gap node of the family", "gap_rows": []}
    gap_rows = data.setdefault("gap_rows", [])
    row = next((r for r in gap_rows if math.isclose(float(r["gap_over_side"]), gap_over_side, rel_tol=1e-3)), None)
    if row is None:
        if family_level_q is None:
            raise ValueError(f"{target}: no gap row at g/s = {gap_over_side:g}; give the family's mesh level")
        row = {"gap_over_side": float(gap_over_side)}
        gap_rows.append(row)
        gap_rows.sort(key=lambda r: float(r["gap_over_side"]))
    row["edge_graded"] = edge_graded_block(rows)
    if family_level_q is not None:
        row.update(family_mesh_rule=EDGE_RULE, family_level_q=float(family_level_q))
    row["stated_error"] = stated_row_error(row)
    write_json(target, data)
    return row
