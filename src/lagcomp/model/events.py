"""Events: instants at which a user function g(t, q, q̇) changes sign.

An event is how a run is asked *when* something happens — a pendulum passing
the vertical, an orbit crossing a plane (a Poincaré section), a bead leaving
a surface.  The expression is compiled with the other kernels (kernel
``event_values``); the adaptive methods evaluate it after every accepted
step and locate each sign change on the step's dense output by Brent's
method, to a few units of rounding in t.

Conventions (the same as scipy's ``solve_ivp`` except at the start point):

* a crossing in direction +1 is g going from negative to ≥ 0, −1 from
  positive to ≤ 0; direction 0 accepts both;
* a zero of g exactly at the start of a step does not count again, so a run
  started on the surface g = 0 does not report an event at its first instant;
* sign changes are looked for between the ends of each step: two crossings
  inside one step cancel and are missed (bound the step with ``max_step``
  when g oscillates faster than the solution);
* a terminal event stops the run at the event, whose state is the last row;
* an event with a ``reset`` changes the state at the event and the run goes on
  from there (a ball bouncing, a kicked pendulum): the state just before and
  just after are both saved rows at the event's time, so that a plot shows the
  jump.  The reset's values are expressions of the state *before* the event
  (and of t and the parameters), evaluated all at once: ``{x.diff(t): -e *
  x.diff(t)}`` reverses the velocity.  Coordinates and velocities it does not
  name keep their values.  A zero of g at the state after a reset does not
  count (the convention above), so an event whose reset leaves g = 0 does not
  fire again at once.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import sympy as sp

from lagcomp.errors import ModelError
from lagcomp.model.expressions import expression


@dataclass(frozen=True)
class Event:
    """A named event g(t, q, q̇) = 0.

    Parameters
    ----------
    name : str
        Identifier under which the event's times and states are reported.
    expr : sympy expression
        g in the coordinates q_i(t), their velocities q_i(t).diff(t), t and parameters.
    direction : int
        +1 (g increasing through 0), −1 (decreasing) or 0 (both).
    terminal : bool
        Stop the run at the first occurrence.
    reset : mapping, optional
        What the event does to the state before the run goes on: ``{q(t): value, q(t).diff(t): value}``, each
        value an expression of the state just before the event (coordinates, velocities), t and parameters.
        Entries left out keep their value.  Not with ``terminal=True``.  Stored as ``((key, value), ...)``
        in the order given.
    """

    name: str
    expr: sp.Expr
    direction: int = 0
    terminal: bool = False
    reset: tuple | None = None

    def __post_init__(self):
        if not isinstance(self.name, str) or not self.name.isidentifier():
            raise ModelError(f"Event name {self.name!r} must be a Python identifier, like 'section'.")
        object.__setattr__(self, "expr", expression(self.expr, f"Event `{self.name}`: the expression"))
        if self.direction not in (-1, 0, 1):
            raise ModelError(f"Event `{self.name}`: direction must be -1, 0 or +1, got {self.direction!r}.")
        object.__setattr__(self, "direction", int(self.direction))
        object.__setattr__(self, "terminal", bool(self.terminal))
        object.__setattr__(self, "reset", self._checked_reset())

    @property
    def changes_state(self) -> bool:
        """Whether the event changes the state where it occurs (a reset; a contact's impact)."""
        return self.reset is not None

    def _checked_reset(self) -> tuple | None:
        """`reset` as ((key, value), ...), keys q(t) or q(t).diff(t), values sympy expressions; None for none."""
        if self.reset is None:
            return None
        if self.terminal:
            raise ModelError(f"Event `{self.name}`: a terminal event stops the run, so it cannot also reset the "
                             "state; drop `terminal=True` to go on after the reset, or the `reset` to stop there.")
        pairs = tuple(self.reset.items()) if isinstance(self.reset, Mapping) else self.reset
        try:
            pairs = tuple((key, value) for key, value in pairs)
        except (TypeError, ValueError):
            raise ModelError(f"Event `{self.name}`: `reset` must map coordinates q(t) and velocities q(t).diff(t) "
                             f"to their values after the event, like {{x.diff(t): -e*x.diff(t)}}; got "
                             f"{self.reset!r}.") from None
        if not pairs:
            raise ModelError(f"Event `{self.name}`: `reset` is empty; leave it out (None) for an event that only "
                             "records.")
        checked = []
        for key, value in pairs:
            if reset_target(key) is None:
                raise ModelError(f"Event `{self.name}`: reset key {key!r} is neither a coordinate q(t) nor a "
                                 "velocity q(t).diff(t).")
            checked.append((key, expression(value, f"Event `{self.name}`: the reset value of {key}")))
        keys = [key for key, _ in checked]
        repeated = sorted({str(k) for k in keys if keys.count(k) > 1})
        if repeated:
            raise ModelError(f"Event `{self.name}`: reset gives {repeated} more than once.")
        return tuple(checked)


def reset_target(key) -> tuple[sp.Expr, int] | None:
    """(the coordinate q(t), 0) for a reset key q(t), (q(t), 1) for q(t).diff(t); None for anything else."""
    if isinstance(key, sp.core.function.AppliedUndef) and len(key.args) == 1 and key.args[0].is_Symbol:
        return key, 0
    if (isinstance(key, sp.Derivative) and isinstance(key.expr, sp.core.function.AppliedUndef)
            and key.variable_count == ((key.expr.args[0], 1),)):
        return key.expr, 1
    return None


def reset_role(event: Event, key) -> str:
    """How the value `event`'s reset gives `key` is named among a System's expressions (messages, cache keys)."""
    return f"event {event.name} reset {key}"
