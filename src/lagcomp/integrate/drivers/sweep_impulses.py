"""The contacts' impulses at the impacts a run or a sweep kept (`lagcomp.integrate.contacts.sweep_impulses`),
compiled.

Each comes from its jump: M (q̇⁺ − q̇⁻) = Gᵀ P over the contacts closed at the impact, P by least squares.  A
sweep of 10⁴ bouncing balls keeps some 5·10⁴ impacts, which a Python loop (three kernel calls and a
least-squares solve each) took 1 s over, three times the sweep itself; this loop takes 0.09 s.  Which contacts
count as closed is decided on the impact solver's own scale, written as its loop
(`lagcomp.kernel_support.impacts.contact_impacts`; `contacts.touching` is the same sum as a matrix product).
A module of its own, imported only by a run that keeps a contact's impacts.
"""

from __future__ import annotations

import numpy as np
from numba import njit, types

from lagcomp.integrate.drivers.kernel_types import (
    EVENT_GRADIENTS,
    EVENTS,
    INDICES,
    INT,
    MASS_MATRIX,
    MATRIX,
    VECTOR,
)
from lagcomp.kernel_support.impacts import touching

#: contact_impulses(mass_matrix, event_values, event_gradients, contact_events, firing, n, P, count, times,
#: before, after, mass, values, gradients, out)
SIGNATURE = types.none(MASS_MATRIX, EVENTS, EVENT_GRADIENTS, INDICES, INT, INT, MATRIX, INDICES, MATRIX,
                       types.float64[:, :, ::1], types.float64[:, :, ::1], MATRIX, VECTOR, MATRIX,
                       types.float64[:, :, ::1])


@njit(SIGNATURE, cache=True, error_model="numpy", nogil=True)
def contact_impulses(mass_matrix, event_values, event_gradients, contact_events, firing, n, P, count, times,
                     before, after, mass, values, gradients, out):
    """``out[k, r]`` (C,) = the normal impulses of the C contacts (events ``contact_events``) at the kept
    impact r < min(``count[k]``, cap) of contact event `firing` in trajectory k (parameters ``P[k]``), at time
    ``times[k, r]`` with states ``before[k, r]`` and ``after[k, r]`` ((q, q̇), q of size `n`): least squares
    of Gᵀ P = M (q̇⁺ − q̇⁻) over the contacts closed then (the firing one, and those whose gap is within
    `CLOSED_GAP` Σ_j |∂g/∂q_j| (|q_j| + 1), the impact solver's scale), 0 for the others.  ``mass`` (n, n),
    ``values`` (E,) and ``gradients`` (E, *) are work arrays for the kernels; rows of ``out`` past a
    trajectory's count are left as they are."""
    c_all = contact_events.shape[0]
    for k in range(times.shape[0]):
        p = P[k]
        for r in range(min(count[k], times.shape[1])):
            t, y = times[k, r], before[k, r]
            mass_matrix(t, y, p, mass)
            event_values(t, y, p, values)
            event_gradients(t, y, p, gradients)
            closed = np.empty(c_all, dtype=np.bool_)
            m = 0
            for a in range(c_all):
                event = contact_events[a]
                closed[a] = event == firing or touching(values[event], gradients, event, y[:n])
                m += closed[a]
            transposed = np.empty((n, m))
            column = 0
            for a in range(c_all):
                if closed[a]:
                    for j in range(n):
                        transposed[j, column] = gradients[contact_events[a], j]
                    column += 1
            dv = np.empty(n)
            for j in range(n):
                dv[j] = after[k, r, n + j] - y[n + j]
            solution = np.linalg.lstsq(transposed, mass @ dv, rcond=np.finfo(np.float64).eps * max(n, m))[0]
            column = 0
            for a in range(c_all):
                if closed[a]:
                    out[k, r, a] = solution[column]
                    column += 1
                else:
                    out[k, r, a] = 0.0
