"""The documentation site covers the API and the examples (issue 37): every public name has a page in the
API reference, every bundled example a gallery script, and the README stays a page or two.

The reference pages (docs/api/*.rst) list names in ``autosummary`` tables under a ``currentmodule``;
Sphinx builds a page for each (``.ci/run``, warnings as errors), so a name listed here is a name documented.
"""

from __future__ import annotations

import importlib
import re
import types
from pathlib import Path

import pytest

import lagcomp
from lagcomp import examples

ROOT = Path(__file__).resolve().parents[1]
PUBLIC_SUBMODULES = ("lagcomp.analysis", "lagcomp.plots", "lagcomp.examples", "lagcomp.accuracy")


def _documented() -> set[str]:
    """Full names of the autosummary entries of docs/api/*.rst."""
    names = set()
    for page in sorted((ROOT / "docs" / "api").glob("*.rst")):
        module = None
        in_table = False
        for line in page.read_text(encoding="utf-8").splitlines():
            if match := re.match(r"\.\. currentmodule:: (\S+)", line):
                module = match.group(1)
            elif line.startswith(".. autosummary::"):
                in_table = True
            elif in_table and (match := re.fullmatch(r"   ([A-Za-z_][\w.]*)", line)):
                names.add(f"{module}.{match.group(1)}")
            elif in_table and line and not line.startswith("   "):
                in_table = False
    return names


def test_all_lists_every_public_name_of_lagcomp():
    public = {name for name in dir(lagcomp) if not name.startswith("_")
              and not isinstance(getattr(lagcomp, name), types.ModuleType)}
    assert sorted(set(lagcomp.__all__) ^ public) == []
    assert len(lagcomp.__all__) == len(set(lagcomp.__all__))


@pytest.mark.parametrize("module", ("lagcomp",) + PUBLIC_SUBMODULES)
def test_every_name_of_all_is_in_the_api_reference(module):
    documented = _documented()
    names = importlib.import_module(module).__all__
    assert names and sorted(name for name in names if f"{module}.{name}" not in documented) == []


def test_the_reference_names_only_what_exists():
    missing = []
    for full in _documented():
        module, _, name = full.rpartition(".")
        if not hasattr(importlib.import_module(module), name):
            missing.append(full)
    assert missing == []


def test_every_bundled_example_has_a_gallery_script():
    scripts = "".join(path.read_text(encoding="utf-8") for path in (ROOT / "docs" / "gallery").rglob("*.py"))
    run = set(re.findall(r'examples\.get\("(\w+)"', scripts))
    assert sorted(set(examples.EXAMPLES) - run) == []


def test_the_readme_is_short_and_points_to_the_docs():
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    assert len(text.splitlines()) <= 200
    for page in ("docs/getting-started.md", "docs/guide/systems.md", "docs/errors.md", "docs/benchmarks.md"):
        assert f"]({page})" in text and (ROOT / page).exists()


def test_ci_builds_the_docs_with_warnings_as_errors_after_the_tests():
    ci = (ROOT / ".ci" / "run").read_text(encoding="utf-8")
    pytest_at = ci.index("\npython -m pytest\n")
    assert pytest_at < ci.index("pip install --quiet '.[docs]'")
    builds = [line for line in ci.splitlines() if line.startswith("python -m sphinx ")]
    assert [re.search(r"-b (\w+) docs ", line).group(1) for line in builds] == ["html", "doctest"]
    assert all(" -W " in line and pytest_at < ci.index(line) for line in builds)
    assert all(line.endswith("|| { cat \"$docs_log\"; exit 1; }") for line in builds)  # a failed build fails CI


def test_public_subpackages_are_reachable_as_attributes_without_an_import_of_their_own():
    """``lc.analysis.linearize(...)`` as the docs write it, in a fresh process (no earlier ``import lagcomp.analysis``
    to hide a missing attribute)."""
    import subprocess
    import sys

    probe = ("import sys, lagcomp as lc; assert 'lagcomp.analysis' not in sys.modules; "
             "print(lc.analysis.linearize.__module__, lc.plots.__name__)")
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True)
    assert out.stdout.split() == ["lagcomp.analysis.oscillations", "lagcomp.plots"]
