"""The report's first screen: the answer on one screen, before the sections that show how it was reached.

* too few runs to name any effect, first, with how many to record;
* the causes: each named effect with its parameters, their standard errors, and how far the gap shrinks with it
  (or that it leaves the gap unchanged within its error);
* the constants the simulation was built from, and where each came from (meta.json, an option, the calibration, a
  default);
* every data warning (meta.json keys not read, skipped files, masked glitches, the diagnosis's own warnings);
* which force model fits and why, one sentence each;
* one run's time series: the data against the fitted model and the calibrated simulation.

Every number is read from diagnosis.json and model.json (:class:`~validation.report.context.ReportContext`).
"""
from __future__ import annotations

from typing import TYPE_CHECKING

from ..claims import gap_value, shrink_value
from ..context import ReportContext
from ..html import Figure, Section, Table
from .gap_diagnosis import gap_without, named_effects, not_shrinking, too_few_runs_text, unchanged_within_error

if TYPE_CHECKING:
    from ...diagnosis import Diagnosis, EffectVerdict

__all__ = ["section", "causes_text", "cause_rows", "constant_rows", "data_warnings", "model_sentences"]


def _estimate(effect, parameter: str) -> str:
    return effect.estimate(parameter).format()


def _params(effect) -> str:
    """The effect's parameters with their standard errors (or why there is none), and its derived quantities."""
    return ", ".join([f"{k} = {_estimate(effect, k)}" for k in effect.params]
                     + [f"{k} = {iv.format()}" for k, iv in (effect.derived or {}).items()])


def cause_rows(diagnosis: "Diagnosis") -> list[list]:
    """One row per effect named as a cause (and each member of an indistinguishable pair the model fits): its
    parameters with their standard errors, the gap without and with it, and the shrink."""
    pairs = {e for pr in diagnosis.indistinguishable or [] for e in pr["effects"]}
    rows = []
    for e in diagnosis.effects:
        if not e.significant or not_shrinking(diagnosis, e) or not (e.named or e.name in pairs):
            continue
        before = gap_without(diagnosis, e)
        rows.append([e.name + (" (one of an indistinguishable pair)" if e.name in pairs else ""), _params(e),
                     gap_value(before, diagnosis.noise_floor), gap_value(e.gap_after, diagnosis.noise_floor),
                     unchanged_within_error(diagnosis, e)
                     or shrink_value(1 - e.gap_after / before if before else float("nan"), e.gap_after)])
    return rows


def _gap_moves(diagnosis: "Diagnosis", effect: "EffectVerdict", shown) -> str:
    """What a named effect does to the gap: as added (from the gap of the effects added before it); where that rose,
    also given the model's other effects (the final model refitted without it), on which it was judged."""
    before = gap_without(diagnosis, effect)
    text = f"the gap {shown(before)} -> {shown(effect.gap_after)}"
    if effect.gap_after >= before and effect.gap_change_given_others is not None:
        without = effect.gap_without_given_others
        text += (f" as added, before the effects added after it; given the other effects "
                 f"{shown(without)} -> {shown(without + effect.gap_change_given_others)}")
    return text


def causes_text(diagnosis: "Diagnosis") -> str:
    """The answer's first sentences: too few runs (first, when so), the gap before, the named causes and the gap
    after, and an effect that improved held-out runs but raised the gap beyond its error."""
    floor = diagnosis.noise_floor

    def shown(g: float) -> str:
        v = gap_value(g, floor)
        return v if isinstance(v, str) else f"{v:.3g}"

    text = too_few_runs_text(diagnosis)
    text += (" " if text else "") + (f"The calibrated simulation alone leaves a gap of {shown(diagnosis.gap_before)} "
                                     "(the unexplained fraction of the data beyond the noise floor).")
    named = named_effects(diagnosis)
    pairs = diagnosis.indistinguishable or []
    if named:
        text += " The causes, in the order added: " + "; ".join(
            f"{e.name} ({_params(e)}; " + (f"it {w})" if (w := unchanged_within_error(diagnosis, e)) else
                                           f"{_gap_moves(diagnosis, e, shown)})")
            for e in named) + "."
    for pr in pairs:
        a, b = pr["effects"]
        text += f" {a} or {b}: the data cannot tell them apart; the model fits {pr['kept_in_model']}."
    if named or pairs:
        text += f" With them the gap is {shown(diagnosis.gap_after)}."
    elif not too_few_runs_text(diagnosis):
        text += " No candidate effect is named."
    text += "".join(f" {e.name} is {not_shrinking(diagnosis, e)}." for e in diagnosis.effects
                    if not_shrinking(diagnosis, e))
    return text


