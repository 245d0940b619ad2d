"""What every sweep loop does with the rows a driver call wrote: shared by the sweeps of all driver families.

A sweep runs each trajectory with the ordinary resumable driver and a small row buffer, and after
every call folds those rows into the outputs the caller asked for (`lagcomp.integrate.sweep`):
the largest energy deviation |E - E0| over the saved rows, and the rows themselves into
``dense[k]`` while it has room (`fold_rows`); the event rows into the trajectory's event outputs
(`fold_events`); at the end, how the trajectory ended (`record_end`).
"""

from __future__ import annotations

from numba import njit, types

from lagcomp.integrate.drivers.kernel_types import (
    ENERGY,
    FLOAT,
    INDICES,
    INT,
    MATRIX,
    VECTOR,
)
from lagcomp.integrate.drivers.run_state import NFEV, NREJECTED, NSTEPS, TIME

#: Rows of each trajectory's output buffer in a sweep, and the step budget of a sweep's driver call (none).
SWEEP_ROWS = 64
NO_PAUSE = 2**63 - 1

_FOLD = types.Tuple((types.float64, types.int64))(ENERGY, VECTOR, MATRIX, INT, VECTOR, FLOAT, FLOAT,
                                                  types.float64[:, :, ::1], INT, INT)


@njit(_FOLD, cache=True, error_model="numpy", nogil=True)
def fold_rows(energy, ts, ys, n_saved, p, e0, deviation, dense, k, row):
    """Fold rows ``ts[:n_saved]``, ``ys[:n_saved]`` of trajectory `k` into `deviation` and ``dense[k, row:]``.

    Returns the new (deviation, row): `deviation` is the largest |energy - e0| so far, `row` the next
    free row of ``dense[k]`` (rows past ``dense.shape[1]`` are not kept).
    """
    n2 = ys.shape[1]
    for r in range(n_saved):
        deviation = max(deviation, abs(energy(ts[r], ys[r], p) - e0))
        if row < dense.shape[1]:
            for c in range(n2):
                dense[k, row, c] = ys[r, c]
            row += 1
    return deviation, row


_FIRST_ROW = INT(MATRIX, types.float64[:, :, ::1], INT)


@njit(_FIRST_ROW, cache=True, error_model="numpy", nogil=True)
def first_row(Y0, dense, k):
    """Write the initial state of trajectory `k` as the first row of ``dense[k]`` (if it keeps rows);
    returns the next free row."""
    if dense.shape[1] == 0:
        return 0
    for c in range(Y0.shape[1]):
        dense[k, 0, c] = Y0[k, c]
    return 1


_EVENTS = types.none(INT, VECTOR, MATRIX, MATRIX, INDICES, types.int64[:, ::1], types.float64[:, :, ::1],
                     types.float64[:, :, :, ::1], INT)


@njit(_EVENTS, cache=True, error_model="numpy", nogil=True)
def fold_events(n_rows, ev_t, ev_y, ev_y_after, ev_i, event_count, event_t, event_y, k):
    """Fold the `n_rows` event rows a driver call wrote (time ``ev_t``, state ``ev_y`` just before, ``ev_y_after``
    just after, event ``ev_i``) into trajectory `k`'s outputs: ``event_count[k, e]`` counts every occurrence of
    event e, ``event_t[k, e]`` and ``event_y[k, e]`` keep the first ``event_t.shape[2]`` of them.  A row of
    ``event_y`` holds the state before (its first N columns, N = ``ev_y.shape[1]``) and, when it is 2N wide (a
    sweep of a model whose events reset the state), the state after in the next N."""
    cap = event_t.shape[2]
    width = ev_y.shape[1]
    after = event_y.shape[3] >= 2 * width
    for r in range(n_rows):
        e = ev_i[r]
        j = event_count[k, e]
        if j < cap:
            event_t[k, e, j] = ev_t[r]
            for c in range(width):
                event_y[k, e, j, c] = ev_y[r, c]
            if after:
                for c in range(width):
                    event_y[k, e, j, width + c] = ev_y_after[r, c]
        event_count[k, e] = j + 1


_RECORD = types.none(INT, VECTOR, VECTOR, INDICES, INT, FLOAT, FLOAT, MATRIX, VECTOR, INDICES, types.int64[:, ::1],
                     MATRIX)


@njit(_RECORD, cache=True, error_model="numpy", nogil=True)
def record_end(k, y, clock, counters, code, e0, deviation, final, t_final, status, counts, energy_stats):
    """Write how trajectory `k` ended into row k of the outputs: its state, time and status, its counters
    [nfev, nsteps, nrejected], and [E0, largest |E - E0|]."""
    for c in range(y.shape[0]):
        final[k, c] = y[c]
    t_final[k] = clock[TIME]
    status[k] = code
    counts[k, 0] = counters[NFEV]
    counts[k, 1] = counters[NSTEPS]
    counts[k, 2] = counters[NREJECTED]
    energy_stats[k, 0] = e0
    energy_stats[k, 1] = deviation
