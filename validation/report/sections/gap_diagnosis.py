"""The diagnosis as a report section: its figures (gap by candidate, residual maps before and after,
residual by library term) and its reading paragraph and table, from diagnosis.json; and the diagnose command's
files (:func:`write_diagnosis`)."""
from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from cubedimer.atomic import save_figure as _save

from ...diagnosis.identify.statistics import format_p
from ..claims import anti_damping_text, gap_value, shrink_value
from ..context import ReportContext
from ..html import Figure, Section, Table

if TYPE_CHECKING:
    from ...diagnosis import Diagnosis, EffectVerdict

__all__ = ["section", "diagnosis_figures", "diagnosis_section", "write_diagnosis"]


def write_diagnosis(diagnosis: "Diagnosis", out_dir: str | Path) -> list[Path]:
    """Write diagnosis.json, the figures and report.html (the diagnosis as a report section) into ``out_dir``.

    ``diagnosis`` is what :func:`validation.diagnosis.diagnose` returns; returns the paths of diagnosis.json and
    report.html."""
    from cubedimer.atomic import write_json

    from ..html import write_report

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    write_json(out / "diagnosis.json", diagnosis.to_json())
    figs = diagnosis_figures(diagnosis, out / "figures")
    write_report([diagnosis_section(diagnosis, figs)], out, "Sim-to-real gap diagnosis")
    return [out / "diagnosis.json", out / "report.html"]


def diagnosis_figures(diagnosis: "Diagnosis", out_dir: str | Path) -> list[Figure]:
    """The diagnosis's figures as PNG files in ``out_dir``: the gap by candidate, the residual maps before and after,
    and the residual by library term."""
    import matplotlib.pyplot as plt

    out = Path(out_dir)
    figs = []
    # 1. gap by candidate
    fig, ax = plt.subplots(figsize=(6, 3.6), constrained_layout=True)
    names = ["calibrated\nsimulation"] + [e.name.replace("_", "\n") for e in diagnosis.effects]
    vals = [diagnosis.gap_before] + [e.gap_after for e in diagnosis.effects]
    colors = ["0.5"] + ["tab:green" if e.significant and not not_shrinking(diagnosis, e) else "tab:gray"
                        for e in diagnosis.effects]
    ax.bar(range(len(vals)), np.maximum(vals, 1e-5), color=colors)
    ax.axhline(0.01, color="k", ls="--", lw=0.8, label="'explained within noise' threshold")
    ax.set_xticks(range(len(vals)), names, fontsize=7)
    ax.set_ylabel("gap (unexplained fraction beyond noise)")
    ax.set_yscale("log")
    ax.set_title("Gap before and after adding each effect (green: identified, not raising the gap beyond its error)")
    ax.legend(fontsize=7)
    figs.append(Figure(_save(fig, out / "gap_by_effect.png"),
                       "Gap of the calibrated simulation and after adding each candidate (identified ones cumulatively, "
                       "others on top of the identified set); the gap is the unexplained fraction of acceleration variance and energy "
                       "balance in excess of the derivative-noise floor; dashed: the threshold below which it counts as explained."))
    # 2. residual maps over (theta, y), before and after, thetaddot and yddot
    fig, axes = plt.subplots(2, 2, figsize=(8, 6), constrained_layout=True)
    for col, key in enumerate(("before", "after")):
        reg = diagnosis.localization[key]["regions"]["theta_y"]
        xe, ye = np.array(reg["x_edges"]), np.array(reg["y_edges"]) * 1e6
        for row, (eq, unit) in enumerate((("rms_yddot", "m/s$^2$"), ("rms_thetaddot", "1/s$^2$"))):
            ax = axes[row, col]
            m = ax.pcolormesh(xe, ye, np.array(reg[eq], float).T, shading="flat", cmap="magma")
            fig.colorbar(m, ax=ax, label=f"RMS residual [{unit}]")
            ax.set_xlabel(r"$\theta$")
            ax.set_ylabel(r"$y$ [$\mu$m]")
            ax.set_title(f"{eq.replace('rms_', '')} residual, {key}", fontsize=9)
    figs.append(Figure(_save(fig, out / "residual_maps.png"),
                       "Where the gap lies in state space: RMS acceleration residual over (theta, y) bins (quantile bins), "
                       "before and after the identified effects."))
    # 3. residual explained by single library terms
    fig, axes = plt.subplots(1, 2, figsize=(8, 3.4), constrained_layout=True)
    for ax, eq in zip(axes, ("yddot", "thetaddot")):
        rows = sorted(diagnosis.localization["before"]["terms"][eq], key=lambda d: -d["explained_fraction_alone"])[:8]
        ax.barh([r["term"] for r in rows][::-1], [r["explained_fraction_alone"] for r in rows][::-1], color="tab:blue")
        ax.set_xlabel("fraction of residual variance explained alone")
        ax.set_title(f"{eq} residual of the calibrated simulation", fontsize=9)
    figs.append(Figure(_save(fig, out / "residual_terms.png"),
                       "Which library terms carry the gap: each term's share of the residual variance when fitted alone."))
    return figs


