"""The unrolled LDLᵀ of the emitted rhs: x = M⁻¹ f against a 40-digit solve, and the status it returns.

The system is a free particle in n dimensions with the constant mass matrix
M = L D Lᵀ, L unit lower triangular and D diagonal given by parameters l_ij
(i > j) and d_j, pushed by a constant force b (V = −b·q): rhs's accelerations
are M⁻¹ b, and the pivots of M are the d_j, chosen by the test.  The contract
(the kernel docstring): 0 and x when every pivot is positive, else j + 1 for
the first pivot j that is not, whatever the later ones.
"""

from __future__ import annotations

import mpmath
import numpy as np
import pytest
import sympy as sp
from hypothesis import given, settings
from hypothesis import strategies as st

import lagcomp as lc
from lagcomp.model import t

SIZES = (1, 2, 3, 4)


def free_particle(n: int) -> lc.System:
    """T = ½ q̇ᵀ L D Lᵀ q̇ = ½ Σ_k d_k (q̇_k + Σ_{i>k} l_ik q̇_i)², V = −b·q."""
    q = lc.coordinates(" ".join(f"q{i}" for i in range(n)) + ("," if n == 1 else ""))
    l = {(i, j): sp.Symbol(f"l{i}{j}") for i in range(n) for j in range(i)}
    d = [sp.Symbol(f"d{j}") for j in range(n)]
    b = [sp.Symbol(f"b{i}") for i in range(n)]
    T = sum(d[k] * (q[k].diff(t) + sum(l[(i, k)] * q[i].diff(t) for i in range(k + 1, n))) ** 2
            for k in range(n)) / 2
    V = -sum(b[i] * q[i] for i in range(n))
    defaults = {s.name: 0.0 for s in l.values()} | {s.name: 1.0 for s in d + b}
    return lc.System(list(q), T=T, V=V, name=f"free_particle_{n}", defaults=defaults)


@pytest.fixture(scope="module")
def models(tmp_path_factory):
    cache = tmp_path_factory.mktemp("unrolled-pivots")
    return {n: lc.compile(free_particle(n), cache_dir=cache) for n in SIZES}


def status_and_x(model, lower: list[float], pivots: list[float], b: list[float]):
    """rhs's status and accelerations for M = L D Lᵀ (L's strict lower triangle `lower` row by row, D `pivots`)."""
    n = len(b)
    names = [f"l{i}{j}" for i in range(n) for j in range(i)]
    values = dict(zip(names, lower)) | {f"d{j}": v for j, v in enumerate(pivots)} | {f"b{i}": v for i, v in enumerate(b)}
    out = np.full(2 * n, 7.0)
    status = model.kernels.rhs(0.0, np.zeros(2 * n), model.parameter_vector(values), out)
    return status, out[n:]


def exact_matrix(lower: list[float], pivots: list[float]) -> mpmath.matrix:
    """L D Lᵀ in the working precision of mpmath."""
    n = len(pivots)
    L = mpmath.eye(n)
    for (i, j), v in zip([(i, j) for i in range(n) for j in range(i)], lower):
        L[i, j] = v
    return L * mpmath.diag(pivots) * L.T


def factors(n: int, pivot):
    return st.tuples(st.lists(st.floats(-1.0, 1.0), min_size=n * (n - 1) // 2, max_size=n * (n - 1) // 2),
                     st.lists(pivot, min_size=n, max_size=n), st.lists(st.floats(-3.0, 3.0), min_size=n, max_size=n))


GOOD = st.floats(0.5, 2.0)


@settings(max_examples=40, deadline=None)
@given(data=st.data(), n=st.sampled_from(SIZES))
def test_positive_definite_mass_matrix_solves_to_the_40_digit_solution(models, data, n):
    lower, pivots, b = data.draw(factors(n, GOOD))
    status, x = status_and_x(models[n], lower, pivots, b)
    assert status == 0
    with mpmath.workdps(40):
        M = exact_matrix(lower, pivots)
        exact = np.array([float(v) for v in mpmath.lu_solve(M, mpmath.matrix(b))])
        condition = np.linalg.cond(np.array(M.tolist(), dtype=float))
    # M's entries rounded (relative ε each) and a backward-stable solve: |x − x*| ≤ c n ε κ(M) |x*| (normwise)
    bound = 8 * n * np.finfo(float).eps * condition * np.linalg.norm(exact)
    assert np.linalg.norm(x - exact) <= bound


@settings(max_examples=60, deadline=None)
@given(data=st.data(), n=st.sampled_from(SIZES))
def test_status_is_the_first_pivot_that_is_not_positive(models, data, n):
    lower, pivots, b = data.draw(factors(n, st.one_of(GOOD, st.just(0.0), st.floats(-2.0, -0.5))))
    bad = [j for j, d in enumerate(pivots) if d <= 0.0]
    status, _ = status_and_x(models[n], lower, pivots, b)
    assert status == (bad[0] + 1 if bad else 0)


@pytest.mark.parametrize("n", SIZES)
def test_a_nan_pivot_is_a_bad_pivot(models, n):
    """NaN fails every comparison: the first NaN pivot is reported, not a silent NaN in x."""
    model = models[n]
    for j in range(n):
        p = model.parameter_vector()
        p[model.parameters.index(f"d{j}")] = np.nan
        assert model.kernels.rhs(0.0, np.zeros(2 * n), p, np.empty(2 * n)) == j + 1
