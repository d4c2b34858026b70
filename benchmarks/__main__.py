"""Run every benchmark module and write one markdown table file.

Each module ``benchmarks/bench_*.py`` exposes ``main() -> str`` returning a markdown section; every
such module is found and run (``acousim``, ``executor``, ``fitting``, ``twin``).
``--only NAME`` runs one (e.g. ``--only acousim``).
"""
from __future__ import annotations

import argparse
import importlib
import os
import pkgutil
import platform
import sys
import time
from pathlib import Path

from cubedimer.atomic import atomic_write_text


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m benchmarks", description=__doc__)
    p.add_argument("--out", default="benchmarks/results.md", help="markdown file to write")
    p.add_argument("--only", action="append", default=None, help="run only these benchmark modules")
    args = p.parse_args(argv)
    here = Path(__file__).parent
    names = sorted(m.name[len("bench_"):] for m in pkgutil.iter_modules([str(here)]) if m.name.startswith("bench_"))
    if args.only:
        names = [n for n in names if n in args.only]
    sections = [
        "# Benchmarks",
        "",
        f"Machine: {platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}; "
        f"written {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}.",
        "",
    ]
    for name in names:
        print(f"[bench] {name} ...", file=sys.stderr, flush=True)
        t0 = time.perf_counter()
        mod = importlib.import_module(f"benchmarks.bench_{name}")
        sections.append(mod.main())
        sections.append(f"\n_{name}: {time.perf_counter() - t0:.1f} s wall._\n")
    text = "\n".join(sections) + "\n"
    out = Path(args.out)
    atomic_write_text(out, text)  # readable by others as the umask allows
    print(text)
    print(f"[bench] written {out}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
