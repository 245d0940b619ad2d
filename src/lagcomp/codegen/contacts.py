"""The impact branches of ``event_reset``: what a contact's event does to the velocities.

For the events of contacts (`lagcomp.model.contacts.Contact`) the branch writes,
CSE'd together, the work arrays the impact solver reads
(`lagcomp.kernel_support.impacts.contact_impacts`):

* ``_mass[i, j]``, j ≤ i: the mass matrix M(q, t) (its lower triangle);
* for every contact d of the system: ``_gap[d]`` = g_d, ``_gradient[d, j]`` =
  ∂g_d/∂q_j and ``_normal_velocity[d]`` = ġ_d = Σ_j ∂g_d/∂q_j q̇_j + ∂g_d/∂t,
  and ``_restitution[d]`` = e_d;

then calls the solver, which takes the contact whose event fired and every
other contact closed at that instant and adds M⁻¹ Gᵀ P to the velocities the branch writes
(``out[n:]``, a copy of q̇ before the impact).  Every contact is written
because an impact on one may involve the others (three balls in a row); one
branch serves all the contacts' events.
"""

from __future__ import annotations

import sympy as sp

from lagcomp.ir import ContactImpact


def impact_branches(eom, restitutions: tuple, time, kernel) -> tuple:
    """The branch of ``event_reset`` shared by the events of `eom` that are contacts: ((their event indices,
    branch `Kernel`),), or () when there are none.

    `restitutions` holds, per event, e (a plain expression) for a contact and None for another event;
    `time` is the time symbol of the plain expressions; `kernel`(name, doc, args, stores, solve) builds a
    CSE'd `Kernel` over the module's loads (`lagcomp.codegen.lower._kernel`).
    """
    events = tuple(e for e, restitution in enumerate(restitutions) if restitution is not None)
    if not events:
        return ()
    n = eom.n
    stores = [(f"_mass[{i}, {j}]", eom.M[i, j]) for i in range(n) for j in range(i + 1) if eom.M[i, j] != 0]
    for d, e in enumerate(events):
        gap = eom.events[e]
        gradient = [gap.diff(q) for q in eom.q]
        stores.append((f"_gap[{d}]", gap))
        stores += [(f"_gradient[{d}, {j}]", g) for j, g in enumerate(gradient) if g != 0]
        rate = sum((g * qd for g, qd in zip(gradient, eom.qd, strict=True)), gap.diff(time))
        stores.append((f"_normal_velocity[{d}]", rate))
        stores.append((f"_restitution[{d}]", sp.sympify(restitutions[e])))
    branch = kernel("event_reset", "", ("t", "y", "p", "e", "out"), stores, ContactImpact(n=n, events=events))
    return ((events, branch),)


def contacts_constant(names: tuple[str, ...], restitutions: tuple) -> tuple:
    """The module constant ``CONTACTS``: ((name, event index, restitution), ...), the restitution a float or
    the name of its parameter, for the checks a run makes before it starts (`lagcomp.integrate.contacts`);
    () without contacts (then no constant)."""
    contacts = tuple(
        (names[e], e, restitution.name if isinstance(restitution, sp.Symbol) else float(restitution))
        for e, restitution in enumerate(restitutions) if restitution is not None)
    if not contacts:
        return ()
    return (("CONTACTS", "The contacts: (name, event index, restitution: a number or its parameter's name).",
             contacts),)
