"""The variational kernels' layouts that codegen shaped for numba's compile time, against the series of an ODE.

`lagcomp.codegen.taylor_variational` and `taylor_jacobian` compute the positions of a coefficient in S and T
once per pass (and per j), not at every access; in a loop over blocks of columns the block's offset ``_b``
enters them and X's rows, and a padding column has no row.  Oracle: the Duffing oscillator ẍ = −k x − c x³
(products and squares in its Taylor program: the writers' loops over j), whose j-th derivative at t = 0 sympy
writes as Dʲx (D g = v ∂g/∂x + (−k x − c x³) ∂g/∂v), differentiates with respect to x₀, v₀, k and c and
evaluates to 40 digits: the normalized Taylor coefficients of every row of y = (x, S) at t = 0.  Both writers,
in one pass and in a loop over blocks of 3 columns (4 columns: one padding column).
"""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

import lagcomp as lc
from lagcomp.cache import Cache, load_module, source_key
from lagcomp.codegen import taylor_kernel_frame
from lagcomp.codegen.taylor_jacobian import jacobian_source
from lagcomp.codegen.taylor_variational import forward_source
from lagcomp.integrate.taylor_sensitivities import values_import

ORDER = 10
X0, V0, K, C = 0.7, -0.4, 2.1, 1.3


@pytest.fixture(scope="module")
def oscillator(cache_dir):
    (x,) = lc.coordinates("x")
    k, c = sp.symbols("k c", positive=True)
    system = lc.System([x], T=x.diff(lc.t) ** 2 / 2, V=k * x**2 / 2 + c * x**4 / 4, name="compile_cost_duffing",
                       parameters=(k, c), defaults={"k": K, "c": C}, q0=(X0,), qd0=(V0,))
    return lc.compile(system, cache_dir=cache_dir)


def _series() -> np.ndarray:
    """The coefficients of (x, ẋ) and of their partials by x₀, v₀, k, c: rows as the kernel's X, (10, ORDER + 1)."""
    x, v, k, c = sp.symbols("x v k c")
    derivatives = [x]
    for _ in range(ORDER + 1):
        g = derivatives[-1]
        derivatives.append(sp.expand(v * g.diff(x) + (-k * x - c * x**3) * g.diff(v)))
    # x's coefficient j is D^j x / j!, ẋ's D^(j+1) x / j!; x₀, v₀ are x, v at t = 0
    state = [[derivatives[j + i] / sp.factorial(j) for j in range(ORDER + 1)] for i in (0, 1)]
    rows = [*state, *([u.diff(w) for u in row] for w in (x, v, k, c) for row in state)]
    values = {x: X0, v: V0, k: K, c: C}
    return np.array([[float(u.evalf(40, subs=values)) for u in row] for row in rows])


def _coefficients(model, source_of, program=None) -> np.ndarray:
    """X of `source_of`'s kernel (4 columns: x₀, v₀, then the parameters k and c) at the series' start, for
    `program` (the model's by default)."""
    program = model._taylor_program if program is None else program
    source = (model.source_path.read_text(encoding="utf-8") + f"from {values_import(model)} import taylor_coefficients\n"
              + source_of(program, 4, (0, 1), 1.0))
    entry = Cache(str(model.source_path.parent.parent)).store(f"variational-{source_key(source)}", source,
                                                              model.name, {})
    module = load_module(entry)
    y = np.array([X0, V0, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0])
    X = np.full((10, ORDER + 1), np.nan)
    W = np.full((module.VARIATIONAL_WORK, ORDER + 1), np.nan)
    assert module.taylor_variational_coefficients(0.0, y, np.array([K, C]), X, W) == 0
    return X


@pytest.mark.parametrize("looped", [False, True])
@pytest.mark.parametrize("source_of", [forward_source, jacobian_source])
def test_variational_coefficients_match_the_series_of_the_ode(oscillator, monkeypatch, source_of, looped):
    assert oscillator.parameters == ("k", "c")
    if looped:      # blocks of 3: columns 0-2, then 3 and a padding column
        monkeypatch.setattr(taylor_kernel_frame, "UNROLLED_COLUMNS", 1)
        monkeypatch.setattr(taylor_kernel_frame, "BLOCK", 3)
    source = source_of(oscillator._taylor_program, 4, (0, 1), 1.0)
    assert ("for _b in range(0, 6, 3):" in source) == looped
    X, exact = _coefficients(oscillator, source_of), _series()
    # each row to a few ulps of its largest coefficient (the terms of a coefficient of the cubic cancel)
    scale = np.abs(exact).max(axis=1, keepdims=True)
    assert np.all(np.abs(X - exact) <= 1e-14 * scale), (np.abs(X - exact) / scale).max()


def _renamed(program: dict, old: str, new: str) -> dict:
    """`program` with its scalar `old` named `new` (the setup's entry and the operations' constants)."""
    setup = [{**entry, "name": new} if entry["name"] == old else entry for entry in program["setup"]]
    body = [{**op, "const": new} if op["const"] == old else op for op in program["body"]]
    assert setup != program["setup"] and body != program["body"]
    return {**program, "setup": setup, "body": body}


@pytest.mark.parametrize("source_of", [forward_source, jacobian_source])
def test_the_writers_variables_leave_the_programs_scalars_alone(oscillator, source_of):
    # the decomposition names its scalars _k0, _k1, ... (here 1/M₀₀ is _k6): named _k1, the kernel reads the
    # same scalar after the positions of the pass are set (a variable _k1 of the writer would overwrite it)
    program = _renamed(oscillator._taylor_program, "_k6", "_k1")
    X, exact = _coefficients(oscillator, source_of, program), _series()
    scale = np.abs(exact).max(axis=1, keepdims=True)
    assert np.all(np.abs(X - exact) <= 1e-14 * scale), (np.abs(X - exact) / scale).max()