def constant_rows(diagnosis: "Diagnosis") -> list[list]:
    """The constants used (diagnosis.json ``constants``): name, value, unit, standard error, where it came from."""
    from ...diagnosis.summarise.constants import SOURCES

    rows = []
    for c in diagnosis.constants:
        value, unit = c["value"], c["unit"]
        if unit == "m":
            value, unit = value * 1e6, "um"
            std = None if c.get("std_error") is None else c["std_error"] * 1e6
        else:
            std = c.get("std_error")
        source = SOURCES.get(c["source"], c["source"])
        rows.append([c["name"], value, unit, std, source + (f" ({c['note']})" if c.get("note") and c["source"] not in
                                                           ("meta.json", "default") else "")])
    return rows


def data_warnings(diagnosis: "Diagnosis", model_json: dict) -> list[str]:
    """Every data warning, one line each: the diagnosis's (y's orientation, meta.json keys it does not read, too few
    runs, the loader's), the skipped files with their reasons, and the masked tracking glitches."""
    # (too few runs is the answer's first sentence)
    out = [w["message"] for w in diagnosis.data_warnings or [] if w.get("code") != "too_few_runs"]
    skipped = {(d["file"], d["reason"]) if isinstance(d, dict) else (str(d), "") for d in
               list(diagnosis.skipped_files or []) + list(model_json.get("skipped_files") or [])}
    out += [f"{f} skipped: {why}" if why else f"{f} skipped" for f, why in sorted(skipped)]
    if diagnosis.glitch_frames_masked:
        out.append(f"{diagnosis.glitch_frames_masked} tracking-glitch frames masked by the loader (filled as missing)")
    return out


def model_sentences(context: ReportContext) -> list[str]:
    """Which force model fits and why, one sentence per compared simulation, from its gap components (section 7)."""
    from ...diagnosis.summarise.model_comparison import row_label

    floor = context.diagnosis.noise_floor
    out = []
    for r in context.models.rows:
        y, th, en = r.components
        shown = gap_value(r.gap, floor)
        gap = shown if isinstance(shown, str) else f"{shown:.3g}"
        if r.gap <= 0.01:
            why = "it fits: its gap is within the 0.01 counted as explained"
        elif th > 1:
            why = (f"it does not fit the hinge: its theta equation leaves {th:.3g} of the hinge accelerations' variance "
                   "unexplained, more than predicting no hinge acceleration at all (1)")
        elif th > max(y, en):
            why = f"it misses the hinge: its theta equation leaves {th:.3g} unexplained (y equation {y:.2g})"
        else:
            why = f"it misses part of the motion (y equation {y:.2g}, theta equation {th:.2g}, energy {en:.2g})"
        out.append(f"{row_label(r.model)}: gap {gap}; {why}.")
    out += [f"{n}: not compared ({why})." for n, why in context.unavailable().items()]
    return out


def section(context: ReportContext) -> Section:
    """The first screen: the answer, its constants, the data warnings, the force models and one run's time series."""
    from ..figures import timeseries_overlay_figure

    diag = context.diagnosis
    warnings = data_warnings(diag, context.model_json)
    reading = (causes_text(diag) + " " + " ".join(model_sentences(context))
               + (" Data warnings: " + "; ".join(warnings) + "." if warnings else " No data warnings."))
    figures = []
    if diag.overlay:
        figures.append(Figure(*timeseries_overlay_figure(diag.overlay, context.fit_model, context.figs_dir)))
    causes = cause_rows(diag)
    tables = [Table("Causes: each named effect with its parameters and how far the gap shrinks with it",
                    ["effect", "parameters (SI, +- standard error)", "gap without it", "gap with it", "shrink"],
                    causes,
                    {"parameters (SI, +- standard error)": "fitted with the named effects; the standard error over runs "
                                                           "(delete-one-run jackknife) with the parameter's systematic "
                                                           "part added (docs/diagnosis.md; both, and the 95 % interval, "
                                                           "in diagnosis.json)",
                     "gap without it": "the gap with the effects named before it (the calibrated simulation's for the "
                                       "first)", "gap with it": "the gap once it is added",
                     "shrink": "1 - gap with it / gap without it; where the gap with it is higher, but by less "
                               "than 2 standard errors of the runs' paired changes, that it leaves the gap unchanged "
                               "within its error, with the change +- its standard error"}),
              Table("Constants used", ["constant", "value", "unit", "standard error", "from"], constant_rows(diag),
                    {"from": "where the value came from: the data set's meta.json, a default, a command-line option of "
                             "the model, or the calibration on the runs"})]
    tables = tables if causes else tables[1:]  # no causes, no empty table: the reading says why
    if warnings:
        tables.append(Table("Data warnings", ["warning"], [[w] for w in warnings]))
    return Section("answer", "The answer", reading, figures, tables,
                   {"causes": [r[0].split(" (")[0] for r in causes], "too_few_runs": bool(too_few_runs_text(diag)),
                    "data_warnings": warnings, "constants": {c["key"]: c["value"] for c in diag.constants},
                    "models": model_sentences(context)})
