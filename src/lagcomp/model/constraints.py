"""Constraints a System may carry, each with a name (its reaction is reported under it).

* `Holonomic(name, Phi)`: Φ(q, t) = 0 — a rod of fixed length, a bead held on
  a turning hoop, an imposed angle φ − φ(t) = 0.
* `Nonholonomic(name, expr)`: Λ(q, t)·q̇ + b(q, t) = 0, written as one
  expression linear in the velocities — rolling without slipping.

Both enter Lagrange's equations through a multiplier λ_k (see
`lagcomp.mechanics.lagrange` for the normal form and the sign convention):
λ_k is the generalized force the constraint exerts along its row Λ_k, scaled
as the constraint is written.  Writing Φ = x² + y² − l² instead of
√(x² + y²) − l multiplies Λ by 2r and divides λ by it.

Released constraints — the textbook way to compute a reaction, adding a
coordinate that breaks the constraint and then imposing it — are just
declared constraints: give the extra coordinate, declare the constraint, and
read its λ from `Solution.reactions`.
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from lagcomp.errors import ModelError
from lagcomp.model.expressions import expression


@dataclass(frozen=True)
class Holonomic:
    """A position constraint Φ(q, t) = 0.

    Parameters
    ----------
    name : str
        Identifier under which the multiplier (reaction) is reported.
    Phi : sympy expression
        Φ(q, t); must not contain velocities.
    """

    name: str
    Phi: sp.Expr

    def __post_init__(self):
        _check_name(self.name)
        object.__setattr__(self, "Phi", expression(self.Phi, f"Constraint `{self.name}`: Phi"))

    @property
    def expr(self) -> sp.Expr:
        return self.Phi


@dataclass(frozen=True)
class Nonholonomic:
    """A velocity constraint Λ(q, t)·q̇ + b(q, t) = 0.

    Parameters
    ----------
    name : str
        Identifier under which the multiplier (reaction) is reported.
    expr : sympy expression
        Λ·q̇ + b, linear in the velocities q̇ = q.diff(t).
    """

    name: str
    expr: sp.Expr

    def __post_init__(self):
        _check_name(self.name)
        object.__setattr__(self, "expr", expression(self.expr, f"Constraint `{self.name}`: the expression"))


def _check_name(name: str) -> None:
    if not isinstance(name, str) or not name.isidentifier():
        raise ModelError(f"Constraint name {name!r} must be a Python identifier, like 'rod' or 'rolling'.")
