"""Kinematic trees of rigid links and joints, compiled from recursive multibody algorithms (issue 39).

`Tree` and `Link` describe the system, the joints (`lagcomp.multibody.joints`) how links move; ``lc.compile(tree)``
emits the articulated-body algorithm as straight-line code (`lagcomp.codegen.tree_lower`).
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
from lagcomp.multibody.tree import Link, Tree

__all__ = ["Cylindrical", "Free", "Link", "Planar", "Prismatic", "Revolute", "Spherical", "Tree", "Universal"]
