"""The user's description of a mechanical system.

A `System` is what a physicist writes down: generalized coordinates q_i(t),
the kinetic energy T(q, q̇, t), the potential V(q, t), generalized forces
Q_i(q, q̇, t) that do not derive from V, and a Rayleigh dissipation function
D(q, q̇, t) whose forces are −∂D/∂q̇_i.  Imposed motions are explicit
expressions of `t` written straight into T, V or Q (a hoop turned at
φ(t) = Ωt + ε sin 2t, a tray moved along a(t)).  Every other free symbol is a
parameter, passed by name at run time.

Instead of (or as well as) writing T, V and Q, a System may list `bodies`
(particles and rigid bodies, `lagcomp.model.bodies`) and `loads` (forces,
torques, springs, dampers, gravity, `lagcomp.model.loads`), described in a
`frame` that may move with an imposed motion (`lagcomp.model.frames`).  Their
kinetic and potential energies, generalized forces and dissipation are added
to what is written directly, once, when the System is built: the fields T, V,
forces and dissipation then hold the totals that the derivation uses.

Validation happens here, when the System is built, and is cheap (free-symbol
checks only); the symbolic derivation lives in `lagcomp.mechanics`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field, replace

import sympy as sp
from sympy.physics.mechanics import dynamicsymbols

from lagcomp.errors import InitialConditionError, ModelError, ParameterError, UndeclaredSymbolError
from lagcomp.names import by_name
from lagcomp.model.assemble import assemble
from lagcomp.model.constraints import Holonomic, Nonholonomic
from lagcomp.model.contacts import Contact
from lagcomp.model.friction import Friction
from lagcomp.model.frames import as_frame
from lagcomp.model.inputs import inputs_in, is_input, substitute_laws
from lagcomp.model.events import Event, reset_role, reset_target
from lagcomp.model.expressions import expression

#: The time symbol shared with ``sympy.physics.mechanics.dynamicsymbols``.
t = dynamicsymbols._t


def coordinates(names: str) -> tuple[sp.Function, ...]:
    """Generalized coordinates as functions of time, e.g. ``coordinates("x theta")``.

    Always returns a tuple, even for one name.  The result is interchangeable
    with ``sympy.physics.mechanics.dynamicsymbols``.
    """
    made = dynamicsymbols(names)
    return tuple(made) if isinstance(made, (list, tuple)) else (made,)


def _sympify(value, what: str) -> sp.Expr:
    return expression(value, f"`{what}`")


def _refuse_non_real(expr: sp.Expr, what: str) -> None:
    """Refuse the imaginary unit and infinities: the kernels compute in real float64."""
    if expr.has(sp.I):
        raise ModelError(f"{what} contains the imaginary unit I: lagcomp's systems are real; "
                         "write T, V, forces, constraints and events as real expressions.")
    bad = [value for value in (sp.zoo, sp.oo, -sp.oo, sp.nan) if expr.has(value)]
    if bad:
        raise ModelError(f"{what} contains {bad[0]}: every term must be finite.")


def _sequence(value, what: str, of: str) -> tuple:
    """`value` as a tuple (None as empty), or a ModelError naming the field and what it must hold."""
    if value is None:
        return ()
    if not isinstance(value, (str, bytes)):
        try:
            return tuple(value)
        except TypeError:
            pass
    raise ModelError(f"`{what}` must be a sequence of {of}, got {type(value).__name__} {value!r}.")


def _coordinate_tuple(coordinates) -> tuple:
    """The coordinates as a tuple: one coordinate alone is accepted as a sequence of one."""
    if _is_coordinate(coordinates):
        return (coordinates,)
    if isinstance(coordinates, (str, bytes)) or not hasattr(coordinates, "__iter__"):
        raise ModelError(f"`coordinates` must be a sequence of functions of t (from lagcomp.coordinates('q1 q2') "
                         f"or dynamicsymbols), got {type(coordinates).__name__} {coordinates!r}.")
    return tuple(coordinates)


def _is_coordinate(q) -> bool:
    return isinstance(q, sp.core.function.AppliedUndef) and q.args == (t,)


def _unique_names(names: list[str], kind: str) -> None:
    """Refuse two distinct symbols of one name (``Symbol("k")`` and ``Symbol("k", positive=True)``):
    values are passed by name, so the name must say which one is meant."""
    repeated = sorted({name for name in names if names.count(name) > 1})
    if repeated:
        raise ModelError(f"Distinct {kind} share the name(s) {repeated} (symbols that differ only in their "
                         "assumptions, or in their class): values are passed by name, so rename one of each.")


@dataclass(frozen=True)
class System:
    """A Lagrangian system: coordinates, energies, forces, and run defaults.

    Parameters
    ----------
    coordinates : sequence of functions of t
        The generalized coordinates q_i(t), from `coordinates` or
        ``dynamicsymbols``.  Their order is the order of q in every kernel.
    T : sympy expression, optional when `bodies` are given
        Kinetic energy T(q, q̇, t), at most quadratic in the velocities q̇ = q.diff(t).
    V : sympy expression, optional
        Potential energy V(q, t).
    forces : sequence or mapping, optional
        Generalized forces Q_i(q, q̇, t) not derived from V: one expression per
        coordinate, or a mapping {coordinate: Q} (missing ones are zero).
    dissipation : sympy expression, optional
        Rayleigh dissipation function D(q, q̇, t); adds −∂D/∂q̇_i to Q_i.
    constraints : sequence of Holonomic / Nonholonomic, optional
        Named constraints, enforced with Lagrange multipliers (reactions).
    parameters : sequence of symbols, optional
        The parameters in the order kernels receive them.  Inferred from the
        free symbols (sorted by name) when omitted; when given, any other free
        symbol is an error.
    name : str
        A Python identifier naming the system (module names, CLI, cache).
    description : str
        One line for ``lagcomp list``.
    defaults : mapping of str to float
        Default parameter values by name; ``simulate`` fills missing values from it.
    q0, qd0 : sequence of float, optional
        Default initial coordinates and velocities.
    t_end : float
        Default length of a run started from the command line.
    events : sequence of Event, optional
        Named functions g(t, q, q̇) whose zeros the adaptive methods locate
        (`lagcomp.model.events`); compiled with the other kernels.
    bodies : sequence of Particle / RigidBody, optional
        Bodies whose kinetic energy (and own potential) is added to T (and V);
        sympy.physics.mechanics Particle and RigidBody are accepted.
    loads : sequence, optional
        Force, Torque, Spring, Damper, Gravity, or sympy.physics.mechanics load
        pairs; they add to `forces`, V and `dissipation`.
    frame : ReferenceFrame or MovingFrame, optional
        The frame bodies and loads are described in: a sympy ReferenceFrame
        (Galilean; needed for sympy.physics.vector objects), or a MovingFrame
        with an imposed acceleration and rotation, whose inertial terms are
        added for every body.  T, V and forces written directly are taken as given.

    After construction T, V, forces and dissipation hold the totals (written
    directly plus bodies and loads); `dataclasses.replace` keeps track of which
    part was written directly, so replacing `bodies` or any other field does not count
    the bodies twice.
    """

    coordinates: tuple
    T: sp.Expr = sp.S.Zero
    V: sp.Expr = sp.S.Zero
    forces: tuple = ()
    dissipation: sp.Expr = sp.S.Zero
    constraints: tuple = ()
    parameters: tuple | None = None
    name: str = "system"
    description: str = ""
    defaults: Mapping[str, float] = field(default_factory=dict)
    q0: tuple | None = None
    qd0: tuple | None = None
    t_end: float = 10.0
    events: tuple = ()
    bodies: tuple = ()
    loads: tuple = ()
    frame: object = None
    #: (what was written directly, the totals) when bodies or loads were merged in; see `_merge`.
    _written: tuple | None = field(default=None, repr=False, compare=False)
    #: The inputs supplied at run time, u(t) of `lagcomp.model.inputs.Input` without a law, sorted by name.
    _inputs: tuple = field(default=(), init=False, repr=False, compare=False)

    def __post_init__(self):
        coords = _coordinate_tuple(self.coordinates)
        if not coords:
            raise ModelError("A System needs at least one coordinate.")
        for q in coords:
            if not _is_coordinate(q):
                raise ModelError(
                    f"Coordinate {q!r} is not a function of t; create coordinates with "
                    "lagcomp.coordinates('q1 q2') or sympy.physics.mechanics.dynamicsymbols."
                )
        if len(set(coords)) != len(coords):
            raise ModelError(f"Coordinates are repeated: {coords}.")
        _unique_names([q.func.__name__ for q in coords], "coordinates")
        if not isinstance(self.name, str) or not self.name.isidentifier():
            raise ModelError(f"System name {self.name!r} must be a Python identifier, like 'double_pendulum'.")
        set_ = object.__setattr__
        set_(self, "coordinates", coords)
        self._normalize_containers()
        set_(self, "T", _sympify(self.T, "T"))
        set_(self, "V", _sympify(self.V, "V"))
        set_(self, "dissipation", _sympify(self.dissipation, "dissipation"))
        set_(self, "forces", self._normalized_forces(coords))
        roles = self._merge(coords)
        set_(self, "constraints", self._checked_constraints())
        set_(self, "events", self._checked_events())
        self._substitute_laws()
        for role, expr in self.expressions().items():
            _refuse_non_real(expr, role)
        set_(self, "parameters", self._checked_parameters(coords, roles))
        _unique_names([s.name for s in self.parameters], "parameters")
        self._check_input_names()
        set_(self, "defaults", self._checked_defaults())
        set_(self, "q0", self._checked_initial(self.q0, "q0"))
        set_(self, "qd0", self._checked_initial(self.qd0, "qd0"))

    def _normalize_containers(self) -> None:
        """The sequence and mapping fields as tuples and dicts, and the plain fields checked, before any use."""
        set_ = object.__setattr__
        for what, of in (("constraints", "Holonomic / Nonholonomic constraints"), ("events", "Events"),
                         ("bodies", "Particles / RigidBodies"), ("loads", "loads (Force, Torque, Spring, ...)")):
            set_(self, what, _sequence(getattr(self, what), what, of))
        if self.parameters is not None:
            set_(self, "parameters", _sequence(self.parameters, "parameters", "sympy Symbols"))
        if not isinstance(self.forces, Mapping):
            set_(self, "forces", _sequence(self.forces, "forces", "generalized forces, one per coordinate"))
        if self.defaults is None:
            set_(self, "defaults", {})
        if not isinstance(self.defaults, Mapping):
            raise ParameterError(f"`defaults` must be a mapping of parameter name to value, like {{'m': 1.0}}, "
                                 f"got {type(self.defaults).__name__}.")
        if not isinstance(self.description, str):
            raise ModelError(f"`description` must be a string, got {type(self.description).__name__}.")
        try:
            t_end = float(self.t_end)
        except (TypeError, ValueError):
            t_end = math.nan
        if isinstance(self.t_end, bool) or not (t_end > 0 and math.isfinite(t_end)):
            raise ModelError(f"`t_end` must be a positive, finite number of time units, got {self.t_end!r}.")
        set_(self, "t_end", t_end)

    # -- bodies and loads ----------------------------------------------------------

    def _merge(self, coords) -> dict:
        """Add the bodies' and loads' T, V, Q and D to the fields; return their roles for validation.

        A System made by `dataclasses.replace` receives the totals of the old one
        in T, V, forces and dissipation, and `_written` = (written, totals): a field
        still equal to the old total is taken back to what was written directly.
        """
        set_ = object.__setattr__
        given = (self.T, self.V, self.forces, self.dissipation)
        if self._written is not None:
            written, totals = self._written
            given = tuple(w if g == tot else g for g, w, tot in zip(given, written, totals))
        frame = as_frame(self.frame)
        set_(self, "bodies", tuple(self.bodies))
        set_(self, "loads", tuple(self.loads))
        if not self.bodies and not self.loads:
            set_(self, "_written", None)
            T, V, forces, D = given
            set_(self, "T", T), set_(self, "V", V), set_(self, "forces", forces), set_(self, "dissipation", D)
            if T == 0:
                raise ModelError(f"{self.name!r} has no kinetic energy: give T, or bodies whose T lagcomp writes.")
            return {}
        parts = assemble(coords, self.bodies, self.loads, frame)
        T, V, forces, D = given
        totals = (T + parts.T, V + parts.V, tuple(a + b for a, b in zip(forces, parts.Q)), D + parts.D)
        set_(self, "bodies", parts.bodies)
        set_(self, "loads", parts.loads)
        set_(self, "T", totals[0]), set_(self, "V", totals[1])
        set_(self, "forces", totals[2]), set_(self, "dissipation", totals[3])
        set_(self, "_written", (given, totals))
        if totals[0] == 0:
            raise ModelError(f"{self.name!r} has no kinetic energy: its bodies are all massless and T is not given.")
        return parts.roles

    # -- inputs ---------------------------------------------------------------------

    def _substitute_laws(self) -> None:
        """Replace every Input that has a feedback law by the law, in every expression (and in the totals
        `_written` keeps, so that `dataclasses.replace` still recognizes them); record the other inputs."""
        set_ = object.__setattr__
        velocities = [q.diff(t) for q in self.coordinates]
        new = substitute_laws(self.expressions(), velocities)
        if any(new[role] is not expr for role, expr in self.expressions().items()):
            set_(self, "T", new["T"]), set_(self, "V", new["V"]), set_(self, "dissipation", new["dissipation"])
            forces = tuple(new[f"forces[{q.func.__name__}]"] for q in self.coordinates)
            set_(self, "forces", forces)
            set_(self, "constraints", tuple(
                replace(c, **{"Phi" if isinstance(c, Holonomic) else "expr": new[f"constraint {c.name}"]})
                for c in self.constraints))
            set_(self, "events", tuple(replace(e, expr=new[f"event {e.name}"], reset=None if e.reset is None else
                                               tuple((k, new[reset_role(e, k)]) for k, _ in e.reset))
                                       for e in self.events))
            if self._written is not None:
                set_(self, "_written", (self._written[0], (self.T, self.V, forces, self.dissipation)))
        set_(self, "_inputs", inputs_in(self.expressions().values()))
        for e in self.events:
            read = inputs_in(value for _, value in e.reset or ())
            if read:
                raise ModelError(f"Event `{e.name}`: its reset reads the input {read[0]}, which resets cannot read "
                                 "yet; write the value from the state, t and parameters, or give the input a law.")

    def _check_input_names(self) -> None:
        """Refuse an input named like a coordinate or a parameter, or two inputs of one name: inputs are
        supplied by name."""
        names = [u.func.__name__ for u in self._inputs]
        _unique_names(names, "inputs")
        taken = {*self.coordinate_names, *self.parameter_names}
        clash = sorted(set(names) & taken)
        if clash:
            raise ModelError(f"Input(s) {clash} of {self.name!r} are named like a coordinate or a parameter; "
                             "inputs are supplied by name at run time: rename them.")

    @property
    def inputs(self) -> tuple:
        """The inputs u(t) supplied at run time (those without a law), sorted by name."""
        return self._inputs

    @property
    def input_names(self) -> tuple[str, ...]:
        return tuple(u.func.__name__ for u in self._inputs)

    # -- validation ---------------------------------------------------------------

    def _normalized_forces(self, coords) -> tuple:
        forces = self.forces
        if isinstance(forces, Mapping):
            unknown = [k for k in forces if k not in coords]
            if unknown:
                raise ModelError(f"`forces` names {unknown}, which are not coordinates of {self.name!r}.")
            return tuple(_sympify(forces.get(q, 0), f"forces[{q}]") for q in coords)
        if not forces:
            return (sp.S.Zero,) * len(coords)
        if len(forces) != len(coords):
            raise ModelError(
                f"`forces` has {len(forces)} entries but there are {len(coords)} coordinates; "
                "give one generalized force per coordinate or a mapping {coordinate: force}."
            )
        return tuple(_sympify(Q, f"forces[{i}]") for i, Q in enumerate(forces))

    def _checked_constraints(self) -> tuple:
        constraints = tuple(self.constraints)
        for c in constraints:
            if not isinstance(c, (Holonomic, Nonholonomic)):
                raise ModelError(f"Constraint {c!r} must be a lagcomp Holonomic or Nonholonomic constraint.")
        names = [c.name for c in constraints]
        repeated = sorted({n for n in names if names.count(n) > 1})
        if repeated:
            raise ModelError(f"Constraint names must be unique; repeated: {repeated}.")
        velocities = [q.diff(t) for q in self.coordinates]
        for c in constraints:
            if isinstance(c, Holonomic) and c.Phi.has(*velocities):
                raise ModelError(
                    f"Holonomic constraint `{c.name}` contains velocities; declare it as Nonholonomic(name, expr) instead."
                )
        return constraints

    def _checked_events(self) -> tuple:
        events = tuple(self.events)
        for e in events:
            if not isinstance(e, Event):
                raise ModelError(f"Event {e!r} must be a lagcomp Event(name, expr, direction, terminal).")
        names = [e.name for e in events]
        repeated = sorted({n for n in names if names.count(n) > 1})
        if repeated:
            raise ModelError(f"Event names must be unique; repeated: {repeated}.")
        for e in events:
            for key, _ in e.reset or ():
                coordinate, _ = reset_target(key)
                if coordinate not in self.coordinates:
                    raise ModelError(f"Event `{e.name}`: its reset sets {key}, but {coordinate} is not a coordinate "
                                     f"of {self.name!r} (coordinates {list(self.coordinate_names)}).")
        contacts = [e.name for e in events if isinstance(e, Contact)]
        for e in events:
            if isinstance(e, Friction) and isinstance(e.normal, str) and e.normal not in contacts:
                raise ModelError(f"Friction `{e.name}`: normal={e.normal!r} names no contact of this system "
                                 f"(contacts {contacts}); give a Contact's name or N as an expression.")
        return events

    def expressions(self) -> dict[str, sp.Expr]:
        """Every user expression by role, for validation and display."""
        exprs = {"T": self.T, "V": self.V, "dissipation": self.dissipation}
        exprs.update({f"forces[{q.func.__name__}]": Q for q, Q in zip(self.coordinates, self.forces)})
        exprs.update({f"constraint {c.name}": c.expr for c in self.constraints})
        exprs.update({f"event {e.name}": e.expr for e in self.events})
        exprs.update({reset_role(e, key): value for e in self.events for key, value in e.reset or ()})
        exprs.update({f"contact {e.name} restitution": e.restitution for e in self.events if isinstance(e, Contact)})
        exprs.update({f"friction {e.name} {part}": getattr(e, part) for e in self.events if isinstance(e, Friction)
                      for part in ("normal", "static", "kinetic") if not isinstance(getattr(e, part), str)})
        return exprs

    @property
    def constraint_names(self) -> tuple[str, ...]:
        return tuple(c.name for c in self.constraints)

    @property
    def event_names(self) -> tuple[str, ...]:
        return tuple(e.name for e in self.events)

    def _checked_parameters(self, coords, roles=None) -> tuple:
        found: set[sp.Symbol] = set()
        for role, expr in {**(roles or {}), **self.expressions()}.items():
            for f in expr.atoms(sp.core.function.AppliedUndef):
                if f not in coords and not (is_input(f) and f.args == (t,)):
                    raise UndeclaredSymbolError(
                        f"{f} in {role} is not a coordinate of {self.name!r}: add it to the coordinates, "
                        "write an imposed motion as an explicit expression of t, or make it an input (lagcomp.Input)."
                    )
            found |= {s for s in expr.free_symbols if s != t}
        impostor = next((s for s in found if s.name == t.name), None)
        if impostor is not None:
            raise ModelError(
                f"{self.name!r} contains a symbol named t ({sp.srepr(impostor)}) that is not lagcomp's time "
                "symbol, so it would become a parameter: write imposed motions with lagcomp.t "
                "(= sympy.physics.mechanics.dynamicsymbols._t)."
            )
        if self.parameters is None:
            return tuple(sorted(found, key=lambda s: s.name))
        declared = tuple(self.parameters)
        for s in declared:
            if not isinstance(s, sp.Symbol):
                raise ModelError(f"Parameter {s!r} must be a sympy Symbol.")
        undeclared = sorted(found - set(declared), key=lambda s: s.name)
        if undeclared:
            where = next((role for role, expr in {**(roles or {}), **self.expressions()}.items()
                          if expr.has(undeclared[0])), None)
            raise UndeclaredSymbolError(
                f"Symbol(s) {', '.join(s.name for s in undeclared)} appear in {self.name!r}"
                f"{f' (first in {where})' if where else ''} but are neither "
                "coordinates, parameters nor t: add them to `parameters` (or omit `parameters` to infer them)."
            )
        return declared

    def _checked_defaults(self) -> dict:
        names = {s.name for s in self.parameters}
        named = by_name(self.defaults, "defaults", sorted(names))
        unknown = sorted(set(named) - names)
        if unknown:
            raise ParameterError(f"Default values given for unknown parameter(s) {unknown}; parameters are {sorted(names)}.")
        checked = {}
        for k, v in named.items():
            try:
                v = float(v)
            except (TypeError, ValueError) as err:
                raise ParameterError(f"Default value of parameter `{k}` must be a number, got {v!r}.") from err
            if not math.isfinite(v):
                raise ParameterError(f"Default value of parameter `{k}` is {v}; it must be finite.")
            checked[k] = v
        return checked

    def _checked_initial(self, values, what: str):
        if values is None:
            return None
        try:
            values = tuple(float(v) for v in values)
        except (TypeError, ValueError) as err:
            raise InitialConditionError(
                f"`{what}` must be a sequence of {len(self.coordinates)} numbers (one per coordinate "
                f"{list(self.coordinate_names)}), got {values!r}."
            ) from err
        if len(values) != len(self.coordinates):
            raise InitialConditionError(f"`{what}` has {len(values)} values for {len(self.coordinates)} coordinates.")
        if not all(math.isfinite(v) for v in values):
            raise InitialConditionError(f"`{what}` = {list(values)} is not finite.")
        return values

    # -- views --------------------------------------------------------------------

    @property
    def n(self) -> int:
        """Number of generalized coordinates."""
        return len(self.coordinates)

    @property
    def coordinate_names(self) -> tuple[str, ...]:
        return tuple(q.func.__name__ for q in self.coordinates)

    @property
    def parameter_names(self) -> tuple[str, ...]:
        return tuple(s.name for s in self.parameters)

    def fingerprint(self) -> str:
        """A canonical text of everything the derivation depends on (for cache keys)."""
        parts = [self.name, repr(self.coordinate_names), repr(self.parameter_names)]
        parts += [f"{role}={sp.srepr(expr)}" for role, expr in self.expressions().items()]
        parts += [f"{type(c).__name__} {c.name}" for c in self.constraints]
        if self._inputs:  # (an input prints as a function of t: its name says that it is one)
            parts.append(f"inputs={self.input_names!r}")
        return "\n".join(parts)
