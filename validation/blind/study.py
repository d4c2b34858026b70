"""A blind study: cases of every selected kind, resumable, summarised per kind in one table.

Finished cases are saved as ``cases/caseNNN/result.json`` (candidate kind) or ``cases/KIND/caseNNN/result.json``
and not recomputed on a rerun.  ``summary.json`` holds the configuration, the candidate summary under
``summary`` (with its cases under ``cases``) and every kind's summary and cases under ``kinds``.
"""
from __future__ import annotations

import json
import logging
from pathlib import Path

import numpy as np

from cubedimer.atomic import atomic_write_text, write_json

from .candidates import candidates_table, confusion_figure, draw_case, run_case, summarize
from .config import KINDS, BlindConfig
from .extended import OUT_OF_CANDIDATE, draw_extended_case, run_extended_case

__all__ = ["run_blind", "summarize_kind", "blind_table", "case_dir"]

logger = logging.getLogger(__name__)


def case_dir(out: Path, kind: str, index: int) -> Path:
    """The folder of case ``index`` of ``kind`` in a study folder."""
    return out / "cases" / f"case{index:03d}" if kind == "candidates" else out / "cases" / kind / f"case{index:03d}"


def _draw(kind: str, config: BlindConfig, index: int) -> dict:
    if kind == "candidates":
        return draw_case(config.seed, index, config.pressure_error, config.resonator)
    return draw_extended_case(kind, config.seed, index, config.pressure_error)


def _case_task(item: tuple) -> tuple[str, dict]:
    kind, case, config, out_dir = item
    run = run_case if kind == "candidates" else run_extended_case
    return kind, run(case, config, Path(out_dir))  # the result exactly as saved, so a resumed study is identical


def run_blind(config: BlindConfig, out_dir: str | Path, executor=None, progress: bool = True) -> dict:
    """Run (or resume) a blind study; writes ``summary.json``, ``blind_table.md`` and the confusion matrix
    (candidate kind).  Returns ``{kind: summary}`` for the kinds of ``config``."""
    from cubedimer.executor import ExecutorConfig, map_ordered

    out = Path(out_dir)
    (out / "cases").mkdir(parents=True, exist_ok=True)
    results: dict[str, dict[int, dict]] = {k: {} for k in config.kinds}
    todo = []
    for i in range(config.cases):  # interleaved over kinds, so that a study stopped early has every kind
        for kind in config.kinds:
            path = case_dir(out, kind, i) / "result.json"
            if path.exists():
                results[kind][i] = json.loads(path.read_text())
            else:
                path.parent.mkdir(parents=True, exist_ok=True)
                todo.append((kind, _draw(kind, config, i), config, str(path.parent)))
    n_done = sum(len(r) for r in results.values())
    if n_done:
        (logger.info if progress else logger.debug)("resuming: %d cases done, %d to run", n_done, len(todo))
    for kind, r in map_ordered(_case_task, todo, executor or ExecutorConfig(), desc="blind cases", progress=progress):
        results[kind][r["index"]] = r
    ordered = {k: [results[k][i] for i in sorted(results[k])] for k in config.kinds}
    summaries = {k: summarize_kind(k, ordered[k]) for k in config.kinds}
    doc = {"config": {**config.__dict__, "kinds": list(config.kinds)},
           "kinds": {k: {"summary": summaries[k], "cases": ordered[k]} for k in config.kinds}}
    if "candidates" in summaries:
        doc["summary"], doc["cases"] = summaries["candidates"], ordered["candidates"]
        confusion_figure(ordered["candidates"], out / "confusion_matrix.png")
    write_json(out / "summary.json", doc)
    atomic_write_text(out / "blind_table.md", blind_table(summaries, config))
    return summaries


def _rate(values: list) -> float | None:
    values = [v for v in values if v is not None]
    return float(np.mean(values)) if values else None


def _spread(values: list) -> dict | None:
    """Median and range of the non-missing values."""
    v = [x for x in values if x is not None]
    return {"median": float(np.median(v)), "min": float(min(v)), "max": float(max(v))} if v else None


