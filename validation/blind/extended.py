"""Blind cases beyond the candidate effects: causes no candidate describes, a drifting pressure, tracking
glitches and a file in the wrong units.

Each kind has a draw (every random choice from ``SeedSequence([seed, KIND_CODES[kind], index])``), a run
(generate the data, hide the truth, diagnose, score; ``result.json`` in the case's folder) and a score:

* ``out_of_candidate``: ``-k theta^3`` in thetaddot (``cubic_hinge``) or ``-c y^2 ydot`` in yddot
  (``y_damping``), alternating by case index, on twin-like data (:mod:`validation.blind.twin_like`).  Scored:
  *forced* (a candidate is named), the leading discovered term of the effect's equation against the truth
  (``theta^3`` or ``y^2*ydot``) and its coefficient's error.
* ``drift``: the pressure drifts sinusoidally within each run (relative amplitude log-uniform in
  ``DRIFT_AMPLITUDE``), with one candidate effect of ``DRIFT_EFFECTS`` on top in half the cases.  Scored: drift
  detected, its amplitude against the truth, the effects identified on top (exact set; forced = a candidate
  named that is not present).
* ``glitches``: a candidate case (drawn as :func:`validation.blind.candidates.draw_from` does) diagnosed twice on
  the same twin data: clean, and with ``GLITCHES_PER_RUN`` isolated outlier frames per run of
  ``GLITCH_SIZE`` times the tracking noise in y or theta.  Scored: the glitched diagnosis against its clean
  twin (same effects named, exactness, parameter errors) and the frames masked against those inserted.
* ``unit_slip``: a candidate case with one run rewritten with y in micrometres or t in milliseconds
  (alternating by index).  Scored: exactly that file skipped, the reason naming the unit, and the
  identification on the other runs against the truth.
"""
from __future__ import annotations

from typing import TYPE_CHECKING

import json
import shutil
from pathlib import Path

import numpy as np

from cubedimer.atomic import write_json
from cubedimer.dataset import write_run_csv

from .candidates import (diagnose_blind, draw_from, draw_parameters, generate_twin_case, hide_truth, not_generated,
                         score_case)
from .config import BlindConfig

if TYPE_CHECKING:
    from ..diagnosis import Diagnosis

__all__ = ["KIND_CODES", "OUT_OF_CANDIDATE", "DRIFT_AMPLITUDE", "DRIFT_EFFECTS", "GLITCHES_PER_RUN", "GLITCH_SIZE",
           "UNIT_SLIPS", "draw_extended_case", "run_extended_case", "insert_glitches", "slip_units", "score_out_of_candidate", "score_drift",
           "score_glitches", "score_unit_slip"]

#: Stable stream code of each kind (part of every case's seed).
KIND_CODES = {"out_of_candidate": 1, "drift": 2, "glitches": 3, "unit_slip": 4}

#: Out-of-candidate effects: (equation, library term of the truth, sign of its coefficient, strength range).
#: ``cubic_hinge``: k [1/s^2] of -k theta^3 (hardening; about 15-70 % of the soft Gor'kov hinge's restoring
#: acceleration at theta = 0.3); ``y_damping``: c [1/(m^2 s)] of -c y^2 ydot (c (100 um)^2 = 2-20 1/s).
OUT_OF_CANDIDATE: dict[str, tuple[str, str, float, tuple[float, float]]] = {
    "cubic_hinge": ("thetaddot", "theta^3", -1.0, (1.0e4, 5.0e4)),
    "y_damping": ("yddot", "y^2*ydot", -1.0, (2.0e8, 2.0e9)),
}
#: Relative pressure amplitude of a drift (log-uniform) and the range of its period [s].
DRIFT_AMPLITUDE = (0.01, 0.06)
DRIFT_PERIOD = (1.5, 4.0)
#: Candidates that may act on top of a drift (their strengths from STRENGTHS), one in half the drift cases.
DRIFT_EFFECTS = ("linear_damping", "quadratic_drag", "pair_scattering")
#: Glitch frames per run (inclusive range) and their size in tracking-noise standard deviations (log-uniform).
GLITCHES_PER_RUN = (3, 8)
GLITCH_SIZE = (15.0, 100.0)
#: The unit slips a case can carry, alternating by index.
UNIT_SLIPS = ("y_micrometres", "t_milliseconds")
#: Twin tracking noise (y [m], theta), the default camera's.
_NOISE = (1.0e-6, 0.005)


