"""The integration methods `simulate` offers, as data (a registry, like scipy's METHODS).

Each `Method` names its driver and the tableau whose arrays it takes.  A driver is a library
function of `lagcomp.integrate.drivers` (``"module:function"``), compiled once per installation,
which takes the model kernels named by `Method.kernels` as its first arguments; `Method.sweep` is
its loop over many trajectories, taking the same kernels and then ``energy``.
"""

from __future__ import annotations

import functools
import weakref
from dataclasses import dataclass

import numpy as np
from numba import types

from lagcomp.integrate import collocation, compositions, radau, tableaux
from lagcomp.integrate.collocation import Collocation
from lagcomp.integrate.compositions import Composition
from lagcomp.integrate.drivers.kernel_types import AddressedKernel
from lagcomp.integrate.radau import RadauIIA
from lagcomp.integrate.tableaux import Tableau, driver_arguments

#: How the Gauss-Legendre methods solve their stage equations: name -> the driver's ``newton``
#: argument (`lagcomp.integrate.drivers.collocation` explains both).
IMPLICIT_SOLVERS = {"fixed_point": False, "newton": True}
#: The faster of the two on the double pendulum with gauss2 at h = 0.01: 1e5 steps in 0.10 s
#: (14 evaluations of f per step) against 0.19 s for Newton (9 evaluations, one Jacobian and one LU);
#: measured with bench/bench_collocation.py, which also shows the stiff cases where Newton wins.
DEFAULT_IMPLICIT_SOLVER = "fixed_point"
#: Machine epsilon of float64; the Taylor method's default tolerance (heyoka's default too).
EPS = 2.220446049250313e-16
#: Relative tolerances below this (100 machine epsilons) ask more of the Runge-Kutta error estimates
#: than float64 can give.
RTOL_MIN = 100 * EPS
#: Iterations (fixed-point sweeps or Newton steps) allowed per step before the run stops (status -5).
MAX_STAGE_ITERATIONS = 100

#: Kernels a driver calls only at events, always bound by address (`AddressedKernel`): numba unboxes one in ~5 µs
#: instead of a dispatcher's ~35 µs at each driver call, and a run with many events makes many calls (one per 16
#: event rows): binding ``event_reset`` as a dispatcher made the Hénon-Heiles section run (4 800 crossings) 1.2×
#: slower; the kernel's call through its C wrapper costs nothing that counts.
RARELY_CALLED = ("event_reset",)

#: The library modules of the explicit fixed-step drivers and of their sweep loops.
_FIXED_STEP = "lagcomp.integrate.drivers.fixed_step"
_FIXED_SWEEPS = "lagcomp.integrate.drivers.fixed_sweeps"


