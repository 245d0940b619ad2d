r"""The forward kinematics of a tree: each node's frame, and its motion, in the base frame, bound in a `Program`.

One module for every consumer of where the links are: the ``geometry`` kernel and the link points of a state-space
model (frames only), `lagcomp.link_point` (a point as an expression, through a `Program` that binds nothing) and
the closed loops' constraint rows (`lagcomp.multibody.closure`: points, their velocities, accelerations and
Jacobians).  `WorldKinematics` forms each quantity the first time one asks for it, for the nodes on the asked
paths only, and binds each as an intermediate quantity (a node's rotation is its parent's times its placement,
never multiplied out further).

Node i (parent λ; the base: C = 1, o = 0, ω = v = α = a = 0) is placed in its parent's frame by X_i = (R_i, r_i)
(`lagcomp.multibody.kinematics.placement`: x_λ = R_i x_i, r_i its origin in λ's axes), so in the base frame

    C_i = C_λ R_i,    o_i = o_λ + ρ_i,    ρ_i = C_λ r_i,

C_i's column j being node i's axis j in base components (x_base = C_i x_i + o_i), and ŝ_i = C_i a_i its joint
axis.  With v the velocity of the origin o_i and α, a the angular and origin accelerations at q̈ = 0 (the terms
that do not multiply q̈: what a constraint's γ = −Λ̇ q̇ needs), "transport" τ_i = α_λ × ρ_i + ω_λ × (ω_λ × ρ_i):

* revolute: ω_i = ω_λ + ŝ_i q̇_i, v_i = v_λ + ω_λ × ρ_i, α_i = α_λ + (ω_λ × ŝ_i) q̇_i, a_i = a_λ + τ_i;
* prismatic: ω_i = ω_λ, v_i = v_λ + ω_λ × ρ_i + ŝ_i q̇_i, α_i = α_λ, a_i = a_λ + τ_i + 2 ω_λ × ŝ_i q̇_i;
* spherical (three nodes, one frame: part 0 turned by R(σ), parts 1 and 2 at identity; `lagcomp.multibody.mrp`):
  parts 0 and 1 carry the parent's motion to the joint's centre (ω_i = ω_λ, v_i = v_λ + ω_λ × ρ_i, α_i = α_λ,
  a_i = a_λ + τ_i), part 2 adds the joint's rotation with its body rate ω = J(σ) σ̇ in base axes, ω̂ = C ω:
  ω_i = ω_λ + ω̂, v_i = v_λ, α_i = α_λ + ω_λ × ω̂ + C J̇σ̇ (the derivative of C ω at σ̈ = 0; C ω × C ω = 0),
  a_i = a_λ.

A point p fixed in node L's frame (ρ = C_L p) is at P = o_L + ρ, moves with v_L + ω_L × ρ and accelerates (at q̈ = 0)
with a_L + α_L × ρ + ω_L × (ω_L × ρ).  Its Jacobian column for node j on its path, along the recursions' joint
rates (q̇_j; a spherical part's ω_k), is ŝ_j × (P − o_j) for a revolute or spherical node (ŝ_j = C_j e_k: a ball
joint turns its body about its body axes) and ŝ_j for a prismatic one; `lagcomp.multibody.charts` maps the
columns of a ball joint to its MRPs (Jᵀ).  A free joint is three prismatic nodes and a spherical joint; universal,
cylindrical and planar joints are revolute and prismatic nodes.
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from lagcomp.multibody.kinematics import placement, rate_product
from lagcomp.multibody.program import Program, add, cross, mat_vec

IDENTITY = [[sp.S.One if i == j else sp.S.Zero for j in range(3)] for i in range(3)]
ZERO = [sp.S.Zero] * 3


@dataclass(frozen=True)
class Frame:
    """A node's frame in base axes: rotation C (rows; columns the node's axes), origin o, the origin's offset ρ from
    the parent's origin, and the joint axis ŝ (module docstring)."""

    R: list
    o: list
    offset: list
    axis: list


@dataclass(frozen=True)
class Motion:
    """A node's angular velocity ω, its origin's velocity v, and the angular and origin accelerations α, a at
    q̈ = 0, in base axes (module docstring)."""

    w: list
    v: list
    alpha: list
    a: list


BASE_FRAME = Frame(IDENTITY, ZERO, ZERO, ZERO)
BASE_MOTION = Motion(ZERO, ZERO, ZERO, ZERO)


