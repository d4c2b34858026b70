"""The discovery against pysindy's strongest configuration, chosen by leave-one-run-out cross-validation.

On the truths of :mod:`benchmarks.bench_model_error` (not sparse in the cubic library: a double pendulum, a
Duffing-van der Pol pair with sin and rational forces, and the suite's paper-like twin), each pysindy configuration of ``peer_configurations`` is
scored by leave-one-run-out cross-validation **on the fitted runs only**: fitted on the other runs, integrated from
the held-out fitted run's first (smoothed) state over ``bench_model_error.HORIZON_PERIODS`` slow periods, RMS position
error over the RMS position (mean of the two coordinates; inf on a blow-up), mean over the held-out runs.  The
configuration of least cross-validated error is pysindy's strongest; it is refitted on all fitted runs and scored
like ours on the exact held-out runs of ``bench_model_error`` (20 runs not used in any fit): terms, terms outside the
Taylor support, Taylor terms missed, median relative coefficient error on the Taylor terms found, and the long-time
error from the first state and along the runs (medians over the held-out runs).  pysindy's best configuration of at
most the Taylor support's size per equation (by the same cross-validation) is reported beside it.

Configurations (scaled variables of :mod:`fitting.selection.sparse_regression`, Savitzky-Golay states and
accelerations over 0.25 periods of the faster coordinate, as in ``bench_model_error``):

* STLSQ over ``bench_model_error.THRESHOLDS`` (ridge alpha 0.3);
* SR3 with the L0 and with the L1 penalty over ``SR3_LAMBDAS``;
* the bagged ensemble (``EnsembleOptimizer``, 20 models) of STLSQ at the best STLSQ threshold;
* the weak form (``WeakPDELibrary``, cubic with a constant, on the first-order state) with K test functions per
  run in ``WEAK_K`` and half-width H in ``WEAK_H_PERIODS`` slow periods, STLSQ over ``WEAK_THRESHOLDS``.

MIOSR is left out (its solver, gurobipy, is not installed).  Ours: ``discover_model(DiscoveryConfig())``, and the
same capped at the Taylor support's size per equation (``DiscoveryConfig(max_terms=...)``, the front's point there).
Per case the rows are ours (both; and ``FRONT_PICK``, the default fit's front point of least held-out error within
the Taylor size), pysindy's strongest, its best at most the Taylor size, and the cross-validated best of each family
(``FAMILIES``); above the rows, the issue's first target per case: ours at most the Taylor size (the capped fit, and
``FRONT_PICK``) against the best of pysindy's reported configurations at any size, from the first state; and the issue's second
target per case: every point of our default fit's front (``FrontPoint.coef``, its supports fitted on all runs by
integral-form least squares and refined by the output error, ``discover_model(..., refine_front=True)``; stored in the
cache) scored like the rest on the held-out runs, against pysindy's best at that size or smaller (the larger
equation's terms): the configuration its cross-validation picks among those, and the best of them on the held-out
runs.

The grid (``GRID_LEVELS`` x ``GRID_RUNS`` x ``GRID_SEEDS``, every truth at the levels it reaches, the twin at 1 and
5 % only; ``--full``) costs hours on one core:
every case's results are written, atomically, to a cache folder (``--cache-dir``; default the suite's user cache,
``bench/strongest_peer``), so an interrupted run resumes where it stopped and the table is rebuilt from the cache in
seconds.  pysindy's results are kept per case; ours are recomputed when ``OURS_VERSION`` changes.  An unreadable
entry is recomputed.

Run ``python -m benchmarks.bench_strongest_peer [--full | --truths ... --levels 0.01 0.05 0.12 --runs 4 8 16]
[--seeds 201] [--cache-dir DIR | --no-cache] [--cached-only] [--only peer|ours]``; ``--cached-only`` tabulates the
finished cases of an unfinished grid and lists the others; ``--only peer`` (``ours``) fills only pysindy's (our) side
of every case into the cache, so that two processes fill a grid's two sides in parallel; without ``--full`` or a grid option only ``QUICK_CASES`` are run
(``make bench``: minutes on one core).
"""
from __future__ import annotations

import argparse
import json
import sys
import time
import warnings
from pathlib import Path
from typing import Callable, Sequence

import numpy as np
from numpy.typing import NDArray

