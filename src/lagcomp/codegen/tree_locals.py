"""The kernel locals of a kinematic tree: the names every kernel of a tree reads its state and parameters by.

The eager module (`lagcomp.codegen.tree_lower`) and every on-demand kind (`lagcomp.codegen.tree_companion`) build
their programs over the same symbols, so that a companion's f is the eager ``rhs``'s bitwise and the emitted names are
those of a Lagrange module (`lagcomp.codegen.bindings.user_local`).
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from lagcomp.codegen.bindings import user_local
from lagcomp.codegen.tree_slip import slipping_nodes
from lagcomp.multibody.joints import t
from lagcomp.multibody.kinematics import local_nodes
from lagcomp.multibody.tree import Tree


@dataclass(frozen=True)
class TreeLocals:
    """The kernel locals of a tree: coordinates `q`, velocities `qd`, parameters `p` (symbols, in order), the
    loads binding them to y and p (and the modes of friction pressed by an expression), and the tree's nodes and
    gravity over them."""

    q: tuple
    qd: tuple
    p: tuple
    loads: tuple
    nodes: tuple
    gravity: tuple
    #: Each parameter (and t) to its local: what a loop's points are written over (`lagcomp.codegen.tree_constraints`).
    mapping: dict

    @property
    def n(self) -> int:
        return len(self.q)


def tree_locals(tree: Tree) -> TreeLocals:
    """`TreeLocals` of `tree`: q and q̇ from y[:n] and y[n:], the parameters from p in `Tree.parameters`' order."""
    n = tree.n
    q = tuple(sp.Symbol(user_local("q", name, i), real=True) for i, name in enumerate(tree.coordinate_names))
    qd = tuple(sp.Symbol(user_local("qd", name, i), real=True) for i, name in enumerate(tree.coordinate_names))
    mapping = {s: sp.Symbol(user_local("p", s.name, k), real=True) for k, s in enumerate(tree.parameters)}
    loads = [(s.name, f"y[{i}]") for i, s in enumerate(q)] + [(s.name, f"y[{n + i}]") for i, s in enumerate(qd)]
    loads += [(local.name, f"p[{k}]") for k, local in enumerate(mapping.values())]
    p = tuple(mapping.values())
    mapping[t] = sp.Symbol("t", real=True)
    nodes, slip_loads = slipping_nodes(tree, local_nodes(tree, q, qd, mapping), q, qd, mapping)
    loads += slip_loads   # (friction elements pressed by an expression: their modes, `lagcomp.codegen.tree_slip`)
    gravity = tuple(sp.sympify(g).xreplace(mapping) for g in tree.gravity)
    return TreeLocals(q, qd, p, tuple(loads), tuple(nodes), gravity, mapping)
