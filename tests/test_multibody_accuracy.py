"""The kernels' accuracy contract for tree models: `lc.kernel_accuracy` of a `lagcomp.Tree`, errors in ulps against
`lagcomp.accuracy.tree_reference` (d'Alembert's principle over the tree's own forward kinematics in 160 digits).

The reference is checked first against another that shares nothing with it: the Systems' reference (plain sympy
Lagrange equations of T and V, `lagcomp.accuracy.reference`) of the same trees written with lc.RigidBody
(`multibody_models.lagrangian_system`).  Then each tree's kernels are held to a few times the error measured
(`BOUNDS`); the module docstring of `lagcomp.accuracy` defines the errors.
"""

from __future__ import annotations

import mpmath
import multibody_models as mm
import numpy as np
import pytest
import sympy as sp

import lagcomp as lc
from lagcomp.accuracy import (
    kernel_accuracy,
    random_states,
    reference_equations,
    tree_reference,
)


def ball_and_elbow() -> lc.Tree:
    """A ball joint with a rotated, offset placement, a damper and a constant moment, then a revolute elbow about an
    unaligned axis with a spring; gravity along no axis."""
    m1, m2, k = sp.symbols("m1 m2 k", positive=True)
    tilt = [[0.0, -0.6, 0.8], [1.0, 0.0, 0.0], [0.0, 0.8, 0.6]]
    return lc.Tree([
        lc.Link("upper", lc.Spherical(("s1", "s2", "s3"), origin=(0.1, 0.2, 0.3), rotation=tilt, damping=0.25,
                                      torque=(0.4, -0.3, 0.2)), mass=m1, com=(0.2, -0.1, -0.5), inertia=(0.3, 0.4, 0.2)),
        lc.Link("lower", lc.Revolute("elbow", axis=(0.3, 0.4, 1.0), origin=(0.5, 0.1, -1.0), stiffness=k, rest=0.2),
                parent="upper", mass=m2, com=(0.2, 0, -0.3), inertia=(0.2, 0.25, 0.1)),
    ], gravity=(0.3, -0.2, -9.81), name="ball_and_elbow")


def floating_pair() -> lc.Tree:
    """A floating base (lc.Free, rotated placement) carrying a revolute link."""
    tilt = [[0.0, -0.6, 0.8], [1.0, 0.0, 0.0], [0.0, 0.8, 0.6]]
    return lc.Tree([
        lc.Link("base", lc.Free(("x", "y", "z", "b1", "b2", "b3"), origin=(0.1, 0.2, 0.3), rotation=tilt), mass=3.0,
                com=(0.1, -0.2, 0.05), inertia=(0.3, 0.4, 0.5)),
        lc.Link("arm", lc.Revolute("th", axis=(0.3, 0.4, 1.0), origin=(0.5, 0.1, 0.0)), parent="base", mass=1.0,
                com=(0.2, 0, -0.3), inertia=(0.2, 0.25, 0.1)),
    ], gravity=(0.3, -0.2, -9.81), name="floating_pair")


def held_chain() -> lc.Tree:
    """A planar 3-link chain whose tip is held on the vertical line x = X (a loop to the base, one direction)."""
    X, l2 = sp.symbols("X l2", positive=True)
    chain = mm.planar_chain(3)
    return lc.Tree(chain.links, gravity=chain.gravity, name="held_chain",
                   loops=[lc.Loop("tip", ("link2", (l2, 0, 0)), (None, (X, 0, 0)), directions="x")])


TREES = {
    "cart_pole": mm.cart_pole,
    "universal_chain_2": lambda: mm.universal_chain(2),
    "planar_chain_3": lambda: mm.planar_chain(3),
    "random_tree_1": lambda: mm.random_tree(1)[0],
    "ball_and_elbow": ball_and_elbow,
    "floating_pair": floating_pair,
    "held_chain": held_chain,
}

#: Normwise bounds (ulps) of rhs and energy at 20 random states, random parameters: about 2× the largest figure
#: measured over three draws of states and parameters (in the comment: rhs, energy).  The loop's reactions get
#: `REACTIONS`: λ solves the augmented system, worse conditioned near a stretched chain (measured 17-373).
BOUNDS = {
    "cart_pole": 36,            # 17.6, 2.0
    "universal_chain_2": 16,    # 6.7, 3.0
    "planar_chain_3": 20,       # 9.9, 3.0
    "random_tree_1": 300,       # 150.6, 73 (floats of every digit, springs, rotated placements)
    "ball_and_elbow": 80,       # 39.1, 5.0
    "floating_pair": 60,        # 29.6, 7.0
    "held_chain": 32,           # 15.0, 4.5
}
REACTIONS = 800


def _parameters(tree: lc.Tree, seed: int) -> dict:
    rng = np.random.default_rng(seed)
    return {name: float(rng.uniform(0.5, 2.0)) for name in tree.parameter_names if name not in tree.defaults}


@pytest.mark.parametrize("name", ["cart_pole", "universal_chain_2", "planar_chain_3"])
def test_the_tree_reference_is_the_lagrange_equations_of_the_same_bodies(name):
    """q̈ and T + V of `tree_reference` and of the Systems' reference (sympy's Lagrange equations of the same bodies
    written with lc.RigidBody) agree to 35 digits at random states: two derivations that share nothing."""
    tree = TREES[name]()
    system = mm.lagrangian_system(tree)
    params = _parameters(tree, 0)
    lagrange = reference_equations(system)
    ours = tree_reference(tree)
    p_tree = [params[s] for s in tree.parameter_names] + [0.0, 0.0]
    p_system = [params[s.name] for s in system.parameters] + [0.0, 0.0]
    rng = np.random.default_rng(1)
    for _ in range(4):
        y = np.concatenate([rng.uniform(-1, 1, tree.n), rng.standard_normal(tree.n)])
        a, _, (T, V) = ours.evaluate(0.7, y, p_tree, 40)
        b, _, (T2, V2) = lagrange.evaluate(0.7, y, p_system, 40)
        with mpmath.workdps(40):
            scale = max(abs(x) for x in b)
            assert max(abs(x - z) for x, z in zip(a, b)) <= mpmath.mpf(10) ** -35 * scale
            assert abs(T + V - T2 - V2) <= mpmath.mpf(10) ** -35 * (abs(T2) + abs(V2))


@pytest.mark.parametrize("name", sorted(TREES))
def test_tree_kernels_are_accurate(name, cache_dir):
    """rhs (q̈), the loop's reactions and the energy of each tree within `BOUNDS` ulps (normwise) of the reference."""
    tree = TREES[name]()
    model = lc.compile(tree, cache_dir=cache_dir)
    acc = kernel_accuracy(model, random_states(model, 20, seed=1), t=np.linspace(0, 1, 20),
                          params=_parameters(tree, 0), baumgarte=(0.5, 2.0) if tree.closures else (0.0, 0.0))
    assert acc.skipped == 0
    assert set(acc.errors) == ({"rhs", "energy", "reactions"} if tree.closures else {"rhs", "energy"})
    for kernel, error in acc.errors.items():
        assert error.max_normwise <= (REACTIONS if kernel == "reactions" else BOUNDS[name]), (kernel, error.max_normwise)
