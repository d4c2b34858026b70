"""How a fitting method describes its result to a reader: :class:`MethodDescription` and the text pieces every
method's description uses.

Each registered method (:class:`fitting.methods.registry.FittingMethod`) returns a :class:`MethodDescription` from
``describe(result)``: the paragraph the report (``python -m validation report``, section 3) prints about the fit, the
table of the fitted model, the figures of the fit output directory the section shows and the phrase the z-score
figure's title uses for the selected terms.  The report writes what the method says and nothing of its own, so a
new method is described in its own words.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Mapping

import numpy as np

__all__ = ["DescriptionTable", "MethodDescription", "FIT_FIGURES", "model_equation_text", "damping_rates",
           "anti_damping_text", "fallback_text", "model_found_text"]

#: The figures :func:`fitting.output.plots.plot_fit` writes for every method: (file name in the fit's output directory,
#: caption).
FIT_FIGURES: tuple[tuple[str, str], ...] = (
    ("zscores.png", "z-scores (mean / std across runs, zeros included) of every library term; red: selected, dashed: "
                    "the paper's z = 3."),
    ("coefficients.png", "Distribution across runs of the refined coefficients of the selected terms."),
    ("optimisation.png", "Optimisation trajectory of the long-time refinement."),
)


@dataclass(frozen=True)
class DescriptionTable:
    """A table of a description: title, column headers and rows of cells (numbers SI, None for an empty cell)."""

    title: str
    header: tuple[str, ...]
    rows: tuple[tuple, ...]


@dataclass(frozen=True)
class MethodDescription:
    """What a method says about its result.

    Attributes
    ----------
    text : str
        The paragraph on how the model was found and what it is (the report's section 3 reading).
    table : DescriptionTable
        The fitted model, one row per term.
    figures : tuple of (str, str)
        (file name in the fit's output directory, caption) of the figures to show, in order; a file the fit did not
        write is left out.
    selected_by : str
        How the terms were selected, completing "red: selected ..." in the z-score figure's title (e.g. "by
        integral-form discovery"); empty when there is nothing to add.
    """

    text: str
    table: DescriptionTable
    figures: tuple[tuple[str, str], ...] = field(default=FIT_FIGURES)
    selected_by: str = ""


def model_equation_text(equations: Mapping[str, Mapping[str, float]]) -> list[str]:
    """The model as equations, e.g. ``yddot = -1.9e4 y + ...`` (SI), from model.json's ``equations``."""
    lines = []
    for eq in ("yddot", "thetaddot"):
        terms = equations.get(eq, {})
        parts = []
        for t, c in terms.items():
            sign = "-" if c < 0 else "+"
            factor = "" if t == "1" else f" {t}"
            parts.append(f"{sign} {abs(c):.4g}{factor}")
        body = " ".join(parts).lstrip("+ ") if parts else "0"
        lines.append(f"{eq} = {body}")
    return lines


def damping_rates(equations: Mapping[str, Mapping[str, float]]) -> dict[str, float]:
    """The model's linear damping as rates [1/s] (positive: damping): minus the coefficients of ydot in yddot and of
    thetadot in thetaddot, where the model has them."""
    out = {}
    for eq, term, label in (("yddot", "ydot", "gamma_y (ydot in yddot)"),
                            ("thetaddot", "thetadot", "gamma_theta (thetadot in thetaddot)")):
        if term in equations.get(eq, {}):
            out[label] = -float(equations[eq][term])
    return out


def anti_damping_text(coefficients: Mapping[str, float]) -> str:
    """A sentence flagging fitted velocity coefficients that feed energy in: ``{label: rate}`` with the rate as a
    damping rate [1/s] (positive: damping; negative: anti-damping).  Empty when none is negative."""
    anti = {k: v for k, v in coefficients.items() if np.isfinite(v) and v < 0}
    if not anti:
        return ""
    listed = ", ".join(f"{k} {v:+.3g} 1/s" for k, v in anti.items())
    return (f" Anti-damping: the fitted damping rate{'s' if len(anti) > 1 else ''} {listed} "
            f"{'are' if len(anti) > 1 else 'is'} negative, i.e. the term feeds energy into the motion, which a passive "
            "dimer in air cannot do. It may come from the y origin (a misplaced origin makes the trap's asymmetry read "
            "as a velocity term), from a drive (a pressure or a field that does work on the dimer) or from a wrong "
            "model (the term standing in for a missing one); it is not physical damping.")


#: What ordered the terms a fallback dropped (model.json ``fallback["order"]``), in words.
_FALLBACK_ORDER = {"z": "the smallest z of the fit first", "ensemble p-value": "the largest per-run p-value first"}


def fallback_text(record: Mapping) -> str:
    """The sentences on a fallback (model.json ``fallback``): the model the method found blew up, and the one written
    is the best candidate that integrates over every run, re-optimised; empty without a fallback."""
    fb = record.get("fallback")
    if not fb:
        return ""
    n = sum(len(v) for v in record["equations"].values())
    cands = fb.get("candidates") or []
    sane = sum(1 for c in cands if not c.get("blown_up_runs"))
    order = _FALLBACK_ORDER.get(fb.get("order", ""), "")
    return (f" That model was not written: {fb['reason']}. The model written ({n} terms) is its fallback, the "
            f"candidate of least long-time loss among those that integrate over every run ({sane} of {len(cands)}"
            + (f"; terms dropped with {order}" if order else "") + f"): {fb['used']}, re-optimised jointly against the "
            "long-time behaviour. Its coefficients have moved from those the standard errors and z of the table "
            "belong to.")


def model_found_text(record: Mapping, gives: str, gave: str) -> str:
    """How a method's account names the model written: ``"{gives}: <equations>."``; after a fallback,
    ``"{gave} of <n> terms."`` (the blown-up model's size), :func:`fallback_text` and ``" It reads <equations>."``."""
    equations = "; ".join(model_equation_text(record["equations"]))
    fb = record.get("fallback")
    if not fb:
        return f"{gives}: {equations}."
    n_found = sum(len(v) for v in fb["blown_up_model"]["equations"].values())
    return f"{gave} of {n_found} terms." + fallback_text(record) + f" It reads {equations}."
