"""The attractor atlas as a report section (``python -m validation report DATA --atlas ATLAS_DIR``).

``python -m acousim atlas`` writes ``atlas.json`` (settings, per-dimer outcome counts, the source paper's
observations) with a basin map per dimer and the phase histogram; :func:`atlas_section` turns them into a section
that shows where field drops of the simulated dimers settle beside the measured runs' classes.
"""
from __future__ import annotations

import json
from pathlib import Path

from ..context import ReportContext
from ..html import Figure, Section, Table

__all__ = ["section", "atlas_section", "AtlasSectionError"]


class AtlasSectionError(ValueError):
    """The folder holds no readable atlas; ``str(err)`` is one line naming it."""


def atlas_section(atlas_dir: str | Path) -> Section:
    """The section of the atlas in ``atlas_dir`` (its ``atlas.json`` and figures).

    Raises
    ------
    AtlasSectionError
        No readable ``atlas.json`` in ``atlas_dir``.
    """
    atlas_dir = Path(atlas_dir)
    try:
        data = json.loads((atlas_dir / "atlas.json").read_text(encoding="utf-8"))
        dimers, settings = data["dimers"], data["settings"]
    except (OSError, ValueError, KeyError, TypeError):
        raise AtlasSectionError(f"--atlas {atlas_dir}: no readable atlas.json (write one with python -m acousim "
                                f"atlas --out {atlas_dir})") from None
    outcomes = ("escaped", "folded", "locked-in-phase", "locked-anti-phase", "locked-quadrature", "locked-p:q",
                "independent", "theta-at-rest")
    rows = []
    for label, d in dimers.items():
        c, o = d.get("counts", {}), d.get("observations", {})
        rows.append([label] + [c.get(k, 0) for k in outcomes] + [o.get("with_2fy", 0), o.get("n_attractors", 0)])
    figures = [Figure(p, f"Basin map of {p.stem.removeprefix('basin_')}: where each drop (duration x hinge angle at "
                         "the drop) settles; dots mark long-lived states.")
               for p in sorted(atlas_dir.glob("basin_*.png"))]
    if (atlas_dir / "phase_histogram.png").is_file():
        figures.append(Figure(atlas_dir / "phase_histogram.png",
                              "The settled y-theta phase of the locked drops, per dimer."))
    t_off = settings.get("t_off", [])
    span = f"{min(t_off) * 1e3:g}-{max(t_off) * 1e3:g} ms" if t_off else "the chosen durations"
    reading = (f"Field drops of {len(dimers)} simulated dimer(s) (full-wave model, the air's computed damping, "
               f"p0 = {settings.get('pressure_amplitude_pa', float('nan')) / 1e3:g} kPa), over drop durations of {span} "
               f"and the hinge angle at the drop, classified like the measured runs once each run has settled. Set "
               f"the measured classes above against where the physics lets drops settle: a class the atlas never "
               f"reaches is a mechanism outside the simulation (docs/twin.md).")
    table = Table("Outcomes of the atlas's drops per dimer", ["dimer", *outcomes, "2 f_y >= 5 %", "long-lived classes"],
                  rows)
    return Section("atlas", "The attractor atlas of the simulation", reading, figures, [table],
                   {label: d.get("counts", {}) for label, d in dimers.items()})


def section(context: ReportContext) -> Section | None:
    """:func:`atlas_section` of the report's ``--atlas`` folder (None: none given)."""
    return None if context.atlas is None else atlas_section(context.atlas)