def summarize_kind(kind: str, results: list[dict]) -> dict:
    """The scores of one kind's cases (rates over the scored cases; failed and not generated counted apart)."""
    if kind == "candidates":
        return summarize(results)
    scored = [r for r in results if r.get("scored", True)]
    ok = [r for r in scored if r["error"] is None]
    out: dict = {"n_cases": len(results), "n_scored": len(scored),
                 "not_generated": len(results) - len(scored), "failed": len(scored) - len(ok)}
    if kind == "out_of_candidate":
        out["per_effect"] = {}
        for name in OUT_OF_CANDIDATE:
            sub = [r for r in ok if r["case"]["effect"] == name]
            out["per_effect"][name] = {
                "n": len(sub), "not_forced_rate": _rate([not r["forced"] for r in sub]),
                "leading_term_right_rate": _rate([r["leading_right"] for r in sub]),
                "coefficient_error": _spread([r["coefficient_relative_error"] for r in sub]),
                "drift_false_alarms": sum(bool(r["drift_detected"]) for r in sub),
                "named": sorted({n for r in sub for n in r["identified"]}),
                "leading_terms": sorted({str(r["leading_term"]) for r in sub})}
        out["not_forced_rate"] = _rate([not r["forced"] for r in ok])
        out["leading_term_right_rate"] = _rate([r["leading_right"] for r in ok])
    elif kind == "drift":
        out["detected_rate"] = _rate([r["drift_detected"] for r in ok])
        out["amplitude_error"] = _spread([r["amplitude_relative_error"] for r in ok])
        out["true_amplitude"] = _spread([r["true_relative_amplitude"] for r in ok])
        with_eff = [r for r in ok if r["true_set"]]
        out["n_with_effect"] = len(with_eff)
        out["exact_rate_no_effect"] = _rate([r["exact"] for r in ok if not r["true_set"]])
        out["exact_rate_with_effect"] = _rate([r["exact"] for r in with_eff])
        out["not_forced_rate"] = _rate([not r["forced"] for r in ok])
        out["pressure_error"] = _spread([abs(r["pressure_calibrated_pa"] / r["pressure_true_pa"] - 1) for r in ok])
    elif kind == "glitches":
        out["exact_rate_clean"] = _rate([r["exact_clean"] for r in ok])
        out["exact_rate"] = _rate([r["exact"] for r in ok])
        out["same_identified_rate"] = _rate([r["same_identified"] for r in ok])
        out["accuracy_lost"] = sum(r["accuracy_lost"] for r in ok)
        out["glitches_inserted"] = sum(r["glitches_inserted"] for r in ok)
        out["glitches_masked"] = sum(r["glitches_masked"] or 0 for r in ok)
        out["glitches_masked_clean"] = sum(r["glitches_masked_clean"] or 0 for r in ok)
        d = [r["max_parameter_error"] - r["max_parameter_error_clean"] for r in ok
             if r["max_parameter_error"] is not None and r["max_parameter_error_clean"] is not None]
        out["parameter_error_change"] = _spread(d)
        out["pressure_error_change"] = _spread([r["pressure_error"] - r["pressure_error_clean"] for r in ok
                                                if r["pressure_error"] is not None and r["pressure_error_clean"] is not None])
    elif kind == "unit_slip":
        out["skipped_by_name_rate"] = _rate([r["skipped_by_name"] for r in ok])
        out["unit_named_rate"] = _rate([r["unit_named"] for r in ok])
        out["exact_rate"] = _rate([r["exact"] for r in ok])
        out["per_slip"] = {s: {"n": len(sub), "skipped_by_name_rate": _rate([r["skipped_by_name"] for r in sub])}
                           for s in sorted({r["case"]["slip"] for r in ok})
                           for sub in [[r for r in ok if r["case"]["slip"] == s]]}
    else:
        raise ValueError(f"unknown case kind {kind!r}")
    return out


def _pct(v) -> str:
    return "-" if v is None else f"{100 * v:.0f} %"


def _sp(d, scale=100.0, unit=" %") -> str:
    if d is None:
        return "-"
    return f"{scale * d['median']:.3g}{unit} ({scale * d['min']:.3g}-{scale * d['max']:.3g})"


def _count(s: dict) -> str:
    return f"{s['n_scored']} scored of {s['n_cases']} ({s['not_generated']} not generated, {s['failed']} failed)"


