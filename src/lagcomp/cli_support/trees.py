"""The commands' handling of a kinematic tree (`lagcomp.Tree`) named on the command line (issue 39).

``lagcomp run``, ``sweep``, ``animate``, ``bench`` and ``precompile`` take a tree's compiled model as they take any
model's.  ``lagcomp show`` prints what a tree is made of (`show_tree`): its equations are its recursions
(`Model.equations()`), no symbolic M and F.  ``lagcomp stability`` reads a System's T and V (`lagcomp.analysis.stability_sweep`), which a tree
does not have: it is refused by name (`refuse_tree`).
"""

from __future__ import annotations

from lagcomp.errors import LagcompError


def is_tree(system) -> bool:
    """Whether `system` (what a model file or module gave) is a `lagcomp.Tree`."""
    from lagcomp.multibody.tree import Tree

    return isinstance(system, Tree)


def refuse_tree(tree, command: str, instead: str) -> None:
    """A LagcompError: `command` is not available for `tree`; `instead` says what to use."""
    raise LagcompError(f"lagcomp {command} is not available for the kinematic tree {tree.name!r} (issue 39): "
                       f"{instead}")


def show_tree(tree, model) -> int:
    """``lagcomp show`` of a tree: its links and joints, coordinates, parameters, loops and events, how its kernels
    are formed, its equations (the recursion over a table of its nodes) and its module."""
    print(f"{tree.name}: {tree.description or '(no description)'}   [kinematic tree]\n")
    print(f"coordinates q  = ({', '.join(tree.coordinate_names)})")
    print(f"parameters  p  = ({', '.join(tree.parameter_names)})   [kernel order]")
    print(f"defaults       = {tree.defaults}")
    print(f"gravity        = ({', '.join(str(float(g) if g.is_number else g) for g in tree.gravity)})")
    print("\nlinks (parent first):")
    for link in tree.links:
        moved = [q for q, node in zip(tree.coordinate_names, tree.nodes) if node.link == link.name]
        parent = link.parent if link.parent is not None else "(base)"
        print(f"  {link.name:<12} on {parent:<12} {type(link.joint).__name__}({', '.join(moved)})  mass {link.mass}")
    if tree.constraint_names:
        print(f"\nloops          = {', '.join(c.loop for c in tree.closures)} "
              f"(constraints {', '.join(tree.constraint_names)}, holonomic)")
    if tree.events:
        print(f"events         = {', '.join(tree.event_names)}")
    from lagcomp.codegen.tree_lower import FORMULATION

    print(f"\n{FORMULATION}")
    print("(no symbolic M and F: Model.mass_matrix and Model.forcing evaluate them)")
    print(f"\n{model.equations()}")
    print(f"\noperations: {model.operations}")
    print(f"generated module: {model.source_path}")
    return 0