#: the candidate effects whose parameters are damping rates [1/s] (positive: energy taken out of the motion)
DAMPING_RATES = {"linear_damping": ("gamma_y", "gamma_theta")}


def _origin_text(cal: dict) -> str:
    """Where the data's y origin lies, with the reference named: the simulation's Z_eq at the calibrated pressure (the
    one the effects' y is measured from) and at the nominal one."""
    nominal = cal["y_origin_above_nominal_Z_eq_m"] * 1e6
    calibrated = cal.get("y_origin_above_calibrated_Z_eq_m")
    if calibrated is None:
        return f"the data's y origin lies {nominal:+.2f} um above the simulation's Z_eq at the nominal pressure. "
    return (f"the data's y origin lies {calibrated * 1e6:+.2f} um above the simulation's Z_eq at the calibrated pressure "
            f"(the effects' y origin) and {nominal:+.2f} um above its Z_eq at the nominal pressure. ")


def gap_without(diagnosis: "Diagnosis", effect: "EffectVerdict") -> float:
    """The gap a model effect was added to: that of the model's effects added before it, or the calibrated
    simulation's gap for the first (:func:`validation.diagnosis.summarise.verdicts.gap_without`)."""
    from ...diagnosis.summarise.verdicts import gap_without as before

    return before(diagnosis.effects, diagnosis.gap_before, effect)


def not_shrinking(diagnosis: "Diagnosis", effect: "EffectVerdict") -> str:
    """For a model effect whose addition raises the gap beyond its error, what it is, with the two gaps and the
    change with its standard error; else ``""``.  A diagnosis rejects such an effect (code ``not_shrinking_gap``); one
    written before that rule named it, and is read the same way (any rise, where the change carries no error)."""
    from ...diagnosis.summarise.verdicts import gap_change_detail, gap_rise, gap_rises
    from ...diagnosis.summarise.verdicts import not_shrinking as rejected_for_it

    if not effect.significant or not (effect.named or rejected_for_it(effect)):
        return ""  # only a named effect (or one rejected for it): a pair's kept member is judged as a pair
    before = gap_without(diagnosis, effect)
    if not rejected_for_it(effect) and not gap_rises(effect, before):
        return ""
    how = ("does not shrink the gap" if gap_rise(effect, before)[3] is None
           else "raises the gap beyond its error")
    return f"not named: it improved held-out runs, but adding it {how} ({gap_change_detail(effect, before)})"


