"""The window table of docs/twin.md from a held-y map: python docs/scripts/held_y_table.py MAP_DIR

MAP_DIR is the output of python -m acousim held-y.  One row per dimer and pressure, sorted by r = f_theta / f_y; per
amplitude A the hinge starts that lock in phase / anti-phase / fold (of 15), marked ** where both phase classes
hold >= 15 % of the starts, with the largest 2 f_y share of the runs locked at f_y in each class.
"""
import json
import sys
from pathlib import Path

import numpy as np

from acousim.atlas.held_y import cell_summary
from cubedimer.attractors import LOCKED_AT_FY

cells = [json.loads(p.read_text()) for p in sorted(Path(sys.argv[1], "cells").glob("*.json"))]
by_row = {}
for c in cells:
    by_row.setdefault((c["pressure_pa"], c["r"], c["dimer"]), []).append(c)
amps = sorted({c["amplitude_m"] for c in cells})
print("| p0, dimer | r = f_theta/f_y | " + " | ".join(f"A = {a * 1e6:.0f} um" for a in amps) + " |")
print("|---|---|" + "---|" * len(amps))
for (p0, r, dimer), row in sorted(by_row.items()):
    entries = []
    for a in amps:
        c = next((c for c in row if c["amplitude_m"] == a), None)
        if c is None:
            entries.append("")
            continue
        s = cell_summary(c)
        share = {k: max([x["share_2fy"] for x in c["runs"] if x["outcome"] == k and np.isfinite(x["share_2fy"])],
                        default=np.nan) for k in LOCKED_AT_FY[:2]}
        text = f"{s['in_phase']}/{s['anti_phase']}/{s['folded']}"
        if s["at_rest"]:
            text += f" (rest {s['at_rest']})"
        if s["ratio_locked"] or s["quadrature"] or s["independent"]:
            text += f" (other {s['ratio_locked'] + s['quadrature'] + s['independent']})"
        text = f"**{text}**" if s["two_phase_classes"] else text
        lines = "/".join("-" if not np.isfinite(v) else f"{100 * v:.1f}" for v in share.values())
        entries.append(f"{text}; {lines} %")
    print(f"| {p0 / 1e3:g} kPa, {dimer} | {r:.3f} | " + " | ".join(entries) + " |")
rows = [cell_summary(c) for c in cells]
print(f"\n{len(rows)} cells, {np.mean([r['seconds'] for r in rows]):.1f} s per cell on average "
      f"({min(r['seconds'] for r in rows):.0f}-{max(r['seconds'] for r in rows):.0f} s), "
      f"{sum(r['seconds'] for r in rows) / 60:.0f} min in all; largest Floquet |mu| over the locked orbits "
      f"{np.nanmax([r['max_floquet'] for r in rows]):.3f}, smallest {np.nanmin([r['max_floquet'] for r in rows]):.3f}")