from benchmarks import bench_model_error as bme

#: SR3's penalty weights (scaled variables)
SR3_LAMBDAS = tuple(np.round(np.logspace(-5, -1, 6), 7))
#: the weak form's test functions per run and half-widths in slow periods, and its STLSQ thresholds
WEAK_K = (100, 300)
WEAK_H_PERIODS = (0.25, 0.75)
WEAK_THRESHOLDS = (1e-3, 1e-2)
ENSEMBLE_MODELS = 20
#: the grid of ``make bench``: truncation levels, run counts, fresh seeds
GRID_LEVELS = (0.01, 0.05, 0.12)
GRID_RUNS = (4, 8, 16)
GRID_SEEDS = (201,)
#: the quick default (``make bench``, minutes on one core): the cases that decided the first target on the earlier
#: grids, one per truth, at 5 % truncation with 4 runs; ``--full`` (or any of --truths/--levels/--runs) runs the grid
QUICK_CASES = (("duffing_vdp", 0.05, 4), ("double_pendulum", 0.05, 4))


def _sindy_coef(optimizer, derivs, scales) -> NDArray:
    from fitting.selection.sparse_regression import _sindy, pysindy_to_canonical, scaled_data

    X, A = scaled_data(derivs, scales)
    dt = float(derivs[0].t[1] - derivs[0].t[0]) / scales.time
    names, model = _sindy(optimizer, X, A, dt)
    return scales.to_si(pysindy_to_canonical(names, model.coefficients()))


def _weak_coef(derivs, scales, k: int, h_periods: float, threshold: float, f_slow: float) -> NDArray:
    import pysindy as ps

    from cubedimer.terms import STATE_NAMES
    from fitting.selection.sparse_regression import pysindy_to_canonical

    X = [d.state / scales.state for d in derivs]
    t = (derivs[0].t - derivs[0].t[0]) / scales.time
    n = min(len(x) for x in X)
    lib = ps.WeakPDELibrary(function_library=ps.PolynomialLibrary(degree=3, include_bias=True),
                            spatiotemporal_grid=t[:n], K=k, H_xt=[h_periods / f_slow / scales.time], p=4)
    model = ps.SINDy(optimizer=ps.STLSQ(threshold=threshold, alpha=bme.STLSQ_ALPHA, normalize_columns=True),
                     feature_library=lib)
    np.random.seed(0)  # the test functions' centres come from numpy's global generator
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model.fit([x[:n] for x in X], t=t[1] - t[0], feature_names=list(STATE_NAMES))
    coef = np.asarray(model.coefficients())[[1, 3]]
    return scales.to_si(pysindy_to_canonical(model.get_feature_names(), coef))


def peer_configurations(f_slow: float, stlsq_threshold: float | None = None) -> dict[str, Callable]:
    """name -> fit(derivs, scales) -> SI coefficients (2, 35); with ``stlsq_threshold`` only the ensemble at it."""
    import pysindy as ps

    if stlsq_threshold is not None:
        def ensemble(derivs, scales, thr=stlsq_threshold):
            np.random.seed(0)
            return _sindy_coef(ps.EnsembleOptimizer(ps.STLSQ(threshold=thr, alpha=bme.STLSQ_ALPHA), bagging=True,
                                                    n_models=ENSEMBLE_MODELS), derivs, scales)
        return {f"E-STLSQ {stlsq_threshold:g}": ensemble}
    out: dict[str, Callable] = {}
    for thr in bme.THRESHOLDS:
        out[f"STLSQ {thr:g}"] = lambda d, s, thr=thr: _sindy_coef(ps.STLSQ(threshold=float(thr),
                                                                           alpha=bme.STLSQ_ALPHA), d, s)
    for reg in ("L0", "L1"):
        for lam in SR3_LAMBDAS:
            out[f"SR3-{reg} {lam:g}"] = lambda d, s, reg=reg, lam=lam: _sindy_coef(
                ps.SR3(reg_weight_lam=float(lam), regularizer=reg, max_iter=100), d, s)
    for k in WEAK_K:
        for h in WEAK_H_PERIODS:
            for thr in WEAK_THRESHOLDS:
                out[f"weak K={k} H={h:g}T thr={thr:g}"] = (
                    lambda d, s, k=k, h=h, thr=thr: _weak_coef(d, s, k, h, thr, f_slow))
    return out


