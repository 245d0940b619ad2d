"""Kinematic trees for tests/test_multibody.py, and the same systems built two other ways: as a lagcomp System of
lc.RigidBody with frames from lc.rotated (the Lagrangian path), and as a Pinocchio model.

The chains and the cart-pole are `lagcomp.examples.trees`' (re-exported here), the Pinocchio models
`lagcomp.multibody.pinocchio_peer`'s; trees here place every joint frame without rotation (identity `rotation`)
and turn about x, y or z, so that `lc.rotated` can build the same frames; `random_tree` exercises rotated
placements and unaligned axes against Pinocchio only.
"""

from __future__ import annotations

import numpy as np
import sympy as sp
from sympy.physics.vector import ReferenceFrame

import lagcomp as lc
from lagcomp.examples.trees import cart_pole, planar_chain, universal_chain
from lagcomp.multibody.pinocchio_peer import pinocchio_model

__all__ = ["PAIRS", "cart_pole", "lagrangian_system", "pinocchio_model", "planar_chain", "random_tree",
           "universal_chain"]

#: The trees that tests/test_multibody.py and tests/test_multibody_jacobians.py compare with the same systems on
#: the Lagrangian path, by name: conftest's `tree_pair(name)` compiles each pair once per worker.
PAIRS = {
    "rigid_double_pendulum": lambda: planar_chain(2, "rigid_double_pendulum"),
    "planar_chain_4": lambda: planar_chain(4),
    "universal_chain_2": lambda: universal_chain(2),
    "cart_pole": cart_pole,
}


# -- the same systems on the Lagrangian path ----------------------------------------------------------------------


def _rodrigues(axis, angle) -> sp.Matrix:
    a = sp.Matrix(axis)
    K = sp.Matrix([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return sp.cos(angle) * sp.eye(3) + sp.sin(angle) * K + (1 - sp.cos(angle)) * a * a.T


def lagrangian_system(tree: lc.Tree) -> lc.System:
    """`tree` as a lc.System of lc.RigidBody: each link's frame from lc.rotated about its joint's axis, its
    centre of mass as a sympy Vector, V = −Σ m g·r_G + the springs, the dampers and torques as generalized forces
    (joint frames without rotation only)."""
    N = ReferenceFrame("N")
    frames, origins, bodies = [], [], []
    V, forces = sp.S.Zero, {}
    for i, node in enumerate(tree.nodes):
        j = node.joint
        assert sp.Matrix(j.rotation) == sp.eye(3), "lc.rotated builds frames of unrotated joints only"
        parent_frame = N if node.parent < 0 else frames[node.parent]
        parent_origin = 0 * N.x if node.parent < 0 else origins[node.parent]
        offset = sum((e * u for e, u in zip(j.origin, (parent_frame.x, parent_frame.y, parent_frame.z))), 0 * N.x)
        axis = j.axis[0] * parent_frame.x + j.axis[1] * parent_frame.y + j.axis[2] * parent_frame.z
        q = j.coordinate
        if j.kind == "revolute":
            frame = lc.rotated(parent_frame, (q, "xyz"[list(j.axis).index(1)]), name=f"F{i}")
            origin = parent_origin + offset
        else:
            frame, origin = parent_frame, parent_origin + offset + q * axis
        frames.append(frame)
        origins.append(origin)
        com = origin + node.com[0] * frame.x + node.com[1] * frame.y + node.com[2] * frame.z
        if node.mass != 0:
            bodies.append(lc.RigidBody(node.mass, com, node.inertia, frame, name=f"body{i}"))
            V -= node.mass * sum(g * r for g, r in zip(tree.gravity, com.to_matrix(N)))
        V += j.stiffness * (q - j.rest) ** 2 / 2
        forces[q] = j.torque - j.damping * q.diff(lc.t)
    return lc.System(list(tree.coordinates), V=V, forces=forces, bodies=bodies, frame=N, name=f"{tree.name}_lagrange")


def random_tree(seed: int) -> tuple[lc.Tree, dict]:
    """A numeric tree of 3 to 6 links with random topology, joint kinds, unaligned axes, rotated placements, mass
    properties and gravity (for Pinocchio: every link has mass and a positive definite inertia)."""
    rng = np.random.default_rng(seed)
    links = []
    for i in range(int(rng.integers(3, 7))):
        axis = tuple(rng.normal(size=3).round(3))
        R = _random_rotation(rng)
        kind = lc.Prismatic if rng.random() < 0.25 else lc.Revolute
        joint = kind(f"q{i}", axis=axis, origin=tuple(rng.normal(size=3).round(3)), rotation=R,
                     stiffness=float(rng.uniform(0, 2)), rest=float(rng.normal()), damping=float(rng.uniform(0, 1)))
        moments = rng.uniform(1.0, 1.5, size=3)   # (any three in [1, 1.5] satisfy I_a + I_b ≥ I_c)
        Q = _random_rotation(rng)
        Q = np.array(Q)
        inertia = Q @ np.diag(moments) @ Q.T
        links.append(lc.Link(f"l{i}", joint, parent=None if i == 0 else f"l{int(rng.integers(0, i))}",
                             mass=float(rng.uniform(0.5, 2)), com=tuple(rng.normal(size=3).round(3)),
                             inertia=((inertia + inertia.T) / 2).tolist()))
    return lc.Tree(links, gravity=tuple(rng.normal(size=3) * 5), name=f"random_tree_{seed}"), {}


def _random_rotation(rng) -> list:
    Q, R = np.linalg.qr(rng.normal(size=(3, 3)))
    Q = Q @ np.diag(np.sign(np.diag(R)))
    if np.linalg.det(Q) < 0:
        Q[:, 0] = -Q[:, 0]
    return Q.tolist()
