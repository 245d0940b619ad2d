"""Closed kinematic loops of a tree: a cut joint, described by the two points it holds together.

A mechanism with a closed loop (a four-bar linkage, a slider-crank) is written as a spanning tree of its links plus
the joints the tree leaves out.  Each left-out ("cut") joint is a `Loop`: a point fixed in one link, a point fixed in
another link (or in the base), and the directions, along the base frame's axes or given vectors, in which the joint
holds the two points together.  A pin (revolute) joint of a planar mechanism in the x-y plane closes in x and y; a
ball joint in 3D closes in x, y and z; a slider's pin running in a rail fixed along x of the base closes in y.
Each direction d_k is one holonomic constraint

    Φ_k(q) = d_k · (P_first(q) − P_second(q)) = 0,

built from the tree's forward kinematics (`lagcomp.multibody.closure`), named ``<loop>_<axis>`` ("x", "y", "z") or
``<loop>_<k>`` (a vector, k its position).  Its multiplier λ_k (``Solution.reactions``) is the component along d_k of
the force (N) the second link exerts on the first at the cut joint: the generalized force of that pair of forces is
Λ_kᵀ λ_k with Λ_k = ∂Φ_k/∂q, the virtual work of F on δP_first and of −F on δP_second.

Rotations are not closed: a cut joint holds points, so a loop whose closing joint must also fix an orientation (a
weld, or a revolute joint of a spatial loop whose axis is not already kept aligned by the tree) is not supported yet.
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from lagcomp.errors import ModelError
from lagcomp.multibody.joints import ISSUE, unit_axis


@dataclass(frozen=True)
class Loop:
    """A cut joint closing a kinematic loop of a `Tree` (module docstring): holonomic constraints on the tree.

    Parameters
    ----------
    name : str
        An identifier; the constraints are named ``<name>_x``, ``<name>_y``, ... (one per direction).
    first : (str, 3 expressions)
        A link's name and a point fixed in that link, in its frame (m).
    second : (str or None, 3 expressions)
        Another link's name (None: the fixed base) and a point fixed in it, in its frame (m).
    directions : str or sequence, default "xyz"
        The directions in which the joint holds the two points together, in the base frame: a string of the axes
        ("xy" for a pin of a planar mechanism in the x-y plane, "y" for a slider in a rail along x), or a sequence
        of axes ``"x"``, ``"y"``, ``"z"`` and 3-vectors (normalised).  Name only directions in which the
        mechanism could otherwise move: a direction the tree's joints already keep closed (z of a planar
        mechanism) is refused.

    Examples
    --------
    The pin at B of a four-bar, cut between the coupler's far end and the rocker's::

        lc.Loop("pin_B", ("coupler", (b, 0, 0)), ("rocker", (c, 0, 0)), directions="xy")
    """

    name: str
    first: tuple
    second: tuple
    directions: object = "xyz"


@dataclass(frozen=True)
class Closure:
    """A checked `Loop`: the two links (None: the base), their points (sympy), the unit directions (base frame)
    and one constraint name per direction."""

    loop: str
    first: str
    first_point: tuple
    second: str | None
    second_point: tuple
    directions: tuple
    names: tuple


def closures(loops, links, tree_name: str) -> tuple[Closure, ...]:
    """The `Closure` of each of `loops` against the tree's `links` (their names), every problem a `ModelError`."""
    if isinstance(loops, Loop):
        loops = (loops,)
    checked, taken = [], set()
    for loop in loops:
        if not isinstance(loop, Loop):
            raise ModelError(f"{tree_name}: `loops` is a sequence of lc.Loop, got {loop!r}.")
        closure = _closure(loop, links, tree_name)
        repeated = sorted(taken & {closure.loop, *closure.names})
        if repeated:
            raise ModelError(f"{tree_name}: the name(s) {repeated} of loop {loop.name!r} are taken by another loop: "
                             "give each loop its own name.")
        taken |= {closure.loop, *closure.names}
        checked.append(closure)
    return tuple(checked)


def _closure(loop: Loop, links, tree_name: str) -> Closure:
    what = f"{tree_name}: loop {loop.name!r}"
    if not isinstance(loop.name, str) or not loop.name.isidentifier():
        raise ModelError(f"{tree_name}: a loop's name must be a Python identifier like 'pin_B', got {loop.name!r}.")
    first, first_point = _end(loop.first, "first", links, what, base_allowed=False)
    second, second_point = _end(loop.second, "second", links, what, base_allowed=True)
    if first == second:
        raise ModelError(f"{what} joins link {first!r} to itself: a cut joint joins two different links (or a "
                         "link and the base, second=(None, point)).")
    directions, labels = _directions(loop.directions, what)
    return Closure(loop.name, first, first_point, second, second_point, directions,
                   tuple(f"{loop.name}_{label}" for label in labels))


def _end(end, which: str, links, what: str, base_allowed: bool):
    """(link name or None, point) of one end of a loop."""
    base = " (None: the base)" if base_allowed else ""
    if isinstance(end, str) or not hasattr(end, "__len__") or len(end) != 2:
        raise ModelError(f"{what}: `{which}` must be a pair (link name{base}, point in its frame), got {end!r}.")
    link, point = end
    if link is None and not base_allowed:
        raise ModelError(f"{what}: `first` must name a link; only `second` may be the base (None).")
    if link is not None and link not in links:
        raise ModelError(f"{what}: `{which}` names the link {link!r}, which is not a link of the tree; its links "
                         f"are {list(links)}.")
    try:
        point = tuple(sp.sympify(x) for x in point)
    except (TypeError, sp.SympifyError) as err:
        raise ModelError(f"{what}: the point of `{which}` must be three expressions, got {point!r}.") from err
    if len(point) != 3:
        raise ModelError(f"{what}: the point of `{which}` must be three expressions, got {point!r}.")
    return link, point


def _directions(directions, what: str) -> tuple[tuple, tuple]:
    """The unit directions (sympy 3-tuples) and their labels ("x" or the position), checked independent."""
    items = list(directions) if isinstance(directions, str) else list(directions or ())
    if not items or len(items) > 3:
        raise ModelError(f"{what}: `directions` must name one to three directions ('xy', 'xyz', 'y', or vectors), "
                         f"got {directions!r}.")
    units, labels = [], []
    for k, item in enumerate(items):
        units.append(unit_axis(item, f"{what}: direction {item!r}"))
        labels.append(item if isinstance(item, str) else str(k))
    if len(set(labels)) != len(labels) or sp.Matrix(units).rank() < len(units):
        raise ModelError(f"{what}: the directions {directions!r} are not independent: each must add a constraint "
                         "(name each axis once; vectors must not be combinations of each other).")
    return tuple(units), tuple(labels)


def refuse_idle_direction(closure: Closure, k: int) -> None:
    """The `ModelError` for direction `k` of `closure`, along which no joint of the tree can move the cut
    points apart (its row of the constraint matrix is identically zero: the augmented system would be singular)."""
    raise ModelError(
        f"loop {closure.loop!r}: the tree's joints cannot move {closure.first!r} and "
        f"{'the base' if closure.second is None else repr(closure.second)} apart along its direction "
        f"{closure.names[k]!r} (the constraint's row of Λ = ∂Φ/∂q is identically zero), so that constraint is "
        "redundant and the augmented system singular: leave the direction out (a planar mechanism in the x-y "
        f"plane closes in 'xy' only). Rotational closure is not available yet ({ISSUE}).")
