r"""Kane's equations as ``sympy.physics.mechanics.KanesMethod`` forms them, as a `FirstOrderForm`.

`kane_form(km)` reads a KanesMethod after ``km.kanes_equations(bodies, loads)``
and returns, over plain symbols (q_i(t) → q_i, u_i(t) → u_i):

    q̇ = N(q, u, t)       from ``km.kindiffdict()`` (the kinematic differential equations)
    M(q, t) u̇ = F         ``km.mass_matrix`` and ``km.forcing``: sympy's convention is
                          mass_matrix · u̇ = forcing; with velocity constraints the last
                          n_v rows are the constraints differentiated once, so M is
                          n_u × n_u, square, and in general not symmetric
    Φ(q, t) = 0           the configuration constraints (``km._f_h``, which sympy
                          does not expose publicly)
    Ψ(q, u, t) = 0        the velocity constraints k_nh u + f_nh = 0

No multipliers (C has no rows): Kane's method eliminates the constraint forces.
u is ordered as KanesMethod orders it (independent speeds, then dependent
ones), q likewise.  Because the differentiated velocity constraints are rows
of M, Ψ stays at its initial value along exact solutions: a run must start
with Ψ = 0 (and Φ = 0), which `lagcomp.kane_model` checks.

Every symbol that is neither a coordinate, a speed nor t is a parameter
(sorted by name unless the caller orders them).  Functions of time other than
q and u ("specified" inputs) are refused: lagcomp passes parameters as
numbers.

`kane_energy(km, form)` is T + V when it can be formed: T from the bodies'
kinetic energies in N (as the model states their velocities, in u), V from
the bodies' ``potential_energy`` plus, for each load that is a constant
force in N on a point, −F · r with r the point's position from a point of its
position tree whose velocity in N is set to zero — accepted only when dV/dt = −F · v holds at random states
(so that a force whose point moves other than its position says is not
turned into a wrong potential).  Otherwise None, and the kernel returns NaN.

`kane_events(km, form, events)`: the g(q, u, t) of `lagcomp.Event`s over the
same plain symbols, for the event kernel.

`auxiliary_reactions(km, form)`: with auxiliary speeds, ``km.auxiliary_eqs``
= 0 determines the noncontributing forces the user applied (functions of t
that appear only there); they are solved symbolically as functions of
(q, u, u̇) and returned by name, to be evaluated at the u̇ of the dynamics.
"""

from __future__ import annotations

import random

import sympy as sp
from sympy.physics import mechanics as me
from sympy.physics.mechanics import dynamicsymbols

from lagcomp.errors import ModelError
from lagcomp.mechanics.first_order import FirstOrderForm

__all__ = ["kane_form", "kane_energy", "auxiliary_reactions"]

t = dynamicsymbols._t


def _name(f) -> str:
    return f.func.__name__


class _Plain:
    """Rewrites expressions of a KanesMethod over plain symbols: q̇ by N, then q(t) → q, u(t) → u."""

    def __init__(self, km: me.KanesMethod, extra=()):
        self.q, self.u = list(km.q), list(km.u)
        self.kindiff = km.kindiffdict()
        functions = self.q + self.u + list(extra)
        self.symbols = {f: sp.Symbol(_name(f), real=True) for f in functions}
        self.udot = {u.diff(t): sp.Symbol(f"_{_name(u)}_dot", real=True) for u in self.u}

    def __call__(self, expr, what: str, accelerations: bool = False):
        expr = sp.sympify(expr).xreplace(self.kindiff)
        if accelerations:
            expr = expr.xreplace(self.udot)
        left = expr.atoms(sp.Derivative)
        if left:
            raise ModelError(f"{what} still holds the derivative(s) {sorted(map(str, left))} after the kinematic "
                             "differential equations were substituted; KanesMethod's equations should not.")
        expr = expr.xreplace(self.symbols)
        specified = {f for f in expr.atoms(sp.core.function.AppliedUndef) if t in f.args}
        if specified:
            raise ModelError(
                f"{what} depends on {sorted(map(str, specified))}, functions of time that are neither coordinates "
                "nor speeds of the KanesMethod: lagcomp passes parameters as numbers. Replace them by symbols "
                "(parameters) or by explicit expressions of t."
            )
        return expr


