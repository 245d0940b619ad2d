"""Kinematic trees of rigid links and joints, compiled from recursive multibody algorithms (issue 39).

`Tree` and `Link` describe the system (`Loop` a cut joint closing a loop), the joints (`lagcomp.multibody.joints`)
how links move, `link_point` where a link's point is (what events and contacts read); ``lc.compile(tree)`` emits the articulated-body algorithm as straight-line code
(`lagcomp.codegen.tree_lower`).
"""

from lagcomp.multibody.joints import (
    Cylindrical,
    Free,
    Planar,
    Prismatic,
    Revolute,
    Spherical,
    Universal,
)
from lagcomp.multibody.loops import Loop
from lagcomp.multibody.points import link_point
from lagcomp.multibody.tree import Link, Tree

__all__ = ["Cylindrical", "Free", "Link", "Loop", "Planar", "Prismatic", "Revolute", "Spherical", "Tree", "Universal", "link_point"]
