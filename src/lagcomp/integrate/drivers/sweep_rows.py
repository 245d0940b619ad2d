"""What every sweep loop does with the rows a driver call wrote: shared by the sweeps of all driver families.

A sweep runs each trajectory with the ordinary resumable driver and a small row buffer, and after
every call folds those rows into the outputs the caller asked for (`lagcomp.integrate.sweep`):
the largest energy deviation |E - E0| over the saved rows, and the rows themselves into
``dense[k]`` while it has room.
"""

from __future__ import annotations

from numba import njit, types

from lagcomp.integrate.drivers.kernel_types import ENERGY, FLOAT, INT, MATRIX, VECTOR

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
