"""A warning for a reset that stopped the motion across its event's surface, after which the body went through it.

An event with a reset (``lc.Event(..., reset=...)``) fires on a crossing of its zero in its direction.  A reset
that leaves ġ = 0 on the surface (a "plastic floor" written as ``reset={xd: 0}``) hands what follows to the
acceleration: pushed back through the surface (gravity, for a floor), the motion leaves the zero on the side the
event fires into, which is a departure from the zero, not a crossing of it (the drivers tell the two apart after a
reset, `lagcomp.integrate.drivers.events.return_before`), so the event does not fire again and the body sinks
through the floor with the run's status 0.  Nothing the user wrote asks for that, and the drivers cannot tell it
from a reset whose kick carries on through the surface, so it is found after the run from the saved rows and
reported (`ResetWarning`); a surface that holds a body is a contact (`lc.Contact`: impacts, then resting
contact with its force).
"""

from __future__ import annotations

import warnings

import numpy as np

from lagcomp.errors import ResetWarning
from lagcomp.integrate.contacts import contacts_of, frictions_of
from lagcomp.integrate.drivers.events import ACTION_RESET

#: |ġ| just after a reset at most this fraction of |ġ| just before: the reset stopped the motion across the surface.
STOPPED = 1e-9
#: How far past its zero a saved row must be for the motion to have gone through: this fraction of the distance the
#: approach speed |ġ⁻| covers in the time since the reset (rounding of a body left resting on the zero stays far
#: below it).
THROUGH = 1e-6
#: The saved rows after a reset that are looked at (sinking shows at the first; a long run's rows cost a kernel call
#: each).
CHECKED_ROWS = 1000


def warn_of_resets_gone_through(model, p, actions, records, ts, ys) -> None:
    """Warn (`ResetWarning`, once per event) when a reset stopped a motion across its event's surface (ġ ≠ 0 before,
    0 after) and a saved row after it, before the event's next occurrence, lies past the zero on the side the event
    fires into.  The user's events only: a contact's or friction element's events switch modes, whose motion
    the module itself holds.  `actions`: the run's event actions; `records`: {name: EventRecord}; `ts` (rows,),
    `ys` (rows, ≥ N): the saved rows."""
    kernels, size = model.kernels, model.state_size
    if actions is None or not hasattr(kernels, "event_gradients"):
        return
    elements = {name for name, *_ in (*contacts_of(model), *frictions_of(model))}
    values, gradients = np.empty(len(model.events)), np.empty((len(model.events), size + 1 + len(model.parameters)))
    ydot = np.empty(size)
    for e, (event, action) in enumerate(zip(model.events, actions.tolist(), strict=True)):
        record = records.get(event.name)
        if (action != ACTION_RESET or event.name in elements or event.direction == 0 or record is None
                or record.t.size == 0):
            continue
        before = np.hstack([record.q, record.qd])
        after = np.hstack([record.q_after, record.qd_after])
        for r, t in enumerate(record.t.tolist()):
            approach = _rate(kernels, t, before[r], p, e, gradients, ydot)
            leaving = _rate(kernels, t, after[r], p, e, gradients, ydot)
            if approach is None or leaving is None or approach == 0.0 or not abs(leaving) <= STOPPED * abs(approach):
                continue
            following = record.t[r + 1] if r + 1 < record.t.size else np.inf
            for row in np.flatnonzero((ts > t) & (ts <= following))[:CHECKED_ROWS].tolist():
                kernels.event_values(ts[row], ys[row, :size], p, values)
                if event.direction * values[e] > 0.0 and abs(values[e]) > THROUGH * abs(approach) * (ts[row] - t):
                    warnings.warn(
                        f"event {event.name!r}: its reset at t = {t:.6g} stopped the motion across the event's "
                        f"surface (ġ = {leaving:.3g} after, {approach:.3g} before), and the motion then went through "
                        f"the surface (g = {values[e]:.3g} at t = {ts[row]:.6g}) without the event firing again: an "
                        "event fires on a crossing of its zero, and leaving the zero is not one. A floor or wall that "
                        "holds a body is lc.Contact(name, gap, restitution=e) (impacts, then resting contact).",
                        ResetWarning, stacklevel=4)
                    break
            else:
                continue
            break


def _rate(kernels, t, y, p, e, gradients, ydot) -> float | None:
    """ġ of event `e` at (t, y): ∂g/∂y · f + ∂g/∂t from the emitted ``event_gradients`` and ``rhs``; None when
    either kernel cannot give it (events reading inputs have no gradients)."""
    size = y.size
    if kernels.event_gradients(t, y, p, gradients) != 0 or kernels.rhs(t, y, p, ydot) != 0:
        return None
    return float(gradients[e, :size] @ ydot + gradients[e, size])