def unchanged_within_error(diagnosis: "Diagnosis", effect: "EffectVerdict") -> str:
    """For a model effect whose addition leaves the gap higher, but by less than the rise's error allows to tell from
    none (it stays named), what it does to the gap, with both gaps and the change with its standard error; else
    ``""`` (the gap shrinks, or the effect is not named for the rise: :func:`not_shrinking`)."""
    from ...diagnosis.summarise.verdicts import gap_change_detail, gap_rise

    if not effect.significant or effect.rejected or not_shrinking(diagnosis, effect):
        return ""
    before = gap_without(diagnosis, effect)
    without, with_it, _, error = gap_rise(effect, before)
    if with_it < without or error is None:
        return ""
    return f"leaves the gap unchanged within its error ({gap_change_detail(effect, before)})"


def named_effects(diagnosis: "Diagnosis") -> list:
    """The effects named as causes: named, and not raising the gap beyond its error when added."""
    return [e for e in diagnosis.effects if e.significant and e.named and not not_shrinking(diagnosis, e)]


def _verdict(diagnosis: "Diagnosis", effect: "EffectVerdict", pairs: list[dict]) -> str:
    if any(effect.name in pr["effects"] for pr in pairs):
        return "indistinguishable"
    if not_shrinking(diagnosis, effect):
        return "no: " + not_shrinking(diagnosis, effect).removeprefix("not named: ")
    if effect.significant and effect.named:
        within = unchanged_within_error(diagnosis, effect)
        return "yes: it " + within if within else "yes"
    return "no"


def _params_text(effect: "EffectVerdict") -> str:
    """The effect's parameters, each with its standard error ("kappa = 1.95e4 +- 0.02e4") or "error not determined"
    and the reason."""
    return ", ".join([f"{k} = {effect.estimate(k).format()}" for k in effect.params]
                     + [f"{k} = {iv.format()}" for k, iv in (effect.derived or {}).items()])


def _table_params_text(effect: "EffectVerdict") -> str:
    """The table's parameter cell: the values with their errors, or, for a rejected candidate, why (its fit on top of
    the model is no result)."""
    if effect.rejected:
        return "rejected: " + ", ".join(r["code"].replace("_", " ") for r in effect.rejected_because)
    return _params_text(effect)


def _pressure_text(diagnosis: "Diagnosis") -> str:
    """The calibrated pressure with its standard error (or why there is none)."""
    cal = diagnosis.calibration
    iv = diagnosis.calibration_estimate("pressure_amplitude_pa")
    if iv.determined:
        value, error = iv.format().split(" +- ")
        model = diagnosis.calibration.get("uncertainty", {}).get("pressure_amplitude_pa", {}).get("model_std_error")
        value = f"{value} Pa +- {error} Pa (standard error over runs" + (
            f", with the calibration's systematic {100 * model / iv.value:.2g} %)" if model else ")")
    else:
        value = f"{iv.value:.0f} Pa (error not determined: {iv.reason})"
    return f"Calibrated pressure {value}, {100 * (cal['pressure_ratio'] - 1):+.1f} % from nominal; "


def _cause_text(diagnosis: "Diagnosis", pairs: list[dict]) -> str:
    """The verdict: the effects named alone (each needed given the others), and each indistinguishable pair as one
    verdict naming both, with the held-out evidence."""
    parts = [f"{e.name} ({_params_text(e)})" + (f", which {w}" if (w := unchanged_within_error(diagnosis, e)) else "")
             for e in named_effects(diagnosis)]
    text = f"The gap is caused by {', then '.join(parts)}" if parts else "The gap is caused by"
    for pr in pairs:
        a, b = pr["effects"]
        kept = next((e for e in diagnosis.effects if e.name == pr["kept_in_model"]), None)
        text += (f"{', and' if parts else ''} by {a} or {b}, which the data cannot tell apart: neither improves held-out "
                 f"runs given the other ({a} {format_p(pr['p_given_other'][a])}, {b} {format_p(pr['p_given_other'][b])}), "
                 f"together they do ({format_p(pr['p_together'])}), and the held-out gap with one instead of the other "
                 f"differs by a median {pr['median_difference']:.2g} ({format_p(pr['p_difference'])}, two-sided); the "
                 f"fitted model uses {pr['kept_in_model']}"
                 + (f" ({_params_text(kept)})" if kept else ""))
    if not parts and not pairs:
        text = "No candidate shrinks the gap"
    for e in diagnosis.effects:
        if not_shrinking(diagnosis, e):
            text += f"; {e.name} is {not_shrinking(diagnosis, e)}"
    return text + "."


