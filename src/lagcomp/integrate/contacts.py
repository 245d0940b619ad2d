"""What a run checks of a model's contacts before it starts (`lagcomp.model.contacts.Contact`).

The module's ``CONTACTS`` lists each contact as (name, event index, restitution), the restitution a
number or the name of the parameter that holds it.  A run refuses a restitution outside [0, 1]
(`ParameterError`) and a gap that is negative at the start (`InitialConditionError`): a body that
starts inside another has no impact to apply, and its motion would be meaningless.  "Negative" allows
rounding: g < −`CLOSED_GAP` Σ_j |∂g/∂q_j| (|q_j| + 1), the scale the impact solver uses for "touching".
"""

from __future__ import annotations

import numpy as np

from lagcomp.errors import InitialConditionError, ParameterError
from lagcomp.kernel_support.impacts import CLOSED_GAP


def touching(gradients: np.ndarray, q: np.ndarray) -> np.ndarray:
    """The gaps (C,) that count as touching for contacts of gradients ∂g/∂q (C, n) at q: `CLOSED_GAP` Σ_j
    |∂g/∂q_j| (|q_j| + 1), the impact solver's own scale (`lagcomp.kernel_support.impacts.contact_impacts`)."""
    return CLOSED_GAP * (np.abs(gradients) @ (np.abs(q) + 1.0))


def contacts_of(model) -> tuple:
    """The model's contacts as (name, event index, restitution), () for a module without them."""
    return tuple(getattr(model.kernels, "CONTACTS", ()))


def check_contacts(model, t0: float, Y0: np.ndarray, P: np.ndarray, where=lambda row: "") -> None:
    """Refuse restitutions outside [0, 1] and penetrating starts, for each row of Y0 (rows, N) and P (rows, *).

    `where`(row) says which trajectory a row is, for the message of a sweep ("" for a single run).
    """
    contacts = contacts_of(model)
    if not contacts:
        return
    n = model.n
    values = np.empty(len(model.event_names))
    gradients = np.empty((len(model.event_names), Y0.shape[1] + 1 + len(model.parameters)))
    for row in range(Y0.shape[0]):
        y, p = Y0[row], P[row]
        for name, _, restitution in contacts:
            e = float(p[model.parameters.index(restitution)]) if isinstance(restitution, str) else restitution
            if not 0.0 <= e <= 1.0:
                raise ParameterError(f"Contact `{name}`{where(row)}: its restitution {restitution} = {e} is outside "
                                     "[0, 1] (1 elastic, 0 plastic).")
        model.kernels.event_values(t0, y, p, values)
        model.kernels.event_gradients(t0, y, p, gradients)
        allowed = touching(gradients[:, :n], y[:n])
        for name, event, _ in contacts:
            if values[event] < -allowed[event]:
                raise InitialConditionError(
                    f"Contact `{name}`{where(row)}: its gap is {values[event]:.6g} < 0 at t0 = {t0}: the bodies start "
                    "inside each other. Start with the gap >= 0 (touching is 0).")


def impulses(model, p: np.ndarray, firing: int, t: np.ndarray, before: np.ndarray, after: np.ndarray) -> np.ndarray:
    """The contacts' normal impulses at the k impacts of event `firing` (a contact's): (k, C) at times `t` with
    states `before` and `after` (k, N), columns the model's contacts in order (`contacts_of`).

    From the jump itself: M (q̇⁺ − q̇⁻) = Gᵀ P over the contacts closed then (the firing one, and those whose gap
    is within the impact solver's `CLOSED_GAP` scale), P by least squares (exact for independent contacts); 0
    for the others.  In the units of
    the gap's conjugate force times time (N s for a gap in metres).
    """
    contacts = contacts_of(model)
    n, size = model.n, model.state_size
    out = np.zeros((t.shape[0], len(contacts)))
    events = [event for _, event, _ in contacts]
    mass = np.empty((n, n))
    values = np.empty(len(model.event_names))
    gradients = np.empty((len(model.event_names), size + 1 + len(model.parameters)))
    for row in range(t.shape[0]):
        y = before[row]
        model.kernels.mass_matrix(t[row], y, p, mass)
        model.kernels.event_values(t[row], y, p, values)
        model.kernels.event_gradients(t[row], y, p, gradients)
        G = gradients[events, :n]
        closed = values[events] <= touching(G, y[:n])
        closed[events.index(firing)] = True
        jump = mass @ (after[row, n:size] - y[n:size])
        out[row, closed] = np.linalg.lstsq(G[closed].T, jump, rcond=None)[0]
    return out