def _first_state_error(coef: NDArray, d, n: int) -> float:
    """Long-time error of ``coef`` on one fitted run from its first smoothed state, against its noisy positions."""
    from fitting.model import PolynomialModel

    s = d.state[d.trim:d.trim + n]
    sim, n_valid = PolynomialModel(coef).simulate(s[0], d.t[d.trim:d.trim + n], substeps=8)
    if n_valid < len(s) or not np.all(np.isfinite(sim)):
        return np.inf
    return float(np.mean([np.sqrt(np.mean((sim[:, k] - s[:, k]) ** 2) / np.mean(s[:, k] ** 2)) for k in (0, 2)]))


def loo_error(fit: Callable, derivs: Sequence, f_y: Sequence[float], f_slow: float) -> float:
    """Leave-one-run-out long-time error of a configuration on the fitted runs (mean over the held-out runs)."""
    from fitting.selection.sparse_regression import dataset_scales

    n = int(round(bme.HORIZON_PERIODS / f_slow / (derivs[0].t[1] - derivs[0].t[0])))  # the runs' own frame rate
    errs = []
    for i in range(len(derivs)):
        train = [d for j, d in enumerate(derivs) if j != i]
        try:
            coef = fit(train, dataset_scales(train, [f for j, f in enumerate(f_y) if j != i]))
        except Exception:  # a configuration pysindy cannot fit counts as failed, not as the benchmark's error
            return np.inf
        errs.append(_first_state_error(coef, derivs[i], n))
        if not np.isfinite(errs[-1]):
            return np.inf
    return float(np.mean(errs))


#: bump when ours changes: cached rows of ours from another version are recomputed (the peers' stay)
OURS_VERSION = 9
#: the row of the front's point of least held-out error within the Taylor size (the first target's second reading)
FRONT_PICK = "ours front <= Taylor size"
#: the peer families whose cross-validated best is reported per case, by the prefix of their configurations' names
FAMILIES = ("STLSQ", "SR3-L0", "SR3-L1", "E-STLSQ", "weak")


def default_cache_dir() -> Path:
    """Per-case results: ``<suite cache>/bench/strongest_peer`` (:func:`cubedimer.compile_cache.suite_cache_root`)."""
    from cubedimer.compile_cache import suite_cache_root

    return suite_cache_root() / "bench" / "strongest_peer"


def _cached(path: Path | None, compute: Callable[[], dict]) -> dict:
    """``compute()``'s result, read from ``path`` when a readable entry is there, else computed and written there
    atomically; an unreadable entry is recomputed, never fatal."""
    from cubedimer.atomic import write_json

    if path is not None and path.exists():
        try:
            return json.loads(path.read_text())
        except (OSError, ValueError) as exc:
            print(f"[strongest-peer] cache entry {path} unreadable ({exc}); recomputed", file=sys.stderr)
    out = compute()
    if path is not None:
        path.parent.mkdir(parents=True, exist_ok=True)
        write_json(path, out)
    return out


def _case_key(name: str, level: float, seed: int, fit_runs: int) -> str:
    return f"{name}_{level:g}_{seed}_{fit_runs}"


def peer_case(data, name: str, fit_runs: int) -> dict:
    """Every configuration's leave-one-run-out error on the fitted runs and, for those that integrated, its
    coefficients refitted on all fitted runs: ``{"cv": {cfg: err}, "coef": {cfg: (2, 35) list}, "wall": s}``."""
    from cubedimer.spectra import dominant_frequency
    from fitting.selection.sparse_regression import dataset_scales

    truth = bme.TRUTHS[name]
    derivs = data.sindy_derivs
    f_y = [dominant_frequency(r.y, r.dt) for r in data.runs]
    scales = dataset_scales(derivs, f_y)
    t0 = time.perf_counter()
    cv = {cfg: loo_error(fit, derivs, f_y, truth.f_slow) for cfg, fit in peer_configurations(truth.f_slow).items()}
    best_stlsq = min((c for c in cv if c.startswith("STLSQ")), key=cv.get)
    ens = peer_configurations(truth.f_slow, float(best_stlsq.split()[1]))
    cv.update({cfg: loo_error(fit, derivs, f_y, truth.f_slow) for cfg, fit in ens.items()})
    fits = {**peer_configurations(truth.f_slow), **ens}
    coefs = {cfg: fits[cfg](derivs, scales).tolist() for cfg in cv if np.isfinite(cv[cfg])}  # every one integrated
    return {"cv": {k: (v if np.isfinite(v) else None) for k, v in cv.items()}, "coef": coefs,
            "wall": time.perf_counter() - t0}


