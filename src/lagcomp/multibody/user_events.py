"""The user's events and contacts of a kinematic tree (`lagcomp.Tree` ``events=``), checked.

A tree takes the `lagcomp.Event` s and `lagcomp.Contact` s a `lagcomp.System` takes, written in the tree's
coordinates q_i(t), their velocities q_i(t).diff(t), ``lc.t`` and parameters; a point of a link enters through
`lagcomp.multibody.link_point` (the height of a tip over a floor: ``link_point(links, "lower", (l, 0, 0))[2]``).
They follow the spherical joints' shadow switches (`lagcomp.multibody.shadow`) in the tree's events, so the
index of a user event in the kernels is its position in ``events`` plus the number of ball joints.

A `lagcomp.Friction` element pressed by a contact of the tree (``normal="floor"``) has the contact's normal force,
and its slip force joins the contact's column of the held rows
(`lagcomp.kernel_support.resting.pressed_frictional_accelerations`), so the tree's articulated-body rhs (all
contacts open) stays the motion without friction.  One pressed by an expression N(q, q̇, t) slips with the
generalized force −μk |N| s ∂v/∂q̇ in the recursions' joint forces (`lagcomp.multibody.slip`).  Its velocity must be
linear in the velocities, as on a System.

Refused (`ModelError`, each naming the event): an object that is not an Event, a name used twice or by a shadow
switch, a reset of something that is not a coordinate of the tree, a friction element whose normal names no
contact of the tree.  Contacts and friction elements on a tree with loops are solved with the loops' constraints
held (`lagcomp.kernel_support.constrained_response`, `lagcomp.kernel_support.resting.held_with_constraints`).
"""

from __future__ import annotations

from lagcomp.errors import ModelError
from lagcomp.model.contacts import Contact
from lagcomp.model.events import Event, reset_role, reset_target
from lagcomp.model.friction import Friction
from lagcomp.multibody.joints import t


def checked_events(events, tree) -> tuple[Event, ...]:
    """`events` as a tuple, each checked against `tree` (its coordinates, shadow events and loops)."""
    events = (events,) if isinstance(events, Event) else tuple(events)
    taken = [e.name for e in tree.events]
    for e in events:
        if not isinstance(e, Event):
            raise ModelError(f"{tree.name}: events must be lc.Event or lc.Contact, got {e!r}.")
        if isinstance(e, Friction):
            _check_friction(e, events, tree)
        if e.name in taken:
            raise ModelError(f"{tree.name}: the event name {e.name!r} is used twice (the spherical joints' shadow "
                             f"switches take {[s.name for s in tree.events]}); give each event its own name.")
        taken.append(e.name)
        for key, _ in e.reset or ():
            coordinate, _ = reset_target(key)
            if coordinate not in tree.coordinates:
                raise ModelError(f"{tree.name}: event `{e.name}` resets {key}, but {coordinate} is not a coordinate "
                                 f"of the tree (coordinates {list(tree.coordinate_names)}).")
    return events


def _check_friction(element: Friction, events, tree) -> None:
    """Refuse a friction element whose normal names no contact of the tree, or whose velocity is not linear in q̇."""
    contacts = [e.name for e in events if isinstance(e, Contact)]
    if isinstance(element.normal, str) and element.normal not in contacts:
        raise ModelError(f"{tree.name}: the friction element `{element.name}` names normal={element.normal!r}, which "
                         f"is no contact of the tree (its contacts: {contacts}).")
    rates = [c.diff(t) for c in tree.coordinates]
    v = element.expr
    if not any(v.diff(a) != 0 for a in rates) or any(v.diff(a).diff(b) != 0 for a in rates for b in rates):
        raise ModelError(f"{tree.name}: the friction element `{element.name}`: its velocity must be linear in the "
                         f"velocities q̇ (a(q, t)·q̇ + c(q, t), not constant in them); got {element.expr}.")


def event_roles(events) -> dict:
    """Every expression of the user's `events` by role (for the parameters, the checks and the fingerprint): the
    event function, each reset value, a contact's restitution, a friction element's coefficients and its normal
    force when it is an expression."""
    roles = {}
    for e in events:
        roles[f"event {e.name}"] = e.expr
        roles.update({reset_role(e, key): value for key, value in e.reset or ()})
        if isinstance(e, Contact):
            roles[f"contact {e.name} restitution"] = e.restitution
        if isinstance(e, Friction):
            roles.update({f"friction {e.name} {part}": getattr(e, part) for part in ("static", "kinetic")})
            if not isinstance(e.normal, str):   # (an event's role: it may read t and the coordinates)
                roles[f"event {e.name} normal force"] = e.normal
    return roles
