"""What a run does with a model's contacts before it starts and after it (`lagcomp.model.contacts.Contact`).

Before: the checks below, and the contacts' modes at the start (`set_initial_modes`: closed when at rest on
their zero and pressed shut); each run and each sweep trajectory then works on its own copy of p, whose modes
only the drivers' ``event_reset`` writes.  After: the mode switches (`contact_switches`, the resets replayed on
the modes at the start), the normal forces at the saved rows (`contact_forces_along`) and the impulses.

The module's ``CONTACTS`` lists each contact as (name, event index, restitution), the restitution a
number or the name of the parameter that holds it.  A run refuses a restitution outside [0, 1]
(`ParameterError`) and a gap that is negative at the start (`InitialConditionError`): a body that
starts inside another has no impact to apply, and its motion would be meaningless.  "Negative" allows
rounding: g < −`CLOSED_GAP` Σ_j |∂g/∂q_j| (|q_j| + 1), the scale the impact solver uses for "touching".

Friction elements (`lagcomp.model.friction.Friction`, the module's ``FRICTIONS``) share the modes: a run checks
their coefficients given as parameters (μ ≥ 0, μk ≤ μs), starts each sticking or slipping (`set_initial_modes`,
again after the contacts that start closed), and reports their switches and forces with the contacts'
(`contact_switches`, `contact_forces_along`); a contact's event decides them again in the same reset.
"""

from __future__ import annotations

import contextlib
import weakref

import numpy as np

from lagcomp.errors import InitialConditionError, ModelError, OptionError, ParameterError
from lagcomp.integrate.methods import library_function, method_names
from lagcomp.kernel_support.impacts import CLOSED_GAP


def touching(gradients: np.ndarray, q: np.ndarray) -> np.ndarray:
    """The gaps (C,) that count as touching for contacts of gradients ∂g/∂q (C, n) at q: `CLOSED_GAP` Σ_j
    |∂g/∂q_j| (|q_j| + 1), the impact solver's own scale (`lagcomp.kernel_support.impacts.contact_impacts`)."""
    return CLOSED_GAP * (np.abs(gradients) @ (np.abs(q) + 1.0))


#: {model kernels: (CONTACTS, FRICTIONS, CONTACT_MODES)} (`_declared`).
_DECLARED: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def _declared(kernels) -> tuple:
    """The module's ``CONTACTS`` and ``FRICTIONS`` as tuples (() without them) and ``CONTACT_MODES`` (None without),
    read once per kernels: a run asks a dozen times, and a name a model's kernels do not hold costs an
    AttributeError raised and caught at each read (`lagcomp.companion.ModelKernels`), ~1 µs."""
    try:
        return _DECLARED[kernels]
    except (KeyError, TypeError):
        pass
    declared = (tuple(getattr(kernels, "CONTACTS", ())), tuple(getattr(kernels, "FRICTIONS", ())),
                getattr(kernels, "CONTACT_MODES", None))
    with contextlib.suppress(TypeError):   # (not weakly referenceable: read again at each call)
        _DECLARED[kernels] = declared
    return declared


def contacts_of(model) -> tuple:
    """The model's contacts as (name, event index, restitution), () for a module without them."""
    return _declared(model.kernels)[0]