def diagnosis_section(diagnosis: "Diagnosis", figures: list[Figure]) -> Section:
    """The report section of a diagnosis: the reading (calibration, gap, cause) and the ranked candidates."""
    cal = diagnosis.calibration
    ident = diagnosis.identified
    rem = diagnosis.remaining_gap
    pairs = diagnosis.indistinguishable or []
    drift = cal.get("drift") or {}
    found = ""
    replaced = rem.get("replaced_by_discovered_terms") or []
    if replaced:
        found += (" Not named, because the discovered terms explain its share better on held-out runs: "
                  + ", ".join(r["name"] for r in replaced) + ".")
    skipped = diagnosis.skipped_files or []
    data_text = ""
    if skipped or diagnosis.glitch_frames_masked:
        data_text = (f"{len(skipped)} file(s) skipped (table below); {diagnosis.glitch_frames_masked} tracking-glitch "
                     "frames masked. ")
    # what the data suggest about how they were recorded comes first: it changes how everything after it reads
    # (too few runs is said where the verdict stands)
    warnings_text = "".join(f"Data warning: {w['message']}. " for w in diagnosis.data_warnings or []
                            if w.get("code") != "too_few_runs")
    named = named_effects(diagnosis)
    reading = (
        warnings_text + data_text + _drift_text(drift) + _hinge_gap_text(cal) +
        _pressure_text(diagnosis) + _origin_text(cal) +
        f"The calibrated simulation leaves {100 * diagnosis.gap_before:.1f} % of the data unexplained beyond the noise "
        "floor (the gap: the mean of the unexplained fractions of the vertical accelerations, the hinge angle and the "
        f"energy balance; noise floor {100 * diagnosis.noise_floor:.1f} %). {_verdict_text(diagnosis, pairs)} "
        + (f"With them the gap is {_percent(gap_value(diagnosis.gap_after, diagnosis.noise_floor, percent=True))}: "
           f"{rem['statement']}"
           if named or pairs else _capitalised(remaining_statement(diagnosis)))
        + f".{found}"
        + anti_damping_text({f"{k} of {e.name}": v for e in diagnosis.effects if e.significant
                             and e.name in DAMPING_RATES for k, v in e.params.items() if k in DAMPING_RATES[e.name]})
    )
    terms = rem.get("discovered_terms") or {}
    return Section("diagnosis", "Sim-to-real gap", reading, figures, _diagnosis_tables(diagnosis, pairs, drift, terms),
                   {"gap_before": diagnosis.gap_before, "gap_after": diagnosis.gap_after,
                    "identified": [n for n in ident if n in {e.name for e in named}],
                    "noise_floor": diagnosis.noise_floor, "pressure_amplitude_pa": cal["pressure_amplitude_pa"],
                    "pressure_ratio": cal["pressure_ratio"],
                    "y_origin_above_nominal_Z_eq_m": cal["y_origin_above_nominal_Z_eq_m"],
                    "effects": {e.name: e.params for e in diagnosis.effects
                                if e.significant and not not_shrinking(diagnosis, e)},
                    "data_warnings": [w["code"] for w in diagnosis.data_warnings or []],
                    "drift_detected": bool(drift.get("detected")),
                    "discovered_terms": {eq: [t["term"] for t in ts] for eq, ts in terms.items()}})


def _percent(value: float | str) -> str:
    """A gap in per cent from :func:`gap_value` (``percent=True``): "1.0 %", or its below-the-floor sentence."""
    return value if isinstance(value, str) else f"{value:.1f} %"


def _capitalised(text: str) -> str:
    return text[:1].upper() + text[1:]


