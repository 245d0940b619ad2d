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

    def vector(self, entries) -> list:
        """Each entry of `entries` through `let`."""
        return [self.let(e) for e in entries]

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


def dot(a, b) -> sp.Expr:
    """a · b."""
    return sp.Add(*(x * y for x, y in zip(a, b)))


def cross(a, b) -> list:
    """a × b."""
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def mat_vec(m, v) -> list:
    """m v (m a 3×3 list of rows)."""
    return [dot(row, v) for row in m]


def mat_t_vec(m, v) -> list:
    """mᵀ v."""
    return [dot([m[0][j], m[1][j], m[2][j]], v) for j in range(3)]


def add(a, b) -> list:
    """a + b, entrywise."""
    return [x + y for x, y in zip(a, b)]

