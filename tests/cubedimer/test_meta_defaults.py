"""Every physical default of docs/conventions.md is read from cubedimer.meta: the library retypes none of the
distinctive ones (the drive's 45,650 Hz, the cubes' 2,160 kg/m^3 and 24.9 GPa, the air's 343 m/s and 1.204 kg/m^3)
as a number of its own (read from the source, so that a new module cannot; docstrings and comments may quote them)."""
from __future__ import annotations

import ast
from pathlib import Path

from cubedimer import meta

ROOT = Path(__file__).resolve().parents[2]
PACKAGES = ("cubedimer", "acousim", "fitting", "tracking", "validation")
#: The defaults too distinctive to be anything else when they stand in code as numbers.
DISTINCTIVE = ("frequency_hz", "particle_density_kg_m3", "bulk_modulus_pa", "sound_speed_m_s", "air_density_kg_m3")


def retyped_defaults(source: str) -> list[tuple[int, float]]:
    """(line, value) of every number in ``source``'s code equal to one of the distinctive defaults."""
    values = {float(meta.META_DEFAULTS[k]) for k in DISTINCTIVE}
    return [(n.lineno, n.value) for n in ast.walk(ast.parse(source))
            if isinstance(n, ast.Constant) and type(n.value) in (int, float) and float(n.value) in values]


def test_the_scan_finds_a_retyped_default_and_ignores_prose():
    src = '"""At 45650 Hz."""\nF = 45_650.0  # 45650\nRHO = 2.16e3\nX = 1.2\n'
    assert retyped_defaults(src) == [(2, 45_650.0), (3, 2160.0)]


def test_the_library_reads_its_defaults_from_meta():
    found = []
    for package in PACKAGES:
        for f in sorted((ROOT / package).rglob("*.py")):
            if f == ROOT / "cubedimer" / "meta.py":
                continue
            found += [f"{f.relative_to(ROOT)}:{line}: {value!r}" for line, value in retyped_defaults(f.read_text("utf-8"))]
    assert not found, "defaults retyped instead of read from cubedimer.meta:\n" + "\n".join(found)
    assert meta.DEFAULT_FREQUENCY_HZ == meta.META_DEFAULTS["frequency_hz"]
