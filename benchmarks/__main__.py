"""Run every benchmark module and write one markdown table file.

Each module ``benchmarks/bench_*.py`` exposes ``main() -> str`` returning a markdown section; every
such module is found and run, and its section is written under the marker ``<!-- bench:NAME -->``.
``--only NAME`` runs one (e.g. ``--only acousim``) and, when ``--out`` exists, replaces only that module's
section in it.
"""
from __future__ import annotations

import argparse
import importlib
import os
import pkgutil
import platform
import re
import sys
import time
from pathlib import Path

from cubedimer.atomic import atomic_write_text


#: Each module's section starts with this line, so that ``--only`` can replace it in an existing file.
MARKER = "<!-- bench:{} -->"


def _sections(text: str) -> dict[str, str]:
    """The marked sections of an existing results file, by module name."""
    parts = re.split(r"^<!-- bench:(\w+) -->$", text, flags=re.M)
    return {name: f"{MARKER.format(name)}{body.rstrip()}\n" for name, body in zip(parts[1::2], parts[2::2])}


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m benchmarks", description=__doc__)
    p.add_argument("--out", default="benchmarks/results.md", help="markdown file to write")
    p.add_argument("--only", action="append", default=None, help="run only these benchmark modules")
    args = p.parse_args(argv)
    here = Path(__file__).parent
    names = sorted(m.name[len("bench_"):] for m in pkgutil.iter_modules([str(here)]) if m.name.startswith("bench_"))
    if args.only:
        unknown = sorted(set(args.only) - set(names))
        if unknown:
            p.error(f"--only {', '.join(unknown)}: no such benchmark; choose from {', '.join(names)}")
        names = [n for n in names if n in args.only]
    header = [
        "# Benchmarks",
        "",
        f"Machine: {platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}; "
        f"written {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}"
        + (f" (sections {', '.join(names)}; the others kept from earlier runs)." if args.only else "."),
        "",
    ]
    out = Path(args.out)
    kept = _sections(out.read_text()) if args.only and out.exists() else {}
    for name in names:
        print(f"[bench] {name} ...", file=sys.stderr, flush=True)
        t0 = time.perf_counter()
        mod = importlib.import_module(f"benchmarks.bench_{name}")
        kept[name] = f"{MARKER.format(name)}\n{mod.main()}\n\n_{name}: {time.perf_counter() - t0:.1f} s wall._\n"
    sections = header + [kept[n] for n in sorted(kept)]
    text = "\n".join(sections) + "\n"
    atomic_write_text(out, text)  # readable by others as the umask allows
    print(text)
    print(f"[bench] written {out}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