def _matrix(value, rows: int, cols: int = 1) -> sp.Matrix:
    return sp.zeros(rows, cols) if value is None or getattr(value, "shape", (0,))[0] == 0 else sp.Matrix(value)


def kane_form(km: me.KanesMethod, parameters=None) -> FirstOrderForm:
    """The `FirstOrderForm` of `km` (module docstring); `parameters` fixes the parameter order."""
    if not isinstance(km, me.KanesMethod):
        raise ModelError(f"kane_form needs a sympy KanesMethod, got {type(km).__name__}.")
    try:
        M, F = km.mass_matrix, km.forcing
    except ValueError as err:
        raise ModelError("The KanesMethod has no equations yet: call km.kanes_equations(bodies, loads) "
                         "before compiling it.") from err
    plain = _Plain(km, _auxiliary_unknowns(km))
    q, u = list(km.q), list(km.u)
    qd = [x.diff(t) for x in q]
    missing = [str(x) for x in qd if x not in plain.kindiff]
    if missing:
        raise ModelError(f"The kinematic differential equations do not give {missing}: KanesMethod needs one per "
                         "coordinate (kd_eqs).")
    N = sp.Matrix([plain(plain.kindiff[x], "the kinematic differential equations") for x in qd])
    M = plain(sp.Matrix(M), "the mass matrix")
    F = plain(sp.Matrix(F), "the forcing")
    Phi = plain(_matrix(km._f_h, 0), "the configuration constraints")
    k_nh = getattr(km, "_k_nh", None)
    Psi = sp.zeros(0, 1)
    if k_nh is not None and k_nh.shape[0]:
        Psi = plain(k_nh * sp.Matrix(u) + km._f_nh, "the velocity constraints")
    qs, us = tuple(plain.symbols[x] for x in q), tuple(plain.symbols[x] for x in u)
    return FirstOrderForm(
        q=qs, u=us, parameters=_parameters([N, M, F, Phi, Psi], set(qs) | set(us), parameters),
        coordinate_names=tuple(s.name for s in qs), speed_names=tuple(s.name for s in us),
        N=N, M=M, F=F, C=sp.zeros(0, len(u)), gamma=sp.zeros(0, 1), Phi=Phi, Psi=Psi,
    )


def _parameters(matrices, state: set, order) -> tuple:
    """The parameters: free symbols other than the state and t, sorted by name or in `order`."""
    time = sp.Symbol(t.name, real=True)
    free = set().union(*(m.free_symbols for m in matrices)) - state - {t, time}
    if order is None:
        return tuple(sorted(free, key=lambda s: s.name))
    by_name = {s.name: s for s in free}
    names = [str(s) for s in order]
    missing = sorted(set(by_name) - set(names))
    if missing:
        raise ModelError(f"`parameters` leaves out {missing}, which the KanesMethod's equations use.")
    return tuple(by_name.get(n, sp.Symbol(n, real=True)) for n in names)


def _auxiliary_unknowns(km) -> list:
    """The noncontributing forces: functions of t in ``auxiliary_eqs`` other than q, u and u̇."""
    if not len(km._uaux):
        return []
    known = set(km.q) | set(km.u) | set(km._uaux)
    functions = set().union(*(e.atoms(sp.core.function.AppliedUndef) for e in km.auxiliary_eqs))
    return sorted((f for f in functions if t in f.args and f not in known), key=str)