def too_few_runs_text(diagnosis: "Diagnosis") -> str:
    """With too few runs for the held-out test to name any effect: how many, why, and how many to record; else ``""``."""
    settings = diagnosis.settings or {}
    if settings.get("identification_possible") is not False:
        return ""
    n_runs = len(diagnosis.gap_per_run["runs"])
    return (f"With {n_runs} runs no effect can be named: the held-out test's smallest p is "
            f"{settings['smallest_attainable_p']:.3g}, above alpha = {settings['alpha']:g}; record at least "
            f"{settings['runs_needed']} runs.")


def remaining_statement(diagnosis: "Diagnosis") -> str:
    """What remains when no effect is named: the diagnosis's statement, without "no candidate effect explains" when
    the runs are too few for any candidate to be named (nothing was tested that could have explained it)."""
    statement = diagnosis.remaining_gap["statement"]
    if too_few_runs_text(diagnosis):
        statement = statement.replace("a gap remains that no candidate effect explains",
                                      "a gap remains, which these runs are too few to attribute")
    return statement


def _verdict_text(diagnosis: "Diagnosis", pairs: list[dict]) -> str:
    """The cause (:func:`_cause_text`), or that no candidate improves held-out runs, or that none could (too few
    runs)."""
    if named_effects(diagnosis) or pairs:
        return _cause_text(diagnosis, pairs)
    if too_few_runs_text(diagnosis):
        return too_few_runs_text(diagnosis)
    shrinking = [f"{e.name} is {not_shrinking(diagnosis, e)}" for e in diagnosis.effects if not_shrinking(diagnosis, e)]
    if shrinking:
        return "No candidate shrinks the gap: " + "; ".join(shrinking) + "."
    return "No candidate effect improves held-out runs significantly."


def _drift_text(drift: dict) -> str:
    """A tested drift that was not detected: none, or one too small to count (a detected drift is part of the
    remaining-gap statement, with its table)."""
    if not drift.get("tested") or drift.get("detected"):
        return ""
    if drift["p_value"] < drift["alpha"]:  # significant, but too small to matter: say both
        return (f"No pressure drift: the pressure varies within runs by {100 * drift['relative_amplitude']:.2g} %, a "
                f"variation that is statistically detectable (F-test {format_p(drift['p_value'])}) but smaller than "
                f"the {100 * drift['min_relative_amplitude']:.2g} % counted as a drift, so the simulation keeps one "
                "pressure. ")
    return f"No drift of the pressure within runs (F-test {format_p(drift['p_value'])}). "


def _hinge_gap_text(cal: dict) -> str:
    """The model's hinge gap, when it has one: calibrated with its standard error (and the model's own stated error),
    or why not."""
    if "gap_m" not in cal:
        return ""
    if cal.get("gap_calibrated"):
        model_error = cal.get("gap_model_error_m")
        return (f"The hinge gap is calibrated from the hinge motion: g = {cal['gap_m'] * 1e6:.2f} +- "
                f"{cal['gap_std_m'] * 1e6:.2g} um (standard error; an effective gap of the inviscid full-wave "
                "model)"
                + (f", and +- {model_error * 1e6:.2g} um more from the model's own stated accuracy of the hinge "
                   "stiffness (mesh and interpolation of the table family), which more data do not reduce"
                   if model_error else "") + ". ")
    std = cal.get("gap_std_m")
    return (f"Hinge gap g = {cal['gap_m'] * 1e6:.2f} um: {cal.get('gap_note', 'given')}"
            + (f" (standard error of the profile {std * 1e6:.2g} um)" if std else "") + ". ")


