"""Linear solvers for the generated kernels and the implicit drivers.

numba compiles each into the kernel or driver that calls it, at that
function's first compile, and caches it with it; except the solvers of a
constrained or Kane model's kernels (``kkt_solve``, ``kkt_solve_matrix``,
``gram_solve``, ``lu_solve_matrix``), which the kernels call by symbol
(`lagcomp.kernel_support.symbol_calls`, end of this module): numba optimises
each once, not again inside every kernel that calls it.

* ``ldlt_solve``: symmetric positive definite systems (the mass matrix of a
  large unconstrained system; small ones get the same factorization unrolled
  by the emitter); ``ldlt_solve_matrix``, the same for several right-hand
  sides at once (M⁻¹ applied to a matrix, in ``canonical_jacobian``).
* ``kkt_solve``: the augmented system of a constrained system,
  [M −Λᵀ; Λ 0] (q̈, λ) = (F, γ).  Where M is positive definite it uses the
  Schur complement: with M = L D Lᵀ, W = M⁻¹ Λᵀ and u = M⁻¹ F, the
  multipliers solve (Λ W) λ = γ − Λ u (Λ W is symmetric positive definite
  when the constraints are independent) and q̈ = u + W λ.  Where M is
  singular — a massless rolling hoop carrying a point mass — it falls back
  to ``lu_solve``, Gaussian elimination with partial pivoting of the whole
  matrix, which only needs the augmented matrix to be regular.
  ``kkt_solve_matrix``: the same for several right-hand sides at once, one
  factorization (the Jacobians of a constrained system's q̈ and λ).
* ``lu_factor`` and ``lu_substitute``: the same elimination split in two,
  for a matrix factored once and applied to many right-hand sides (the
  simplified Newton iteration of ``collocation_run``); ``lu_solve_matrix``,
  both for all columns of a matrix (M⁻¹ in a Kane model's ``rhs_jacobian``).
* ``gram_solve``: (A Aᵀ) μ = r for chosen rows and leading columns of a
  constraint matrix, the least-change step of the ``project`` kernels.

A pivot below ``PIVOT_TOLERANCE`` times the matrix's scale counts as zero:
the matrix is then singular to working precision (condition number ≳ 1e14),
and the solver returns j + 1 for the failing pivot j instead of dividing.

Each has ``fastmath=False``: without flags of its own a function takes those
of the caller that first compiles it, and numba caches that version for every
later caller (see `lagcomp.kernel_support.trig`).
"""

import math

import numpy as np
from numba import njit

from lagcomp.kernel_support.symbol_calls import called_by_symbol

#: Pivots below this times the matrix's scale count as zero (also the unrolled LDLᵀ of the kernels).
PIVOT_TOLERANCE = 1e-14


def _ldlt_solve(mm, ff, out, offset):
    """Solve mm x = ff (symmetric, lower triangle used) by LDLᵀ in place; x into out[offset:].

    On return the strict lower triangle of mm holds L, its diagonal D.
    Returns 0, or j + 1 when pivot j is not positive (mm singular or indefinite).
    """
    n = ff.shape[0]
    for j in range(n):
        d = mm[j, j]
        for k in range(j):
            d -= mm[j, k] * mm[j, k] * mm[k, k]
        if not d > PIVOT_TOLERANCE * abs(mm[j, j]):
            return j + 1
        mm[j, j] = d
        for i in range(j + 1, n):
            s = mm[i, j]
            for k in range(j):
                s -= mm[i, k] * mm[j, k] * mm[k, k]
            mm[i, j] = s / d
    for i in range(n):
        for k in range(i):
            ff[i] -= mm[i, k] * ff[k]
    for i in range(n - 1, -1, -1):
        x = ff[i] / mm[i, i]
        for k in range(i + 1, n):
            x -= mm[k, i] * out[offset + k]
        out[offset + i] = x
    return 0


#: `_ldlt_solve` compiled on its own (the impact solver, `lagcomp.kernel_support.impacts`, calls it).
ldlt_solve = njit(cache=True, error_model="numpy", fastmath=False)(_ldlt_solve)

#: `_ldlt_solve` inlined into the calling kernel at numba's IR level, for the kernels whose solve is a loop
#: (n > ``UNROLL_MAX``): there the shape of the kernel's stack arrays (`lagcomp.kernel_support.scratch`) is a
#: constant LLVM sees as the loops' trip counts.  The same operations, bitwise the same results; a 13-link
#: chain's rhs 632 against 787 ns (CPU time, one process, loaded machine).  Not cached on its own: its code is
#: compiled, and cached, as part of each kernel that calls it.
ldlt_solve_inline = njit(error_model="numpy", fastmath=False, inline="always")(_ldlt_solve)


