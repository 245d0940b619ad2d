"""No kernel allocates on a call, on either side of the unroll limits (issue 38 item 4).

Above `UNROLL_MAX` the solve is a loop over M and f gathered into arrays, above `JACOBIAN_UNROLL_MAX` the
Jacobian's is; ``rhs_jacobian`` hands ``rhs_with_jacobian`` a vector for the f it drops.  Those arrays live in
the kernel's stack frame (`lagcomp.kernel_support.scratch`); a heap array made per call shows in numba's
runtime statistics, counted here around calls made from a compiled loop (a call from Python allocates for the
boxed arguments, whatever the kernel does).
"""

import numba
import numpy as np
import pytest
from numba.core.runtime import _nrt_python, rtsys

from lagcomp.codegen.emit import JACOBIAN_UNROLL_MAX
from lagcomp.codegen.lower import UNROLL_MAX

CALLS = 50


@pytest.fixture(scope="module")
def allocations():
    """`allocations(run)`: how many arrays numba's runtime allocated in `run(CALLS)` beyond those of `run(0)`
    (the boxed arguments of the call from Python): the kernel's own, CALLS times (its statistics on)."""
    enabled = _nrt_python.memsys_stats_enabled()
    _nrt_python.memsys_enable_stats()

    def counted(run, calls: int) -> int:
        before = rtsys.get_allocation_stats().alloc
        run(calls)
        return rtsys.get_allocation_stats().alloc - before

    def count(run) -> int:
        run(1)  # compiles
        return counted(run, CALLS) - counted(run, 0)

    yield count
    if not enabled:
        _nrt_python.memsys_disable_stats()


@numba.njit
def _repeat(kernel, t, y, p, out, calls):
    """`calls` calls of ``kernel(t, y, p, out)`` from compiled code (what it returns dropped)."""
    for _ in range(calls):
        kernel(t, y, p, out)


@numba.njit
def _repeat_scalar(kernel, t, y, p, calls):
    """`calls` calls of the scalar ``kernel(t, y, p)`` from compiled code."""
    total = 0.0
    for _ in range(calls):
        total += kernel(t, y, p)
    return total


@numba.njit
def _repeat_pair(kernel, t, y, p, first, second, calls):
    """`calls` calls of ``kernel(t, y, p, first, second)`` from compiled code."""
    status = 0
    for _ in range(calls):
        status |= kernel(t, y, p, first, second)
    return status


def _chain(compiled, n):
    model = compiled("n_link_pendulum", n=n)
    y = np.random.default_rng(n).uniform(-1.0, 1.0, 2 * n)
    return model, y, model.parameter_vector()


@pytest.mark.parametrize("n", [UNROLL_MAX, UNROLL_MAX + 1])
def test_solving_kernels_allocate_nothing(compiled, allocations, n):
    """rhs (M q̈ = F), momenta (M q̇) and velocities (M q̇ = p) at the largest unrolled and the smallest looped n."""
    model, y, p = _chain(compiled, n)
    k = model.kernels
    out, vector, matrix = np.empty(2 * n), np.empty(n), np.empty((n, n))
    x = np.concatenate([y[:n], np.ones(n)])
    counts = {
        "rhs": allocations(lambda calls: _repeat(k.rhs, 0.0, y, p, out, calls)),
        "momenta": allocations(lambda calls: _repeat(k.momenta, 0.0, y, p, vector, calls)),
        "velocities": allocations(lambda calls: _repeat(k.velocities, 0.0, x, p, vector, calls)),
        "mass_matrix": allocations(lambda calls: _repeat(k.mass_matrix, 0.0, y, p, matrix, calls)),
        "forcing": allocations(lambda calls: _repeat(k.forcing, 0.0, y, p, vector, calls)),
        "energy": allocations(lambda calls: _repeat_scalar(k.energy, 0.0, y, p, calls)),
    }
    assert counts == dict.fromkeys(counts, 0)
    assert ("ldlt_solve_inline(mm, ff" in model.source_path.read_text()) == (n > UNROLL_MAX)


@pytest.mark.parametrize("n", [JACOBIAN_UNROLL_MAX, JACOBIAN_UNROLL_MAX + 1])
def test_jacobian_kernels_allocate_nothing(compiled, allocations, n):
    """rhs_with_jacobian and rhs_jacobian (which drops f) at the largest unrolled and the smallest looped n."""
    model, y, p = _chain(compiled, n)
    k = model.kernels
    ydot, jacobian = np.empty(2 * n), np.empty((2 * n, 2 * n))
    counts = {
        "rhs_with_jacobian": allocations(lambda calls: _repeat_pair(k.rhs_with_jacobian, 0.0, y, p, ydot, jacobian, calls)),
        "rhs_jacobian": allocations(lambda calls: _repeat(k.rhs_jacobian, 0.0, y, p, jacobian, calls)),
    }
    assert counts == dict.fromkeys(counts, 0)
    expected = np.empty((2 * n, 2 * n))
    assert k.rhs_with_jacobian(0.0, y, p, ydot, expected) == 0
    assert k.rhs_jacobian(0.0, y, p, jacobian) == 0
    np.testing.assert_array_equal(jacobian, expected)   # the scratch f changes nothing
