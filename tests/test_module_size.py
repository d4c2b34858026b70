"""No module of the suite exceeds 600 lines: a longer one holds more than one concept and is split along them."""
from __future__ import annotations

from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("cubedimer", "acousim", "fitting", "validation", "tracking", "benchmarks")
MAX_LINES = 600


@pytest.mark.parametrize("package", PACKAGES)
def test_no_module_exceeds_the_line_limit(package):
    long = {str(f.relative_to(ROOT)): n for f in sorted((ROOT / package).rglob("*.py"))
            if (n := len(f.read_text(encoding="utf-8").splitlines())) > MAX_LINES}
    assert not long, f"modules over {MAX_LINES} lines (split them along their concepts): {long}"