def check_contacts(model, t0: float, Y0: np.ndarray, P: np.ndarray, where=lambda row: "") -> np.ndarray | None:
    """Refuse restitutions outside [0, 1] and penetrating starts, for each row of Y0 (rows, N) and P (rows, *),
    whose contacts are open (`parameter_vector`'s modes).

    `where`(row) says which trajectory a row is, for the message of a sweep ("" for a single run).  Returns which
    contacts are at rest on their zero at the start (rows, C): the gap and ġ within `touching`'s scale (of q and
    q̇), candidates for closed contacts (`set_initial_modes`); None without contacts.
    """
    contacts = contacts_of(model)
    if not contacts:
        return None
    for name, _, restitution in contacts:
        e = P[:, model.parameters.index(restitution)] if isinstance(restitution, str) else np.array([restitution])
        bad = np.flatnonzero(~((e >= 0.0) & (e <= 1.0)))
        if bad.size:
            row = int(bad[0])
            raise ParameterError(f"Contact `{name}`{where(row)}: its restitution {restitution} = {e[row]} is outside "
                                 "[0, 1] (1 elastic, 0 plastic).")
    n, rows = model.n, Y0.shape[0]
    events = [event for _, event, _ in contacts]
    values = np.empty((rows, len(model.event_names)))
    gradients = np.empty((rows, len(model.event_names), Y0.shape[1] + 1 + len(model.parameters)))
    partials = np.empty(rows, dtype=bool)       # (no partials: events that read inputs)
    for row in range(rows):                     # (the kernels one row at a time; the tests below on all rows)
        model.kernels.event_values(t0, Y0[row], P[row], values[row])
        partials[row] = model.kernels.event_gradients(t0, Y0[row], P[row], gradients[row]) == 0
    G = gradients[:, events, :n]                                        # (rows, C, n)
    gaps = values[:, events]
    allowed = CLOSED_GAP * np.einsum("rcj,rj->rc", np.abs(G), np.abs(Y0[:, :n]) + 1.0)   # `touching`, per row
    inside = np.argwhere(gaps < -allowed)
    if inside.size:
        row, c = (int(i) for i in inside[0])
        raise InitialConditionError(
            f"Contact `{contacts[c][0]}`{where(row)}: its gap is {gaps[row, c]:.6g} < 0 at t0 = {t0}: the bodies "
            "start inside each other. Start with the gap >= 0 (touching is 0).")
    rate = np.einsum("rcj,rj->rc", G, Y0[:, n:2 * n]) + gradients[:, events, 2 * n]
    still = np.abs(rate) <= CLOSED_GAP * np.einsum("rcj,rj->rc", np.abs(G), np.abs(Y0[:, n:2 * n]) + 1.0)
    return (gaps <= allowed) & still & partials[:, None]


#: The compiled loop that computes impulses from the jumps (`lagcomp.integrate.drivers.sweep_impulses`).
IMPULSES = "lagcomp.integrate.drivers.sweep_impulses:contact_impulses"


def impulses(model, p: np.ndarray, firing: int, t: np.ndarray, before: np.ndarray, after: np.ndarray) -> np.ndarray:
    """The contacts' normal impulses at the k occurrences of event `firing` (a contact's) in one run: (k, C) at
    times `t` with states `before` and `after` (k, N), columns the model's contacts in order (`contacts_of`);
    `sweep_impulses` for one trajectory."""
    count = np.array([t.shape[0]], dtype=np.int64)
    return sweep_impulses(model, firing, p[None, :], count, t[None, :], before[None], after[None])[0]


def sweep_impulses(model, firing: int, P: np.ndarray, count: np.ndarray, times: np.ndarray, before: np.ndarray,
                   after: np.ndarray) -> np.ndarray:
    """The contacts' normal impulses (N, cap, C) at the first min(count[k], cap) occurrences of event `firing` (a
    contact's) in each of N trajectories (parameters P (N, *), times (N, cap), states before and after the
    event (N, cap, size)), NaN beyond them; in the units of the gap's conjugate force times time (N s for a gap
    in metres).

    From the jump itself: M (q̇⁺ − q̇⁻) = Gᵀ P over the contacts closed then (the firing one, and those whose gap
    is within the impact solver's `CLOSED_GAP` scale), P by least squares (exact for independent contacts); 0
    for the others (a lift-off, which does not jump: 0 for all).  Compiled (`IMPULSES`): a sweep of 10⁴ bouncing
    balls keeps some 5·10⁴ impacts.  The gaps are read with every contact open (`with_open_contacts`): a closed
    contact's event value is its force.
    """
    contact_events = np.array([index for _, index, _ in contacts_of(model)], dtype=np.int64)
    n, n_events = model.n, len(model.event_names)
    values = np.full((*times.shape, contact_events.size), np.nan)
    if model.k:
        return _constrained_impulses(model, contact_events, firing, with_open_contacts(model, P), count, times, before,
                                     after, values)
    library_function(IMPULSES)(
        model.kernels.mass_matrix, model.kernels.event_values, model.kernels.event_gradients, contact_events,
        firing, n, np.ascontiguousarray(with_open_contacts(model, P), dtype=np.float64),
        np.ascontiguousarray(count, dtype=np.int64), np.ascontiguousarray(times, dtype=np.float64),
        np.ascontiguousarray(before, dtype=np.float64), np.ascontiguousarray(after, dtype=np.float64),
        np.empty((n, n)), np.empty(n_events), np.empty((n_events, model.state_size + 1 + len(model.parameters))),
        values)
    return values