def auxiliary_reactions(km: me.KanesMethod, form: FirstOrderForm) -> tuple[tuple[str, ...], sp.Matrix]:
    """Names and expressions, over (q, u, u̇ = ``_<u>_dot``), of the noncontributing forces.

    Empty without auxiliary speeds.  Raises ModelError when ``auxiliary_eqs`` = 0
    does not determine them (as many unknown forces as auxiliary speeds, entering linearly).
    """
    unknowns = _auxiliary_unknowns(km)
    if not len(km._uaux):
        return (), sp.zeros(0, 1)
    if len(unknowns) != len(km._uaux):
        raise ModelError(
            f"The KanesMethod has {len(km._uaux)} auxiliary speed(s) {[str(x) for x in km._uaux]} but its "
            f"auxiliary equations hold {len(unknowns)} unknown force(s) {[str(x) for x in unknowns]}: lagcomp "
            "reports the noncontributing forces as reactions, one per auxiliary speed, named by the functions of "
            "time (e.g. R = dynamicsymbols('R')) you apply along the auxiliary directions."
        )
    plain = _Plain(km, unknowns)
    eqs = plain(sp.Matrix(km.auxiliary_eqs), "the auxiliary equations", accelerations=True)
    symbols = [plain.symbols[f] for f in unknowns]
    A, b = sp.linear_eq_to_matrix(list(eqs), symbols)
    if A.free_symbols & set(symbols) or A.det() == 0:
        raise ModelError("The auxiliary equations do not determine the noncontributing forces "
                         f"{[str(x) for x in unknowns]} (not linear in them, or singular).")
    return tuple(s.name for s in symbols), A.LUsolve(b)


def kane_events(km: me.KanesMethod, form: FirstOrderForm, events) -> tuple[tuple, tuple]:
    """(the `lagcomp.Event`s, their g over the plain symbols of `form`) of a Kane model.

    g may hold q(t), u(t), q̇ (replaced by N from the kinematic equations), t
    and parameters of the equations; any other symbol is refused by name
    (a parameter the equations lack would have no slot in p).
    """
    from lagcomp.model.contacts import Contact
    from lagcomp.model.events import Event
    from lagcomp.model.friction import Friction

    plain = _Plain(km)
    allowed = set(form.q) | set(form.u) | set(form.parameters) | {t}
    specs, exprs = [], []
    for event in events or ():
        if not isinstance(event, Event):
            raise ModelError(f"`events` of a KanesMethod are lagcomp.Event(name, g(q, u, t)), got {event!r}.")
        if isinstance(event, Friction):
            raise ModelError(f"Friction `{event.name}` on a KanesMethod: stick-slip needs the Lagrange form (M from "
                             "T); build the model as a lagcomp.System.")
        if isinstance(event, Contact):
            raise ModelError(f"Contact `{event.name}` on a KanesMethod: impacts need the Lagrange form (M from T); "
                             "build the model as a lagcomp.System, or use an Event with a reset.")
        g = plain(event.expr, f"event `{event.name}`")
        stray = sorted(str(x) for x in g.free_symbols - allowed)
        if stray:
            raise ModelError(f"Event `{event.name}` holds {stray}, which are neither coordinates, speeds, t nor "
                             f"parameters of the KanesMethod's equations {[x.name for x in form.parameters]}.")
        specs.append(event)
        exprs.append(g)
    names = [e.name for e in specs]
    if len(set(names)) != len(names):
        raise ModelError(f"Event names must be distinct, got {names}.")
    return tuple(specs), tuple(exprs)


