"""Self-contained HTML reports: sections with a reading paragraph, figures (embedded PNG) and tables.

:func:`write_report` writes ``report.html`` (images embedded as base64, no external resources, no
scripts), the figures as PNG under ``figures/`` and the numbers as ``numbers.json``, each atomically.
"""
from __future__ import annotations

import base64
import html
import math
import shutil
from dataclasses import dataclass, field
from pathlib import Path

from cubedimer.atomic import atomic_write_text

from cubedimer.atomic import write_json

__all__ = ["Figure", "Table", "Section", "write_report", "format_number"]


@dataclass(frozen=True)
class Figure:
    """A PNG file and its caption."""

    path: Path
    caption: str


@dataclass(frozen=True)
class Table:
    """A table: title, column headers and rows of cells (numbers are formatted with 4 significant digits), and what
    each column holds (``columns``: header -> definition, printed under the table)."""

    title: str
    header: list[str]
    rows: list[list]
    columns: dict[str, str] = field(default_factory=dict)


@dataclass(frozen=True)
class Section:
    """One report section: an id (anchor), a title, a one-paragraph reading, figures, tables and numbers."""

    id: str
    title: str
    reading: str
    figures: list[Figure] = field(default_factory=list)
    tables: list[Table] = field(default_factory=list)
    numbers: dict = field(default_factory=dict)


def format_number(v) -> str:
    """Cells: floats with 4 significant digits, None/NaN as an em dash, others as text."""
    if v is None:
        return "\u2014"
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, (int,)) and not isinstance(v, bool):
        return str(v)
    if isinstance(v, float):
        if not math.isfinite(v):
            return "\u2014"
        return f"{v:.4g}"
    return str(v)


_CSS = """
body{font-family:system-ui,-apple-system,'Segoe UI',sans-serif;max-width:1100px;margin:2em auto;padding:0 1em;color:#1d1d1f;line-height:1.45}
h1{font-size:1.7em;margin-bottom:.2em} h2{border-bottom:1px solid #ccc;padding-bottom:.2em;margin-top:2em}
.meta{color:#555;font-size:.9em} nav a{margin-right:1em}
figure{display:inline-block;margin:.6em .6em .6em 0;vertical-align:top;max-width:100%}
figure img{max-width:520px;width:100%;border:1px solid #e3e3e3}
figcaption{font-size:.85em;color:#444;max-width:520px}
table{border-collapse:collapse;margin:.8em 0;font-size:.85em} th,td{border:1px solid #ccc;padding:3px 7px;text-align:right}
th{background:#f2f2f2} td:first-child,td:nth-child(2),th:first-child{text-align:left}
.reading{background:#f7f9fc;border-left:3px solid #4a78c2;padding:.5em .8em}
.table-scroll{overflow-x:auto;max-width:100%} .columns{font-size:.8em;color:#444}
"""


def _img(path: Path) -> str:
    data = base64.b64encode(Path(path).read_bytes()).decode("ascii")
    return f'<img alt="{html.escape(Path(path).stem)}" src="data:image/png;base64,{data}">'


def write_report(sections: list[Section], out_dir: str | Path, title: str, subtitle: str = "",
                 extra_numbers: dict | None = None) -> Path:
    """Write report.html, figures/*.png and numbers.json into ``out_dir``; returns the HTML path."""
    out = Path(out_dir)
    fig_dir = out / "figures"
    fig_dir.mkdir(parents=True, exist_ok=True)
    parts = [
        "<!DOCTYPE html>",
        '<html lang="en"><head><meta charset="utf-8">',
        f"<title>{html.escape(title)}</title><style>{_CSS}</style></head><body>",
        f"<h1>{html.escape(title)}</h1>",
        f'<p class="meta">{html.escape(subtitle)}</p>' if subtitle else "",
        "<nav>" + "".join(f'<a href="#{s.id}">{html.escape(s.title)}</a>' for s in sections) + "</nav>",
    ]
    numbers: dict = dict(extra_numbers or {})
    for s in sections:
        parts.append(f'<section id="{s.id}"><h2>{html.escape(s.title)}</h2>')
        parts.append(f'<p class="reading">{html.escape(s.reading)}</p>')
        for f in s.figures:
            target = fig_dir / Path(f.path).name
            if Path(f.path).resolve() != target.resolve():
                shutil.copyfile(f.path, target)
            parts.append(f"<figure>{_img(target)}<figcaption>{html.escape(f.caption)}</figcaption></figure>")
        for t in s.tables:
            # a table wider than the page scrolls sideways inside its box instead of being cut off
            parts.append(f'<h3>{html.escape(t.title)}</h3><div class="table-scroll"><table><thead><tr>'
                         + "".join(f"<th>{html.escape(str(h))}</th>" for h in t.header) + "</tr></thead><tbody>")
            for row in t.rows:
                parts.append("<tr>" + "".join(f"<td>{html.escape(format_number(c))}</td>" for c in row) + "</tr>")
            parts.append("</tbody></table></div>")
            if t.columns:
                parts.append('<p class="columns">' + "; ".join(
                    f"<b>{html.escape(h)}</b>: {html.escape(t.columns[h])}" for h in t.header if h in t.columns)
                             + ".</p>")
        parts.append("</section>")
        numbers[s.id] = s.numbers
    parts.append("</body></html>")
    path = out / "report.html"
    atomic_write_text(path, "\n".join(p for p in parts if p))
    write_json(out / "numbers.json", numbers)
    return path
