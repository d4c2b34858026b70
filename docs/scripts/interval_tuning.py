"""The 95 % intervals over finished blind studies: coverage per named true parameter and the smallest relative
systematic part d with which at least 92 % of them hold the truth (docs/diagnosis.md, "Coverage of the 95 %
intervals").

Each study directory is a ``python -m validation blind --out OUT`` folder; its ``cases/*/result.json`` are read as they
are (a study stopped early counts its finished cases).  A case that records ``intervals`` (the estimate, its jackknife
error ``statistical_std_error``, degrees of freedom and the truth) is checked with the interval as stated,
``SE^2 = SE_jackknife^2 + (d |estimate|)^2``; an older case that recorded only whether the jackknife's interval held the
truth (``interval_covers``) and the error (``parameter_relative_error``) counts as held once
``|error| <= t(0.975, 9) d`` (``--old``: a sufficient condition).  Clopper-Pearson 95 % bounds on every coverage.

    python docs/scripts/interval_tuning.py OUT_9611 OUT_9612 OUT_9613 --old OUT_9162 OUT_7301 OUT_7302
"""
from __future__ import annotations

import argparse
import glob
import json
import math

import numpy as np
from scipy import stats

TARGET = 0.92


def _bounds(k: int, n: int) -> str:
    lo = 0.0 if k == 0 else stats.beta.ppf(0.025, k, n - k + 1)
    hi = 1.0 if k == n else stats.beta.ppf(0.975, k + 1, n - k)
    return f"{k} of {n} ({k / n:.0%}; 95 % bounds {lo:.0%}-{hi:.0%})" if n else "-"


def _cases(folder: str) -> list[dict]:
    out = []
    for f in sorted(glob.glob(f"{folder}/cases/*/result.json")):
        r = json.loads(open(f).read())
        if r.get("scored", True) and r.get("error") is None:
            out.append(r)
    return out


def thresholds(folders: list[str], old: list[str]) -> dict[tuple[str, str], list[float]]:
    """Per (effect, parameter): each named case's smallest d with which its interval holds the truth."""
    out: dict[tuple[str, str], list[float]] = {}
    for r in (c for f in folders for c in _cases(f)):
        for eff, ps in (r.get("intervals") or {}).items():
            for p, iv in ps.items():
                if iv.get("std_error") is None:
                    continue
                stat = iv.get("statistical_std_error")
                stat = iv["std_error"] if stat is None else stat
                need = ((iv["value"] - iv["truth"]) / stats.t.ppf(0.975, iv["dof"])) ** 2 - stat**2
                out.setdefault((eff, p), []).append(0.0 if need <= 0 else math.sqrt(need) / abs(iv["value"]))
    for r in (c for f in old for c in _cases(f)):
        for eff, ps in (r.get("interval_covers") or {}).items():
            for p, covered in ps.items():
                err = (r.get("parameter_relative_error") or {}).get(eff, {}).get(p)
                if covered is None or err is None:
                    continue
                out.setdefault((eff, p), []).append(0.0 if covered else err / stats.t.ppf(0.975, 9))
    return out


def coverage_now(folders: list[str]) -> dict[str, list[bool]]:
    """Per effect and per parameter: whether the recorded interval (the code that ran) held the truth."""
    out: dict[str, list[bool]] = {}
    for r in (c for f in folders for c in _cases(f)):
        for eff, ps in (r.get("interval_covers") or {}).items():
            for p, covered in ps.items():
                if covered is not None:
                    out.setdefault(eff, []).append(bool(covered))
                    out.setdefault(f"{eff} {p}", []).append(bool(covered))
        if r.get("pressure_interval_covers") is not None:
            out.setdefault("pressure", []).append(bool(r["pressure_interval_covers"]))
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("studies", nargs="+", help="blind study folders whose cases record intervals")
    parser.add_argument("--old", nargs="*", default=[], help="older study folders (interval_covers and errors only)")
    a = parser.parse_args()
    print("recorded coverage (the intervals of the code that ran):")
    for name, flags in coverage_now(a.studies).items():
        print(f"  {name}: {_bounds(sum(flags), len(flags))}")
    print(f"smallest relative systematic part d with >= {TARGET:.0%} held:")
    for (eff, p), th in sorted(thresholds(a.studies, a.old).items()):
        th = np.sort(th)
        d = th[int(math.ceil(TARGET * len(th))) - 1]
        print(f"  {eff} {p}: {len(th)} named, d = {d:.4f} (largest needs {th[-1]:.4f})")


if __name__ == "__main__":
    main()
