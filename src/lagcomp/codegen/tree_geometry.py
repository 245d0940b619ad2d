r"""The ``geometry`` kernel of a kinematic tree (`lagcomp.Tree`): where each link's frame is and how it is turned.

    geometry(t, y, p, out)

writes, for each link of ``Tree.links`` in order, 12 values from ``out[offset]`` on (kind ``"link"``):

* the origin o of the link's frame (on its joint: a revolute joint's axis passes through it), 3 values, in the
  tree's base frame from its origin (m);
* the rotation matrix C, 9 values row-major (C[i, j] at offset + 3 + 3 i + j), whose column j is the link's axis j
  in base components: x_base = C x_link + o.

This is Pinocchio's placement of the joint frame (``data.oMi``) and, for a robot from `lagcomp.from_urdf`, the URDF
link frame (a link whose fixed joints were merged into it keeps its own frame).  The layout mirrors the
Lagrangian ``geometry`` (`lagcomp.codegen.geometry`): module constants ``GEOMETRY`` = ((name, kind, offset), ...)
and ``GEOMETRY_SIZE``, read by `lagcomp.animation_bodies`; a link's centre of mass is at o + C c for its ``com``
c.  A tree adds ``GEOMETRY_PARENTS`` = ((link, parent link or None), ...), the skeleton `lagcomp.animation` draws
as rods from each link's origin to its children's (None: from the base frame's origin).

The values come from the forward kinematics of positions (`lagcomp.multibody.frames`), bound as a straight-line
program like every kernel of a tree (`lagcomp.codegen.tree_lower`); the kernel loads no velocity.  A tree's
closed loops (`lagcomp.Loop`) change nothing here: the links are where the coordinates put them.
"""

from __future__ import annotations

from dataclasses import replace

from lagcomp.codegen.tree_lower import program_kernel
from lagcomp.ir import Kernel
from lagcomp.multibody.frames import link_nodes, world_frames
from lagcomp.multibody.program import Program

#: What a link writes into ``out``: its number of values, and what they are (as `lagcomp.codegen.geometry.KINDS`).
KINDS = {"link": (12, "the link frame's origin, then the rotation matrix C row-major (columns: the link axes)")}

#: The kernel's signature: `out` has ``GEOMETRY_SIZE`` entries.
ARGS = ("t", "y", "p", "out")


def tree_geometry_kernels(tree, local) -> tuple[Kernel, ...]:
    """The ``geometry`` kernel of `tree` over its kernel locals `local` (`lagcomp.codegen.tree_companion.TreeLocals`),
    with its constants ``GEOMETRY``, ``GEOMETRY_SIZE`` and ``GEOMETRY_PARENTS`` (module docstring)."""
    prog = Program()
    frames = world_frames(prog, list(local.nodes))
    last = link_nodes(tree)
    count = KINDS["link"][0]
    layout, stores = [], []
    for k, link in enumerate(tree.links):
        C, o = frames[last[link.name]]
        offset = count * k
        layout.append((link.name, "link", offset))
        entries = [*o, *(C[i][j] for i in range(3) for j in range(3))]
        stores += [(f"out[{offset + i}]", e) for i, e in enumerate(entries)]
    size = count * len(tree.links)
    lines = "\n".join(f"out[{offset}:{offset + count}] {name}: {KINDS[kind][1]}" for name, kind, offset in layout)
    doc = (f"Where the links are, shape (GEOMETRY_SIZE,) = ({size},), into `out`: each link frame's origin in the\n"
           "base frame, then its rotation matrix C (x_base = C x_link + o) row-major. Reads no velocity.\n" + lines)
    kernel = program_kernel("geometry", doc, ARGS, prog, stores, local.loads)
    parents = tuple((link.name, link.parent) for link in tree.links)
    return (replace(kernel, constants=(
        ("GEOMETRY", "The links `geometry` writes, (name, kind, offset into out); a kind's values: "
         + ", ".join(f"{kind} {n}" for kind, (n, _) in KINDS.items()) + ".", tuple(layout)),
        ("GEOMETRY_SIZE", "Length of `geometry`'s out.", size),
        ("GEOMETRY_PARENTS", "Each link and its parent link (None: the base), for drawing the tree.", parents),
    )),)
