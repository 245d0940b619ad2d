"""The unrolled LDLᵀ of the emitted rhs: x = M⁻¹ f against a 40-digit solve, and the status it returns.

The system is a free particle in n dimensions with the constant mass matrix
M = L D Lᵀ, L unit lower triangular and D diagonal given by parameters l_ij
(i > j) and d_j, pushed by a constant force b (V = −b·q): rhs's accelerations
are M⁻¹ b, and the pivots of M are the d_j, chosen by the test.  The contract
(the kernel docstring): 0 and x when every pivot is positive, else j + 1 for
the first pivot j that is not, whatever the later ones.  A second system has
entries of M that are zero at every state (and one of L that is not: fill-in),
whose terms the factorization leaves out; a diagonal M gives the dense form's bits.
"""

from __future__ import annotations

import inspect

import mpmath
import numpy as np
import pytest
import sympy as sp
from hypothesis import assume, given, settings
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
    for (row, column), v in zip([(i, j) for i in range(n) for j in range(i)], lower):
        L[row, column] = v
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


# -- a mass matrix with entries that are zero at every state: the factorization leaves their terms out ----------

#: M's pattern, lower triangle: m21 is zero but L21 is not (fill-in from m10 and m20); row 3 couples to q2 only.
SPARSE = ((1, 0), (2, 0), (3, 2))


def sparse_particle() -> lc.System:
    """T = ½ q̇ᵀ M q̇ with M_ii = 4 + a_i and M_ij = c_ij on `SPARSE` (zero elsewhere), V = −b·q; n = 4."""
    n = 4
    q = lc.coordinates("q0 q1 q2 q3")
    a = [sp.Symbol(f"a{i}") for i in range(n)]
    c = {ij: sp.Symbol(f"c{ij[0]}{ij[1]}") for ij in SPARSE}
    b = [sp.Symbol(f"b{i}") for i in range(n)]
    T = sum((4 + a[i]) * q[i].diff(t) ** 2 for i in range(n)) / 2 + sum(
        c[(i, j)] * q[i].diff(t) * q[j].diff(t) for i, j in SPARSE)
    V = -sum(b[i] * q[i] for i in range(n))
    defaults = {s.name: 0.0 for s in a + list(c.values())} | {s.name: 1.0 for s in b}
    return lc.System(list(q), T=T, V=V, name="sparse_particle", defaults=defaults)


@pytest.fixture(scope="module")
def sparse(tmp_path_factory):
    return lc.compile(sparse_particle(), cache_dir=tmp_path_factory.mktemp("unrolled-sparse"))


def sparse_case(model, a, c, b):
    """rhs's (status, q̈) and M as float64 for diagonal offsets `a`, couplings `c` (in `SPARSE` order), force `b`."""
    values = {f"a{i}": v for i, v in enumerate(a)} | {f"c{i}{j}": v for (i, j), v in zip(SPARSE, c)}
    values |= {f"b{i}": v for i, v in enumerate(b)}
    out = np.full(8, 7.0)
    status = model.kernels.rhs(0.0, np.zeros(8), model.parameter_vector(values), out)
    M = np.diag([4.0 + v for v in a])
    for (i, j), v in zip(SPARSE, c):
        M[i, j] = M[j, i] = v
    return status, out[4:], M


def sparse_draws(diagonal):
    return st.tuples(st.lists(diagonal, min_size=4, max_size=4), st.lists(st.floats(-1.0, 1.0), min_size=3, max_size=3),
                     st.lists(st.floats(-3.0, 3.0), min_size=4, max_size=4))


@settings(max_examples=40, deadline=None)
@given(draw=sparse_draws(st.floats(-1.5, 2.0)))
def test_sparse_mass_matrix_solves_to_the_40_digit_solution(sparse, draw):
    status, x, M = sparse_case(sparse, *draw)
    assert status == 0
    with mpmath.workdps(40):
        exact = np.array([float(v) for v in mpmath.lu_solve(mpmath.matrix(M.tolist()), mpmath.matrix(draw[2]))])
    bound = 8 * 4 * np.finfo(float).eps * np.linalg.cond(M) * np.linalg.norm(exact)
    assert np.linalg.norm(x - exact) <= bound


@settings(max_examples=60, deadline=None)
@given(draw=sparse_draws(st.floats(-6.0, 2.0)))
def test_sparse_status_is_the_first_pivot_that_is_not_positive(sparse, draw):
    status, _, M = sparse_case(sparse, *draw)
    with mpmath.workdps(40):  # pivot j = det M[:j+1, :j+1] / det M[:j, :j]
        minors = [mpmath.mpf(1)] + [mpmath.det(mpmath.matrix(M[:j + 1, :j + 1].tolist())) for j in range(4)]
        pivots = [float(minors[j + 1] / minors[j]) if minors[j] != 0 else float("nan") for j in range(4)]
    first = next((j for j, d in enumerate(pivots) if not d > 0.0), None)
    assume(all(abs(d) > 1e-9 * np.abs(M).max() for d in pivots[:(4 if first is None else first + 1)]))
    assert status == (0 if first is None else first + 1)


def test_a_diagonal_mass_matrix_is_solved_without_its_zeros(models, tmp_path):
    """M = diag(d0, d1): no L, x_i = f_i (1/d_i); the dense form's free particle with l10 = 0 gives the same bits."""
    q0, q1 = lc.coordinates("q0 q1")
    d0, d1, b0, b1 = sp.symbols("d0 d1 b0 b1")
    system = lc.System([q0, q1], T=(d0 * q0.diff(t) ** 2 + d1 * q1.diff(t) ** 2) / 2, V=-b0 * q0 - b1 * q1,
                       name="diagonal_particle", defaults={"d0": 1.0, "d1": 1.0, "b0": 1.0, "b1": 1.0})
    model = lc.compile(system, cache_dir=tmp_path)
    assert "_l1_0" not in inspect.getsource(model.kernels.rhs.py_func)
    rng = np.random.default_rng(3)
    for _ in range(200):
        d, b = rng.uniform(0.1, 10.0, 2), rng.normal(0.0, 3.0, 2)
        out = np.empty(4)
        p = model.parameter_vector({"d0": d[0], "d1": d[1], "b0": b[0], "b1": b[1]})
        assert model.kernels.rhs(0.0, np.zeros(4), p, out) == 0
        status, dense = status_and_x(models[2], [0.0], list(d), list(b))
        assert status == 0 and np.array_equal(dense, out[2:])
        assert np.array_equal(out[2:], b * (1.0 / d))
