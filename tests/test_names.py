"""A user's names cannot change the answer (DESIGN.md, "Two contracts of the emitted code: Names").

Coordinates and parameters may be named like anything the emitted modules use themselves
(``k``, the Taylor program's order loop; ``X``, ``W``, its arrays; ``range``, ``math``, ``np``, ...):
every method must still integrate the system the user wrote.  The references are closed forms
(a harmonic oscillator x(t) = A cos ωt, ω² = k/m) and lagcomp's DOP853 at tight tolerance on a
model whose names collide with nothing.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import sympy as sp

import lagcomp as lc
from lagcomp import examples
from lagcomp.cli import main


def _spring(stiffness: str, mass: str, length: str, coordinate: str) -> lc.System:
    """m x'' = −k (x − l) under the given names, x(0) = 1.2, ẋ(0) = 0: x(t) = l + (1.2 − l) cos(√(k/m) t)."""
    (x,) = lc.coordinates(coordinate)
    k, m, l = sp.symbols(f"{stiffness} {mass} {length}", positive=True, seq=True)
    return lc.System(coordinates=(x,), T=m * x.diff(lc.t) ** 2 / 2, V=k * (x - l) ** 2 / 2, parameters=(k, m, l),
                     name="spring", q0=(1.2,), qd0=(0.0,))


def test_a_spring_with_stiffness_k_integrated_by_taylor_follows_the_closed_form(cache_dir):
    # before the fix, the Taylor program's order loop `for k in range(order)` overwrote the stiffness:
    # x(3) = 2.388 instead of 1.2 cos(3·√(4/2.5)) = −0.0818 (issue 18, part 4)
    model = lc.compile(_spring("k", "m", "l", "x"), cache_dir=cache_dir)
    sol = model.simulate((0.0, 3.0), params={"k": 4.0, "m": 2.5, "l": 0.5}, method="taylor")
    assert sol.status == 0
    exact = 0.5 + 0.7 * math.cos(math.sqrt(4.0 / 2.5) * 3.0)
    assert abs(sol.q[-1, 0] - exact) < 1e-13  # measured 1.7e-16


def test_turn_indicator_by_taylor_agrees_with_dop853(compiled):
    # turn_indicator has a parameter `k` (the spring of the gimbal): taylor ended at θ = 1.1008
    # where dop853, rk4 and gauss2 agree on 0.16144
    model = compiled("turn_indicator")
    taylor = model.simulate((0.0, 10.0), method="taylor")
    reference = model.simulate((0.0, 10.0), rtol=1e-13, atol=1e-13)
    assert taylor.status == 0 and reference.status == 0
    assert abs(taylor.q[-1, 0] - reference.q[-1, 0]) < 1e-12  # measured 2.2e-16
    assert abs(reference.q[-1, 0] - 0.16143697) < 1e-7


def test_cli_run_turn_indicator_by_taylor(capsys, cache_dir, tmp_path):
    out_file = tmp_path / "taylor.npz"
    code = main(["--cache-dir", str(cache_dir), "run", "turn_indicator", "--method", "taylor", "--quiet",
                 "--out", str(out_file)])
    assert code == 0
    assert "theta=0.16143" in capsys.readouterr().out
    assert abs(np.load(out_file)["q"][-1, 0] - 0.16143697) < 1e-7
