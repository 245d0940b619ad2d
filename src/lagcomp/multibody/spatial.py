r"""Spatial algebra over symbolic entries, written to exploit structure (Featherstone's 6D vectors as 3D parts).

Conventions (Featherstone, *Rigid Body Dynamics Algorithms*, 2008, ch. 2, with the angular part first):

* a motion vector (velocity, acceleration) is m = (ω, v): angular part, then the linear velocity of the point at
  the frame's origin; a force vector is f = (n, f): moment about the frame's origin, then the force;
* body i's frame is placed in its parent's by a `Placement` (R, r): R (3×3) maps components along i's axes to
  components along the parent's (x_parent = R x_i), r is i's origin in the parent's axes.  Motion vectors go from
  the parent to i by ``to_child`` (ω_i = Rᵀω, v_i = Rᵀ(v + ω × r)), forces from i to the parent by ``to_parent``
  (f = R f_i, n = R n_i + r × R f_i): the transpose of the first, so power is frame-invariant;
* a spatial inertia is the symmetric 6×6 [[A, B], [Bᵀ, C]] acting as f = (A ω + B v, Bᵀω + C v); a rigid body
  of mass m, first moment h = m c (c its centre of mass) and rotational inertia I_o about the frame's origin has
  A = I_o, B = h×, C = m 1 (`rigid_inertia`).

Nothing here forms a 6×6 product of unknown entries: transforms apply the 3×3 rotation and the cross product with
r; the congruence Xᵀ I X of an inertia (`Inertia.to_parent`) rotates its three blocks and shifts them by r×, with
the symmetry of A and C kept (lower triangles only), C kept a scalar while it is one (a composite rigid body).  Every
entry is bound through a `lagcomp.multibody.program.Program`, so zeros and ones of a joint's axis fold away.
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from lagcomp.multibody.program import Program, add, cross, dot, mat_t_vec, mat_vec

ZERO3 = [sp.S.Zero] * 3


@dataclass(frozen=True)
class Placement:
    """Frame i in its parent's: rotation R (rows, x_parent = R x_i) and origin r (parent's axes)."""

    R: list
    r: list

    def to_child(self, prog: Program, motion):
        """A motion vector (ω, v) of the parent's frame in i's frame: (Rᵀω, Rᵀ(v + ω × r))."""
        w, v = motion
        return prog.vector(mat_t_vec(self.R, w)), prog.vector(mat_t_vec(self.R, add(v, prog.vector(cross(w, self.r)))))

    def to_parent(self, prog: Program, force):
        """A force vector (n, f) of i's frame in the parent's: (R n + r × R f, R f)."""
        n, f = force
        f_parent = prog.vector(mat_vec(self.R, f))
        return prog.vector(add(mat_vec(self.R, n), cross(self.r, f_parent))), f_parent


def motion_cross(prog: Program, a, b):
    """a ×ₘ b of two motion vectors: (ω_a × ω_b, ω_a × v_b + v_a × ω_b)."""
    (wa, va), (wb, vb) = a, b
    return prog.vector(cross(wa, wb)), prog.vector(add(cross(wa, vb), cross(va, wb)))


def force_cross(prog: Program, a, f):
    """a ×* f of a motion vector a and a force vector f: (ω × n + v × f, ω × f)."""
    (w, v), (n, force) = a, f
    return prog.vector(add(cross(w, n), cross(v, force))), prog.vector(cross(w, force))


def add_spatial(prog: Program, a, b):
    """a + b of two spatial vectors (bound)."""
    return prog.vector(add(a[0], b[0])), prog.vector(add(a[1], b[1]))


def spatial_dot(a, b) -> sp.Expr:
    """The pairing aᵀ b of a motion and a force vector (power), unbound."""
    return dot(a[0], b[0]) + dot(a[1], b[1])


def _skew_times(r, m) -> list:
    """(r×) m for a 3×3 m (rows): column j is r × (column j of m)."""
    columns = [cross(r, [m[0][j], m[1][j], m[2][j]]) for j in range(3)]
    return [[columns[j][i] for j in range(3)] for i in range(3)]


def _symmetric(m) -> list:
    """m with its upper triangle mirrored from the lower one (the entries computed once)."""
    return [[m[max(i, j)][min(i, j)] for j in range(3)] for i in range(3)]


@dataclass(frozen=True)
class Inertia:
    """A spatial inertia [[A, B], [Bᵀ, C]] (module docstring); `mass` set when C = mass·1 (C is then ignored)."""

    A: list
    B: list
    C: list
    mass: object = None

    def times(self, prog: Program, motion):
        """I m = (A ω + B v, Bᵀ ω + C v)."""
        w, v = motion
        C = [[self.mass if i == j else 0 for j in range(3)] for i in range(3)] if self.mass is not None else self.C
        return (prog.vector(add(mat_vec(self.A, w), mat_vec(self.B, v))),
                prog.vector(add(mat_t_vec(self.B, w), mat_vec(C, v))))

    def plus(self, prog: Program, other: Inertia) -> Inertia:
        """self + other, entrywise (lower triangles of A and C)."""
        A = _symmetric([[prog.let(self.A[i][j] + other.A[i][j]) if j <= i else None for j in range(3)]
                        for i in range(3)])
        B = [[prog.let(self.B[i][j] + other.B[i][j]) for j in range(3)] for i in range(3)]
        if self.mass is not None and other.mass is not None:
            return Inertia(A, B, None, prog.let(self.mass + other.mass))
        C = _symmetric([[prog.let(self.full_C()[i][j] + other.full_C()[i][j]) if j <= i else None for j in range(3)]
                        for i in range(3)])
        return Inertia(A, B, C)

    def full_C(self) -> list:
        """C as a 3×3 list."""
        if self.mass is None:
            return self.C
        return [[self.mass if i == j else sp.S.Zero for j in range(3)] for i in range(3)]

    def minus_outer(self, prog: Program, U, scale, null: int | None = None) -> Inertia:
        """self − U Uᵀ · scale for a force-like 6-vector U = (U_n, U_f) (the articulated-body update).

        With `null` = k the result's row and column k (0-2 angular, 3-5 linear) are zero, not computed: the
        articulated-body update I − I S Sᵀ I / (Sᵀ I S) annihilates S, and S = e_k for a joint along a coordinate
        axis (its entries would be rounding left over from x − x)."""
        un, uf = U
        sn, sf = prog.vector([x * scale for x in un]), prog.vector([x * scale for x in uf])

        def entry(row, column, value):
            return sp.S.Zero if null in (row, column) else prog.let(value)

        C0 = self.full_C()
        A = _symmetric([[entry(i, j, self.A[i][j] - un[i] * sn[j]) if j <= i else None for j in range(3)]
                        for i in range(3)])
        B = [[entry(i, 3 + j, self.B[i][j] - un[i] * sf[j]) for j in range(3)] for i in range(3)]
        C = _symmetric([[entry(3 + i, 3 + j, C0[i][j] - uf[i] * sf[j]) if j <= i else None for j in range(3)]
                        for i in range(3)])
        return Inertia(A, B, C)

    def to_parent(self, prog: Program, X: Placement) -> Inertia:
        """Xᵀ I X: this inertia of i's frame expressed in the parent's (X = `Placement.to_child`).

        Rotated blocks A' = R A Rᵀ, B' = R B Rᵀ, C' = R C Rᵀ, then shifted by r:
        B'' = B' + r× C', A'' = A' − B' r× + r× B''ᵀ (symmetric), C'' = C'.
        """
        R, r = X.R, X.r
        A1 = _rotated_symmetric(prog, R, self.A)
        RB = [[prog.let(dot(R[i], [self.B[0][j], self.B[1][j], self.B[2][j]])) for j in range(3)] for i in range(3)]
        B1 = [[prog.let(dot(RB[i], R[j])) for j in range(3)] for i in range(3)]
        C1 = None if self.mass is not None else _rotated_symmetric(prog, R, self.C)
        rC = ([[self.mass * e for e in row] for row in _skew_times(r, [[1, 0, 0], [0, 1, 0], [0, 0, 1]])]
              if self.mass is not None else _skew_times(r, C1))
        B2 = [[prog.let(B1[i][j] + rC[i][j]) for j in range(3)] for i in range(3)]
        rB2t = _skew_times(r, [[B2[j][i] for j in range(3)] for i in range(3)])   # r× B''ᵀ
        A2 = _symmetric([[prog.let(A1[i][j] - cross(B1[i], r)[j] + rB2t[i][j]) if j <= i else None
                          for j in range(3)] for i in range(3)])
        return Inertia(A2, B2, C1, self.mass)


def _rotated_symmetric(prog: Program, R, S) -> list:
    """R S Rᵀ of a symmetric S, its lower triangle computed (R S first, bound)."""
    RS = [[prog.let(dot(R[i], [S[0][j], S[1][j], S[2][j]])) for j in range(3)] for i in range(3)]
    return _symmetric([[prog.let(dot(RS[i], R[j])) if j <= i else None for j in range(3)] for i in range(3)])


def rigid_inertia(prog: Program, mass, com, inertia) -> Inertia:
    """The spatial inertia of a rigid body in its frame: mass m, centre of mass c (3-vector), inertia I_G about
    the centre of mass (3×3, body axes): A = I_G + m (|c|² 1 − c cᵀ) (parallel axes), B = (m c)×, C = m 1."""
    h = prog.vector([mass * x for x in com])
    A = _symmetric([[prog.let(inertia[i][j] + mass * ((dot(com, com) if i == j else 0) - com[i] * com[j]))
                     if j <= i else None for j in range(3)] for i in range(3)])
    B = [[0, -h[2], h[1]], [h[2], 0, -h[0]], [-h[1], h[0], 0]]
    return Inertia(A, [[sp.sympify(e) for e in row] for row in B], None, mass)