def _rng(seed: int, kind: str, index: int) -> np.random.Generator:
    return np.random.default_rng(np.random.SeedSequence([seed, KIND_CODES[kind], index]))


def draw_extended_case(kind: str, seed: int, index: int, pressure_error: float = 0.10) -> dict:
    """The hidden truth of case ``index`` of ``kind`` (see the module docstring)."""
    rng = _rng(seed, kind, index)
    case: dict = {"kind": kind, "index": index}
    if kind == "out_of_candidate":
        name = list(OUT_OF_CANDIDATE)[index % len(OUT_OF_CANDIDATE)]
        lo, hi = OUT_OF_CANDIDATE[name][3]
        case.update(effect=name, strength=float(np.exp(rng.uniform(np.log(lo), np.log(hi)))), effects={})
    elif kind == "drift":
        lo, hi = DRIFT_AMPLITUDE
        case["drift"] = float(np.exp(rng.uniform(np.log(lo), np.log(hi))))
        name = str(rng.choice(DRIFT_EFFECTS)) if rng.random() < 0.5 else None
        case["effects"] = {name: draw_parameters(rng, name)} if name else {}
    elif kind in ("glitches", "unit_slip"):
        case.update(draw_from(rng, index, pressure_error), kind=kind)
        if kind == "glitches":
            case["glitch_seed"] = int(rng.integers(2**31))
        else:
            case["slip"] = UNIT_SLIPS[index % len(UNIT_SLIPS)]
            case["slip_run"] = int(rng.integers(1 << 16))  # modulo the number of runs written
        return case
    else:
        raise ValueError(f"unknown extended case kind {kind!r}")
    case["pressure_error_range"] = pressure_error
    case["data_seed"] = int(rng.integers(2**31))
    return case


def run_extended_case(case: dict, config: BlindConfig, out_dir: Path) -> dict:
    """Generate, diagnose blind and score one case of a new kind; writes ``result.json`` in ``out_dir``."""
    data = out_dir / "data"
    if data.exists():
        shutil.rmtree(data)
    kind = case["kind"]
    if kind in ("out_of_candidate", "drift"):
        result = _run_twin_like(case, config, data)
    else:
        error, retries = generate_twin_case(case, config, data)
        if error is not None:
            result = not_generated(case, error, retries)
        else:
            truth = hide_truth(data, out_dir / "truth.json")
            result = _run_glitches(case, config, data, truth) if kind == "glitches" else \
                _run_unit_slip(case, config, data, truth)
            result["twin_redraws"] = retries
    result["kind"] = kind
    write_json(out_dir / "result.json", result)
    shutil.rmtree(data, ignore_errors=True)
    return result


def _run_twin_like(case: dict, config: BlindConfig, data: Path) -> dict:
    from .twin_like import TwinLikeConfig, TwinLikeError, write_twin_like_dataset

    kw = dict(runs=config.runs, duration=config.duration, pressure_error=case["pressure_error_range"],
              effects=case["effects"], drift_period=DRIFT_PERIOD)
    if case["kind"] == "drift":
        kw["drift"] = case["drift"]
    else:
        kw[case["effect"]] = case["strength"]
    error, redraws = None, 0
    for redraws in range(5):  # a drawn start can leave the trap: redraw the data seed, same truth otherwise
        try:
            truth = write_twin_like_dataset(data, TwinLikeConfig(seed=case["data_seed"] + redraws, **kw))
            error = None
            break
        except TwinLikeError as exc:
            error = str(exc)
    if error is not None:
        return {"index": case["index"], "case": case, "scored": False, "error": f"generation: {error}",
                "twin_redraws": redraws}
    diag, error = diagnose_blind(data, config)
    score = score_out_of_candidate if case["kind"] == "out_of_candidate" else score_drift
    result = score(case, truth, diag, error)
    result["twin_redraws"] = redraws
    return result