@dataclass(frozen=True)
class Method:
    """An integration method: its driver, coefficients and what it accepts.

    ``separable_only`` methods need `Model.separable` (explicit symplectic
    compositions), ``holonomic_separable_only`` ones `Model.holonomic_separable`
    (RATTLE); the others integrate any system.
    """

    name: str
    order: int
    adaptive: bool
    #: ``"lagcomp.integrate.drivers.<module>:<function>"``.
    driver: str
    tableau: Tableau | Composition | Collocation | RadauIIA | None
    summary: str
    separable_only: bool = False
    holonomic_separable_only: bool = False
    unconstrained_only: bool = False
    #: Default tolerances (None: atol follows rtol), and the smallest rtol accepted.
    default_rtol: float = 1e-8
    default_atol: float | None = 1e-10
    rtol_min: float = RTOL_MIN
    #: What the driver takes first from the model's generated module, by name: kernels (e.g. ``("rhs",
    #: "project", ...)``) and, for the Taylor method, module data (``TAYLOR_PERIODIC``, ``TAYLOR_WORK``).
    kernels: tuple[str, ...] = ()
    #: What the driver takes instead of `kernels` for a constrained Lagrange model, which it then solves as an
    #: index-2 DAE (`lagcomp.integrate.dae`); empty: such models are refused (`unconstrained_only`) or projected.
    dae_kernels: tuple[str, ...] = ()
    #: Whether the driver evaluates the constraint residual after each step, so that `max_residual` can stop it
    #: (radau does not: it solves the constraints, or a Kane model's are eliminated).
    checks_residual: bool = True
    #: The library sweep loop (``"module:function"``) that runs this method over many trajectories.
    sweep: str | None = None
    #: The library function (``"module:function"``) giving, for a state of N components, the arrays a run of
    #: this method keeps from one driver call to the next besides (y, clock, counters), which `simulate`
    #: passes after the coefficients (Radau's Jacobian and last collocation polynomial; the Gauss methods' (q, p),
    #: summation compensation and last stages, whose function also takes the stage count); None: none.
    carry: str | None = None
    #: Whether the driver switches charts (a ball joint's MRPs to their shadow) at the end of a step that left one,
    #: without locating the event (`lagcomp.integrate.drivers.collocation`): it takes ``event_values`` and
    #: ``event_reset`` after `kernels`, the events' actions after its coefficients, then the event buffers it records
    #: the switches in (times, states before, events, states after; its sweep loop the event outputs), and applies
    #: no other event.
    switches_charts: bool = False
    def solves_dae(self, model) -> bool:
        """Whether this method integrates `model` as an index-2 DAE (a constrained model, `dae_kernels`)."""
        return bool(self.dae_kernels) and model.k > 0

    def bound_driver(self, kernels, addressed: bool = False, dae: bool = False):
        """The driver with the model's `kernels` (its generated module) bound as its first arguments: their
        dispatchers, or if `addressed` `AddressedKernel`s (cheaper for numba to unbox at each driver call,
        each kernel call one level deeper; `lagcomp.integrate.simulate` uses them for a run's first call).
        With `dae`, the kernels named by `dae_kernels` instead of `kernels`.

        Bound once per module, method and binding (`_BOUND_DRIVERS`): the `AddressedKernel`s then look
        their addresses up at the first run only, not at every run.
        """
        try:
            bound = _BOUND_DRIVERS.setdefault(kernels, {})
        except TypeError:  # not weakly referenceable (a stand-in for a module): bound afresh
            return self._bind(kernels, addressed, dae)
        key = (self.name, addressed, dae)
        if key not in bound:
            bound[key] = self._bind(kernels, addressed, dae)
        return bound[key]

    @property
    def driver_kernels(self) -> tuple[str, ...]:
        """What the driver and its sweep loop take first, by name: `kernels`, and the event kernels of the chart
        switches (`switches_charts`)."""
        return (*self.kernels, *_CHART_KERNELS) if self.switches_charts else self.kernels

    def _bind(self, kernels, addressed: bool, dae: bool):
        driver = library_function(self.driver)
        names = self.dae_kernels if dae else self.driver_kernels
        bound = [_kernel(kernels, k) for k in names]
        kinds = driver.signatures[0]
        bound = [AddressedKernel(value, kind) if isinstance(kind, types.FunctionType)
                 and (addressed or name in RARELY_CALLED) else value
                 for value, kind, name in zip(bound, kinds, names, strict=False)]
        return functools.partial(driver, *bound)

    @property
    def implicit(self) -> bool:
        """Whether each step solves implicit stage equations (`IMPLICIT_SOLVERS` choose how)."""
        return isinstance(self.tableau, Collocation)

    def driver_arguments(self, implicit_solver: str = DEFAULT_IMPLICIT_SOLVER) -> tuple:
        """The coefficient arrays (and settings) the driver takes after its common arguments.

        Implicit methods also take the iteration limit and the driver's ``newton``
        argument for `implicit_solver` (a key of `IMPLICIT_SOLVERS`).
        """
        if self.implicit:
            return (*self.tableau.driver_arguments(), MAX_STAGE_ITERATIONS, IMPLICIT_SOLVERS[implicit_solver])
        if self.tableau is None:  # the Taylor method: its order follows from the tolerances; the empty
            return (np.zeros(0),)   # carry restarts with each call (simulate passes one of size n instead)
        if isinstance(self.tableau, Composition | RadauIIA):
            return self.tableau.driver_arguments()
        return driver_arguments(self.tableau)

    @property
    def any_state(self) -> bool:
        """Whether the method integrates y' = f(t, y) for any first-order state y, e.g. a Kane model's (q, u),
        rather than needing the (q, q̇) of Lagrange's equations: the explicit Runge-Kutta tableaux, which
        take ``rhs``, and Radau IIA, which takes ``rhs`` and its Jacobian ``rhs_jacobian`` (∂f/∂y, emitted
        for Kane modules too)."""
        return isinstance(self.tableau, Tableau | RadauIIA)