def ours_case(data, cap: int, name: str) -> dict:
    """Ours with ``DiscoveryConfig()`` and capped at ``cap`` terms per equation (``max_terms``): coefficients,
    selection modes and wall times; and the default fit's front (``front``: per point its cap, terms per equation,
    the discovery's own cross-validated error, whether selected, its coefficients and its long-time error from the
    first state on the held-out runs, median)."""
    from fitting.selection.integral_discovery import DiscoveryConfig, discover_model

    out, f_slow = {}, bme.TRUTHS[name].f_slow
    for label, cfg in (("ours", DiscoveryConfig()), ("ours <= Taylor size", DiscoveryConfig(max_terms=cap))):
        t0 = time.perf_counter()
        res = discover_model(data.runs, data.derivs, cfg, refine_front=label == "ours")
        out[label] = {"coef": res.coef.tolist(), "note": "; ".join(res.selection_modes),
                      "wall": time.perf_counter() - t0}
        if label == "ours" and res.front is not None:
            out["front"] = [{"max_terms": p.max_terms, "n_terms": list(p.n_terms), "cv_error": _finite(p.error),
                             "selected": p.selected, "coef": p.coef.tolist(), "refined": p.refined,
                             "estimate": p.estimate,
                             "long_time": _finite(float(np.median(bme.long_time_errors(p.coef, data, f_slow))))}
                            for p in res.front.points]
    return out


def _finite(x: float) -> float | None:
    return float(x) if np.isfinite(x) else None


def _row(name: str, level: float, seed: int, fit_runs: int, data, method: str, coef: NDArray, note: str,
         wall: float) -> dict:
    truth = bme.TRUTHS[name]
    taylor = bme.compiled(name)[1]
    return {"truth": name, "level": level, "seed": seed, "fit_runs": fit_runs, "residual": data.residual,
            "method": method, "taylor_terms": int((taylor != 0).sum()),
            "taylor_per_eq": tuple(int(v) for v in (taylor != 0).sum(axis=1)), **bme.score(coef, taylor),
            "long_time": float(np.median(bme.long_time_errors(coef, data, truth.f_slow))),
            "long_time_along": float(np.median(bme.long_time_errors(coef, data, truth.f_slow, along=True))),
            "terms_per_eq": tuple(int(v) for v in (coef != 0).sum(axis=1)), "wall": wall, "note": note}


def run_case(name: str, level: float, seed: int, fit_runs: int, cache: Path | None = None) -> list[dict]:
    """The rows of one case: ours (default and capped at the Taylor size), pysindy's strongest, its best at most
    the Taylor size, and each family's cross-validated best; per-case results read from / written to ``cache``."""
    taylor = bme.compiled(name)[1]
    cap = int((taylor != 0).sum(axis=1).max())
    data = bme.make_data(name, level, seed, fit_runs)
    key = _case_key(name, level, seed, fit_runs)
    peer = _cached(cache / f"{key}_peer.json" if cache else None, lambda: peer_case(data, name, fit_runs))
    ours = _cached(cache / f"{key}_ours_v{OURS_VERSION}.json" if cache else None, lambda: ours_case(data, cap, name))
    cv = {k: (np.inf if v is None else v) for k, v in peer["cv"].items()}
    coefs = {k: np.array(v) for k, v in peer["coef"].items()}
    picks = [("pysindy strongest (LOO CV)", min(coefs, key=cv.get))]
    small = [c for c in coefs if ((coefs[c] != 0).sum(axis=1) <= cap).all()]
    if small:
        picks.append(("pysindy best <= Taylor size", min(small, key=cv.get)))
    for fam in FAMILIES:
        members = [c for c in coefs if c.split()[0] == fam]
        if members:
            picks.append((f"pysindy {fam} (LOO CV)", min(members, key=cv.get)))
    rows = [_row(name, level, seed, fit_runs, data, m, np.array(ours[m]["coef"]), ours[m]["note"], ours[m]["wall"])
            for m in ("ours", "ours <= Taylor size")]
    within = [p for p in ours.get("front", []) if max(p["n_terms"]) <= cap and p["cv_error"] is not None]
    if within:  # the front's point of least held-out error within the Taylor size (our cross-validation, not the test)
        p = min(within, key=lambda p: (p["cv_error"], max(p["n_terms"])))
        rows.append(_row(name, level, seed, fit_runs, data, FRONT_PICK, np.array(p["coef"]),
                         f"front point at cap {p['max_terms']}, {p.get('estimate', 'integral form')}; held-out "
                         f"error {100 * p['cv_error']:.2f} %", ours["ours"]["wall"]))
    rows += [_row(name, level, seed, fit_runs, data, m, coefs[c], f"{c}; LOO error {100 * cv[c]:.2f} %",
                  peer["wall"]) for m, c in picks]
    rows[0]["front"] = front_comparison(ours.get("front", []), coefs, cv, data, bme.TRUTHS[name].f_slow)
    for row in rows:
        print(f"[strongest-peer] {key} {row['method']}: {row['terms_per_eq']} terms, {row['outside']} outside, "
              f"{row['missed']} missed, coef err {100 * row['median_error']:.1f} %, long-time "
              f"{100 * row['long_time']:.2f} %, along {100 * row['long_time_along']:.2f} %; {row['note']}",
              file=sys.stderr, flush=True)
    return rows


