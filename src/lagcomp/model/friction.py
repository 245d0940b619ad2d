"""Coulomb friction with stick–slip on a velocity: an element that sticks (v = 0 held) or slips (force −μk |N| sign v).

A friction element acts on a relative velocity v(q, q̇, t), linear in q̇ (v = a(q, t)·q̇ + c(q, t)), pressed by
a normal force N(q, q̇, t) given as an expression (the rope on a table: N = μ g (L − x)), whose magnitude |N|
the law uses (a signed N, m g cos θ on a curved track, presses either way).  Its mode is a slot of p, like a
contact's (`lagcomp.ir.ContactModes`): 0 stick, ±1 slip with s = sign v.

* slip: the generalized force −μk |N| s ∂v/∂q̇, which enters the equations of motion (``rhs_free``) with s read
  from p, so every kernel built from F (and the Taylor program) sees it; the event is s·v (direction −1: v
  reaching 0);
* stick: v = 0 held by the row a q̈ + b = 0 (b = Σ_j ∂v/∂q_j q̇_j + ∂v/∂t: v̇ = a q̈ + b), added to the closed
  contacts' rows (`lagcomp.kernel_support.resting`); its multiplier λ_f is the friction force (two-sided); the
  event is μs |N| − |λ_f| (direction −1: the force needed reaching the static limit);
* the switches (``event_reset``, no velocity jump): stick → slip with s = −sign λ_f (the motion goes against the
  force that held it); slip at v = 0 → stick when the force needed there is within μs |N|, else slip with
  s = −sign λ_f (the other way).

The element is an `Event` whose expression is v: its occurrences are the switches (`Solution.events`), listed
with the new modes in `Solution.friction_switches`.

Pressed by a contact (``normal="floor"``, a `Contact` of the same System): N = λ_c, the contact's normal force,
0 while it is open (the element idles: it never sticks on a limit of 0).  Slipping, the force −μk s λ_c ∂v/∂q̇ is
linear in λ_c: it joins the contact's column of the held-row system, M q̈ = F + (G_cᵀ − μk s aᵀ) λ_c, G_c q̈ + b_c
= 0, a non-symmetric W = G_c M⁻¹ (G_c − μk s a)ᵀ (`lagcomp.kernel_support.resting.pressed_frictional_accelerations`;
the all-open path costs nothing more: ``rhs`` is ``rhs_free`` then).  Sticking, both rows are held, λ_f the
friction force; the event is μs λ_c − |λ_f|.  An impact of that contact alone is frictional
(`lagcomp.kernel_support.impacts.frictional_impact`).

Limits: the system is a Lagrange one (M from T); with bilateral constraints it has no contacts (a sticking
element's row is held beside the constraints', `lagcomp.kernel_support.resting.constrained_frictional_accelerations`).  The Taylor method
integrates friction with one program per mode set, stick rows included (`lagcomp.codegen.taylor.ModePrograms`),
while the contacts and friction elements make at most `lagcomp.codegen.taylor.MODE_PROGRAMS_MAX` mode sets and
no element is pressed by a contact; beyond, or pressed (``normal="floor"``), it refuses them (docs/errors.md,
``friction-with-taylor``).  It also refuses a normal force whose magnitude |N| stays an ``Abs`` of the state
(N that changes sign with q, as the rope's μ g (L − x)): Abs has no Taylor recurrence (``taylor-not-applicable``).
Contacts in the same system: a
contact's event (impact, closing, lift-off) decides the friction modes again from the state after it, in the
same ``event_reset`` branch (`lagcomp.codegen.contacts.contact_event_call`): slip along v ≠ 0, stick at v = 0
unless the holding force exceeds μs |N|.
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from lagcomp.errors import ModelError
from lagcomp.model.events import Event
from lagcomp.model.expressions import expression


@dataclass(frozen=True)
class Friction(Event):
    """A named Coulomb friction element on the velocity ``expr`` = v(q, q̇, t), linear in q̇.

    Written ``Friction("table", x.diff(t), normal=m*g, static=0.5, kinetic=0.4)``.  It is an `Event` with
    direction −1 whose action is the switch of mode; ``direction``, ``terminal`` and ``reset`` are fixed by that
    and refused if given.

    Parameters
    ----------
    name : str
        Identifier under which the switches are reported.
    expr : sympy expression
        The sliding velocity v, linear in the velocities q_i(t).diff(t); may hold q, t and parameters.
    normal : sympy expression or str
        The normal force N pressing the surfaces (q, q̇, t, parameters; |N| is used), in the units of the force
        conjugate to v's coordinate (N for v in m/s); or the name of a `Contact` of the same System, whose normal
        force λ_c presses (0 while it is open: the element is then idle).
    static, kinetic : float or sympy Symbol
        μs and μk ≥ 0 with μk ≤ μs (kinetic defaults to static), numbers or parameters.
    """

    normal: object = None
    static: object = None
    kinetic: object = None

    def __post_init__(self):
        if self.direction not in (-1, 0) or self.terminal or self.reset is not None:
            raise ModelError(f"Friction `{self.name}`: its event is the switch between stick and slip (direction "
                             "-1, the run goes on); leave `direction`, `terminal` and `reset` unset.")
        object.__setattr__(self, "direction", -1)
        super().__post_init__()
        if self.normal is None or self.static is None:
            raise ModelError(f"Friction `{self.name}`: give the normal force (normal=N) and the static coefficient "
                             "(static=μs; kinetic=μk defaults to it).")
        if not isinstance(self.normal, str):    # (a contact's name: the System checks it names one of its contacts)
            object.__setattr__(self, "normal", expression(self.normal, f"Friction `{self.name}`: the normal force"))
        static = _coefficient(self.name, "static", self.static)
        kinetic = static if self.kinetic is None else _coefficient(self.name, "kinetic", self.kinetic)
        if static.is_number and kinetic.is_number and kinetic > static:
            raise ModelError(f"Friction `{self.name}`: the kinetic coefficient {float(kinetic)} exceeds the static "
                             f"one {float(static)}; Coulomb's law needs μk ≤ μs.")
        object.__setattr__(self, "static", static)
        object.__setattr__(self, "kinetic", kinetic)

    @property
    def changes_state(self) -> bool:
        """The drivers apply its ``event_reset``: a switch writes the element's mode into p (the state itself does
        not jump)."""
        return True


def slip_symbol(index: int) -> sp.Symbol:
    """The symbol of friction element `index`'s mode slot (0 stick, ±1 slip) in the equations of motion: the
    kernels read it from p (`lagcomp.codegen.lower`), the slip force −μk |N| s ∂v/∂q̇ is linear in it."""
    return sp.Symbol(f"_slip_mode_{index}", real=True)


def _coefficient(name: str, which: str, value) -> sp.Expr:
    """μ ≥ 0 as a sympy Rational (printed back as the same double), or a parameter Symbol; else a ModelError."""
    if isinstance(value, sp.Symbol):
        return value
    try:
        number = None if isinstance(value, bool) else float(value)
    except (TypeError, ValueError):
        number = None
    if number is None or isinstance(value, sp.Basic) and not value.is_number:
        raise ModelError(f"Friction `{name}`: the {which} coefficient must be a number >= 0 or a parameter symbol, "
                         f"got {value!r}.")
    if not number >= 0.0 or number == float("inf"):
        raise ModelError(f"Friction `{name}`: the {which} coefficient must be >= 0 (and finite), got {number}.")
    return sp.Rational(repr(number))