def _constrained_impulses(model, contact_events, firing: int, P, count, times, before, after, out) -> np.ndarray:
    """`sweep_impulses` of a model with constraints: M (q̇⁺ − q̇⁻) = Gᵀ P + Λᵀ Λ_c, the constraints' impulses Λ_c
    too (`lagcomp.kernel_support.constrained_response`), both by least squares on [Gᵀ Λᵀ]; a loop in Python (a
    constrained model's sweeps of many impacts are not what the compiled loop is for)."""
    n, k = model.n, model.k
    mass, matrix = np.empty((n, n)), np.empty((k, n + 1))
    values = np.empty(len(model.event_names))
    gradients = np.empty((len(model.event_names), model.state_size + 1 + len(model.parameters)))
    for row in range(times.shape[0]):
        p = P[row]
        for r in range(min(int(count[row]), times.shape[1])):
            t, y = float(times[row, r]), before[row, r]
            model.kernels.mass_matrix(t, y, p, mass)
            model.kernels.event_values(t, y, p, values)
            model.kernels.event_gradients(t, y, p, gradients)
            model.kernels.constraint_matrix(t, y, p, matrix)
            G = gradients[contact_events, :n]
            closed = (contact_events == firing) | (values[contact_events] <= touching(G, y[:n]))
            columns = np.hstack([G[closed].T, matrix[:, :n].T])
            jump = mass @ (after[row, r, n:2 * n] - y[n:2 * n])
            solution = np.linalg.lstsq(columns, jump, rcond=np.finfo(np.float64).eps * max(n, columns.shape[1]))[0]
            out[row, r] = 0.0
            out[row, r, closed] = solution[:int(closed.sum())]
    return out


def frictions_of(model) -> tuple:
    """The model's friction elements as (name, event index, mode slot of p, μs, μk), each μ a number or the name
    of its parameter; () without them."""
    return _declared(model.kernels)[1]


def mode_slots(model) -> tuple[int, int] | None:
    """(first slot of p, count) of the model's contact modes (`lagcomp.ir.ContactModes`), None without them;
    the closing flag is the slot after them."""
    contacts, _, first = _declared(model.kernels)
    return None if first is None else (first, len(contacts))


def mode_slot_of(model) -> dict[str, int]:
    """The slot of p of each contact's and friction element's mode, by name."""
    first, _ = mode_slots(model)
    slots = {name: first + d for d, (name, _, _) in enumerate(contacts_of(model))}
    return slots | {name: slot for name, _, slot, _, _ in frictions_of(model)}


def mode_slot_count(kernels) -> int:
    """The slots of p a module's contact modes take (its contacts and the closing flag; 0 without modes): after
    the parameters, before the inputs' headers (`lagcomp.codegen.contacts.mode_slots`)."""
    contacts, frictions, first = _declared(kernels)
    return 0 if first is None else len(contacts) + 1 + len(frictions)


def integrates_modes(model, method) -> bool:
    """Whether `method` integrates the model's modes (closed contacts, sticking friction): it integrates the
    module's ``rhs``, which reads them, or it is the Taylor method and the module's ``taylor_coefficients`` branches
    on them (``TAYLOR_MODE_PROGRAMS``: at most `lagcomp.codegen.taylor.MODE_PROGRAMS_MAX` mode sets)."""
    if "rhs" in method.kernels or method.name != "taylor":
        return "rhs" in method.kernels
    try:
        return hasattr(model.kernels, "TAYLOR_MODE_PROGRAMS")
    except ModelError:      # a model without the Taylor kernels (a kinematic tree's, issue 39) has no mode programs
        return False


