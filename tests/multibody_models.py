"""Kinematic trees for tests/test_multibody.py, and the same systems built two other ways: as a lagcomp System of
lc.RigidBody with frames from lc.rotated (the Lagrangian path), and as a Pinocchio model.

Trees here place every joint frame without rotation (identity `rotation`) and turn about x, y or z, so that
`lc.rotated` can build the same frames; `random_tree` exercises rotated placements and unaligned axes against
Pinocchio only.
"""

from __future__ import annotations

import numpy as np
import sympy as sp
from sympy.physics.vector import ReferenceFrame

import lagcomp as lc


def planar_chain(n: int, name: str | None = None) -> lc.Tree:
    """n rigid links hinged about z, each hinge at the end of the previous link (length l_i along its x), centre
    of mass at (c_i, d_i, 0), inertia about it (J_i, J_i, J_i); gravity −g along y."""
    g = sp.Symbol("g", positive=True)
    links = []
    for i in range(n):
        m, c, d, J = sp.symbols(f"m{i} c{i} d{i} J{i}")
        origin = (0, 0, 0) if i == 0 else (sp.Symbol(f"l{i - 1}"), 0, 0)
        links.append(lc.Link(f"link{i}", lc.Revolute(f"th{i}", axis="z", origin=origin),
                             parent=None if i == 0 else f"link{i - 1}", mass=m, com=(c, d, 0), inertia=(J, J, J)))
    return lc.Tree(links, gravity=(0, -g, 0), name=name or f"planar_chain_{n}")


def universal_chain(n: int) -> lc.Tree:
    """n rigid links hanging from universal joints (x, then y), the next joint at (0, 0, −l_i) of link i, centre
    of mass at (0, 0, −c_i), principal moments (A_i, B_i, C_i); gravity −g along z."""
    g = sp.Symbol("g", positive=True)
    links = []
    for i in range(n):
        m, c, A, B, C = sp.symbols(f"m{i} c{i} A{i} B{i} C{i}")
        origin = (0, 0, 0) if i == 0 else (0, 0, -sp.Symbol(f"l{i - 1}"))
        links.append(lc.Link(f"link{i}", lc.Universal((f"a{i}", f"b{i}"), origin=origin),
                             parent=None if i == 0 else f"link{i - 1}", mass=m, com=(0, 0, -c), inertia=(A, B, C)))
    return lc.Tree(links, gravity=(0, 0, -g), name=f"universal_chain_{n}")


def cart_pole() -> lc.Tree:
    """A cart sliding along x (spring k to x = 0, damper b, force F sin(w t)) carrying a pendulum about z (damper
    e); gravity −g along y."""
    M, m, c, J, g, k, b, F, w, e = sp.symbols("M m c J g k b F w e")
    x, th = lc.coordinates("x th")
    cart = lc.Link("cart", lc.Prismatic(x, axis="x", stiffness=k, damping=b, torque=F * sp.sin(w * lc.t)), mass=M)
    pole = lc.Link("pole", lc.Revolute(th, axis="z", damping=e), parent="cart", mass=m, com=(0, -c, 0),
                   inertia=(J, J, J))
    return lc.Tree([cart, pole], gravity=(0, -g, 0), name="cart_pole_tree")


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


# -- the same systems in Pinocchio --------------------------------------------------------------------------------


def pinocchio_model(tree: lc.Tree, values: dict):
    """A pinocchio.Model of `tree` with the parameters `values` (by name), and the joints' force terms as a
    function tau(t, q, v) (Pinocchio's ABA takes τ as given)."""
    import pinocchio as pin

    def num(e):
        return float(sp.sympify(e).subs({s: values[s.name] for s in sp.sympify(e).free_symbols}))

    model = pin.Model()
    ids = []
    for i, node in enumerate(tree.nodes):
        j = node.joint
        axis = np.array([num(a) for a in j.axis])
        joint = _pinocchio_joint(pin, j.kind, axis)
        R = np.array([[num(e) for e in row] for row in j.rotation])
        placement = pin.SE3(R, np.array([num(e) for e in j.origin]))
        parent = 0 if node.parent < 0 else ids[node.parent]
        ids.append(model.addJoint(parent, joint, placement, f"joint{i}"))
        inertia = np.array([[num(node.inertia[a, b]) for b in range(3)] for a in range(3)])
        model.appendBodyToJoint(ids[-1], pin.Inertia(num(node.mass), np.array([num(c) for c in node.com]), inertia),
                                pin.SE3.Identity())
    model.gravity = pin.Motion(np.array([num(g) for g in tree.gravity]), np.zeros(3))
    return model


def _pinocchio_joint(pin, kind: str, axis):
    """Pinocchio's joint model: its axis-aligned kinds (JointModelRZ, ...) for x, y, z, as its own models of such
    chains use, else the unaligned ones."""
    for k, name in enumerate("XYZ"):
        if np.array_equal(axis, np.eye(3)[k]):
            return getattr(pin, f"JointModel{'R' if kind == 'revolute' else 'P'}{name}")()
    return pin.JointModelRevoluteUnaligned(axis) if kind == "revolute" else pin.JointModelPrismaticUnaligned(axis)


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