class WorldKinematics:
    """The `Frame` and `Motion` of the nodes of a tree (`lagcomp.multibody.kinematics.LocalNode`, parents first),
    each formed in `prog` the first time one asks for it (nodes off every asked path never are); node −1 is the
    base."""

    def __init__(self, prog: Program, nodes):
        self.prog, self.nodes = prog, nodes
        self._frames: dict[int, Frame] = {}
        self._motions: dict[int, Motion] = {}

    def frame(self, i: int) -> Frame:
        """Node `i`'s `Frame`: C_i = C_λ R_i, o_i = o_λ + C_λ r_i."""
        if i < 0:
            return BASE_FRAME
        if i not in self._frames:
            prog, node = self.prog, self.nodes[i]
            parent, X = self.frame(node.parent), placement(prog, node)
            columns = [prog.vector(mat_vec(parent.R, [X.R[0][j], X.R[1][j], X.R[2][j]])) for j in range(3)]
            R = [[columns[j][k] for j in range(3)] for k in range(3)]
            offset = prog.vector(mat_vec(parent.R, X.r))
            axis = prog.vector(mat_vec(R, node.axis))
            self._frames[i] = Frame(R, prog.vector(add(parent.o, offset)), offset, axis)
        return self._frames[i]

    def motion(self, i: int) -> Motion:
        """Node `i`'s `Motion` (module docstring)."""
        if i < 0:
            return BASE_MOTION
        if i not in self._motions:
            self._motions[i] = self._outward(i)
        return self._motions[i]

    def _outward(self, i: int) -> Motion:
        prog, node = self.prog, self.nodes[i]
        parent, frame = self.motion(node.parent), self.frame(i)
        r = frame.offset
        transport = add(cross(parent.alpha, r), cross(parent.w, cross(parent.w, r)))
        v, w, alpha, a = add(parent.v, cross(parent.w, r)), parent.w, parent.alpha, add(parent.a, transport)
        if node.kind == "spherical" and node.part == 2:   # (parts 0 and 1 carry the parent's motion: r = 0 here)
            omega, jdot = rate_product(prog, node)
            turn = prog.vector(mat_vec(frame.R, omega))
            w, alpha = add(w, turn), add(add(alpha, cross(parent.w, turn)), mat_vec(frame.R, jdot))
        elif node.kind == "revolute":
            rate = [x * node.qd for x in frame.axis]
            w, alpha = add(w, rate), add(alpha, cross(parent.w, rate))
        elif node.kind == "prismatic":
            rate = [x * node.qd for x in frame.axis]
            v, a = add(v, rate), add(a, [2 * x for x in cross(parent.w, rate)])
        return Motion(prog.vector(w), prog.vector(v), prog.vector(alpha), prog.vector(a))

    def path(self, i: int) -> list[int]:
        """Node `i` and its ancestors."""
        out = []
        while i >= 0:
            out.append(i)
            i = self.nodes[i].parent
        return out

    def position(self, i: int, p) -> list:
        """The base-frame position o_i + C_i p of the point `p` (3 expressions) fixed in node `i`'s frame."""
        frame = self.frame(i)
        return self.prog.vector(add(frame.o, self.prog.vector(mat_vec(frame.R, p))))

    def point(self, i: int, p) -> tuple[list, list, list, dict]:
        """Position, velocity, acceleration at q̈ = 0 and Jacobian columns {node: 3-vector} along the recursions'
        joint rates of the point `p` fixed in node `i`'s frame (the base's for i < 0)."""
        motion = self.motion(i)   # (before the frame: each node's frame and motion bound in turn, parents first)
        prog, frame = self.prog, self.frame(i)
        r = prog.vector(mat_vec(frame.R, p))
        P = prog.vector(add(frame.o, r))
        v = prog.vector(add(motion.v, cross(motion.w, r)))
        a = prog.vector(add(add(motion.a, cross(motion.alpha, r)), cross(motion.w, cross(motion.w, r))))
        columns = {}
        for j in self.path(i):
            J = self.frame(j)
            columns[j] = (J.axis if self.nodes[j].kind == "prismatic"
                          else prog.vector(cross(J.axis, [x - y for x, y in zip(P, J.o)])))
        return P, v, a, columns


def world_frames(prog: Program, nodes) -> list[tuple[list, list]]:
    """(C (rows), o) of each of `nodes` (parents first) in the base frame, bound in `prog` (module docstring)."""
    world = WorldKinematics(prog, nodes)
    return [(world.frame(i).R, world.frame(i).o) for i in range(len(nodes))]


def link_nodes(tree) -> dict[str, int]:
    """{link name: the index of its joint's last node} of `tree` (`lagcomp.multibody.Tree`): the node whose frame
    is the link's."""
    return {node.link: i for i, node in enumerate(tree.nodes)}