def _common(case: dict, diag: "Diagnosis | None", error: str | None) -> dict:
    return {"index": case["index"], "case": case, "error": error, "scored": True,
            "identified": [] if diag is None else list(diag.identified),
            "gap_before": None if diag is None else diag.gap_before,
            "gap_after": None if diag is None else diag.gap_after,
            "drift_detected": None if diag is None else bool(diag.calibration["drift"]["detected"]),
            "discovered_terms": None if diag is None else {
                eq: [(t["term"], t["coefficient"]) for t in terms]
                for eq, terms in diag.remaining_gap["discovered_terms"].items()}}


def score_out_of_candidate(case: dict, truth: dict, diag: "Diagnosis | None", error: str | None) -> dict:
    """Forced onto a candidate (any candidate named), leading discovered term right, its coefficient's error."""
    eq, term, sign, _ = OUT_OF_CANDIDATE[case["effect"]]
    r = _common(case, diag, error)
    found = [] if diag is None else diag.remaining_gap["discovered_terms"][eq]
    lead = found[0] if found else None
    true_coef = sign * case["strength"]
    r.update(forced=bool(r["identified"]) if diag is not None else None,
             true_term=term, equation=eq, true_coefficient=true_coef,
             leading_term=None if lead is None else lead["term"],
             leading_right=lead is not None and lead["term"] == term,
             coefficient_relative_error=(abs(lead["coefficient"] / true_coef - 1)
                                         if lead is not None and lead["term"] == term else None),
             pressure_true_pa=truth["pressure_amplitude_pa"],
             pressure_calibrated_pa=None if diag is None else diag.calibration["pressure_amplitude_pa"])
    return r


def score_drift(case: dict, truth: dict, diag: "Diagnosis | None", error: str | None) -> dict:
    """Drift detected, its amplitude against the truth (median over runs), the effects named on top."""
    r = _common(case, diag, error)
    true_set = sorted(case["effects"])
    true_amp = float(np.median(truth["relative_half_range"]))
    amp = None if diag is None else diag.calibration["drift"].get("relative_amplitude")
    r.update(true_set=true_set, exact=diag is not None and sorted(r["identified"]) == true_set,
             forced=diag is not None and bool(set(r["identified"]) - set(true_set)),
             true_relative_amplitude=true_amp, relative_amplitude=amp,
             amplitude_relative_error=None if amp is None else abs(amp / true_amp - 1),
             pressure_true_pa=truth["pressure_amplitude_pa"],
             pressure_calibrated_pa=None if diag is None else diag.calibration["pressure_amplitude_pa"])
    return r


def _read_csv(path: Path) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    lines = [ln for ln in path.read_text().splitlines() if ln.strip() and not ln.lstrip().startswith("#")]
    header = [h.strip() for h in lines[0].split(",")]
    a = np.array([[float(v) for v in ln.split(",")] for ln in lines[1:]])
    return tuple(a[:, header.index(c)] for c in ("t", "y", "theta"))


def _write_csv(path: Path, t, y, theta, note: str) -> None:
    write_run_csv(path, t, y, theta, [note], t_decimals=9, y_digits=10, theta_decimals=10, missing="nan")


def insert_glitches(data: Path, seed: int) -> int:
    """Add isolated outlier frames to every run of ``data`` (in place); returns how many were inserted.

    Per run: ``GLITCHES_PER_RUN`` frames, each in y or theta, of ``GLITCH_SIZE`` tracking-noise standard
    deviations with a random sign; at least 10 frames from each other, from the ends and from missing frames."""
    rng = np.random.default_rng(seed)
    total = 0
    for path in sorted(data.glob("*.csv")):
        t, y, th = _read_csv(path)
        n = t.size
        free = np.ones(n, bool)
        free[:10] = free[-10:] = False
        for i in np.flatnonzero(~(np.isfinite(y) & np.isfinite(th))):
            free[max(0, i - 10): i + 11] = False
        k = int(rng.integers(GLITCHES_PER_RUN[0], GLITCHES_PER_RUN[1] + 1))
        for _ in range(k):
            i = int(rng.choice(np.flatnonzero(free)))
            free[max(0, i - 10): i + 11] = False
            size = float(np.exp(rng.uniform(*np.log(GLITCH_SIZE)))) * rng.choice([-1.0, 1.0])
            if rng.random() < 0.5:
                y[i] += size * _NOISE[0]
            else:
                th[i] = np.clip(th[i] + size * _NOISE[1], -0.999, 0.999)
        _write_csv(path, t, y, th, f"twin run with {k} tracking glitches")
        total += k
    return total