@njit(cache=True, error_model="numpy", fastmath=False)
def ldlt_solve_matrix(mm, b):
    """Solve mm X = b for all m columns of b, shape (n, m), in place: X overwrites b.

    mm (n, n) symmetric, lower triangle used, is factored once by LDLᵀ as in
    ``ldlt_solve`` (L and D overwrite it).  Returns 0, or j + 1 when pivot j
    is not positive (mm singular or indefinite); b is then invalid.
    """
    n = mm.shape[0]
    for j in range(n):
        d = mm[j, j]
        for k in range(j):
            d -= mm[j, k] * mm[j, k] * mm[k, k]
        if not d > PIVOT_TOLERANCE * abs(mm[j, j]):
            return j + 1
        mm[j, j] = d
        for i in range(j + 1, n):
            s = mm[i, j]
            for k in range(j):
                s -= mm[i, k] * mm[j, k] * mm[k, k]
            mm[i, j] = s / d
    for c in range(b.shape[1]):
        for i in range(n):
            for k in range(i):
                b[i, c] -= mm[i, k] * b[k, c]
        for i in range(n - 1, -1, -1):
            x = b[i, c] / mm[i, i]
            for k in range(i + 1, n):
                x -= mm[k, i] * b[k, c]
            b[i, c] = x
    return 0


@njit(cache=True, error_model="numpy", fastmath=False)
def lu_solve(a):
    """Solve the N×N system stored as a = [A | r], shape (N, N + 1), in place.

    Gaussian elimination with partial pivoting (LU of A applied to r); the
    solution ends in a[:, N].  Returns 0, or j + 1 when pivot j is below
    PIVOT_TOLERANCE × max|A| (A singular to working precision).
    """
    size = a.shape[0]
    scale = 0.0
    for i in range(size):
        for j in range(size):
            scale = max(scale, abs(a[i, j]))
    for j in range(size):
        pivot = j
        for i in range(j + 1, size):
            if abs(a[i, j]) > abs(a[pivot, j]):
                pivot = i
        if not abs(a[pivot, j]) > PIVOT_TOLERANCE * scale:
            return j + 1
        if pivot != j:
            for c in range(j, size + 1):
                a[j, c], a[pivot, c] = a[pivot, c], a[j, c]
        for i in range(j + 1, size):
            factor = a[i, j] / a[j, j]
            for c in range(j + 1, size + 1):
                a[i, c] -= factor * a[j, c]
    for i in range(size - 1, -1, -1):
        x = a[i, size]
        for c in range(i + 1, size):
            x -= a[i, c] * a[c, size]
        a[i, size] = x / a[i, i]
    return 0


@njit(cache=True, error_model="numpy", fastmath=False)
def lu_factor(a, pivots):
    """LU factorization with partial pivoting of the square a, in place: PA = LU.

    On return a holds U on and above the diagonal and the multipliers of L
    (unit diagonal) below it, and row j was swapped with row pivots[j] at
    step j.  Returns 0, or j + 1 when pivot j is below PIVOT_TOLERANCE ×
    max|a| (a singular to working precision).
    """
    size = a.shape[0]
    scale = 0.0
    for i in range(size):
        for j in range(size):
            scale = max(scale, abs(a[i, j]))
    for j in range(size):
        pivot = j
        for i in range(j + 1, size):
            if abs(a[i, j]) > abs(a[pivot, j]):
                pivot = i
        pivots[j] = pivot
        if not abs(a[pivot, j]) > PIVOT_TOLERANCE * scale:
            return j + 1
        if pivot != j:
            for c in range(size):
                a[j, c], a[pivot, c] = a[pivot, c], a[j, c]
        for i in range(j + 1, size):
            a[i, j] /= a[j, j]
            for c in range(j + 1, size):
                a[i, c] -= a[i, j] * a[j, c]
    return 0


@njit(cache=True, error_model="numpy", fastmath=False)
def lu_substitute(a, pivots, r):
    """Solve A x = r in place (x overwrites r), with a and pivots from ``lu_factor`` of A."""
    size = a.shape[0]
    for j in range(size):
        r[j], r[pivots[j]] = r[pivots[j]], r[j]
    for i in range(size):
        for c in range(i):
            r[i] -= a[i, c] * r[c]
    for i in range(size - 1, -1, -1):
        x = r[i]
        for c in range(i + 1, size):
            x -= a[i, c] * r[c]
        r[i] = x / a[i, i]


@njit(cache=True, error_model="numpy", fastmath=False)
def _lu_solve_matrix(a, b):
    """Solve A X = b for all m columns of b, shape (n, m), in place: X overwrites b, LU overwrites a.

    ``lu_factor`` of the square a, then ``lu_substitute`` for each column: the pivots and the
    elimination of ``lu_solve``, so the same status for the same A.  Returns 0, or j + 1 when pivot
    j is below PIVOT_TOLERANCE × max|a| (a singular to working precision); b is then invalid.
    """
    pivots = np.empty(a.shape[0], dtype=np.int64)
    status = lu_factor(a, pivots)
    if status:
        return status
    for c in range(b.shape[1]):
        lu_substitute(a, pivots, b[:, c])
    return 0


