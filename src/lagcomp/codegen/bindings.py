"""Where the kernels read each model symbol: its local in the user namespace and its slot of y or p.

The naming contract is `lagcomp.codegen.lower`'s (its docstring, Names): every local bound to a user
symbol matches `USER_NAMESPACE`, and no other name of the emitted code does.  `symbol_bindings` gives
the mapping symbol → local and the loads (``q_x = y[0]``) every lowered kernel starts from.
"""

from __future__ import annotations

import re
import unicodedata

import sympy as sp

from lagcomp.codegen.contacts import contact_events, friction_events, mode_slots
from lagcomp.mechanics.lagrange import EOM
from lagcomp.model.friction import slip_symbol
from lagcomp.model.inputs import MAX_ORDER
from lagcomp.model.system import t

#: The user namespace (`lagcomp.codegen.lower`'s docstring, Names): a prefix for each kind of user symbol,
#: then ``_`` or a digit.
USER_NAMESPACE = re.compile(r"(q|qd|p|mom|u|ud|udd|uddd)[_0-9]")


def user_local(prefix: str, name: str, index: int) -> str:
    """The local of the user symbol `name`, the `index`-th of its kind `prefix` (q, qd, p or mom).

    ``<prefix>_<name>`` when that is an identifier Python keeps as written (NFKC-stable), else
    ``<prefix><index>_`` and the name's letters, other characters as ``_``: distinct names of one
    kind always get distinct locals, and no local of one kind is one of another.
    """
    local = f"{prefix}_{name}"
    if local.isidentifier() and unicodedata.normalize("NFKC", local) == local:
        return local
    letters = "".join(c if f"a{c}".isidentifier() and unicodedata.normalize("NFKC", c) == c else "_"
                      for c in name)
    return f"{prefix}{index}_{letters}"


#: The locals of the Baumgarte gains α, β, stored after the user parameters in p for constrained systems.
BAUMGARTE = ("_baumgarte_alpha", "_baumgarte_beta")


def baumgarte_gains(eom: EOM) -> tuple[sp.Symbol, sp.Symbol]:
    """The symbols of the Baumgarte gains: named like their locals, unless a parameter has that name
    (the symengine CSE tells symbols apart by name only, not by assumptions)."""
    taken, gains = {s.name for s in eom.parameters}, []
    for name in BAUMGARTE:
        while name in taken:
            name += "_"
        gains.append(sp.Symbol(name, real=True))
    return tuple(gains)


def symbol_slots(eom: EOM) -> list[tuple[sp.Symbol, str, str, int]]:
    """Each model symbol with its local in the user namespace and where the kernels read it:
    (symbol, local, array, index), the array ``y`` (state) or ``p`` (parameters).

    Coordinates and velocities are named after the coordinate (``q_x``, ``qd_x``; the velocity
    symbol's own name is ``x_dot``), parameters after themselves (``p_k``); the Baumgarte gains
    are lagcomp's, `BAUMGARTE`.
    """
    n, names = eom.n, eom.system.coordinate_names
    slots = [(s, user_local("q", names[i], i), "y", i) for i, s in enumerate(eom.q)]
    slots += [(s, user_local("qd", names[i], i), "y", n + i) for i, s in enumerate(eom.qd)]
    slots += [(s, user_local("p", s.name, k), "p", k) for k, s in enumerate(eom.parameters)]
    if eom.k:
        slots += [(s, BAUMGARTE[i], "p", len(eom.parameters) + i) for i, s in enumerate(baumgarte_gains(eom))]
    elements = friction_events(eom.frictions)
    if elements:    # the friction elements' modes (their slip force is linear in them): `ContactModes`
        first = first_mode_slot(eom) + len(contact_events(eom.restitutions)) + 1
        slots += [(slip_symbol(f), user_local("slip", eom.system.event_names[e], f), "p", first + f)
                  for f, e in enumerate(elements)]
    return slots


def symbol_bindings(eom: EOM) -> tuple[dict, tuple[tuple[str, str], ...]]:
    """Map each model symbol to its local symbol (`symbol_slots`), and list the loads that bind them (``y[0]``)."""
    mapping, loads = {}, []
    for symbol, local, array, index in symbol_slots(eom):
        mapping[symbol] = sp.Symbol(local, real=True)
        loads.append((local, f"{array}[{index}]"))
    for u, order, local, slot in input_slots(eom):
        mapping[u.diff(t, order) if order else u] = sp.Symbol(local, real=True)
        loads.append((local, f"input_value(t, p, {slot}, {order})"))
    # distinct by construction: prefixes per kind, and a System refuses two symbols of one name
    assert len({local for local, _ in loads}) == len(loads), loads
    mapping[t] = sp.Symbol("t", real=True)
    return mapping, tuple(loads)


#: The locals of an input and of its derivatives, by order: ``u_x``, ``ud_x``, ``udd_x``, ``uddd_x``.
INPUT_PREFIXES = ("u", "ud", "udd", "uddd")


def input_slots(eom: EOM) -> list[tuple]:
    """Each input u(t) supplied at run time, with each derivative order the kernels may read (0 to
    `MAX_ORDER`): (u, order, local, header slot).

    The header slot is the entry of p holding where the input's table starts: p holds the user
    parameters, then the Baumgarte gains of a constrained system or the contacts' modes
    (`lagcomp.codegen.contacts.mode_slots`), then one header per input in name order
    (`lagcomp.kernel_support.inputs` describes the tables after them).
    """
    first = len(eom.parameters) + (len(BAUMGARTE) if eom.k else 0) + mode_slots(eom)
    return [(u, order, user_local(INPUT_PREFIXES[order], u.func.__name__, j), first + j)
            for j, u in enumerate(eom.system.inputs) for order in range(MAX_ORDER + 1)]


def first_mode_slot(eom: EOM) -> int:
    """The first slot of p of the contacts' modes: after the parameters and a constrained system's Baumgarte
    gains."""
    return len(eom.parameters) + (len(BAUMGARTE) if eom.k else 0)
