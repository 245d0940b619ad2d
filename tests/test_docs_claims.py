"""What the README, the documentation's pages and docs/errors.md claim, against what lagcomp does (issue 24, item 8).

The README's API material moved to the pages under docs/ (issue 37); these checks follow it there.
"""

from __future__ import annotations

import re
from pathlib import Path

import lagcomp as lc

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text(encoding="utf-8")
PAGES = {path.relative_to(ROOT).as_posix(): path.read_text(encoding="utf-8")
         for path in sorted((ROOT / "docs").rglob("*.md")) if "_build" not in path.parts}
DEVELOPMENT = PAGES["docs/development.md"]
SWEEPS = PAGES["docs/guide/sweeps.md"]


def test_every_lc_name_the_readme_and_the_pages_use_is_importable():
    names = set(re.findall(r"\blc\.([A-Za-z_]\w*)", README + "".join(PAGES.values())))
    assert "Sweep" in names
    assert sorted(name for name in names if not hasattr(lc, name)) == []


def test_sweep_load_npz_is_reachable_from_lagcomp():
    from lagcomp import Sweep

    assert Sweep.load_npz.__self__ is Sweep and "load_npz" in SWEEPS


def test_the_docs_give_the_measured_test_suite_time():
    assert "a few minutes" not in README + DEVELOPMENT
    assert re.search(r"about \d+ minutes on 2 cores: \d+ tests in \d+ min", DEVELOPMENT)  # a figure, measured
    assert "docs/development.md" in README  # and the README says where


def test_errors_table_claims_no_completeness():
    text = (ROOT / "docs" / "errors.md").read_text(encoding="utf-8")
    assert not text.startswith("# What lagcomp says when something is wrong\n\nEvery way")
    assert "please report it" in text
