"""The position of a point fixed in a link of a tree, as an expression of the tree's coordinates.

What a tree's events and contacts are written with (`lagcomp.Tree` ``events=``): the height of a link's tip over a
floor, the distance of a point from a wall.  ``lc.link_point(links, "lower", (l, 0, 0))`` is the base-frame
position (m) of the point (l, 0, 0) of link ``lower``'s frame, a 3×1 sympy Matrix over the coordinates q_i(t) and
the parameters, from the same forward kinematics as the closed loops' (`lagcomp.multibody.closure`): each joint's
placement and rotation composed outward from the base, the expression left as the product the tree forms (not
expanded).  Its time derivative (``.diff(lc.t)``) is the point's velocity.

The path from the base to the link must go through revolute and prismatic joints (and the joints made of them:
universal, cylindrical, planar); a point beyond a spherical or free joint is refused (its rotation is over the
joint's modified Rodrigues parameters, whose shadow switch would make the expression jump).
"""

from __future__ import annotations

import sympy as sp

from lagcomp.errors import ModelError
from lagcomp.multibody.closure import WorldKinematics
from lagcomp.multibody.joints import ISSUE, t
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
    last_node = {node.link: i for i, node in enumerate(tree.nodes)}
    if link not in last_node:
        raise ModelError(f"link_point: {link!r} is not a link of the tree; its links are {sorted(last_node)}.")
    try:
        p = tuple(sp.sympify(x) for x in point)
    except (TypeError, sp.SympifyError):
        p = ()
    if len(p) != 3:
        raise ModelError(f"link_point: the point on {link!r} must be three expressions (m, link axes), got {point!r}.")
    i = last_node[link]
    while i >= 0:
        if tree.nodes[i].joint.kind not in ("revolute", "prismatic"):
            raise ModelError(f"link_point: the path to {link!r} goes through the {tree.nodes[i].joint.kind} joint of "
                             f"{tree.nodes[i].link!r}: points are placed through revolute and prismatic joints (and "
                             f"the joints made of them) only, for now ({ISSUE}).")
        i = tree.nodes[i].parent
    q, qd = list(tree.coordinates), [c.diff(t) for c in tree.coordinates]
    nodes = local_nodes(tree, q, qd, {})
    position, *_ = WorldKinematics(_Inline(), nodes).point(last_node[link], p)
    return sp.Matrix(position)