def _run_glitches(case: dict, config: BlindConfig, data: Path, truth: dict) -> dict:
    clean_diag, clean_err = diagnose_blind(data, config)
    inserted = insert_glitches(data, case["glitch_seed"])
    diag, err = diagnose_blind(data, config)
    return score_glitches(case, truth, clean_diag, clean_err, diag, err, inserted)


def score_glitches(case: dict, truth: dict, clean_diag: "Diagnosis | None", clean_error: str | None, diag: "Diagnosis | None",
                   error: str | None, inserted: int) -> dict:
    """The glitched diagnosis against its clean twin: each scored as a candidate case, then compared."""
    clean = score_case(case, truth, clean_diag, clean_error)
    glitched = score_case(case, truth, diag, error)

    def worst(r):
        errs = [e for p in r["parameter_relative_error"].values() for e in p.values()]
        return max(errs) if errs else None

    wc, wg = worst(clean), worst(glitched)
    return {"index": case["index"], "case": case, "scored": True, "error": error or clean_error,
            "true_set": clean["true_set"], "identified_clean": clean["identified"],
            "identified": glitched["identified"], "exact_clean": clean["exact"], "exact": glitched["exact"],
            "same_identified": sorted(clean["identified"]) == sorted(glitched["identified"]),
            "accuracy_lost": clean["exact"] and not glitched["exact"],
            "max_parameter_error_clean": wc, "max_parameter_error": wg,
            "glitches_inserted": inserted,
            "glitches_masked": None if diag is None else diag.glitch_frames_masked,
            "glitches_masked_clean": None if clean_diag is None else clean_diag.glitch_frames_masked,
            "pressure_error_clean": _pressure_error(clean), "pressure_error": _pressure_error(glitched)}


def _pressure_error(r: dict) -> float | None:
    if not r["pressure_calibrated_pa"]:
        return None
    return abs(r["pressure_calibrated_pa"] / r["pressure_true_pa"] - 1)


def slip_units(data: Path, slip: str, pick: int) -> str:
    """Rewrite one run of ``data`` (the ``pick``-th modulo the number of runs) with y in micrometres
    (``y_micrometres``) or t in milliseconds (``t_milliseconds``); returns its file name."""
    files = sorted(data.glob("*.csv"))
    path = files[pick % len(files)]
    t, y, th = _read_csv(path)
    if slip == "y_micrometres":
        y = y * 1e6
    elif slip == "t_milliseconds":
        t = t * 1e3
    else:
        raise ValueError(f"unknown unit slip {slip!r}")
    _write_csv(path, t, y, th, "units: see the other runs")
    return path.name


def _run_unit_slip(case: dict, config: BlindConfig, data: Path, truth: dict) -> dict:
    name = slip_units(data, case["slip"], case["slip_run"])
    diag, error = diagnose_blind(data, config)
    return score_unit_slip(case, truth, diag, error, name)


#: words of which a skip reason must hold one to name the unit of each slip (a t in milliseconds is named by the
#: physics bound on the vertical frequency and by the cross-run check, "milliseconds"; "units of t" by the check
#: against the Gor'kov trap frequency)
_SLIP_WORDS = {"y_micrometres": ("micrometre",), "t_milliseconds": ("millisecond", "units of t")}


def score_unit_slip(case: dict, truth: dict, diag: "Diagnosis | None", error: str | None, slipped: str) -> dict:
    """The slipped file skipped, and only it; its reason naming the unit; the rest scored as a candidate case."""
    r = score_case(case, truth, diag, error)
    skipped = [] if diag is None else diag.skipped_files
    names = [s["file"] for s in skipped]
    reason = next((s["reason"] for s in skipped if s["file"] == slipped), None)
    r.update(case=case, slipped_file=slipped, skipped_files=skipped, skipped_by_name=names == [slipped],
             unit_named=reason is not None and any(w in reason.lower() for w in _SLIP_WORDS[case["slip"]]))
    return r
