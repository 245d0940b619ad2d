"""Kernels at the edge of UNROLL_MAX: the largest unrolled LDLᵀ, and the smallest looped one (LDLᵀ and
momenta from gathered arrays)."""

import numpy as np
import pytest

from lagcomp.codegen.lower import UNROLL_MAX


@pytest.mark.parametrize("n", [UNROLL_MAX, UNROLL_MAX + 1])
def test_kernels_agree_with_mass_matrix_and_forcing(compiled, n):
    model = compiled("n_link_pendulum", n=n)
    k = model.kernels
    rng = np.random.default_rng(8)
    for _ in range(3):
        y = rng.normal(size=2 * n)
        p = model.parameter_vector({f"{s}{i}": rng.uniform(0.5, 2.0) for s in "ml" for i in range(1, n + 1)})
        M, F, out, momenta = np.empty((n, n)), np.empty(n), np.empty(2 * n), np.empty(n)
        k.mass_matrix(0.0, y, p, M)
        k.forcing(0.0, y, p, F)
        assert k.rhs(0.0, y, p, out) == 0
        k.momenta(0.0, y, p, momenta)
        np.testing.assert_allclose(out[:n], y[n:])
        np.testing.assert_allclose(out[n:], np.linalg.solve(M, F), rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(momenta, M @ y[n:], rtol=1e-12, atol=1e-12)
        velocities = np.empty(n)
        assert k.velocities(0.0, np.concatenate([y[:n], momenta]), p, velocities) == 0
        np.testing.assert_allclose(velocities, y[n:], rtol=1e-9, atol=1e-12)
        assert k.energy_function(0.0, y, p) == k.energy(0.0, y, p)  # h = T + V: the same kernel


def test_looped_solve_for_large_systems_matches_numpy(compiled, rng):
    n = UNROLL_MAX + 1     # the smallest looped solve: the model above, compiled once
    model = compiled("n_link_pendulum", n=n)
    assert "return ldlt_solve_inline(mm, ff, out, " in model.source_path.read_text()
    for _ in range(5):
        q, qd = rng.uniform(-2, 2, n), rng.uniform(-2, 2, n)
        qdd = model.rhs(0.0, np.concatenate([q, qd]))[n:]
        expected = np.linalg.solve(model.mass_matrix(q), model.forcing(q, qd))
        np.testing.assert_allclose(qdd, expected, rtol=1e-10, atol=1e-10)