def _embedded(name: str, tableau: Tableau, summary: str) -> Method:
    """An adaptive embedded Runge-Kutta pair: the library driver `embedded_run` with `tableau`'s data."""
    module = "lagcomp.integrate.drivers.embedded"
    return Method(name, tableau.order, True, f"{module}:embedded_run", tableau, summary,
                  kernels=("rhs", "project", "constraint_residual", "event_values", "event_reset"),
                  sweep=f"{module}_sweep:sweep_embedded")


#: The Gauss-Legendre driver, its sweep loop and the kernels of the canonical equations they take.
_COLLOCATION = "lagcomp.integrate.drivers.collocation:collocation_run"
_COLLOCATION_SWEEP = "lagcomp.integrate.drivers.collocation:collocation_sweep"
_CANONICAL_KERNELS = ("velocities", "momenta", "momentum_rate", "canonical_partials")
_COLLOCATION_CARRY = "lagcomp.integrate.drivers.collocation:new_carry"
#: The kernels a driver that switches charts takes after its `Method.kernels` (`Method.switches_charts`).
_CHART_KERNELS = ("event_values", "event_reset")

METHODS = {
    m.name: m
    for m in (
        Method("rk4", 4, False, f"{_FIXED_STEP}:runge_kutta_run", tableaux.RK4, "classic Runge-Kutta, fixed step `dt`",
               kernels=("rhs", "project", "constraint_residual"), sweep=f"{_FIXED_SWEEPS}:runge_kutta_sweep"),
        _embedded("dopri5", tableaux.DOPRI5, "Dormand-Prince 5(4), adaptive, quartic dense output (scipy's RK45)"),
        _embedded("dop853", tableaux.DOP853,
                  "Dormand-Prince 8(5,3), adaptive, 7th-order dense output (Hairer's DOP853)"),
        _embedded("tsit5", tableaux.TSIT5, "Tsitouras 5(4), adaptive, quartic dense output"),
        _embedded("bs3", tableaux.BS3, "Bogacki-Shampine 3(2), adaptive, cubic dense output (scipy's RK23)"),
        Method("verlet", 2, False, f"{_FIXED_STEP}:composition_run", compositions.VERLET,
               "Störmer-Verlet, symplectic, fixed step, separable systems", separable_only=True,
               kernels=("rhs",), sweep=f"{_FIXED_SWEEPS}:composition_sweep"),
        Method("yoshida4", 4, False, f"{_FIXED_STEP}:composition_run", compositions.YOSHIDA4,
               "Yoshida's triple-jump composition of Verlet, symplectic, order 4", separable_only=True,
               kernels=("rhs",), sweep=f"{_FIXED_SWEEPS}:composition_sweep"),
        Method("yoshida6", 6, False, f"{_FIXED_STEP}:composition_run", compositions.YOSHIDA6,
               "Yoshida's 7-stage composition of Verlet, symplectic, order 6", separable_only=True,
               kernels=("rhs",), sweep=f"{_FIXED_SWEEPS}:composition_sweep"),
        Method("rattle", 2, False, "lagcomp.integrate.drivers.rattle:rattle_run", compositions.VERLET,
               "RATTLE (constrained Störmer-Verlet), symplectic, fixed step, constraints held to round-off; "
               "separable systems with holonomic scleronomic constraints", holonomic_separable_only=True,
               kernels=("forcing", "mass_matrix", "constraint_residuals", "constraint_matrix", "CONSTRAINT_COUNT"),
               sweep="lagcomp.integrate.drivers.rattle:rattle_sweep"),
        Method("gauss1", 2, False, _COLLOCATION, collocation.GAUSS1,
               "implicit midpoint rule on (q, p), symplectic for any Lagrangian", unconstrained_only=True,
               kernels=_CANONICAL_KERNELS, sweep=_COLLOCATION_SWEEP, switches_charts=True,
               carry=_COLLOCATION_CARRY),
        Method("gauss2", 4, False, _COLLOCATION, collocation.GAUSS2,
               "2-stage Gauss-Legendre on (q, p), symplectic, order 4", unconstrained_only=True,
               kernels=_CANONICAL_KERNELS, sweep=_COLLOCATION_SWEEP, switches_charts=True,
               carry=_COLLOCATION_CARRY),
        Method("gauss3", 6, False, _COLLOCATION, collocation.GAUSS3,
               "3-stage Gauss-Legendre on (q, p), symplectic, order 6", unconstrained_only=True,
               kernels=_CANONICAL_KERNELS, sweep=_COLLOCATION_SWEEP, switches_charts=True,
               carry=_COLLOCATION_CARRY),
        Method("radau", 5, True, "lagcomp.integrate.drivers.radau:radau_run", radau.RADAU5,
               "Radau IIA order 5 (Hairer-Wanner's RADAU5), implicit, adaptive, for stiff systems, with the "
               "model's exact Jacobian; constrained systems as index-2 DAEs, constraints held without projection",
               kernels=("rhs", "rhs_jacobian", "event_values"), carry="lagcomp.integrate.drivers.radau:new_carry",
               dae_kernels=("dae_residual", "dae_jacobian", "event_values"), checks_residual=False,
               sweep="lagcomp.integrate.drivers.radau_sweep:sweep_radau"),
        Method("taylor", 20, True, "lagcomp.integrate.drivers.taylor:taylor_run", None,
               "Taylor series to order ceil(-ln(tol)/2 + 1) (20 at machine precision), adaptive, dense "
               "output from the series (Jorba & Zou); unconstrained systems", unconstrained_only=True,
               default_rtol=EPS, default_atol=None, rtol_min=EPS,
               # the model's Taylor kernel, its events' values and resets, and its data: periodic coordinates, work rows
               kernels=("taylor_coefficients", "event_values", "event_reset", "TAYLOR_PERIODIC", "TAYLOR_WORK"),
               sweep="lagcomp.integrate.drivers.taylor:sweep_taylor"),
    )
}