def with_open_contacts(model, p: np.ndarray) -> np.ndarray:
    """`p` (or rows of it) with every contact open and closing not allowed: its ``event_values`` are the gaps."""
    slots = mode_slots(model)
    if slots is None:
        return p
    first, count = slots
    p = p.copy()
    p[..., first:first + count + 1] = 0.0
    return p


def set_initial_modes(model, method, t0: float, Y0: np.ndarray, P: np.ndarray, resting: np.ndarray | None,
                      where=lambda row: "") -> None:
    """Write into each row of P (rows, *) the contacts' modes at the start and whether impacts may close them.

    Impacts may close a contact when `method` integrates the modes (`integrates_modes`); a Taylor program that is
    the motion without contacts (a module with more mode sets than the Taylor method's bound) keeps every contact
    open, and refuses to start with one closed (`OptionError`).  A contact starts closed when it is at rest on its
    zero (`resting` (rows, C), from `check_contacts`) and its normal force with those contacts closed is positive:
    the ones whose force would pull are opened, one pass per contact at most, until the forces of the rest all push.
    """
    slots = mode_slots(model)
    if slots is None:
        return
    first, count = slots
    closing = 1.0 if integrates_modes(model, method) else 0.0
    P[:, first:first + count] = 0.0
    P[:, first + count] = closing
    _set_friction_modes(model, method, t0, Y0, P, where)
    forces = np.empty(count + len(frictions_of(model)))
    for row in np.flatnonzero(resting.any(axis=1)) if resting is not None else ():
        y, p, candidates = Y0[row], P[row], resting[row].copy()
        for _ in range(count):
            p[first:first + count] = candidates
            if model.kernels.contact_forces(t0, y, p, forces) != 0:
                candidates[:] = False
                break
            pushing = candidates & (forces[:count] > 0.0)
            if (pushing == candidates).all() or not pushing.any():
                candidates = pushing
                break
            candidates = pushing
        p[first:first + count] = candidates
        if candidates.any():        # the holding forces of sticking elements change with the closed contacts
            _set_friction_modes(model, method, t0, Y0[row:row + 1], P[row:row + 1], where)
        if candidates.any() and not closing:
            from lagcomp.codegen.taylor import MODE_PROGRAMS_MAX  # (imports sympy: only for this message)

            names = [name for (name, _, _), closed in zip(contacts_of(model), candidates, strict=True) if closed]
            raise OptionError(f"Contact(s) {names}{where(row)} start closed (touching, at rest, pressed shut), which "
                              f"`{method.name}` cannot integrate: its program is the motion without contacts (more "
                              f"than {MODE_PROGRAMS_MAX} mode sets, or friction pressed by a contact). Use "
                              f"{method_names(lambda m: 'rhs' in m.kernels and 'event_reset' in m.kernels)}.")


