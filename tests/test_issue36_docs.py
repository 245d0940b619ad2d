"""Issue 36 part 4: what the documentation says against what lagcomp does.

The issue found docs/errors.md naming "state" as `sensitivity_control`'s default (it is "both") and saying `fit`
refuses taylor (it runs it), the friction module's docstring saying taylor refuses all friction, and the precompile
figure given for 11 driver modules where there were 12.  Each claim is read from the text and checked against the
behaviour, so that the two cannot part again unnoticed.
"""

import inspect
import re
from pathlib import Path

import numpy as np
import pytest
import sympy as sp

import lagcomp as lc
from lagcomp.cli import library_drivers
from lagcomp.integrate.simulate import simulate
from lagcomp.model import friction

DOCS = Path(__file__).resolve().parent.parent / "docs"
NUMBERS = {"ten": 10, "eleven": 11, "twelve": 12, "thirteen": 13, "fourteen": 14, "fifteen": 15}


def _row(case: str) -> str:
    """docs/errors.md's row of `case`, whole."""
    rows = [line for line in (DOCS / "errors.md").read_text(encoding="utf-8").splitlines()
            if line.startswith(f"| `{case}` |")]
    assert len(rows) == 1, case
    return rows[0]


def test_the_error_table_names_the_default_sensitivity_control_simulate_has():
    default = inspect.signature(simulate).parameters["sensitivity_control"].default
    named = re.findall(r'"(\w+)" \(the default', _row("sensitivity-control-unknown"))
    assert named == [default] == ["both"]


def test_fit_runs_the_taylor_method_the_error_table_offers(cache_dir):
    """The row of methods that cannot fit offers taylor among those that can; a fit with it recovers a spring's
    stiffness from its exact motion x = cos(√(k/m) t) (k = 4, m = 1) to the fit's accuracy."""
    assert "taylor" in _row("fit-without-sensitivities").split("|")[5]
    x, = lc.coordinates("x")
    k, m = sp.symbols("k m", positive=True)
    spring = lc.compile(lc.System([x], T=m * x.diff(lc.t) ** 2 / 2, V=k * x**2 / 2, name="docs36_spring",
                                  defaults={"k": 1.0, "m": 1.0}, q0=(1.0,), qd0=(0.0,)), cache_dir=cache_dir)
    times = np.linspace(0.0, 3.0, 31)
    fit = spring.fit(times, np.cos(2.0 * times)[:, None], {"k": 3.0}, method="taylor")
    assert fit.success and fit.estimates["k"] == pytest.approx(4.0, rel=1e-8)


def test_the_friction_docstring_cites_refusals_the_error_table_has():
    """It says which friction taylor refuses by naming error-table rows (pressed friction, an Abs normal force),
    not that it refuses all friction: each row it cites exists, and it no longer claims a blanket refusal."""
    cited = re.findall(r"``([a-z]+(?:-[a-z]+)+)``", friction.__doc__)       # (the table's case names: hyphenated)
    assert {"friction-with-taylor", "taylor-not-applicable"} <= set(cited)
    for case in cited:
        _row(case)
    assert not re.search(r"refuses (models with|all|every|any) friction", friction.__doc__, flags=re.IGNORECASE)


def test_the_docs_count_the_driver_modules_precompile_compiles():
    """`lagcomp precompile` compiles one module per `library_drivers` module; the prose that counts them says so."""
    modules = len({reference.partition(":")[0] for reference in library_drivers()})
    claims = re.findall(r"all (\w+) driver modules", (DOCS / "getting-started.md").read_text(encoding="utf-8"))
    claims += re.findall(r"for the (\w+) modules", (DOCS / "performance.md").read_text(encoding="utf-8"))
    assert claims and [NUMBERS[word] for word in claims] == [modules] * len(claims)
