r"""The equations of motion of a kinematic tree in many-digit arithmetic, from its description alone: the accuracy
reference of a tree model.

A System's reference (`lagcomp.accuracy.reference`) differentiates its T and V symbolically.  A `lagcomp.Tree` has
no T and V, and writing them out symbolically swells beyond use (one ball joint's T, multiplied out: 13,000
operations).  `tree_reference` forms the same equations numerically instead, with none of the recursions' code
(no spatial algebra, articulated inertias or motion subspaces; `lagcomp.multibody.aba` ...), by d'Alembert's
principle over the tree's forward kinematics, all in mpmath at 4 × `digits` digits:

* each node's frame (R, o) in the base frame: R = R_parent · P · J(q), o = o_parent + R_parent · origin
  (+ R_parent P a q for a prismatic node), P the joint frame's placement, J the rotation by q about the unit axis
  a (Rodrigues' formula) of a revolute node, R(σ) = 1 + (8 [σ]×² + 4 (1 − σ·σ) [σ]×) / (1 + σ·σ)² of a ball
  joint's modified Rodrigues parameters σ (its three nodes share one frame, placed by the first);
* derivatives by central differences of step h = 10^−(digits + 5): along the path q(s) = q + s q̇ for the
  velocities and accelerations at q̈ = 0 (g = o + R c each centre of mass: ġ, g̈₀; ω = vee(Rᵀ Ṙ), α₀ = vee(Rᵀ R̈),
  body axes), and along each coordinate for the Jacobians J_g = ∂g/∂q, J_ω = vee(Rᵀ ∂R/∂q);
* M = Σ m J_gᵀ J_g + J_ωᵀ I J_ω,  F = Q − Σ m J_gᵀ (g̈₀ − gravity) + J_ωᵀ (I α₀ + ω × I ω);
* Q_i = torque − k (q − rest) − c q̇ of a revolute or prismatic node; of a ball joint's σ_j,
  (τ − c ω_rel) · vee(Jᵀ ∂J/∂σ_j), ω_rel = vee(Jᵀ J̇) its rotation's rate relative to the parent (body axes);
* T = Σ ½ m |ġ|² + ½ ωᵀ I ω,  V = −Σ m gravity · g + Σ ½ k (q − rest)²;
* a loop direction d: Φ = d · (P_first − P_second), Λ = ∂Φ/∂q, γ = −d²Φ/ds² along q + s q̇, and the system
  [[M, −Λᵀ], [Λ, 0]] (q̈, λ) = (F, γ − 2α Λ q̇ − β² Φ) of `lagcomp.accuracy.reference`.

The differences' truncation (h², 10^−2(digits+5)) and rounding (10^−4 digits / h²) are far below 10^−digits.
"""

from __future__ import annotations

from dataclasses import dataclass

import mpmath
import sympy as sp

from lagcomp.model.system import t
from lagcomp.multibody.tree import Tree

#: The working precision, in multiples of the reference's digits (second differences lose 2 (digits + 5)).
GUARD = 4


def _skew(v) -> mpmath.matrix:
    return mpmath.matrix([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])


def _vee(W) -> list:
    """The vector w of the skew part of W, (W − Wᵀ)/2 = [w]× (Rᵀ R̈ is not skew: Rᵀ R̈ = [α]× − Ṙᵀ Ṙ)."""
    return [(W[2, 1] - W[1, 2]) / 2, (W[0, 2] - W[2, 0]) / 2, (W[1, 0] - W[0, 1]) / 2]


def _rodrigues(axis, angle) -> mpmath.matrix:
    a = mpmath.matrix(axis)
    a = a / mpmath.norm(a)
    return mpmath.cos(angle) * mpmath.eye(3) + mpmath.sin(angle) * _skew(a) + (1 - mpmath.cos(angle)) * a * a.T


def _mrp(sigma) -> mpmath.matrix:
    s = sum(x**2 for x in sigma)
    S = _skew(sigma)
    return mpmath.eye(3) + (8 * S * S + 4 * (1 - s) * S) / (1 + s) ** 2


@dataclass(frozen=True)
class _Description:
    """The tree's numbers at one state: per node (mass, com, inertia, axis, origin, placement, stiffness, rest,
    damping, torque), gravity and the loops' (first point, second point, directions)."""

    nodes: list
    gravity: mpmath.matrix
    loops: list


