"""Parameter values keyed by name (no sympy import: `lagcomp.load` runs without it)."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from lagcomp.errors import ParameterError


def by_name(values: Mapping, what: str, parameters) -> dict:
    """`values` keyed by parameter name: a sympy Symbol key stands for its name.

    `what` names the argument in messages (``params``, ``defaults``); `parameters`
    lists the names it may use.  A key that is neither a str nor a Symbol, or a
    parameter given twice (once by name, once by Symbol), or a boolean value (``True`` is no mass), is a
    ParameterError.
    """
    named = {}
    for key, value in values.items():
        name = key.name if getattr(key, "is_Symbol", False) and isinstance(getattr(key, "name", None), str) else key
        if not isinstance(name, str):
            raise ParameterError(f"`{what}` keys must be parameter names (or their sympy Symbols), got {key!r}; "
                                 f"the parameters are {list(parameters)}.")
        if name in named:
            raise ParameterError(f"`{what}` gives parameter `{name}` twice (by name and by Symbol).")
        if isinstance(value, (bool, np.bool_)):  # float(True) is 1.0: a flag passed where a number was meant
            raise ParameterError(f"`{what}` gives parameter `{name}` the boolean {value!r}; give it a number.")
        named[name] = value
    return named
