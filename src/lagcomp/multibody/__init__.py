"""Kinematic trees of rigid links and joints, compiled from recursive multibody algorithms (issue 39).

`Tree` and `Link` describe the system, the joints (`lagcomp.multibody.joints`) how links move; ``lc.compile(tree)``
emits the articulated-body algorithm as straight-line code (`lagcomp.codegen.tree_lower`).
"""

from lagcomp.multibody.joints import (
    Cylindrical as Cylindrical,
    Free as Free,
    Planar as Planar,
    Prismatic as Prismatic,
    Revolute as Revolute,
    Spherical as Spherical,
    Universal as Universal,
)
from lagcomp.multibody.tree import Link as Link, Tree as Tree

__all__ = ["Cylindrical", "Free", "Link", "Planar", "Prismatic", "Revolute", "Spherical", "Tree", "Universal"]
