"""q̈ of a long ball-jointed chain to the accuracy its mass matrix allows (issue 39's q̈ target on the bench's
hardest system, ``spherical_30`` of bench/bench_scale.py: 30 bodies, 90 DOF).

On that chain Pinocchio 4.1's ABA departs from the exact q̈ by 1.4e-11 to 3.9e-10 (normwise, at the bench's five
states), more than a backward-stable solve of M q̈ = F may (cond(M) ε: 3e-12 to 3e-11): its articulated inertias
drift from symmetric, the drift growing about 1.8× per ball joint towards the root (up to 2e-8 at the second joint
from rounding near the tip), and the update I − U D⁻¹ Uᵀ turns it into inertia the parent adds.  lagcomp's
articulated inertias are symmetric by construction (`lagcomp.multibody.spatial.Inertia` keeps lower triangles): this
test holds its q̈ to the bound, against `lagcomp.accuracy.tree_reference` (d'Alembert's principle in many digits,
none of the recursions' code).  docs/benchmarks.md ("Multibody at scale") has the measurements.
"""

from __future__ import annotations

import mpmath
import numpy as np
import pytest
from random_systems import python_kernels

import lagcomp as lc
from lagcomp.accuracy import tree_reference
from lagcomp.examples.trees import spherical_chain

#: ε of float64.
EPS = float(np.finfo(float).eps)
#: The normwise bound (max |Δq̈| / max |q̈|): issue 39's 1e-12; measured 1.9e-15 at this state (3.6e-15 at most
#: over the bench's five), Pinocchio's ABA 3.9e-10.
RELATIVE = 1e-12


@pytest.mark.slow
def test_a_30_body_ball_chain_within_its_conditioning(cache_dir):
    """At the bench's worst state for Pinocchio (|σ| up to 3.5, cond(M) 3.5e4): lagcomp's q̈ within 1e-12 and
    within cond(M) ε of the 25-digit q̈ (the rhs run as plain Python: numba need not compile it)."""
    tree = spherical_chain(30)
    model = lc.compile(tree, cache_dir=cache_dir)
    rhs = python_kernels(model.source_path.read_text(encoding="utf-8"))["rhs"]
    rng = np.random.default_rng(30)     # (bench_scale.build's parameters, then its second state)
    values = {name: (9.81 if name == "g" else float(rng.uniform(1.0, 1.5))) for name in tree.parameter_names}
    p, n = model.parameter_vector(values), model.n
    y = np.random.default_rng(1).uniform(-2.0, 2.0, 2 * n)
    M, F = tree_reference(tree).mass_matrix_and_forcing(0.0, y, p, 25)
    with mpmath.workdps(50):
        exact = np.array([float(x) for x in mpmath.lu_solve(mpmath.matrix(M), mpmath.matrix(F))])
    condition = np.linalg.cond(np.array([[float(x) for x in row] for row in M]))
    out = np.empty(2 * n)
    assert rhs(0.0, y, p, out) == 0
    error = np.max(np.abs(out[n:] - exact)) / np.max(np.abs(exact))
    assert condition > 1e4              # (the state is the ill-conditioned one it is meant to be)
    assert error <= min(RELATIVE, condition * EPS)