#: Other accepted spellings.
ALIASES = {"rk45": "dopri5", "dopri853": "dop853", "rk23": "bs3", "leapfrog": "verlet", "stormer_verlet": "verlet",
           "shake": "rattle",
           "midpoint": "gauss1", "gl1": "gauss1", "gl2": "gauss2", "gl3": "gauss3"}


#: {generated module: {(method name, addressed): its bound driver}} (`Method.bound_driver`).
_BOUND_DRIVERS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def _kernel(kernels, name: str):
    """The kernel `name` of the generated module `kernels`, or for an ``event_reset`` that resets nothing
    (``RESET_EVENTS`` empty) the library's `lagcomp.integrate.drivers.events.unchanged_state`, compiled once per
    installation rather than once per model."""
    if name == "event_reset" and not getattr(kernels, "RESET_EVENTS", True):
        from lagcomp.integrate.drivers.events import unchanged_state

        return unchanged_state
    return getattr(kernels, name)


def method_names(test) -> str:
    """The registry's methods that pass `test`, as "a, b or c" (messages name what would work)."""
    names = [name for name, m in METHODS.items() if test(m)]
    return ", ".join(names[:-1]) + " or " + names[-1] if len(names) > 1 else names[0]


def library_function(reference: str):
    """The function ``"package.module:name"`` names, imported now (numba loads or compiles it then).

    numba's cache files of the drivers that do not read back are removed and compiled again
    (`lagcomp.numba_cache.import_library_module`); those compiled from other library sources were
    removed when the drivers' package was imported (`lagcomp.numba_cache.refresh_stale_drivers`).
    """
    from lagcomp.numba_cache import import_library_module

    module, _, name = reference.partition(":")
    return getattr(import_library_module(module), name)


def implicit_solver_for(method: Method, name: str | None) -> str:
    """The stage-equation solver `name` checked against `method`; None gives the default."""
    from lagcomp.errors import OptionError

    if name is None:
        return DEFAULT_IMPLICIT_SOLVER
    if not isinstance(name, str) or name not in IMPLICIT_SOLVERS:
        raise OptionError(f"Unknown implicit_solver {name!r}; choose one of {', '.join(map(repr, IMPLICIT_SOLVERS))}.")
    if not method.implicit:
        implicit = ", ".join(m.name for m in METHODS.values() if m.implicit)
        raise OptionError(f"`implicit_solver` applies to the implicit methods ({implicit}); {method.name} is explicit.")
    return name


def get_method(name: str) -> Method:
    """The method called `name` (case-insensitive, aliases accepted)."""
    from lagcomp.errors import OptionError

    key = str(name).lower()
    key = ALIASES.get(key, key)
    if key not in METHODS:
        raise OptionError(f"Unknown method {name!r}; choose one of {', '.join(METHODS)}.")
    return METHODS[key]
