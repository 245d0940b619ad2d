"""Unilateral contacts: a gap g(q, t) ≥ 0 that closes with an impact.

A contact is an event on its gap (direction −1: the gap closing) whose
action is an impact: the velocities jump by impulses along the gap's
gradient so that the normal velocity v = ġ leaves at −e times its arrival
value (Newton's restitution), for this contact and every other contact
closed at that instant together (`lagcomp.kernel_support.impacts`: a small
complementarity problem; Newton's cradle).  Positions do not jump.  The run
reports each impact as an occurrence of the event, with the states just
before and just after.

Conventions and limits of this first form:

* the gap is a length (or an angle) that is positive when the contact is
  open, zero when touching; g < 0 is penetration, which a run refuses at its
  start (below rounding) and never produces afterwards;
* the restitution coefficient e is a number in [0, 1] or one parameter
  (checked against [0, 1] when a run gets its value): 1 is elastic (kinetic
  energy kept), 0 plastic;
* a contact pressed shut stays shut (`lagcomp.kernel_support.resting`): a
  constraint whose multiplier is the normal force, released when that force
  would turn negative (lift-off); impacts that accumulate under a pressing
  force (a bouncing ball's Zeno point) close it; the Taylor method keeps
  contacts open (its runs end at such a point with EVENTS_ACCUMULATED);
* a contact is frictionless unless a `lagcomp.model.friction.Friction` names it
  (``normal="floor"``): its normal force then presses that element, and an
  impact of it alone is frictional (`lagcomp.kernel_support.impacts.frictional_impact`);
  contacts need the Lagrange formulation (M from T) or a kinematic tree;
* on a system with constraints (a System's, a tree's loops) an impact keeps the
  constraints' velocities and a closed contact's row is held beside theirs
  (`lagcomp.kernel_support.constrained_response`); friction elements there are
  refused.
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from lagcomp.errors import ModelError
from lagcomp.model.events import Event


@dataclass(frozen=True)
class Contact(Event):
    """A named unilateral contact with gap ``expr`` = g(q, t) ≥ 0 and restitution coefficient ``restitution``.

    Written ``Contact("floor", y, restitution=0.9)``.  It is an `Event` with direction −1 and an impact
    for its action; ``direction``, ``terminal`` and ``reset`` are fixed by that and refused if given.

    Parameters
    ----------
    name : str
        Identifier under which the impacts are reported.
    expr : sympy expression
        The gap g(q, t), in the coordinates q_i(t) (not their velocities), t and parameters.
    restitution : float or sympy Symbol
        Newton's coefficient e in [0, 1], or a parameter whose value is checked at each run.  A number is kept
        as the fraction its repr writes, which the kernels print back as the same double.
    """

    restitution: object = 1.0

    def __post_init__(self):
        if self.direction not in (-1, 0) or self.terminal or self.reset is not None:
            raise ModelError(f"Contact `{self.name}`: a contact's event closes its gap (direction -1) and "
                             "continues after an impact; leave `direction`, `terminal` and `reset` unset.")
        object.__setattr__(self, "direction", -1)
        super().__post_init__()
        if any(isinstance(d, sp.Derivative) for d in self.expr.atoms(sp.Derivative)):
            raise ModelError(f"Contact `{self.name}`: the gap must depend on the coordinates, t and parameters, "
                             f"not on velocities; got {self.expr}.")
        object.__setattr__(self, "restitution", _checked_restitution(self.name, self.restitution))

    @property
    def changes_state(self) -> bool:
        """A contact's event is its impact: it changes the velocities."""
        return True


def _checked_restitution(name: str, value) -> sp.Expr:
    """A number in [0, 1] as a sympy Rational, or a parameter Symbol; anything else is a ModelError."""
    if isinstance(value, sp.Symbol):
        return value
    try:
        number = float(value)
    except (TypeError, ValueError):
        number = None
    if number is None or isinstance(value, bool) or isinstance(value, sp.Basic) and not value.is_number:
        raise ModelError(f"Contact `{name}`: restitution must be a number in [0, 1] or a parameter symbol, "
                         f"got {value!r}.")
    if not 0.0 <= number <= 1.0:
        raise ModelError(f"Contact `{name}`: restitution must be in [0, 1] (1 elastic, 0 plastic), got {number}.")
    return sp.Rational(repr(number))  # exact: printed back as the same double