def _lambdified(tree: Tree):
    """A function (t, q, q̇, p) → `_Description` values, every description expression lambdified to mpmath."""
    n = tree.n
    q = sp.symbols(f"_tq0:{n}", real=True)
    v = sp.symbols(f"_tv0:{n}", real=True)
    signals = {**{c.diff(t): vi for c, vi in zip(tree.coordinates, v)}, **dict(zip(tree.coordinates, q))}
    rows = []
    for node in tree.nodes:
        j = node.joint
        rows.append([node.mass, *node.com, *node.inertia, *j.axis, *j.origin, *(e for row in j.rotation for e in row),
                     j.stiffness, j.rest, j.damping, j.torque])
    loops = [[*c.first_point, *c.second_point, *(x for d in c.directions for x in d)] for c in tree.closures]
    exprs = [[sp.sympify(e).xreplace(signals) for e in row] for row in [*rows, list(tree.gravity), *loops]]
    return sp.lambdify((t, q, v, tree.parameters), exprs, modules="mpmath")


def _frames(tree: Tree, numbers: list, q) -> list:
    """(R, o) of every node at the coordinates `q` (module docstring), and each ball joint's own rotation J."""
    frames, own = [], {}
    for i, node in enumerate(tree.nodes):
        row = numbers[i]
        axis, origin = row[13:16], mpmath.matrix(row[16:19])
        placement = mpmath.matrix([row[19:22], row[22:25], row[25:28]])
        R0, o0 = (mpmath.eye(3), mpmath.matrix(3, 1)) if node.parent < 0 else frames[node.parent]
        kind = node.joint.kind
        if kind == "spherical" and list(node.joint.axis).index(1) > 0:    # parts 1, 2: part 0's frame
            frames.append((R0, o0))
            continue
        o = o0 + R0 * origin
        if kind == "spherical":
            joint = own[i] = _mrp(q[i:i + 3])
        elif kind == "revolute":
            joint = _rodrigues(axis, q[i])
        else:
            joint = mpmath.eye(3)
            o = o + R0 * placement * mpmath.matrix(axis) / mpmath.norm(mpmath.matrix(axis)) * q[i]
        frames.append((R0 * placement * joint, o))
    return frames, own


