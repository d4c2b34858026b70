"""The repository carries every convention itself: no tracked file points to a document outside it, and every
repository document a file names exists."""
import re
import shutil
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

#: Documents that live outside a user's clone (spelt in pieces so that this file does not name them itself).
OUTSIDE = ("PHYSICS" + ".md", "FORMATS" + ".md", "../" + "shared")


def _tracked_text_files() -> list[Path]:
    if shutil.which("git") is None or not (ROOT / ".git").exists():
        pytest.skip("not a git checkout: the tracked files are unknown")
    names = subprocess.run(["git", "ls-files", "-z"], cwd=ROOT, capture_output=True, check=True).stdout.split(b"\0")
    out = []
    for n in names:
        p = ROOT / n.decode()
        if not n or not p.is_file() or p.suffix.lower() in (".png", ".vtu", ".npz", ".npy", ".jpg"):
            continue
        try:
            out.append((p, p.read_text(encoding="utf-8")))
        except UnicodeDecodeError:
            continue
    return out


def test_no_tracked_file_points_outside_the_repository():
    offenders = [f"{p.relative_to(ROOT)}:{k}: {line.strip()[:100]}"
                 for p, text in _tracked_text_files() for k, line in enumerate(text.splitlines(), 1)
                 if any(o in line for o in OUTSIDE)]
    assert not offenders, "\n".join(offenders)


def test_every_named_repository_document_exists():
    named = {m for _, text in _tracked_text_files() for m in re.findall(r"\bdocs/[\w/.-]+?\.md\b", text)}
    assert {"docs/conventions.md", "docs/formats.md"} <= named
    missing = sorted(n for n in named if not (ROOT / n).is_file())
    assert not missing, missing
