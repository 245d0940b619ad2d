"""The integration methods `simulate` offers, as data (a registry, like scipy's METHODS).

Each `Method` names the driver function emitted into every generated module
(`lagcomp/codegen/templates/drivers.py` and `symplectic.py`) and the tableau whose arrays it takes.
"""

from __future__ import annotations

from dataclasses import dataclass

from lagcomp.integrate import collocation, compositions, tableaux
from lagcomp.integrate.collocation import Collocation
from lagcomp.integrate.compositions import Composition
from lagcomp.integrate.tableaux import Tableau, driver_arguments


@dataclass(frozen=True)
class Method:
    """An integration method: its driver, coefficients and what it accepts.

    ``separable_only`` methods need `Model.separable` (explicit symplectic
    compositions); the others integrate any system.
    """

    name: str
    order: int
    adaptive: bool
    driver: str
    tableau: Tableau | Composition | Collocation
    summary: str
    separable_only: bool = False
    unconstrained_only: bool = False

    def driver_arguments(self) -> tuple:
        """The coefficient arrays (and settings) the driver takes after its common arguments."""
        if isinstance(self.tableau, Collocation):
            return (*self.tableau.driver_arguments(), MAX_FIXED_POINT_SWEEPS)
        if isinstance(self.tableau, Composition):
            return self.tableau.driver_arguments()
        return driver_arguments(self.tableau)


#: Fixed-point sweeps allowed per Gauss-Legendre step before the run stops (status -5).
MAX_FIXED_POINT_SWEEPS = 100


METHODS = {
    m.name: m
    for m in (
        Method("rk4", 4, False, "rk4_run", tableaux.RK4, "classic Runge-Kutta, fixed step `dt`"),
        Method("dopri5", 5, True, "dopri5_run", tableaux.DOPRI5,
               "Dormand-Prince 5(4), adaptive, quartic dense output (scipy's RK45)"),
        Method("dop853", 8, True, "dop853_run", tableaux.DOP853,
               "Dormand-Prince 8(5,3), adaptive, 7th-order dense output (Hairer's DOP853)"),
        Method("verlet", 2, False, "composition_run", compositions.VERLET,
               "Störmer-Verlet, symplectic, fixed step, separable systems", separable_only=True),
        Method("yoshida4", 4, False, "composition_run", compositions.YOSHIDA4,
               "Yoshida's triple-jump composition of Verlet, symplectic, order 4", separable_only=True),
        Method("yoshida6", 6, False, "composition_run", compositions.YOSHIDA6,
               "Yoshida's 7-stage composition of Verlet, symplectic, order 6", separable_only=True),
        Method("gauss1", 2, False, "collocation_run", collocation.GAUSS1,
               "implicit midpoint rule on (q, p), symplectic for any Lagrangian", unconstrained_only=True),
        Method("gauss2", 4, False, "collocation_run", collocation.GAUSS2,
               "2-stage Gauss-Legendre on (q, p), symplectic, order 4", unconstrained_only=True),
        Method("gauss3", 6, False, "collocation_run", collocation.GAUSS3,
               "3-stage Gauss-Legendre on (q, p), symplectic, order 6", unconstrained_only=True),
    )
}

#: Other accepted spellings.
ALIASES = {"rk45": "dopri5", "dopri853": "dop853", "leapfrog": "verlet", "stormer_verlet": "verlet",
           "midpoint": "gauss1", "gl1": "gauss1", "gl2": "gauss2", "gl3": "gauss3"}


def get_method(name: str) -> Method:
    """The method called `name` (case-insensitive, aliases accepted)."""
    from lagcomp.errors import OptionError

    key = str(name).lower()
    key = ALIASES.get(key, key)
    if key not in METHODS:
        raise OptionError(f"Unknown method {name!r}; choose one of {', '.join(METHODS)}.")
    return METHODS[key]