class TreeReference:
    """`lagcomp.accuracy.reference.ReferenceEquations.evaluate` for a tree: (q̈, λ, (T, V)) at one state."""

    def __init__(self, tree: Tree):
        self.tree, self.n, self.k = tree, tree.n, len(tree.constraint_names)
        self._numbers = _lambdified(tree)

    def evaluate(self, t_value, y, p, digits: int) -> tuple[list, list, tuple]:
        n, k = self.n, self.k
        with mpmath.workdps(GUARD * digits):
            h = mpmath.mpf(10) ** -(digits + 5)
            t0 = mpmath.mpf(float(t_value))
            q = [mpmath.mpf(float(x)) for x in y[:n]]
            v = [mpmath.mpf(float(x)) for x in y[n:]]
            params = [mpmath.mpf(float(x)) for x in p]
            alpha, beta = params[-2], params[-1]
            numbers = self._numbers(t0, q, v, params[:len(self.tree.parameters)])
            M, F, T, V, loops = self._dynamics(numbers, q, v, h)
            A = mpmath.matrix(n + k, n + k)
            right = mpmath.matrix(n + k, 1)
            for i in range(n):
                right[i] = F[i]
                for j in range(n):
                    A[i, j] = M[i][j]
            for c, (phi, row, gamma) in enumerate(loops):
                velocity = sum(row[j] * v[j] for j in range(n))
                right[n + c] = gamma - 2 * alpha * velocity - beta**2 * phi
                for j in range(n):
                    A[n + c, j], A[j, n + c] = row[j], -row[j]
            solution = mpmath.lu_solve(A, right)
        with mpmath.workdps(digits):
            return ([+solution[i] for i in range(n)], [+solution[n + c] for c in range(k)], (+T, +V))

    def mass_matrix_and_forcing(self, t_value, y, p, digits: int) -> tuple[list, list]:
        """M (n rows of n) and F of M q̈ = F at (t, y), to `digits` digits: the reference of the kernels
        ``mass_matrix`` and ``forcing`` (p as `evaluate` takes it: the tree's parameters first)."""
        n = self.n
        with mpmath.workdps(GUARD * digits):
            q = [mpmath.mpf(float(x)) for x in y[:n]]
            v = [mpmath.mpf(float(x)) for x in y[n:2 * n]]
            params = [mpmath.mpf(float(x)) for x in p[:len(self.tree.parameters)]]
            numbers = self._numbers(mpmath.mpf(float(t_value)), q, v, params)
            M, F, *_ = self._dynamics(numbers, q, v, mpmath.mpf(10) ** -(digits + 5))
        with mpmath.workdps(digits):
            return [[+x for x in row] for row in M], [+x for x in F]

    def _dynamics(self, numbers, q, v, h):
        """M, F, T, V and each loop direction's (Φ, Λ, γ) at (q, q̇ = v) (module docstring)."""
        tree, n = self.tree, self.n
        path = [self._state(numbers, [qi + s * vi for qi, vi in zip(q, v)]) for s in (-h, 0, h)]
        columns = [[self._state(numbers, [qi + (s if i == j else 0) for i, qi in enumerate(q)]) for s in (-h, h)]
                   for j in range(n)]
        gravity = mpmath.matrix(numbers[n])
        M = [[mpmath.mpf(0)] * n for _ in range(n)]
        F = self._forces(numbers, q, v, path, columns, h)
        T = V = mpmath.mpf(0)
        for b, node in enumerate(tree.nodes):
            row = numbers[b]
            mass, com, inertia = row[0], mpmath.matrix(row[1:4]), mpmath.matrix([row[4:7], row[7:10], row[10:13]])
            (R, g), (Rm, gm), (Rp, gp) = ((s[0][b][0], s[0][b][1] + s[0][b][0] * com) for s in
                                          (path[1], path[0], path[2]))
            gdot, gddot = (gp - gm) / (2 * h), (gp - 2 * g + gm) / h**2
            omega = mpmath.matrix(_vee(R.T * (Rp - Rm) / (2 * h)))
            accel = mpmath.matrix(_vee(R.T * (Rp - 2 * R + Rm) / h**2))
            Jg, Jw = [], []
            for j in range(n):
                (Rjm, ojm), (Rjp, ojp) = (c[0][b] for c in columns[j])
                Jg.append((ojp + Rjp * com - ojm - Rjm * com) / (2 * h))
                Jw.append(mpmath.matrix(_vee(R.T * (Rjp - Rjm) / (2 * h))))
            Iw = inertia * omega
            linear = mass * (gddot - gravity)
            angular = inertia * accel + mpmath.matrix(_cross(omega, Iw))
            for i in range(n):
                F[i] -= _dot(Jg[i], linear) + _dot(Jw[i], angular)
                for j in range(n):
                    M[i][j] += mass * _dot(Jg[i], Jg[j]) + _dot(Jw[i], inertia * Jw[j])
            T += mass * _dot(gdot, gdot) / 2 + _dot(omega, Iw) / 2
            V -= mass * _dot(gravity, g)
            stiffness, rest = row[28], row[29]
            V += stiffness * (q[b] - rest) ** 2 / 2
        loops = self._loops(numbers, path, columns, h)
        return M, F, T, V, loops

    def _state(self, numbers, q):
        return _frames(self.tree, numbers, q)

    def _forces(self, numbers, q, v, path, columns, h) -> list:
        """Q of the joints' torques, springs and dampers (module docstring)."""
        F = []
        for i, node in enumerate(self.tree.nodes):
            stiffness, rest, damping, torque = numbers[i][28:32]
            if node.joint.kind != "spherical":
                F.append(torque - stiffness * (q[i] - rest) - damping * v[i])
                continue
            part = list(node.joint.axis).index(1)
            first = i - part
            J = path[1][1][first]
            rate = mpmath.matrix(_vee(J.T * (path[2][1][first] - path[0][1][first]) / (2 * h)))
            moment = [numbers[first + a][31] - numbers[first + a][30] * rate[a] for a in range(3)]
            dJ = (columns[i][1][1][first] - columns[i][0][1][first]) / (2 * h)
            F.append(_dot(moment, _vee(J.T * dJ)))
        return F

    def _loops(self, numbers, path, columns, h) -> list:
        """(Φ, Λ, γ) of each loop direction."""
        tree, n = self.tree, self.n
        links = {node.link: b for b, node in enumerate(tree.nodes)}
        found, base = [], n + 1    # (the rows of `numbers`: the nodes', gravity, the loops')
        for c, closure in enumerate(tree.closures):
            row = numbers[base + c]
            first, second = mpmath.matrix(row[0:3]), mpmath.matrix(row[3:6])

            def gap(state, closure=closure, first=first, second=second):
                R1, o1 = state[0][links[closure.first]]
                P2 = second if closure.second is None else (state[0][links[closure.second]][1]
                                                            + state[0][links[closure.second]][0] * second)
                return o1 + R1 * first - P2

            gaps = [gap(s) for s in path]
            for d, direction in enumerate(closure.directions):
                axis = row[6 + 3 * d:9 + 3 * d]
                phi = _dot(axis, gaps[1])
                gamma = -_dot(axis, (gaps[2] - 2 * gaps[1] + gaps[0]) / h**2)
                jac = [_dot(axis, (gap(columns[j][1]) - gap(columns[j][0])) / (2 * h)) for j in range(n)]
                found.append((phi, jac, gamma))
        return found


def _dot(a, b):
    return sum((a[i] * b[i] for i in range(3)), mpmath.mpf(0))


def _cross(a, b) -> list:
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def tree_reference(tree: Tree) -> TreeReference:
    """The many-digit equations of motion of `tree` (module docstring)."""
    return TreeReference(tree)
