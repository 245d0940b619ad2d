"""What the README and docs/errors.md claim, against what lagcomp does (issue 24, item 8)."""

from __future__ import annotations

import re
from pathlib import Path

import lagcomp as lc

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text(encoding="utf-8")


def test_every_lc_name_the_readme_uses_is_importable():
    names = set(re.findall(r"\blc\.([A-Za-z_]\w*)", README))
    assert "Sweep" in names
    assert sorted(name for name in names if not hasattr(lc, name)) == []


def test_sweep_load_npz_is_reachable_from_lagcomp():
    from lagcomp import Sweep

    assert Sweep.load_npz.__self__ is Sweep and "load_npz" in README


def test_readme_gives_the_measured_test_suite_time():
    assert "a few minutes" not in README
    assert re.search(r"about \d+ minutes on 2 cores: \d+ tests in \d+ min", README)  # a figure, measured


def test_errors_table_claims_no_completeness():
    text = (ROOT / "docs" / "errors.md").read_text(encoding="utf-8")
    assert not text.startswith("# What lagcomp says when something is wrong\n\nEvery way")
    assert "please report it" in text
