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

Modes (`lagcomp.ir.ContactModes`, unconstrained Lagrange modules): each contact has a slot of p, 0 open, 1
closed, after the parameters (before the inputs' headers, whose tables end p at lengths each run chooses), and
one more slot, 1 when an impact may close a contact.  Such a module's ``rhs`` is ``rhs_free`` (M q̈ = F) and,
when some contact is closed, ``closed_contacts`` (`lagcomp.kernel_support.resting`); its ``event_values`` gives
a closed contact's normal force instead of its gap (lift-off when it would turn negative), ``contact_forces``
the normal forces for the saved rows, and the impact branch also stores ``_bias`` (g̈ = G q̈ + b) for
`lagcomp.kernel_support.resting.contact_event`.

Friction elements (`lagcomp.model.friction.Friction`) share that mechanism: their modes follow the closing flag,
a sticking element is one more held row of ``closed_contacts`` (after the contacts'), ``contact_forces`` gives
its friction force after the normal forces, ``friction_limits`` the static limits μs |N|, and each element's event
has its own branch of ``event_reset`` (`friction_branches`) that writes its new mode.  The contacts' branch decides
the friction modes again after its event (`contact_event_call`).

An element pressed by a contact (``normal="floor"``, `pressing`): its N is the contact's normal force λ_c, so its
slip force is not part of ``rhs_free``; ``closed_contacts`` stores μk (``_kinetic``) and calls
`lagcomp.kernel_support.resting.pressed_frictional_accelerations`, whose derivation is there (the slip force joins
the contact's column: W = G M⁻¹ Cᵀ), ``friction_limits`` multiplies μs by λ_c from ``contact_forces`` (0 while
open), and the contacts' branch stores μs, μk for the frictional impact (`pressed_contact_event`).  Modules
without such an element are emitted as before.
"""

from __future__ import annotations

from dataclasses import replace

import sympy as sp

from lagcomp.ir import ContactImpact, ContactModes, FrictionSwitch, ReturnZero


def contact_events(restitutions: tuple) -> tuple[int, ...]:
    """The event indices of the contacts, in contact order (`restitutions`: e per event, None for another)."""
    return tuple(e for e, restitution in enumerate(restitutions) if restitution is not None)


def friction_events(frictions: tuple) -> tuple[int, ...]:
    """The event indices of the friction elements, in element order (`frictions`: (N, μs, μk) per event, None for
    another)."""
    return tuple(e for e, friction in enumerate(frictions) if friction is not None)


def mode_slots(eom) -> int:
    """How many slots of p the modes take: one per contact, the closing flag, one per friction element
    (`ContactModes`); 0 without contacts and friction (a constrained system's too: its contacts, or its friction
    elements without contacts, `lagcomp.model.system.System`)."""
    count, elements = len(contact_events(eom.restitutions)), len(friction_events(eom.frictions))
    return count + 1 + elements if count or elements else 0


def pressing(eom) -> tuple[int, ...]:
    """Per friction element, the index in contact order of the contact that presses it (its ``normal`` names
    one), −1 for an N given as an expression; () when no element is pressed by a contact."""
    names = eom.system.event_names
    contact_of = {names[e]: d for d, e in enumerate(contact_events(eom.restitutions))}
    normals = [eom.frictions[e][0] for e in friction_events(eom.frictions)]
    if not any(isinstance(normal, str) for normal in normals):
        return ()
    return tuple(contact_of[normal] if isinstance(normal, str) else -1 for normal in normals)


def modes_of(eom, kind: str, first: int) -> ContactModes:
    """The `ContactModes` of kernel `kind` of `eom`, whose modes start at slot `first` of p."""
    return ContactModes(kind, eom.n, len(contact_events(eom.restitutions)), first, contact_events(eom.restitutions),
                        friction_events(eom.frictions), pressing(eom), eom.k)


def constraint_stores(eom) -> list:
    """The stores of ``_constraint[c, j]`` = Λ_cj, the constraint matrix of a constrained `eom` (none without)."""
    return [(f"_constraint[{c}, {j}]", eom.C[c, j]) for c in range(eom.k) for j in range(eom.n) if eom.C[c, j] != 0]


def _gap_rate(gap, eom, time):
    """ġ = Σ_j ∂g/∂q_j q̇_j + ∂g/∂t."""
    return sum((gap.diff(q) * qd for q, qd in zip(eom.q, eom.qd, strict=True)), gap.diff(time))


def _bias(gap, eom, time):
    """b of g̈ = G q̈ + b: Σ_j ∂ġ/∂q_j q̇_j + ∂ġ/∂t (ġ's dependence on q̇ is G, which multiplies q̈)."""
    return _gap_rate(_gap_rate(gap, eom, time), eom, time)


def resting_kernels(eom, time, first: int, kernel) -> tuple:
    """The kernels of a module with modes: ``rhs`` (``rhs_free`` then ``closed_contacts`` when some contact is
    closed or some friction element sticks), ``closed_contacts``, ``contact_forces`` and, with friction,
    ``friction_limits`` (`ContactModes`); `first` is the first mode slot of p, `kernel`(name, doc, args, stores,
    solve) builds a CSE'd kernel over the module's loads."""
    events, elements = contact_events(eom.restitutions), friction_events(eom.frictions)
    n, count, rows = eom.n, len(events), len(events) + len(elements)
    friction_doc = ("\nFriction elements (FRICTIONS): a sticking one's mode (0) holds v = 0 too, a row of\n"
                    "closed_contacts after the contacts'; a slipping one's force is part of rhs_free."
                    if elements else "")
    rhs = kernel("rhs", "State derivative dy/dt = (q̇, q̈), shape (2n,): ``rhs_free`` (M q̈ = F), and while some\n"
                 f"contact is closed (its mode p[{first} + d] = 1) q̈ corrected by its normal force, ≥ 0\n"
                 "(closed_contacts).\n\n"
                 "Returns 0, or k > 0 when M (or the closed contacts' W) is singular here; `out` is then invalid."
                 + friction_doc, ("t", "y", "p", "out"), [], modes_of(eom, "rhs", first))
    stores = [(f"_mass[{i}, {j}]", eom.M[i, j]) for i in range(n) for j in range(i + 1) if eom.M[i, j] != 0]
    stores += constraint_stores(eom)
    for d, e in enumerate(events):
        gap = eom.events[e]
        stores += [(f"_gradient[{d}, {j}]", gap.diff(q)) for j, q in enumerate(eom.q) if gap.diff(q) != 0]
        stores.append((f"_bias[{d}]", _bias(gap, eom, time)))
    for f, e in enumerate(elements):    # v̇ = a q̈ + b: a = ∂v/∂q̇, b = v's partials in q and t times (q̇, 1)
        velocity = eom.events[e]
        stores += [(f"_gradient[{count + f}, {j}]", velocity.diff(qd)) for j, qd in enumerate(eom.qd)
                   if velocity.diff(qd) != 0]
        stores.append((f"_bias[{count + f}]", _gap_rate(velocity, eom, time)))
        if pressing(eom):
            stores.append((f"_kinetic[{f}]", sp.sympify(eom.frictions[e][2])))
    friction_doc = (f"\nWith friction: {rows} entries, the contacts' then the friction elements' forces along v\n"
                    "(held while sticking: the multiplier of v = 0; 0 while slipping)." if elements else "")
    closed = kernel("closed_contacts",
                    "q̈ in out[n:2n] (the free one on entry) with the closed contacts' normal forces, which go into\n"
                    f"`forces` ({count},), 0 for an open contact; with `unilateral` 1 a closed contact whose force\n"
                    "would pull pushes with 0 instead (lagcomp.kernel_support.resting). Returns 0 or the status of\n"
                    "a singular M or W." + friction_doc,
                    ("t", "y", "p", "out", "forces", "unilateral"), stores, modes_of(eom, "closed", first))
    forces = kernel("contact_forces",
                    f"The contacts' normal forces ({count},) into `out` at y under the modes in p, 0 for an open\n"
                    "contact: the multipliers of the closed contacts' constraints g = const (units of the force\n"
                    "conjugate to g). Returns 0 or the status of rhs." + friction_doc,
                    ("t", "y", "p", "out"), [], modes_of(eom, "forces", first))
    forces = replace(forces, constants=(
        ("CONTACT_MODES", "The first slot of p holding the contacts' modes (0 open, 1 closed), one per contact in "
                          "the order of CONTACTS, then the flag that lets an impact close a contact.", first),))
    if not elements:
        return rhs, closed, forces
    pressed = pressing(eom)
    limits = kernel("friction_limits",
                    f"The friction elements' static limits μs |N| ({len(elements)},) into `out` at y (N the normal\n"
                    "force, in the units of the friction force). Returns 0."
                    + ("\nAn element pressed by a contact: N = its normal force under the modes in p\n"
                       "(contact_forces), 0 while it is open." if pressed else ""),
                    ("t", "y", "p", "out"),
                    [(f"out[{f}]", eom.frictions[e][1] * (1 if isinstance(eom.frictions[e][0], str)
                                                          else sp.Abs(eom.frictions[e][0])))
                     for f, e in enumerate(elements)],
                    modes_of(eom, "limits", first) if pressed else ReturnZero())
    names = eom.system.event_names
    limits = replace(limits, constants=(
        ("FRICTIONS", "The friction elements: (name, event index, slot of p of its mode (0 stick, ±1 slip), static "
                      "and kinetic coefficients: numbers or their parameters' names).",
         tuple((names[e], e, first + count + 1 + f, *(_number_or_name(mu) for mu in eom.frictions[e][1:]))
               for f, e in enumerate(elements))),))
    return rhs, closed, forces, limits


def _number_or_name(value):
    """A coefficient as the module's constants keep it: a float, or the name of its parameter."""
    return value.name if isinstance(value, sp.Symbol) else float(value)


def friction_branches(eom, first: int, kernel) -> tuple:
    """The branches of ``event_reset`` of the friction elements' events: ((event index, `Kernel`), ...), each
    writing its element's new mode (`FrictionSwitch`); () without friction."""
    events, elements = contact_events(eom.restitutions), friction_events(eom.frictions)
    count = len(events)
    return tuple(
        (e, kernel("event_reset", "", ("t", "y", "p", "e", "out"), [],
                   FrictionSwitch(slot=first + count + 1 + f, row=count + f, rows=count + len(elements), element=f,
                                  elements=len(elements), pressed=bool(pressing(eom)))))
        for f, e in enumerate(elements))


def friction_switch_lines(solve: FrictionSwitch, indent: str) -> list[str]:
    """The emitted lines of a friction element's branch of ``event_reset`` (`FrictionSwitch`)."""
    limits = [f"_limits = np.empty({solve.elements})", "friction_limits(t, y, p, _limits)"]
    restore = [f"p[{solve.slot}] = _mode", "if _status != 0:", f"{indent}return _status"]
    held = [f"_mode = p[{solve.slot}]", f"p[{solve.slot}] = 0.0", f"_forces = np.empty({solve.rows})",
            "_status = contact_forces(t, y, p, _forces)"]
    return held + (limits + restore if solve.pressed else restore + limits) + [
            f"p[{solve.slot}] = friction_mode_after(_mode, _forces[{solve.row}], _limits[{solve.element}])",
            "return 0"]


def impact_branches(eom, restitutions: tuple, time, kernel, modes: int | None = None) -> tuple:
    """The branch of ``event_reset`` shared by the events of `eom` that are contacts: ((their event indices,
    branch `Kernel`),), or () when there are none.

    `restitutions` holds, per event, e (a plain expression) for a contact and None for another event;
    `time` is the time symbol of the plain expressions; `kernel`(name, doc, args, stores, solve) builds a
    CSE'd `Kernel` over the module's loads (`lagcomp.codegen.cse.cse_kernel`); `modes`: the first mode slot of p
    (`ContactModes`), then the branch also stores ``_bias`` and calls the resting contacts' reset.
    """
    events = contact_events(restitutions)
    if not events:
        return ()
    n = eom.n
    stores = [(f"_mass[{i}, {j}]", eom.M[i, j]) for i in range(n) for j in range(i + 1) if eom.M[i, j] != 0]
    stores += constraint_stores(eom)
    for d, e in enumerate(events):
        gap = eom.events[e]
        gradient = [gap.diff(q) for q in eom.q]
        stores.append((f"_gap[{d}]", gap))
        stores += [(f"_gradient[{d}, {j}]", g) for j, g in enumerate(gradient) if g != 0]
        rate = sum((g * qd for g, qd in zip(gradient, eom.qd, strict=True)), gap.diff(time))
        stores.append((f"_normal_velocity[{d}]", rate))
        stores.append((f"_restitution[{d}]", sp.sympify(restitutions[e])))
        if modes is not None:
            stores.append((f"_bias[{d}]", _bias(gap, eom, time)))
    elements = friction_events(eom.frictions) if modes is not None else ()
    for f, e in enumerate(elements):    # v = a·q̇ + c, to decide the modes again from q̇ after the event
        velocity = eom.events[e]
        stores += [(f"_slip_gradient[{f}, {j}]", velocity.diff(qd)) for j, qd in enumerate(eom.qd)
                   if velocity.diff(qd) != 0]
        stores.append((f"_slip_offset[{f}]", velocity.subs({qd: 0 for qd in eom.qd})))
        if pressing(eom):
            stores += [(f"_static[{f}]", sp.sympify(eom.frictions[e][1])),
                       (f"_kinetic[{f}]", sp.sympify(eom.frictions[e][2]))]
    branch = kernel("event_reset", "", ("t", "y", "p", "e", "out"), stores,
                    ContactImpact(n=n, events=events, modes=modes, elements=len(elements),
                                  pressing=pressing(eom) if modes is not None else (), constraints=eom.k))
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


def mode_lines(solve: ContactModes, indent: str) -> tuple[list[str], list[str]]:
    """The emitted lines of a kernel whose solve is `solve`: (after its loads, before its temporaries; after its
    stores)."""
    n, count, first, rows, k = solve.n, solve.count, solve.first, solve.rows, solve.constraints
    slots = [solve.friction_slot(f) for f in range(len(solve.frictions))]
    none_held = " and ".join([f"p[{first + d}] == 0.0" for d in range(count)] + [f"p[{s}] != 0.0" for s in slots])
    if solve.kind == "rhs":
        return [], ["_status = rhs_free(t, y, p, out)", f"if _status != 0 or ({none_held}):", f"{indent}return _status",
                    f"return closed_contacts(t, y, p, out, np.empty({rows + k}), 1.0)"]
    if k and solve.kind in ("forces", "reactions"):
        return [], _constrained_force_lines(solve, none_held, indent)
    if solve.kind == "forces":
        return [], [f"_ydot = np.empty({2 * n})", "_status = rhs_free(t, y, p, _ydot)", "if _status != 0:",
                    f"{indent}return _status", "return closed_contacts(t, y, p, _ydot, out, 0.0)"]
    if solve.kind == "limits":      # the pressed elements' μs times their contact's normal force, 0 while open
        after = [f"_normal = np.empty({rows})", "_status = contact_forces(t, y, p, _normal)"]
        after += [f"out[{f}] = out[{f}] * max(_normal[{d}], 0.0) if _status == 0 else 0.0"
                  for f, d in enumerate(solve.pressing) if d >= 0]
        return [], after + ["return 0"]
    if solve.kind == "closed":
        work = [f"_mass = np.zeros(({n}, {n}))", f"_gradient = np.zeros(({rows}, {n}))", f"_bias = np.empty({rows})"]
        if k and solve.pressing:
            return work + [f"_constraint = np.zeros(({k}, {n}))", f"_kinetic = np.zeros({len(slots)})"], [
                f"return constrained_pressed_frictional_accelerations(_mass, _constraint, _gradient, _bias, "
                f"p[{first}:{first + count}], p[{slots[0]}:{slots[-1] + 1}], "
                f"np.array({list(solve.pressing)}, dtype=np.int64), _kinetic, out[{n}:{2 * n}], forces, unilateral)"]
        if k and slots:
            return work + [f"_constraint = np.zeros(({k}, {n}))"], [
                f"return constrained_frictional_accelerations(_mass, _constraint, _gradient, _bias, "
                f"p[{first}:{first + count}], p[{slots[0]}:{slots[-1] + 1}], out[{n}:{2 * n}], forces, unilateral)"]
        if k:
            return work + [f"_constraint = np.zeros(({k}, {n}))"], [
                f"return constrained_closed_contact_accelerations(_mass, _constraint, _gradient, _bias, "
                f"p[{first}:{first + count}], out[{n}:{2 * n}], forces, unilateral)"]
        if solve.pressing:
            return work + [f"_kinetic = np.zeros({len(slots)})"], [
                f"return pressed_frictional_accelerations(_mass, _gradient, _bias, p[{first}:{first + count}], "
                f"p[{slots[0]}:{slots[-1] + 1}], np.array({list(solve.pressing)}, dtype=np.int64), _kinetic, "
                f"out[{n}:{2 * n}], forces, unilateral)"]
        if not slots:
            return work, [f"return closed_contact_accelerations(_mass, _gradient, _bias, p[{first}:{first + count}], "
                          f"out[{n}:{2 * n}], forces, unilateral)"]
        return work, [f"return frictional_accelerations(_mass, _gradient, _bias, p[{first}:{first + count}], "
                      f"p[{slots[0]}:{slots[-1] + 1}], out[{n}:{2 * n}], forces, unilateral)"]
    after = [f"out[{e}] = p[{s}] * out[{e}]" for e, s in zip(solve.frictions, slots, strict=True)]   # slip: s·v
    after += [f"if not ({none_held}):", f"{indent}_forces = np.empty({rows})",
              f"{indent}if contact_forces(t, y, p, _forces) == 0:"]
    for d, e in enumerate(solve.events):
        after += [f"{indent * 2}if p[{first + d}] != 0.0:", f"{indent * 3}out[{e}] = _forces[{d}]"]
    if slots:
        after += [f"{indent * 2}_limits = np.empty({len(slots)})", f"{indent * 2}friction_limits(t, y, p, _limits)"]
    for f, (e, s) in enumerate(zip(solve.frictions, slots, strict=True)):
        after += [f"{indent * 2}if p[{s}] == 0.0:", f"{indent * 3}out[{e}] = _limits[{f}] - abs(_forces[{count + f}])"]
    return [], after


def _constrained_force_lines(solve: ContactModes, none_held: str, indent: str) -> list[str]:
    """The lines after the stores of a constrained module's ``contact_forces`` (the first `rows` of
    ``closed_contacts``' forces, which end with the constraints' Δμ) and ``reactions`` (``reactions_free`` plus that
    Δμ while some contact is held, unilateral as ``rhs``)."""
    n, rows, k = solve.n, solve.rows, solve.constraints
    free = [f"_ydot = np.empty({2 * n})", "_status = rhs_free(t, y, p, _ydot)", "if _status != 0:",
            f"{indent}return _status", f"_forces = np.empty({rows + k})"]
    if solve.kind == "forces":
        return free + ["_status = closed_contacts(t, y, p, _ydot, _forces, 0.0)", f"out[:] = _forces[:{rows}]",
                       "return _status"]
    return ["_status = reactions_free(t, y, p, out)", f"if _status != 0 or ({none_held}):", f"{indent}return _status",
            *free, "_status = closed_contacts(t, y, p, _ydot, _forces, 1.0)", f"out[:] += _forces[{rows}:]",
            "return _status"]


def _checked_closing(call: str, n: int, count: int, first: int, elements: int, indent: str) -> list[str]:
    """The lines of the impact branch after ``_firing``: the impact (`call`), which may close contacts
    (`lagcomp.kernel_support.resting.impact_and_closing`); with `elements` friction elements, their modes decided
    again from the velocities after it (`friction_modes_after_jump`); then, when it closed some contact, the forces
    at the state after it (``contact_forces``, under the new modes); if one it closed would not push, the modes and
    velocities as before and the impact again without closing (the friction modes again after it).  Leaves
    ``_stuck`` (some element sticks) for `_overload_lines` with elements; returns at the end without."""
    modes = f"p[{first}:{first + count}]"
    again = call.replace(f"p[{first + count}], out", "0.0, out")
    frictions = f"p[{first + count + 1}:{first + count + 1 + elements}]"
    decide = (f"friction_modes_after_jump(_slip_gradient, _slip_offset, out[{n}:{2 * n}], {frictions})"
              if elements else "")
    lines = [f"_modes = {modes}.copy()", f"_status = {call}", "if _status != 0:", f"{indent}return _status"]
    if elements:
        lines.append(f"_stuck = {decide}")
    lines += [f"if not ({modes} == _modes).all():", f"{indent}_forces = np.empty({count + elements})",
              f"{indent}_status = contact_forces(t, out, p, _forces)",
              f"{indent}for _d in range({count}):",
              f"{indent * 2}if p[{first} + _d] != 0.0 and _modes[_d] == 0.0 and (_status != 0 or not "
              "_forces[_d] > 0.0):",
              f"{indent * 3}{modes} = _modes", f"{indent * 3}out[{n}:{2 * n}] = y[{n}:{2 * n}]"]
    if not elements:
        return lines + [f"{indent * 3}return {again}", "return 0"]
    return lines + [f"{indent * 3}_status = {again}", f"{indent * 3}if _status != 0:",
                    f"{indent * 4}return _status", f"{indent * 3}_stuck = {decide}", f"{indent * 3}break"]


def _overload_lines(count: int, elements: int, first: int, indent: str) -> list[str]:
    """The lines that end the impact branch of a module with friction: while some element sticks (``_stuck``) and
    its holding force exceeds μs |N|, the most overloaded slips (`slip_most_overloaded`, one pass per element)."""
    frictions = f"p[{first + count + 1}:{first + count + 1 + elements}]"
    return ["if _stuck:", f"{indent}_forces = np.empty({count + elements})", f"{indent}_limits = np.empty({elements})",
            f"{indent}for _pass in range({elements}):",
            f"{indent * 2}if contact_forces(t, out, p, _forces) != 0:", f"{indent * 3}break",
            f"{indent * 2}friction_limits(t, out, p, _limits)",
            f"{indent * 2}if not slip_most_overloaded(_forces[{count}:], _limits, {frictions}):",
            f"{indent * 3}break",
            "return 0"]


def contact_event_call(n: int, count: int, first: int, firing: str, indent: str, elements: int = 0,
                       pressed: tuple[int, ...] = (), constraints: int = 0) -> list[str]:
    """The end of the impact branch of a module with modes: q̈ without contacts, then
    `lagcomp.kernel_support.resting.contact_event` on the mode slots of p, whose closings stand only when the
    closed contacts push at the state after the impact (`_checked_closing`: one rule for every module with
    modes); with `elements` friction elements, their modes decided again from the state after the event
    (`friction_modes_after_jump`: slip along v ≠ 0, stick at v = 0 unless the holding force exceeds μs |N|, then
    `slip_most_overloaded`), so that no mode is stale after an impact, a closing or a lift-off.  With friction
    elements `pressed` by a contact (their contact's index or −1 each), the impact is `pressed_contact_event`'s:
    frictional.  With `constraints` (a constrained module), the ``constrained_`` routines on ``_constraint`` too."""
    call = (f"contact_event(_mass, _gap, _gradient, _normal_velocity, _restitution, _bias, _ydot[{n}:{2 * n}], "
            f"y[:{n}], t, _firing, p[{first}:{first + count}], p[{first + count}], out[{n}:{2 * n}])")
    if constraints:
        call = f"constrained_contact_event(_mass, _constraint, {call[len('contact_event(_mass, '):]}"
    if pressed:
        name = "constrained_pressed_contact_event" if constraints else "pressed_contact_event"
        call = (f"{name}{call[call.index('('):-1]}, _slip_gradient, _slip_offset, "
                f"np.array({list(pressed)}, dtype=np.int64), _static, _kinetic)")
    lines = [f"_ydot = np.empty({2 * n})", "_status = rhs_free(t, y, p, _ydot)", "if _status != 0:",
             f"{indent}return _status", f"_firing = {firing}"] + _checked_closing(call, n, count, first, elements,
                                                                                indent)
    return lines + (_overload_lines(count, elements, first, indent) if elements else [])
