"""The mass matrix of a 90-coordinate tree (30 links on ball joints, issue 39's 3D chain at scale): the on-demand kind
"dynamics" stores M's lower triangle flat (`lagcomp.ir.FlatMatrix`, symmetric) through the composite-rigid-body
algorithm's shared steps, compiles, and gives the M that the other recursions imply: ½ q̇ᵀ M q̇ is the kinetic energy
of the ``energy`` kernel (outward velocities, no composite inertia), and M q̈ = F with the articulated-body q̈.
tests/test_multibody_big_dynamics.py checks 30 and 45 coordinates against a many-digit reference; here the size alone.
"""

from __future__ import annotations

import numpy as np
import pytest
from random_systems import python_kernels

import lagcomp as lc
from lagcomp.codegen.tree_companion import lower_tree_kind
from lagcomp.examples.trees import spherical_chain
from lagcomp.ir import FlatMatrix


@pytest.mark.slow
def test_a_30_ball_chain_mass_matrix_is_stored_flat_and_consistent(cache_dir):
    tree = spherical_chain(30)
    (mass,) = [k for k in lower_tree_kind(tree, "dynamics").kernels if k.name == "mass_matrix"]
    assert mass.solve == FlatMatrix(90, symmetric=True, status=False)
    assert len(mass.stores) == 90 * 91 // 2 and all(target.startswith("_jac[") for target, _ in mass.stores)
    model = lc.compile(tree, cache_dir=cache_dir)
    kernels = python_kernels(model.source_path.read_text(encoding="utf-8"))   # (rhs and energy as plain Python)
    rng = np.random.default_rng(90)
    params = {name: (9.81 if name == "g" else float(rng.uniform(0.8, 1.4))) for name in model.parameters}
    p = model.parameter_vector(params)
    q, qd = rng.uniform(-0.6, 0.6, 90), rng.uniform(-1.0, 1.0, 90)
    M, F = model.mass_matrix(q, params=params), model.forcing(q, qd, params=params)
    assert np.array_equal(M, M.T) and np.all(np.diag(np.linalg.cholesky(M)) > 0)
    kinetic = kernels["energy"](0.0, np.concatenate([q, qd]), p) - kernels["energy"](0.0, np.concatenate([q, 0 * qd]), p)
    assert abs(0.5 * qd @ M @ qd - kinetic) <= 1e-12 * abs(kinetic)
    ydot = np.empty(180)
    assert kernels["rhs"](0.0, np.concatenate([q, qd]), p, ydot) == 0
    qdd = ydot[90:]
    assert np.max(np.abs(M @ qdd - F)) <= 1e-12 * (np.max(np.abs(M)) * np.max(np.abs(qdd)) + np.max(np.abs(F)))
