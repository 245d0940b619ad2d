"""User expressions checked on the way in: sympy expressions only, never strings.

`sympy.sympify` would read a string's names as new plain symbols, so the
coordinate ``x`` written inside ``"m*x"`` would silently become a parameter
named x: a string is refused instead, naming the field.
"""

from __future__ import annotations

import sympy as sp

from lagcomp.errors import ModelError


def expression(value, what: str) -> sp.Expr:
    """`value` as a sympy expression (numbers accepted), or a ModelError naming `what`."""
    if isinstance(value, str):
        raise ModelError(
            f"{what} is the string {value!r}: write it as a sympy expression of the coordinates (from "
            "lagcomp.coordinates) and their .diff(t); in a string, coordinate names would silently become parameters."
        )
    try:
        expr = sp.sympify(value, strict=True)
    except (sp.SympifyError, TypeError, ValueError) as err:
        raise ModelError(f"{what} must be a sympy expression, got {type(value).__name__} {value!r}.") from err
    if not isinstance(expr, sp.Expr):
        raise ModelError(f"{what} must be a sympy expression, got {type(value).__name__} {value!r}.")
    return expr