def kane_resets(km: me.KanesMethod, form: FirstOrderForm, events) -> tuple:
    """Per event of `events` (`kane_events`' specs), its reset over the state (q, u) of `form`: ((state index,
    value), ...), () for none.  The keys are coordinates q(t) or speeds u(t) of `km` (a Kane state holds u, not
    q̇); the values hold what g may (q, u, q̇ by N, t, the equations' parameters, and by name those `parameters`
    declares besides), as the state before the event."""
    plain = _Plain(km)
    allowed = set(form.q) | set(form.u) | set(form.parameters) | {t}
    # a parameter only `parameters` declares (a restitution the equations lack) is a plain real symbol: by name
    declared = {s.name: s for s in form.parameters}
    index = {f: i for i, f in enumerate([*km.q, *km.u])}
    resets = []
    for event in events:
        reset = []
        for key, value in event.reset or ():
            if key not in index:
                raise ModelError(f"Event `{event.name}`: its reset sets {key}, which is neither a coordinate nor a "
                                 f"speed of the KanesMethod (q {list(km.q)}, u {list(km.u)}): a Kane model's state is "
                                 "(q, u), reset its speeds u(t).")
            v = plain(value, f"the reset of event `{event.name}`")
            v = v.xreplace({s: declared[s.name] for s in v.free_symbols - allowed if s.name in declared})
            stray = sorted(str(x) for x in v.free_symbols - allowed)
            if stray:
                raise ModelError(f"Event `{event.name}`: its reset of {key} holds {stray}, which are neither "
                                 "coordinates, speeds, t nor parameters of the KanesMethod's equations "
                                 f"{[x.name for x in form.parameters]}.")
            reset.append((index[key], v))
        resets.append(tuple(reset))
    return tuple(resets)


def acceleration_symbols(form: FirstOrderForm) -> tuple:
    """The symbols standing for u̇ in `auxiliary_reactions` (``_<u>_dot``), in the order of u."""
    return tuple(sp.Symbol(f"_{s.name}_dot", real=True) for s in form.u)


def kane_energy(km: me.KanesMethod, form: FirstOrderForm, samples: int = 3) -> sp.Expr | None:
    """T + V of `km` over the plain symbols of `form`, or None (module docstring)."""
    plain = _Plain(km, _auxiliary_unknowns(km))
    N = km._inertial
    try:
        T = sum((b.kinetic_energy(N) for b in km.bodies), sp.S.Zero)
        V = sum((sp.sympify(b.potential_energy) for b in km.bodies), sp.S.Zero)
    except (ValueError, AttributeError):
        return None
    check, origin = sp.S.Zero, None
    for load in km.loads or ():
        where, force = load
        if not isinstance(where, me.Point):
            return None
        F = force.to_matrix(N)
        if F.has(*km.q, *km.u, t):
            return None
        origin = origin or _fixed_point(where, N)
        if origin is None:
            return None
        try:
            r = where.pos_from(origin).to_matrix(N)
            v = where.vel(N).to_matrix(N)
        except ValueError:
            return None
        V -= F.dot(r)
        check += F.dot(v)
    V_plain = plain(V, "the potential energy")
    rate = sum((V_plain.diff(x) * n for x, n in zip(form.q, form.N)), sp.S.Zero) + plain(check, "the power")
    if not _vanishes(rate, form, samples):
        return None
    return plain(T, "the kinetic energy") + V_plain


def _fixed_point(point: me.Point, frame) -> me.Point | None:
    """A point of `point`'s position tree whose velocity in `frame` was set to zero, or None."""
    seen, todo = {point}, [point]
    while todo:
        current = todo.pop()
        if current._vel_dict.get(frame) == 0:
            return current
        for other in current._pos_dict:
            if other not in seen:
                seen.add(other)
                todo.append(other)
    return None


def _vanishes(expr: sp.Expr, form: FirstOrderForm, samples: int) -> bool:
    """Whether `expr` is zero at `samples` random states and parameter values (to 1e-9 relative)."""
    rng = random.Random(1)
    symbols = sorted(expr.free_symbols, key=lambda s: s.name)
    for _ in range(samples):
        values = {s: sp.Float(rng.uniform(0.3, 1.3)) for s in symbols}
        scale = sum(abs(sp.Float(a.xreplace(values).evalf(30))) for a in sp.Add.make_args(expr)) or 1
        if abs(sp.Float(expr.xreplace(values).evalf(30))) > 1e-9 * scale:
            return False
    return True
