"""Straight-line programs: the intermediate quantities of a recursion as named assignments.

A recursion over a kinematic tree (`lagcomp.multibody.aba` and its siblings) computes each body's rotation,
velocity, articulated inertia, ... from its parent's or children's.  Written as one expression per output, those
quantities would be multiplied into each other and swell with the depth of the tree (the cost the Lagrangian path
pays on long chains, issue 39).  A `Program` instead binds every non-trivial intermediate value to a fresh local
``_b<k>`` the moment it is formed, so each assignment is a small expression of earlier locals, the coordinates,
velocities and parameters:

* numbers and symbols are never bound (a zero or a one folds into what uses it: a revolute joint's axis e_z, a
  massless frame's zero inertia, an identity placement);
* an expression formed twice is bound once (hash-consing: the light CSE a recursion needs, per assignment);
* assignments no output reads are dropped (`Program.live`).

Each assignment also records the *step* it was formed in (`Program.step`: a node's share of one pass of a
recursion), so that the steps of identical nodes can be emitted as one shared function
(`lagcomp.codegen.outline`).  Locals are numbered with a fixed width (``_b000012``): their names then sort as
they were formed, so the steps of two identical nodes print their sums and products in the same order.
"""

from __future__ import annotations

import contextlib

import sympy as sp

#: The prefix of the locals a program binds (generated names start with ``_``: `lagcomp.codegen.lower`, Names).
PREFIX = "_b"
#: Digits of a local's number (zero-padded: names sort as numbers).
WIDTH = 6


class Program:
    """An ordered list of assignments ``local = expression``, built by `let`."""

    def __init__(self):
        self.assignments: list[tuple[sp.Symbol, sp.Expr]] = []
        #: The step each local was formed in (None: outside any step).
        self.step_of: dict[sp.Symbol, object] = {}
        self._bound: dict = {}
        self._step = None

    @contextlib.contextmanager
    def step(self, key):
        """Tag the assignments formed inside the ``with`` block as the step `key` (any hashable: a pass and a
        node); steps do not nest."""
        outer, self._step = self._step, key
        try:
            yield
        finally:
            self._step = outer

    def let(self, expr) -> sp.Expr:
        """`expr` itself when it is a number, a symbol or a negated symbol, else the local bound to it."""
        expr = sp.sympify(expr)
        if expr.is_Number or expr.is_Symbol or (expr.is_Mul and len(expr.args) == 2 and expr.args[0] == -1
                                                and expr.args[1].is_Symbol):
            return expr
        local = self._bound.get(expr)
        if local is None:
            local = self._bound[expr] = sp.Symbol(f"{PREFIX}{len(self.assignments):0{WIDTH}d}", real=True)
            self.assignments.append((local, expr))
            self.step_of[local] = self._step
        return local

    def regroup(self, start: int, rank: dict, steps: dict) -> None:
        """Reorder the assignments from `start` on by ``rank[local]`` (a stable sort: the caller keeps the order
        topological, each local ranked no lower than the locals it reads) and tag them with the steps `steps` (a
        local absent: no step), without renaming anything (`lagcomp.multibody.forward_mode`: the derivatives
        grouped by the steps they differentiate)."""
        self.assignments[start:] = sorted(self.assignments[start:], key=lambda assignment: rank[assignment[0]])
        for local, _ in self.assignments[start:]:
            self.step_of[local] = steps.get(local)

    def vector(self, entries) -> list:
        """Each entry of `entries` through `let`."""
        return [self.let(e) for e in entries]

    def rebound(self, expr) -> sp.Expr:
        """`expr` with each subexpression this program has bound replaced by its local (a derivative's
        cos q by the local of cos q: `lagcomp.multibody.forward_mode`)."""
        return sp.sympify(expr).xreplace(self._bound)

    def live(self, outputs) -> list[tuple[sp.Symbol, sp.Expr]]:
        """The assignments the expressions `outputs` read, directly or through other assignments, in order."""
        needed = set().union(*(sp.sympify(e).free_symbols for e in outputs)) if outputs else set()
        kept = []
        for local, expr in reversed(self.assignments):
            if local in needed:
                kept.append((local, expr))
                needed |= expr.free_symbols
        return kept[::-1]


# -- 3-vectors and 3×3 matrices as lists of expressions ---------------------------------------------------------


def _is(x, k: int) -> bool:
    """Whether `x` is the exact integer `k` (0 or 1: a Python int or sympy's singleton), without sympy's
    comparison."""
    return x is (sp.S.Zero if k == 0 else sp.S.One) or (type(x) is int and x == k)


def _product(x, y):
    """x y, with a zero or one factor folded before sympy multiplies (the same expression, formed faster: the
    placements and motion subspaces of a tree are mostly zeros and ones)."""
    if _is(x, 0) or _is(y, 0):
        return sp.S.Zero
    if _is(x, 1):
        return y
    return x if _is(y, 1) else x * y


def dot(a, b) -> sp.Expr:
    """a · b."""
    terms = [t for t in (_product(x, y) for x, y in zip(a, b)) if not _is(t, 0)]
    return sp.Add(*terms) if terms else sp.S.Zero


def cross(a, b) -> list:
    """a × b."""
    return [_product(a[1], b[2]) - _product(a[2], b[1]), _product(a[2], b[0]) - _product(a[0], b[2]),
            _product(a[0], b[1]) - _product(a[1], b[0])]


def mat_vec(m, v) -> list:
    """m v (m a 3×3 list of rows)."""
    return [dot(row, v) for row in m]


def mat_t_vec(m, v) -> list:
    """mᵀ v."""
    return [dot([m[0][j], m[1][j], m[2][j]], v) for j in range(3)]


def add(a, b) -> list:
    """a + b, entrywise."""
    return [x + y for x, y in zip(a, b)]

