"""Sphinx configuration of the documentation site: the markdown guides of docs/ (myst-parser), the API reference of
every package's public API (autosummary over each package's ``__all__``, numpydoc docstrings) and the example
gallery of examples/, executed at build time (sphinx-gallery).

Build it with ``make docs`` (everything, offline, warnings as errors) or ``make docs-quick`` (the gallery not
executed); the site is written to docs/_build/html/index.html.
"""
from __future__ import annotations

import importlib
import os
import re
import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
sys.path.insert(0, str(ROOT))  # the checkout's packages, also when the environment holds another install

os.environ.setdefault("MPLBACKEND", "Agg")

import cubedimer  # noqa: E402

project = "cubedimer"
author = "the cubedimer developers"
copyright = "2026, the cubedimer developers"
release = cubedimer.__version__
version = release

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "numpydoc",
    "sphinx_gallery.gen_gallery",
]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
templates_path = ["_templates"]
exclude_patterns = ["_build", "scripts", "auto_examples/*.ipynb", "auto_examples/*.py", "**.zip",
                    "auto_examples/*.md5", "auto_examples/*.json"]

# Docstrings write absolute values and norms as |a|, |theta| or |fitted - simulated|, which reStructuredText would
# read as substitutions: every bar in a docstring stands for itself (escaped before numpydoc and autodoc parse it),
# except on the lines of a grid table.
_BAR = re.compile(r"(?<!\\)\|")
_LITERAL = re.compile(r"``.*?``|`[^`]*`")  # inline literals and roles keep their bars


def _escape_bars(text: str) -> str:
    out, last = [], 0
    for m in _LITERAL.finditer(text):
        out += [_BAR.sub(r"\\|", text[last:m.start()]), m.group(0)]
        last = m.end()
    return "".join(out + [_BAR.sub(r"\\|", text[last:])])


def _literal_bars(app, what, name, obj, options, lines):
    grid = any(line.lstrip().startswith(("+-", "+=")) for line in lines)
    for i, line in enumerate(lines):
        if not (grid and line.lstrip().startswith(("+", "|"))):
            lines[i] = _escape_bars(line)


def setup(app):
    app.connect("autodoc-process-docstring", _literal_bars, priority=100)  # before numpydoc's (500)


# --- markdown (the guides in docs/ as they are)
myst_enable_extensions = ["colon_fence"]
myst_heading_anchors = 4

# --- API reference: one page per public name of each package's __init__ (its __all__), documented under the
# public name (fitting.FitConfig), not the module that defines it, so that internal moves do not change it.
API_PACKAGES = ("cubedimer", "acousim", "acousim.twin", "fitting", "tracking", "validation")
autosummary_generate = True
autosummary_imported_members = True
autodoc_default_options = {"members": True, "show-inheritance": True}
autodoc_typehints = "none"  # numpydoc's Parameters section states types and units
autodoc_preserve_defaults = True  # signatures show defaults as written (FitConfig()), not their whole repr
autodoc_member_order = "bysource"
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_attributes_as_param_list = True
numpydoc_xref_param_type = False

# --- the gallery
sphinx_gallery_conf = {
    "examples_dirs": str(ROOT / "examples"),
    "gallery_dirs": "auto_examples",
    "filename_pattern": r"/plot_",
    "plot_gallery": "True",
    "within_subsection_order": "FileNameSortKey",
    "download_all_examples": False,
    "remove_config_comments": True,
    "capture_repr": (),
    "matplotlib_animations": False,
    "show_memory": False,
    "abort_on_example_error": True,
    "only_warn_on_example_error": False,
}

# --- pages
html_theme = "pydata_sphinx_theme"
html_title = f"cubedimer {release}"
html_theme_options = {
    "navigation_with_keys": False,
    "header_links_before_dropdown": 4,
    "show_toc_level": 2,
    "secondary_sidebar_items": ["page-toc"],
    "footer_start": ["copyright"],
    "footer_end": [],
}
html_static_path: list[str] = []
html_show_sourcelink = False


def _write_api_pages() -> None:
    """docs/api/<package>.rst: the package's summary and an autosummary table of its ``__all__``; a subpackage
    lists only the names its parent package does not already re-export."""
    out = DOCS / "api"
    out.mkdir(exist_ok=True)
    for name in API_PACKAGES:
        module = importlib.import_module(name)
        parent = name.rpartition(".")[0]
        shown = set(getattr(importlib.import_module(parent), "__all__", ())) if parent else set()
        names = [n for n in getattr(module, "__all__", ()) if not n.startswith("_") and n not in shown]
        title = f"``{name}``"
        note = [f"The names of ``{name}`` that ``{parent}`` re-exports are on :doc:`{parent}`.", ""] if parent else []
        lines = [title, "=" * len(title), "", f".. automodule:: {name}", "   :no-members:", "", *note,
                 f".. currentmodule:: {name}", "", ".. autosummary::", "   :toctree: generated", "",
                 *(f"   {n}" for n in names)]
        text = "\n".join(lines) + "\n"
        page = out / f"{name}.rst"
        if not page.exists() or page.read_text() != text:
            page.write_text(text)


_write_api_pages()  # before autosummary reads the pages