def front_comparison(front: list[dict], coefs: dict[str, NDArray], cv: dict[str, float], data,
                     f_slow: float) -> list[dict]:
    """The issue's second target per point of our front: its size (the larger equation's terms), our long-time error
    from the first state on the held-out runs (median), and pysindy's at that size or smaller: the best of its
    configurations on the held-out runs (``best``) and the one its cross-validation picks among them (``cv``)."""
    size = {c: int((v != 0).sum(axis=1).max()) for c, v in coefs.items()}
    held = {c: float(np.median(bme.long_time_errors(v, data, f_slow))) for c, v in coefs.items()}
    out = []
    for p in front:
        n = max(p["n_terms"])
        small = [c for c in coefs if size[c] <= n]
        ours = np.inf if p["long_time"] is None else p["long_time"]
        best = min(small, key=held.get) if small else None
        pick = min(small, key=cv.get) if small else None
        out.append({"size": n, "n_terms": p["n_terms"], "selected": p["selected"], "ours": ours,
                    "best": held[best] if best else None, "best_cfg": best,
                    "cv": held[pick] if pick else None, "cv_cfg": pick})
    return out


def _ratio(ours: float, peer: float | None) -> float:
    """ours / peer; 1 where both blew up, NaN where pysindy has no configuration at that size (nothing to beat)."""
    if peer is None:
        return float("nan")
    if not np.isfinite(ours) and not np.isfinite(peer):
        return 1.0
    return ours / peer if peer > 0 else float("inf")


def targets_front(rows: list[dict]) -> list[str]:
    """The issue's second target per case: at every size on our front (the default fit's path), our long-time error
    from the first state at most pysindy's best at that size or smaller; against the configuration its
    cross-validation picks among those and against the best of them on the held-out runs; the worst point's ratio."""
    out = ["| truth | level | seed | runs | front points (sizes with a pysindy model) | met vs CV pick | worst ratio "
           "(size) | met vs best | worst ratio (size) |", "|---|---|---|---|---|---|---|---|---|"]
    met = {"cv": [], "best": []}
    for r in rows:
        if r["method"] != "ours" or not r.get("front"):
            continue
        pts = [p for p in r["front"] if p["best"] is not None]
        cells = []
        for k in ("cv", "best"):
            ratios = [(_ratio(p["ours"], p[k]), p["size"]) for p in pts]
            ok = all(v <= 1 for v, _ in ratios)
            met[k].append(ok)
            worst = max(ratios, default=(float("nan"), 0))
            lost = ", ".join(str(n) for v, n in ratios if not v <= 1)
            cells.append(f"{'yes' if ok else 'no'} ({sum(v <= 1 for v, _ in ratios)} of {len(ratios)}"
                         f"{'; lost at ' + lost if lost else ''}) | {worst[0]:.2f} ({worst[1]})")
        out.append(f"| {r['truth']} | {100 * r['level']:g} % | {r['seed']} | {r['fit_runs']} | {len(r['front'])} "
                   f"({len(pts)}) | {cells[0]} | {cells[1]} |")
    for k, what in (("cv", "the configuration pysindy's cross-validation picks"),
                    ("best", "the best of pysindy's configurations on the held-out runs")):
        if met[k]:
            out += ["", f"At every size on our front at most {what} at that size or smaller: {sum(met[k])} of "
                        f"{len(met[k])} cases ({100 * np.mean(met[k]):.0f} %; target 90 %)."]
    return out


