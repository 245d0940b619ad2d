"""The position of a point fixed in a link of a tree, as an expression of the tree's coordinates.

What a tree's events and contacts are written with (`lagcomp.Tree` ``events=``): the height of a link's tip over a
floor, the distance of a point from a wall.  ``link_point(links, "lower", (l, 0, 0))`` is the base-frame position
(m) of the point (l, 0, 0) of link ``lower``'s frame, a 3×1 sympy Matrix over the coordinates q_i(t) and the
parameters: the tree's forward kinematics (`lagcomp.multibody.frames`, the recursions' placements composed outward
from the base along the link's path, R_i = R_λ R_Xi, o_i = o_λ + R_λ r_Xi) and the point at o_L + R_L p, the
expression left as the products the tree forms (not expanded).  Its time derivative (``.diff(lc.t)``) is the point's velocity.

Through a spherical or free joint the rotation is R(σ) of the joint's modified Rodrigues parameters
(`lagcomp.multibody.mrp`); the shadow switch σ → −σ/|σ|² leaves R, hence the point, where it is, so an event or a
contact of such a point is continuous across the switch.
"""

from __future__ import annotations

import sympy as sp

from lagcomp.errors import ModelError
from lagcomp.multibody.frames import WorldKinematics, link_nodes
from lagcomp.multibody.joints import t
from lagcomp.multibody.kinematics import local_nodes
from lagcomp.multibody.program import Program


class _Inline(Program):
    """A `Program` that binds nothing: each quantity stays the expression it is formed as."""

    def let(self, expr) -> sp.Expr:
        return sp.sympify(expr)


def link_point(tree_or_links, link: str, point=(0, 0, 0)) -> sp.Matrix:
    """The base-frame position (m) of `point` (3 expressions, link axes, m) fixed in `link`, over the coordinates.

    Parameters
    ----------
    tree_or_links : lagcomp.Tree or sequence of lagcomp.Link
        The tree, or the links it is (or will be) built from: the expression is what an event of that tree reads.
    link : str
        The name of a link of the tree.
    point : 3 expressions
        The point in the link's frame (m); default its origin.

    Returns
    -------
    sympy.Matrix
        3×1, base axes, in the coordinates q_i(t) (``lc.t`` the time) and the tree's parameters.
    """
    from lagcomp.multibody.tree import Tree

    tree = tree_or_links if isinstance(tree_or_links, Tree) else Tree(tree_or_links, name="points")
    last_node = link_nodes(tree)
    if link not in last_node:
        raise ModelError(f"link_point: {link!r} is not a link of the tree; its links are {sorted(last_node)}.")
    try:
        p = tuple(sp.sympify(x) for x in point)
    except (TypeError, sp.SympifyError):
        p = ()
    if len(p) != 3:
        raise ModelError(f"link_point: the point on {link!r} must be three expressions (m, link axes), got {point!r}.")
    q, qd = list(tree.coordinates), [c.diff(t) for c in tree.coordinates]
    return sp.Matrix(WorldKinematics(_Inline(), local_nodes(tree, q, qd, {})).position(last_node[link], p))