def _set_friction_modes(model, method, t0: float, Y0: np.ndarray, P: np.ndarray, where) -> None:
    """Write each friction element's mode at the start into the rows of P, after checking its coefficients.

    v ≠ 0 (beyond `CLOSED_GAP` Σ_j |∂v/∂q̇_j| (|q̇_j| + 1), the contacts' scale of rest): slip with s = sign v.
    v ≈ 0: stick when the force that holds it is within μs |N| (the elements at rest tried together; the one most
    beyond its limit slips, one pass per element at most), else slip against that force (toward the free motion).
    Refuses (`OptionError`) methods that do not integrate the modes (`integrates_modes`): a Taylor program beyond
    the bound on mode sets has no rows for a sticking element (its runs would be silently wrong at the first stick).
    """
    frictions = frictions_of(model)
    if not frictions:
        return
    if not integrates_modes(model, method) or "event_reset" not in method.kernels:
        from lagcomp.codegen.taylor import MODE_PROGRAMS_MAX  # (imports sympy: only for this message)

        raise OptionError(f"Friction element(s) {[f[0] for f in frictions]} of {model.name!r} stick and slip, which "
                          f"`{method.name}` cannot integrate (its program has no rows for a sticking element: more "
                          f"than {MODE_PROGRAMS_MAX} mode sets, or friction pressed by a contact). Use "
                          f"{method_names(lambda m: integrates_modes(model, m) and 'event_reset' in m.kernels)}.")
    _check_coefficients(model, frictions, P, where)
    n, slots = model.n, np.array([slot for _, _, slot, _, _ in frictions])
    events = [event for _, event, _, _, _ in frictions]
    count = len(contacts_of(model))
    values = np.empty(len(model.event_names))
    gradients = np.empty((len(model.event_names), Y0.shape[1] + 1 + len(model.parameters)))
    forces, limits = np.empty(count + len(frictions)), np.empty(len(frictions))
    for row in range(Y0.shape[0]):
        y, p = Y0[row], P[row]
        p[slots] = 1.0                                          # (event_values: v itself)
        model.kernels.event_values(t0, y, p, values)
        if model.kernels.event_gradients(t0, y, p, gradients) != 0:     # (events that read inputs: no partials)
            gradients[:] = 1.0
        v, a = values[events], gradients[events, n:2 * n]
        rest = np.abs(v) <= CLOSED_GAP * (np.abs(a) @ (np.abs(y[n:2 * n]) + 1.0))
        p[slots] = np.where(rest, 0.0, np.sign(v))
        for _ in range(len(frictions)):
            if not rest.any() or model.kernels.contact_forces(t0, y, p, forces) != 0:
                break
            model.kernels.friction_limits(t0, y, p, limits)
            excess = np.where(rest, np.where(limits > 0.0, np.abs(forces[count:]) - limits, np.inf), -np.inf)
            worst = int(np.argmax(excess))
            if excess[worst] <= 0.0:
                break
            p[slots[worst]] = -np.sign(forces[count + worst]) or 1.0
            rest[worst] = False


def _check_coefficients(model, frictions, P: np.ndarray, where) -> None:
    """Refuse friction coefficients (those given as parameters) below 0, or μk > μs (`ParameterError`)."""
    def values(mu):
        return P[:, model.parameters.index(mu)] if isinstance(mu, str) else np.full(P.shape[0], mu)

    for name, _, _, static, kinetic in frictions:
        mu_s, mu_k = values(static), values(kinetic)
        bad = np.flatnonzero(~((mu_k >= 0.0) & (mu_k <= mu_s)))
        if bad.size:
            row = int(bad[0])
            raise ParameterError(f"Friction `{name}`{where(row)}: its coefficients μs = {mu_s[row]}, μk = {mu_k[row]} "
                                 "must satisfy 0 <= μk <= μs.")


def contact_switches(model, p: np.ndarray, t: np.ndarray, y: np.ndarray, event: np.ndarray,
                     stopped_at_last: bool) -> tuple:
    """The mode switches along a run: ((time, element name, new mode), ...) in time order, an element a contact
    (mode 1 closed, 0 open) or a friction element (0 stick, ±1 slip).

    Replays the run's resets on a copy of `p` (the modes at the start): at the event rows (t, states before y,
    event indices `event`), the first resetting row at each time is the reset the driver applied (the others at
    that time it did not, nor any at the last row's time when the run `stopped_at_last` there: a terminal event,
    accumulated events, a failed reset); a contact's ``event_reset`` on the copy writes the modes as the driver's
    did, bitwise.
    """
    slots = mode_slots(model)
    if slots is None:
        return ()
    contacts, frictions = contacts_of(model), frictions_of(model)
    slot_of = mode_slot_of(model)
    element_of = {event_index: name for name, event_index, *_ in contacts + frictions}
    resetting = [e.resets or e.name in slot_of for e in model.events]
    work, out = p.copy(), np.empty(y.shape[1])
    switches, applied_at = [], None
    for r in range(t.shape[0]):
        e = int(event[r])
        if not resetting[e] or t[r] == applied_at or (stopped_at_last and t[r] == t[-1]):
            continue
        applied_at = t[r]
        if e not in element_of:
            continue
        before = work.copy()
        model.kernels.event_reset(float(t[r]), y[r], work, e, out)
        switches += [(float(t[r]), name, float(work[slot])) for name, slot in slot_of.items()
                     if work[slot] != before[slot]]
    return tuple(switches)


