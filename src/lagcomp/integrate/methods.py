"""The integration methods `simulate` offers, as data (a registry, like scipy's METHODS).

Each `Method` names the driver function emitted into every generated module
(`lagcomp/codegen/templates/drivers.py`) and the tableau whose arrays it takes.
"""

from __future__ import annotations

from dataclasses import dataclass

from lagcomp.integrate import tableaux
from lagcomp.integrate.tableaux import Tableau


@dataclass(frozen=True)
class Method:
    """An integration method: its driver, tableau and what it accepts."""

    name: str
    order: int
    adaptive: bool
    driver: str
    tableau: Tableau
    summary: str


METHODS = {
    m.name: m
    for m in (
        Method("rk4", 4, False, "rk4_run", tableaux.RK4, "classic Runge-Kutta, fixed step `dt`"),
        Method("dopri5", 5, True, "dopri5_run", tableaux.DOPRI5,
               "Dormand-Prince 5(4), adaptive, quartic dense output (scipy's RK45)"),
        Method("dop853", 8, True, "dop853_run", tableaux.DOP853,
               "Dormand-Prince 8(5,3), adaptive, 7th-order dense output (Hairer's DOP853)"),
    )
}

#: Other accepted spellings.
ALIASES = {"rk45": "dopri5", "dopri853": "dop853"}


def get_method(name: str) -> Method:
    """The method called `name` (case-insensitive, aliases accepted)."""
    from lagcomp.errors import OptionError

    key = str(name).lower()
    key = ALIASES.get(key, key)
    if key not in METHODS:
        raise OptionError(f"Unknown method {name!r}; choose one of {', '.join(METHODS)}.")
    return METHODS[key]