@njit(cache=True, error_model="numpy", fastmath=False)
def _kkt_solve(a, n):
    """Solve [M −Λᵀ; Λ 0] (q̈, λ) = (F, γ), stored as a = [A | r], shape (n + k, n + k + 1).

    The solution ends in a[:, n + k] (q̈ first, then λ).  Schur complement
    through LDLᵀ of M where M is positive definite, else LU of the whole
    matrix (see the module docstring).  Returns 0, or j + 1 for a zero pivot.
    """
    size = a.shape[0]
    k = size - n
    # Columns of [Λᵀ | F]: W = M⁻¹ Λᵀ in work[:, n:n+k], u = M⁻¹ F in work[:, n+k].
    work = np.empty((n, n + k + 1))
    for j in range(k + 1):
        for i in range(n):
            work[i, n + j] = a[i, n + j] if j == k else -a[i, n + j]
    for i in range(n):
        for j in range(i + 1):
            work[i, j] = a[i, j]
    # LDLᵀ of M in work[:, :n]; not positive definite here: use LU instead.
    for j in range(n):
        d = work[j, j]
        for m in range(j):
            d -= work[j, m] * work[j, m] * work[m, m]
        if not d > PIVOT_TOLERANCE * abs(a[j, j]):
            return lu_solve(a)
        work[j, j] = d
        for i in range(j + 1, n):
            s = work[i, j]
            for m in range(j):
                s -= work[i, m] * work[j, m] * work[m, m]
            work[i, j] = s / d
    for c in range(n, n + k + 1):
        for i in range(n):
            for m in range(i):
                work[i, c] -= work[i, m] * work[m, c]
        for i in range(n - 1, -1, -1):
            x = work[i, c] / work[i, i]
            for m in range(i + 1, n):
                x -= work[m, i] * work[m, c]
            work[i, c] = x
    # Schur complement S = Λ W (k × k) and its right-hand side γ − Λ u.
    schur = np.empty((k, k))
    rhs_ = np.empty(k)
    lam = np.empty(k)
    for r in range(k):
        s = a[n + r, size]
        for i in range(n):
            s -= a[n + r, i] * work[i, n + k]
        rhs_[r] = s
        for c in range(r + 1):
            s = 0.0
            for i in range(n):
                s += a[n + r, i] * work[i, n + c]
            schur[r, c] = s
    if ldlt_solve(schur, rhs_, lam, 0):
        return lu_solve(a)
    for i in range(n):
        x = work[i, n + k]
        for r in range(k):
            x += work[i, n + r] * lam[r]
        a[i, size] = x
    for r in range(k):
        a[n + r, size] = lam[r]
    return 0


@njit(cache=True, error_model="numpy", fastmath=False)
def _kkt_solve_matrix(a, n, b):
    """Solve [M −Λᵀ; Λ 0] X = b for all m columns of b, shape (n + k, m), in place: X overwrites b.

    a, shape (n + k, n + k), holds the matrix as ``kkt_solve`` reads it (M's lower triangle, −Λᵀ, Λ).  The
    same paths as ``kkt_solve``, factored once for all columns: with M = L D Lᵀ, W = M⁻¹ Λᵀ and U = M⁻¹ b_top
    (n, m), the rows of λ solve (Λ W) Λ_x = b_bottom − Λ U by LDLᵀ and the top rows are U + W Λ_x; where M or
    Λ W is not positive definite, LU with partial pivoting of the whole matrix (``lu_solve_matrix``, which
    overwrites a).  Returns 0, or j + 1 for a zero pivot of the LU (a singular); b is then invalid.
    """
    size = a.shape[0]
    k, m = size - n, b.shape[1]
    # Columns of [Λᵀ | b_top]: W in work[:, n:n+k], U in work[:, n+k:].
    work = np.empty((n, n + k + m))
    for i in range(n):
        for j in range(i + 1):
            work[i, j] = a[i, j]
        for c in range(k):
            work[i, n + c] = -a[i, n + c]
        for c in range(m):
            work[i, n + k + c] = b[i, c]
    for j in range(n):
        d = work[j, j]
        for r in range(j):
            d -= work[j, r] * work[j, r] * work[r, r]
        if not d > PIVOT_TOLERANCE * abs(a[j, j]):
            return _lu_solve_matrix(a, b)
        work[j, j] = d
        for i in range(j + 1, n):
            s = work[i, j]
            for r in range(j):
                s -= work[i, r] * work[j, r] * work[r, r]
            work[i, j] = s / d
    for c in range(n, n + k + m):
        for i in range(n):
            for r in range(i):
                work[i, c] -= work[i, r] * work[r, c]
        for i in range(n - 1, -1, -1):
            x = work[i, c] / work[i, i]
            for r in range(i + 1, n):
                x -= work[r, i] * work[r, c]
            work[i, c] = x
    # Schur complement S = Λ W (k × k) and its right-hand sides b_bottom − Λ U (k × m).
    schur = np.empty((k, k))
    lam = np.empty((k, m))
    for r in range(k):
        for c in range(m):
            s = b[n + r, c]
            for i in range(n):
                s -= a[n + r, i] * work[i, n + k + c]
            lam[r, c] = s
        for c in range(r + 1):
            s = 0.0
            for i in range(n):
                s += a[n + r, i] * work[i, n + c]
            schur[r, c] = s
    if ldlt_solve_matrix(schur, lam):
        return _lu_solve_matrix(a, b)
    for c in range(m):
        for i in range(n):
            x = work[i, n + k + c]
            for r in range(k):
                x += work[i, n + r] * lam[r, c]
            b[i, c] = x
        for r in range(k):
            b[n + r, c] = lam[r, c]
    return 0


