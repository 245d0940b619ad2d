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
* a terminal event stops the run at the event, whose state is the last row.
"""

from __future__ import annotations

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
    """

    name: str
    expr: sp.Expr
    direction: int = 0
    terminal: bool = False

    def __post_init__(self):
        if not isinstance(self.name, str) or not self.name.isidentifier():
            raise ModelError(f"Event name {self.name!r} must be a Python identifier, like 'section'.")
        object.__setattr__(self, "expr", expression(self.expr, f"Event `{self.name}`: the expression"))
        if self.direction not in (-1, 0, 1):
            raise ModelError(f"Event `{self.name}`: direction must be -1, 0 or +1, got {self.direction!r}.")
        object.__setattr__(self, "direction", int(self.direction))
        object.__setattr__(self, "terminal", bool(self.terminal))
