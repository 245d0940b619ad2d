"""Sphinx configuration of lagcomp's documentation (``docs/``).

Built with warnings as errors, the gallery executed and the pages' code run by the doctest
builder: ``python docs/build.py`` (what ``.ci/run`` runs).  Every compiled model of the build
goes to one cache directory, ``$LAGCOMP_CACHE_DIR`` if set, else ``docs/_build/lagcomp-cache``,
so a model a gallery script compiled is loaded by the next one that needs it.
"""

from __future__ import annotations

import os
import re
import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent
sys.path.insert(0, str(DOCS / "_ext"))
os.environ.setdefault("LAGCOMP_CACHE_DIR", str(DOCS / "_build" / "lagcomp-cache"))
os.environ.setdefault("MPLBACKEND", "Agg")

project = "lagcomp"
author = "the lagcomp developers"
copyright = "2026, the lagcomp developers"  # noqa: A001
from lagcomp import __version__ as release  # noqa: E402

version = release

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "numpydoc",
    "sphinx.ext.doctest",
    "sphinx.ext.mathjax",
    "sphinx_gallery.gen_gallery",
]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
exclude_patterns = ["_build", "_templates", "figures/*.py", "gallery/README.txt", "**/GALLERY_HEADER.rst", "auto_gallery/*.ipynb",
                    "auto_gallery/*.py", "auto_gallery/*.zip", "auto_gallery/*.md5", "auto_gallery/*.json"]
default_role = "py:obj"  # `name` in a docstring links to that object where Sphinx knows it

# MyST: $…$ math, ::: fences, headings as link targets; docs/errors.md and docs/benchmarks.md start their
# tables under ### headings, which is fine for a page.
myst_enable_extensions = ["dollarmath", "colon_fence", "deflist"]
myst_heading_anchors = 4
suppress_warnings = ["myst.header"]

# API reference: autosummary writes a page per public name (docs/api/generated, not committed).
autosummary_generate = True
autosummary_imported_members = True
autodoc_default_options = {"members": False}
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_validation_checks: set[str] = set()
numpydoc_xref_param_type = False

# The pages' {testcode} blocks run under `sphinx-build -b doctest`; a block that raises fails the build.
doctest_global_setup = """
import os
os.environ.setdefault("MPLBACKEND", "Agg")
"""
doctest_test_doctest_blocks = ""

html_theme = "pydata_sphinx_theme"
html_title = f"lagcomp {release}"
html_theme_options = {"navigation_with_keys": False, "show_toc_level": 2}
html_static_path: list[str] = []

sphinx_gallery_conf = {
    "examples_dirs": ["gallery"],
    "gallery_dirs": ["auto_gallery"],
    "filename_pattern": r"/",  # execute every script
    "abort_on_example_error": True,
    "only_warn_on_example_error": False,
    "image_scrapers": ("lagcomp_scraper.scrape",),
    "matplotlib_animations": False,  # lagcomp's animations are drawn by the scraper above
    "within_subsection_order": "FileNameSortKey",
    "download_all_examples": False,
    "remove_config_comments": True,
    "show_memory": False,
    "plot_gallery": "True",
}


# lagcomp's docstrings are plain text with physics in it: |x| is an absolute value or a norm, never a reST
# substitution, and (*shape, n) is a shape, never emphasis.  Escape the bars and those stars (outside ``literals`` and table rows) before numpydoc and docutils read them.
_LITERAL = re.compile(r"(``.*?``)")


def _escape_bars(line: str) -> str:
    if re.fullmatch(r"\s*[|+].*[|+]\s*", line):  # a grid table's row
        return line
    return "".join(part if part.startswith("``") else part.replace("|", r"\|").replace("(*", r"(\*")
                   for part in _LITERAL.split(line))


def _plain_bars(app, what, name, obj, options, lines):
    literal = False  # inside a literal block (after a "::" line, set by _formula_blocks): text as it stands
    for i, line in enumerate(lines):
        if line.strip() == "::":
            literal = True
        elif literal and line.strip() and not line.startswith(" "):
            literal = False
        if not literal:
            lines[i] = _escape_bars(line)


def _time_symbol(app, what, name, obj, options, lines):
    # `lagcomp.t` is a sympy Symbol, whose own docstring is sympy's class documentation.
    if name == "lagcomp.t":
        lines[:] = ["The time symbol, sympy.physics.mechanics' ``dynamicsymbols._t``: coordinates are functions of it",
                    "(`lagcomp.coordinates`), and imposed motions and inputs are expressions of it."]


def _formula_blocks(app, what, name, obj, options, lines):
    """The bundled examples' docstrings set their formulas off by indentation, aligned by hand: show each
    indented block as preformatted text (a literal block), up to the first numpydoc section."""
    if not name.startswith("lagcomp.examples."):
        return
    out, in_block = [], False
    for i, line in enumerate(lines):
        if line.strip() and i + 1 < len(lines) and set(lines[i + 1].strip()) == {"-"}:
            out += ([""] if in_block else []) + lines[i:]
            break
        indented = line.startswith(" ") and bool(line.strip())
        if indented and not in_block:
            out += ["", "::", ""]
            in_block = True
        elif in_block and line.strip() and not indented:
            out.append("")
            in_block = False
        out.append(line)
    lines[:] = out


def setup(app):
    app.connect("autodoc-process-docstring", _time_symbol, priority=50)
    app.connect("autodoc-process-docstring", _formula_blocks, priority=60)
    app.connect("autodoc-process-docstring", _plain_bars, priority=100)