def blind_table(summaries: dict, config: BlindConfig) -> str:
    """The summaries of a blind study (``{kind: summary}``; a candidate summary alone is accepted too) as
    Markdown, one section per kind, beside the targets."""
    if "per_effect" in summaries and "n_cases" in summaries:
        summaries = {"candidates": summaries}
    lines = [f"# Blind check: {config.cases} cases per kind (seed {config.seed}, {config.runs} runs x "
             f"{config.duration:g} s each)", ""]
    for kind in KINDS:
        s = summaries.get(kind)
        if s is None:
            continue
        if kind == "candidates":
            lines += candidates_table(s)
        elif kind == "out_of_candidate":
            lines += [f"## Effects outside the candidates: {_count(s)}", "",
                      "| effect | n | not forced onto a candidate | leading discovered term right | coefficient error "
                      "median (range) | candidates named | leading terms found | drift false alarms |",
                      "|---|---|---|---|---|---|---|---|"]
            for name, d in s["per_effect"].items():
                eq, term = OUT_OF_CANDIDATE[name][:2]
                lines.append(f"| {name} ({eq}: {term}) | {d['n']} | {_pct(d['not_forced_rate'])} | "
                             f"{_pct(d['leading_term_right_rate'])} | {_sp(d['coefficient_error'])} | "
                             f"{', '.join(d['named']) or 'none'} | {', '.join(d['leading_terms'])} | "
                             f"{d['drift_false_alarms']} |")
            lines.append(f"| all | {s['n_scored'] - s['failed']} | **{_pct(s['not_forced_rate'])}** (target >= 90 %) | "
                         f"**{_pct(s['leading_term_right_rate'])}** (target >= 80 %) | | | | |")
        elif kind == "drift":
            lines += [f"## Drifting pressure: {_count(s)}", "", "| quantity | value | target |", "|---|---|---|",
                      f"| drift detected | **{_pct(s['detected_rate'])}** | >= 90 % |",
                      f"| relative amplitude: true, median (range) | {_sp(s['true_amplitude'])} | |",
                      f"| relative amplitude error, median (range) | {_sp(s['amplitude_error'])} | |",
                      f"| mean-pressure error, median (range) | {_sp(s['pressure_error'])} | |",
                      f"| nothing forced (no candidate named that is absent) | {_pct(s['not_forced_rate'])} | >= 90 % |",
                      f"| exact identification on top: no effect / one effect ({s['n_with_effect']} cases) | "
                      f"{_pct(s['exact_rate_no_effect'])} / {_pct(s['exact_rate_with_effect'])} | |"]
        elif kind == "glitches":
            lines += [f"## Tracking glitches against their clean twins: {_count(s)}", "",
                      "| quantity | value | target |", "|---|---|---|",
                      f"| exact identification: clean / glitched | {_pct(s['exact_rate_clean'])} / "
                      f"{_pct(s['exact_rate'])} | glitched >= clean |",
                      f"| same effects named as the clean twin | {_pct(s['same_identified_rate'])} | 100 % |",
                      f"| cases exact when clean but not with glitches | **{s['accuracy_lost']}** | 0 |",
                      f"| glitch frames inserted / masked (masked on the clean twins) | {s['glitches_inserted']} / "
                      f"{s['glitches_masked']} ({s['glitches_masked_clean']}) | |",
                      f"| change of the largest parameter error, median (range) | "
                      f"{_sp(s['parameter_error_change'], unit=' points')} | ~0 |",
                      f"| change of the pressure error, median (range) | "
                      f"{_sp(s['pressure_error_change'], unit=' points')} | ~0 |"]
        elif kind == "unit_slip":
            per = ", ".join(f"{k}: {_pct(v['skipped_by_name_rate'])} of {v['n']}" for k, v in s["per_slip"].items())
            lines += [f"## One file in the wrong units: {_count(s)}", "", "| quantity | value | target |",
                      "|---|---|---|",
                      f"| the slipped file skipped, and only it | **{_pct(s['skipped_by_name_rate'])}** ({per}) | 100 % |",
                      f"| its reason names the unit | {_pct(s['unit_named_rate'])} | 100 % |",
                      f"| exact identification on the other runs | {_pct(s['exact_rate'])} | as candidates |"]
        lines.append("")
    return "\n".join(lines)