@njit(cache=True, error_model="numpy", fastmath=False)
def _gram_solve(a, rows, columns, rhs, mu):
    """mu = (A Aᵀ)⁻¹ rhs for A = a[rows, :columns]: the multipliers of the least Euclidean change.

    The ``project`` kernels move a state onto its constraints along Aᵀ mu, with A
    the constraint rows (Jacobian or velocity matrix) of `a`.  The Gram matrix
    A Aᵀ, shape (m, m) for m = len(rows), is solved by ``ldlt_solve``: returns 0,
    or j + 1 when pivot j is not positive (dependent constraints).
    """
    m = rows.shape[0]
    g = np.empty((m, m))
    for i in range(m):
        for j in range(i + 1):
            s = 0.0
            for c in range(columns):
                s += a[rows[i], c] * a[rows[j], c]
            g[i, j] = s
    return ldlt_solve(g, rhs, mu, 0)


#: What the generated kernels call: the solvers above, by symbol, optimised once
#: (`lagcomp.kernel_support.symbol_calls`).
kkt_solve = called_by_symbol(_kkt_solve)
kkt_solve_matrix = called_by_symbol(_kkt_solve_matrix)
gram_solve = called_by_symbol(_gram_solve)
lu_solve_matrix = called_by_symbol(_lu_solve_matrix)


@njit(cache=True, error_model="numpy", fastmath=False, nogil=True)
def _power_of_two_scale(largest):
    """The power of two 2^−e that brings ``largest`` (≥ 0) into [1/2, 1), exactly; 1 for 0 or a non-finite value
    (a zero row or column: the factorization then reports it)."""
    return math.ldexp(1.0, -math.frexp(largest)[1]) if largest > 0.0 and np.isfinite(largest) else 1.0


@njit(cache=True, error_model="numpy", fastmath=False, nogil=True)
def equilibrate(a, rows, columns):
    """Scale the square ``a`` in place to R a C, rows first then columns, each scale the power of two that brings
    the row's (then the column's) largest magnitude into [1/2, 1) (LAPACK's ``dgeequ``, rounded to powers of two:
    exact, and the factors' bits independent of the units).

    An iteration matrix has blocks in the units of its equations and its variables (positions, velocities,
    accelerations, forces): `lu_factor`'s pivot test, relative to max|a|, would call it singular or not depending on
    the units (radau on a millimetre four-bar linkage: ITERATION_MATRIX_SINGULAR at t = 0; Gauss-Legendre's
    simplified Newton on a stiff spring pendulum in units of 1000 m, 1000 kg, 1 ms: NOT_CONVERGED at t = 0).  R a C does not depend on them
    (a change of units is a diagonal D_r a D_c, which the scales absorb up to their rounding to powers of two).
    A zero row or column keeps the scale 1 (the factorization then reports it).
    """
    _scale_rows(a, rows)
    _scale_rows(a.T, columns)     # (the columns of a are the rows of its transpose, a view)


@njit(cache=True, error_model="numpy", fastmath=False, nogil=True)
def _scale_rows(a, scales):
    """Scale each row i of the square ``a`` in place by ``scales[i]``, the power of two that brings its largest
    magnitude into [1/2, 1) (`_power_of_two_scale`): one pass of `equilibrate`."""
    n = a.shape[0]
    for i in range(n):
        largest = 0.0
        for j in range(n):
            largest = max(largest, abs(a[i, j]))
        scales[i] = _power_of_two_scale(largest)
        for j in range(n):
            a[i, j] *= scales[i]