def contact_forces_along(model, p: np.ndarray, ts: np.ndarray, ys: np.ndarray, switches: tuple) -> np.ndarray | None:
    """The normal forces (rows, C), then the friction forces along v (rows, F), at the saved rows (ts, ys); None
    without modes.  A contact's force is 0 while it is open; a friction element's is the multiplier that holds
    v = 0 while it sticks and −μk |N| s while it slips with s = sign v (μk |N| = (μk/μs) ``friction_limits``).

    The modes at a row are those at the start (`p`) changed by the `switches` before it; at a switch's time the
    first row is the state before the switch and a second row at the same time the state after."""
    slots = mode_slots(model)
    if slots is None:
        return None
    first, count = slots
    frictions = frictions_of(model)
    sticking = np.array([slot for _, _, slot, _, _ in frictions], dtype=np.int64)
    coefficients = np.array([(_coefficient(model, p, mu_s), _coefficient(model, p, mu_k))
                             for _, _, _, mu_s, mu_k in frictions]).reshape(-1, 2)
    static = coefficients[:, 0]
    kinetic_over_static = np.divide(coefficients[:, 1], static, out=np.zeros_like(static), where=static > 0.0)
    out = np.zeros((ts.shape[0], count + sticking.size))
    limits = np.empty(sticking.size)
    for r, work in _modes_at_rows(model, p, ts, switches):
        if work[first:first + count].any() or (work[sticking] == 0.0).any():
            model.kernels.contact_forces(float(ts[r]), ys[r], work, out[r])
        slipping = work[sticking]
        if slipping.any():
            model.kernels.friction_limits(float(ts[r]), ys[r], work, limits)
            out[r, count:] = np.where(slipping != 0.0, -slipping * kinetic_over_static * limits, out[r, count:])
    return out


def _modes_at_rows(model, p: np.ndarray, ts: np.ndarray, switches: tuple):
    """(row, p with the modes at that row) for each saved row: the modes at the start (`p`) changed by the
    `switches` before it; at a switch's time the first row is the state before the switch and a second row at
    the same time the state after.  The same array each time, changed in place."""
    slot_of = mode_slot_of(model)
    work, k = p.copy(), 0
    for r in range(ts.shape[0]):
        while k < len(switches) and (switches[k][0] < ts[r] or (switches[k][0] == ts[r] and r > 0
                                                                 and ts[r - 1] == ts[r])):
            work[slot_of[switches[k][1]]] = float(switches[k][2])
            k += 1
        yield r, work


def contact_reactions_along(model, p: np.ndarray, ts: np.ndarray, ys: np.ndarray, switches: tuple,
                            reactions: dict) -> dict:
    """`reactions` (the constraints' multipliers by name at the saved rows, computed with the modes at the start)
    with the rows where some contact is closed computed again under the modes there (`_modes_at_rows`): a
    constrained module's ``reactions`` adds the change the closed contacts' forces cause
    (`lagcomp.kernel_support.resting.constrained_closed_contact_accelerations`).  `reactions` itself without
    modes or constraints."""
    slots = mode_slots(model)
    if slots is None or not model.k or not reactions:
        return reactions
    first, count = slots
    names = tuple(reactions)
    values = np.stack([reactions[name] for name in names], axis=1)
    for r, work in _modes_at_rows(model, p, ts, switches):
        if work[first:first + count].any() and model.kernels.reactions(float(ts[r]), ys[r], work, values[r]) != 0:
            values[r] = np.nan
    return {name: values[:, j].copy() for j, name in enumerate(names)}


def _coefficient(model, p: np.ndarray, mu) -> float:
    """A friction coefficient as `FRICTIONS` keeps it (a number or its parameter's name), valued in `p`."""
    return float(p[model.parameters.index(mu)]) if isinstance(mu, str) else float(mu)