def _diagnosis_tables(diagnosis: "Diagnosis", pairs: list[dict], drift: dict, terms: dict) -> list[Table]:
    """The ranked candidates, the discovered library terms, a detected pressure drift and the skipped files."""
    # the first row: the gap before any effect, the calibrated simulation alone
    rows = [["none (the calibrated simulation alone)", None, None, gap_value(diagnosis.gap_before, diagnosis.noise_floor),
             0.0, None, None]]
    rows += [[e.name, _verdict(diagnosis, e, pairs),
              _table_params_text(e), gap_value(e.gap_after, diagnosis.noise_floor), shrink_value(e.shrink, e.gap_after),
              e.p_value, e.p_value_given_others]
             for e in diagnosis.effects]
    n_runs = len(diagnosis.gap_per_run["runs"])
    smallest = (diagnosis.settings or {}).get("smallest_attainable_p", 0.5 ** n_runs)
    columns = {
        "identified": "yes: named as a cause, needed given all the others, and not raising the gap beyond its error "
                      "(where the gap with it is higher, but by less than 2 standard errors of the runs' paired "
                      "changes, that is said with both gaps and the change +- its standard error); no, named by its "
                      "held-out test but raising the gap: significant on held-out runs, yet the gap with it is higher "
                      "than without it beyond that error (both gaps given); indistinguishable: one of a pair the data "
                      "cannot tell apart (named together); no: not a significant held-out improvement",
        "parameters (SI)": "fitted with the named effects, +- the standard error over runs (delete-one-run jackknife) "
                           "with the parameter's systematic part added (docs/diagnosis.md; both, and the 95 % interval, "
                           "are in diagnosis.json); a rejected candidate's fit is no result: the "
                           "reasons of its rejection instead",
        "gap after": "the gap (mean unexplained fraction of the three components beyond the noise floor) with the named "
                     "effects up to this one, or with the named effects plus this one",
        "shrink": "1 - gap after / gap before (the gap of the first row); 'all of it' where the gap after lies below "
                  "the noise floor",
        "held-out p (sign-flip)": f"one-sided sign-flip test over the {n_runs} runs of the held-out improvement when "
                                  f"the effect was added or last tested; the smallest p {n_runs} runs allow is "
                                  f"{smallest:.3g}",
        "p given the others": "the same test of the effect against the named set without it (the backward check)",
    }
    tables = [Table("Candidate effects (ranked)", ["effect", "identified", "parameters (SI)", "gap after", "shrink",
                                                   "held-out p (sign-flip)", "p given the others"], rows, columns)]
    term_rows = [[eq, t["term"], t.get("form", "integral"), t["coefficient"], t["std_error"], t["shrink"], t.get("p_value")]
                 for eq, ts in terms.items() for t in ts]
    if term_rows:
        tables.append(Table("Discovered library terms (what no candidate explains; found in the equation's integral "
                            "form, or in the energy balance for a dissipation)",
                            ["equation", "term", "found in", "coefficient (SI)", "std error", "shrink",
                             "held-out p (sign-flip)"], term_rows,
                            {"found in": "integral: the equation's integral form; energy: the energy balance",
                             "std error": "white-noise standard error of the coefficient",
                             "shrink": "fraction of the equation's remaining gap beyond noise the term removes, added in "
                                       "order", "held-out p (sign-flip)": "one-sided sign-flip test of the term's "
                                                                         "per-run held-out improvement"}))
    if drift.get("detected"):
        tables.append(Table("Pressure drift", ["relative amplitude", "time scale [s]", "F-test p", "window [s]"],
                            [[drift["relative_amplitude"], drift["time_scale_s"], drift["p_value"], drift["window_s"]]]))
    skipped = diagnosis.skipped_files or []
    if skipped:
        tables.append(Table("Skipped files", ["file", "reason"],
                            [[d["file"], d["reason"]] if isinstance(d, dict) else [str(d), ""] for d in skipped]))
    return tables


def section(context: ReportContext) -> Section:
    """Section 6, the sim-to-real gap of the diagnosis's model: :func:`diagnosis_section` with its figures."""
    sec = diagnosis_section(context.diagnosis, diagnosis_figures(context.diagnosis, context.figs_dir))
    return Section("diagnosis", f"6. The sim-to-real gap ({context.spec.label} model)",
                   sec.reading, sec.figures, sec.tables, sec.numbers)