def table(rows: list[dict]) -> list[str]:
    out = ["| truth | residual | seed | runs | Taylor terms | method | terms per equation | outside Taylor | Taylor missed "
           "| median coef. error | long-time error | along the runs | configuration |",
           "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        out.append(f"| {r['truth']} | {100 * r['residual']:.1f} % | {r['seed']} | {r['fit_runs']} | {r['taylor_terms']} "
                   f"| {r['method']} | {r['terms_per_eq'][0]} / {r['terms_per_eq'][1]} | {r['outside']} | "
                   f"{r['missed']} | {100 * r['median_error']:.1f} % | {100 * r['long_time']:.2f} % | "
                   f"{100 * r['long_time_along']:.2f} % | {r['note']} |")
    return out


def targets(rows: list[dict], label: str = "ours <= Taylor size") -> list[str]:
    """The issue's first target per case: ours at most the Taylor size (the row ``label``: the capped fit, or
    ``FRONT_PICK``) against pysindy's strongest (chosen by its cross-validation) and against the best of pysindy's
    reported configurations at any size on the held-out runs (the stricter reading), from the first state; the ratios
    and the summary (share of cases met, worst ratio)."""
    cases: dict[tuple, dict[str, dict]] = {}
    for r in rows:
        cases.setdefault((r["truth"], r["level"], r["seed"], r["fit_runs"]), {})[r["method"]] = r
    out = [f"| truth | level | seed | runs | {label}: terms | long-time | along | pysindy strongest: terms "
           "| long-time | along | ratio | pysindy's best reported: terms | long-time | ratio |",
           "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    ratios = []
    for (name, level, seed, n), m in cases.items():
        if label not in m:
            continue
        ours, cv = m[label], m["pysindy strongest (LOO CV)"]
        best = min((r for k, r in m.items() if k.startswith("pysindy")), key=lambda r: r["long_time"])
        ratios.append((ours["long_time"] / cv["long_time"], ours["long_time"] / best["long_time"]))
        out.append(f"| {name} | {100 * level:g} % | {seed} | {n} | {_terms(ours)} | {100 * ours['long_time']:.2f} % "
                   f"| {100 * ours['long_time_along']:.2f} % | {_terms(cv)} | {100 * cv['long_time']:.2f} % | "
                   f"{100 * cv['long_time_along']:.2f} % | {ratios[-1][0]:.2f} | {_terms(best)} | "
                   f"{100 * best['long_time']:.2f} % | {ratios[-1][1]:.2f} |")
    if ratios:
        r = np.array(ratios)
        for k, what in enumerate(("pysindy's strongest (chosen by its cross-validation)",
                                  "the best of pysindy's reported configurations on the held-out runs")):
            out += ["", f"{label[0].upper() + label[1:]} at most {what} on {int((r[:, k] <= 1).sum())} of "
                        f"{len(r)} cases ({100 * np.mean(r[:, k] <= 1):.0f} %; target 80 %); ratio median "
                        f"{np.median(r[:, k]):.2f}, worst {r[:, k].max():.2f} (target 1.25)."]
    return out


def _terms(row: dict) -> str:
    return f"{row['terms_per_eq'][0]} / {row['terms_per_eq'][1]}"


def main(argv: list[str] | None = None) -> str:
    p = argparse.ArgumentParser(prog="python -m benchmarks.bench_strongest_peer", description=__doc__)
    p.add_argument("--truths", nargs="+", default=None, choices=list(bme.TRUTHS))
    p.add_argument("--levels", nargs="+", type=float, default=None)
    p.add_argument("--seeds", nargs="+", type=int, default=list(GRID_SEEDS))
    p.add_argument("--runs", nargs="+", type=int, default=None)
    p.add_argument("--full", action="store_true",
                   help="the whole grid (every truth, level and run count: hours on one core); default: QUICK_CASES")
    p.add_argument("--cache-dir", type=Path, default=None,
                   help="per-case results (default: the suite's user cache, bench/strongest_peer)")
    p.add_argument("--no-cache", action="store_true", help="compute every case afresh and write nothing")
    p.add_argument("--cached-only", action="store_true",
                   help="tabulate only the cases whose results are all in the cache (an unfinished grid's table, in "
                        "seconds); the others are listed as not measured")
    p.add_argument("--only", choices=("peer", "ours"), default=None,
                   help="compute and cache only pysindy's configurations (peer) or only ours (ours) of every case, "
                        "no table (then --cached-only tabulates)")
    args = p.parse_args(argv if argv is not None else [])  # run by benchmarks.__main__: its own argv is not ours
    quick = not args.full and args.truths is None and args.levels is None and args.runs is None
    args.truths = args.truths or list(bme.TRUTHS)
    args.levels = args.levels or list(GRID_LEVELS)
    args.runs = args.runs or list(GRID_RUNS)
    if min(args.runs) < 2:
        p.error(f"--runs must be at least 2 (leave-one-run-out needs runs to hold out), got {min(args.runs)}")
    cache = None if args.no_cache else (args.cache_dir or default_cache_dir())
    if quick:
        cases = [(name, level, seed, n) for seed in args.seeds for name, level, n in QUICK_CASES]
    else:  # the cheaper run counts first: an interrupted grid has every truth and level at them; a truth only at the
        # levels its runs can reach (the twin's hinge reaches face contact before 12 %)
        cases = [(name, level, seed, n) for seed in args.seeds for n in sorted(args.runs) for level in args.levels
                 for name in args.truths if bme.TRUTHS[name].levels is None or level in bme.TRUTHS[name].levels]
    if args.only:  # one side of every case into the cache (two processes fill a grid's two sides in parallel)
        for name, level, seed, n in cases:
            data, key = bme.make_data(name, level, seed, n), _case_key(name, level, seed, n)
            cap = int((bme.compiled(name)[1] != 0).sum(axis=1).max())
            part, compute = (("peer", lambda: peer_case(data, name, n)) if args.only == "peer" else
                             (f"ours_v{OURS_VERSION}", lambda: ours_case(data, cap, name)))
            _cached(cache / f"{key}_{part}.json" if cache else None, compute)
            print(f"[strongest-peer] {key}: {part} cached", file=sys.stderr, flush=True)
        return ""
    missing = []
    if args.cached_only and cache is not None:
        done = [c for c in cases if all((cache / f"{_case_key(*c[:3], c[3])}_{part}.json").exists()
                                        for part in ("peer", f"ours_v{OURS_VERSION}"))]
        missing = [c for c in cases if c not in done]
        cases = done
    rows = [r for case in cases for r in run_case(*case, cache)]
    note = ([f"Not measured (not in the cache): {', '.join(f'{n} {100 * v:g} % seed {s} {r} runs' for n, v, s, r in missing)}.",
             ""] if missing else [])
    if quick:
        cmd = (f"`python -m benchmarks.bench_strongest_peer --seeds {' '.join(map(str, args.seeds))}` (the quick "
               f"subset {', '.join(f'{n} {100 * v:g} % {r} runs' for n, v, r in QUICK_CASES)}; `--full` for the grid)")
        return "\n".join(["## The discovery against pysindy's strongest configuration (leave-one-run-out CV)", "", cmd,
                          "", *note, *targets(rows), "", *targets(rows, FRONT_PICK), "", *targets_front(rows), "", *table(rows), ""])
    cmd = (f"`python -m benchmarks.bench_strongest_peer --truths {' '.join(args.truths)} --levels "
           f"{' '.join(f'{v:g}' for v in args.levels)} --seeds {' '.join(map(str, args.seeds))} --runs "
           f"{' '.join(map(str, args.runs))}{' --cached-only' if args.cached_only else ''}`")
    return "\n".join(["## The discovery against pysindy's strongest configuration (leave-one-run-out CV)", "", cmd, "",
                      *note, *targets(rows), "", *targets(rows, FRONT_PICK), "", *targets_front(rows), "", *table(rows), ""])


if __name__ == "__main__":
    print(main(sys.argv[1:]))
