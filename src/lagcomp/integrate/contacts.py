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
        for name, event, _ in contacts:
            scale = float(np.sum(np.abs(gradients[event, :n]) * (np.abs(y[:n]) + 1.0)))
            if values[event] < -CLOSED_GAP * scale:
                raise InitialConditionError(
                    f"Contact `{name}`{where(row)}: its gap is {values[event]:.6g} < 0 at t0 = {t0}: the bodies start "
                    "inside each other. Start with the gap >= 0 (touching is 0).")
