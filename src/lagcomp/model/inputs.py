r"""Input signals u(t): quantities the equations read but do not determine (sympy only).

``lc.Input("x_s")`` is u(t), an applied undefined function of `t` like a
coordinate, so the derivation differentiates it by the chain rule: a support
motion x_s(t) written into T brings ẋ_s into the momenta and ẍ_s into the
forcing, exactly as an imposed motion written as an expression of t would.
It may appear anywhere a System takes an expression: T, V, forces,
dissipation, constraints, events, a MovingFrame's motion, bodies and loads.

Two kinds, told apart when the System is built:

* **supplied at run time** (no `law`): the kernels read u, u̇, ü from data in
  the parameter vector (`lagcomp.kernel_support.inputs`), so
  ``model.simulate(..., inputs={"x_s": (times, values)})`` may change the
  signal — its values and its length — without recompiling anything;
* **a feedback law** (``law=`` an expression of q, q̇, t and parameters, and
  other inputs): substituted into every expression of the System before the
  derivation, so Jacobians and linearizations (`lagcomp.analysis`) include
  it; its gains are ordinary parameters.

An input is marked by the keyword ``lagcomp_input`` of its sympy Function, so
that it never equals a coordinate of the same name (``dynamicsymbols("x")``):
sympy keeps a Function's keywords in its identity.
"""

from __future__ import annotations

import sympy as sp
from sympy.physics.mechanics import dynamicsymbols

from lagcomp.errors import ModelError
from lagcomp.model.expressions import expression

#: Highest derivative of an input the kernels evaluate: the pieces are cubic, their third derivative is the last
#: one that is not zero (piecewise constant).
MAX_ORDER = 3

#: The time symbol (`lagcomp.model.system.t`, which imports this module).
t = dynamicsymbols._t


def Input(name: str, law=None) -> sp.Expr:  # noqa: N802 (a constructor, like sympy's Function)
    """An input signal u(t) named ``name``, supplied at run time or given by a feedback `law`.

    Parameters
    ----------
    name : str
        The input's name, used in ``simulate(inputs={name: ...})``; any non-empty string (the kernels
        mangle it like every user name), but not the name of a coordinate or parameter of its System.
    law : sympy expression, optional
        A feedback law of the coordinates, their velocities ``q.diff(lc.t)``, `t`, parameters and other
        inputs, compiled with the model (``lc.Input("tau", law=-Kp*th - Kd*th.diff(lc.t))``).  Without
        it the input is a signal supplied at run time (`lagcomp.Tabulated`).

    Returns
    -------
    sympy expression
        u(t), to be written into T, V, forces, constraints, events, motions.
    """
    if not isinstance(name, str) or not name:
        raise ModelError(f"An Input's name must be a non-empty string, got {name!r}.")
    if law is None:
        return sp.Function(name, lagcomp_input=True, real=True)(t)
    return sp.Function(name, lagcomp_input=True, real=True, lagcomp_law=expression(law, f"Input `{name}`: the law"))(t)


def is_input(expr) -> bool:
    """Whether `expr` is an input u(t) made by `Input` (with or without a law)."""
    return isinstance(expr, sp.core.function.AppliedUndef) and bool(getattr(expr.func, "lagcomp_input", False))


def law_of(u) -> sp.Expr | None:
    """The feedback law of input `u`, or None for a signal supplied at run time."""
    return getattr(u.func, "lagcomp_law", None)


def inputs_in(exprs) -> tuple:
    """The inputs u(t) appearing in `exprs`, sorted by name."""
    found = {f for e in exprs for f in e.atoms(sp.core.function.AppliedUndef) if is_input(f)}
    return tuple(sorted(found, key=lambda u: u.func.__name__))


def substitute_laws(exprs: dict, velocities) -> dict:
    """`exprs` (role -> expression) with every input that has a law replaced by the law.

    A law may use other inputs (a reference signal θ_ref(t) in τ = −Kp (θ − θ_ref)), with laws of
    their own or not.  Laws that end up inside T or a constraint must not hold a velocity
    (`velocities`): T would no longer be quadratic in q̇ nor a constraint of the form lagcomp
    solves, and the equations would become implicit in q̈.
    """
    out = {}
    for role, expr in exprs.items():
        used = [u for u in inputs_in([expr]) if law_of(u) is not None]
        if not used:
            out[role] = expr
            continue
        laws = {u: _resolved(u) for u in used}
        if role == "T" or role.startswith("constraint "):
            _refuse_velocity_laws(laws, velocities, role)
        new = expr.xreplace(laws)  # u̇ of a law: Derivative(law, t), worked out
        out[role] = new.replace(lambda e: isinstance(e, sp.Derivative), lambda e: e.doit())
    return out


def _resolved(u) -> sp.Expr:
    """The law of `u` with the inputs it uses that have laws replaced by theirs, recursively (a law is
    given when its input is made, so it can only use inputs made before: there are no cycles)."""
    law = law_of(u)
    inner = [v for v in inputs_in([law]) if law_of(v) is not None]
    return law.xreplace({v: _resolved(v) for v in inner}) if inner else law


def _refuse_velocity_laws(laws: dict, velocities, role) -> None:
    """Refuse a law holding a velocity for an input that appears in T or a constraint (see `substitute_laws`)."""
    for u, law in laws.items():
        if law.has(*velocities):
            raise ModelError(
                f"The law of Input `{u.func.__name__}` depends on velocities and the input appears in {role}: "
                "the equations would no longer be linear in q̈ (they would be implicit). Use velocity feedback "
                "in forces, or a law of q and t only in T and constraints."
            )


def plain_inputs(exprs, inputs, order: int = MAX_ORDER) -> tuple[list, dict]:
    """`exprs` with u(t) and its t-derivatives up to `order` replaced by Dummy symbols, and that map.

    For numerical checks with lambdify (`lagcomp.mechanics.lagrange._check_mass_matrix`), which
    cannot print an undefined function.
    """
    mapping = {}
    for u in inputs:
        for k in range(order, -1, -1):
            mapping[u.diff(t, k) if k else u] = sp.Dummy(f"{u.func.__name__}_{k}", real=True)
    return [e.xreplace(mapping) for e in exprs], mapping
