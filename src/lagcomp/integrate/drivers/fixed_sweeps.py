"""The sweep loops of the explicit fixed-step drivers: many trajectories in one compiled loop that releases the GIL.

`lagcomp.integrate.sweep` calls a loop on a chunk of trajectories, one row of ``Y0`` (initial
states, (N, 2n)) and ``P`` (parameter vectors, (N, n_p)) each, from several Python threads at
once.  Trajectory k runs the ordinary resumable driver (`fixed_step`) from ``(t0, Y0[k])``, a
buffer of `SWEEP_ROWS` rows at a time, and after every call `fold_rows` folds the rows into the
outputs; the trajectories share only the read-only inputs and write disjoint output rows, so the
result does not depend on the number of threads (bitwise).  Outputs, row k each:

* ``final`` (N, 2n), ``t_final`` (N,), ``status`` (N,) and ``counts`` (N, 3) = [nfev, nsteps,
  nrejected]: where and how the trajectory ended;
* ``dense`` (N, m, 2n): the initial state, then the saved rows (every ``save_every``-th step and
  the last) while they fit; m = 0 keeps none;
* ``energy_stats`` (N, 2): the initial energy T + V and the largest |E - E0| over the saved rows.

The kernels come first, as for the drivers, then the model's ``energy``.
"""

from __future__ import annotations

import numpy as np
from numba import njit, types

from lagcomp.integrate.drivers.fixed_step import composition_run, runge_kutta_run
from lagcomp.integrate.drivers.kernel_types import (
    ENERGY,
    FLOAT,
    INDICES,
    INT,
    MATRIX,
    PROJECT,
    RESIDUAL,
    RHS,
    VECTOR,
)
from lagcomp.integrate.drivers.run_state import COUNTER_SLOTS
from lagcomp.integrate.drivers.sweep_rows import (
    NO_PAUSE,
    SWEEP_ROWS,
    first_row,
    fold_rows,
    record_end,
)
from lagcomp.integrate.status import Status

#: Y0, P, projecting, t0, dt, n_steps, t_end, save_every, final, t_final, status, counts, dense, energy_stats.
FIXED_SWEEP = (MATRIX, MATRIX, INT, FLOAT, FLOAT, INT, FLOAT, INT,
               MATRIX, VECTOR, INDICES, types.int64[:, ::1], types.float64[:, :, ::1], MATRIX)
#: ``runge_kutta_sweep(rhs, project, constraint_residual, energy, <FIXED_SWEEP>, A, C, weights, denominator)``.
RUNGE_KUTTA_SWEEP = types.none(RHS, PROJECT, RESIDUAL, ENERGY, *FIXED_SWEEP, MATRIX, VECTOR, VECTOR, FLOAT)
#: ``composition_sweep(rhs, energy, <FIXED_SWEEP>, weights)``.
COMPOSITION_SWEEP = types.none(RHS, ENERGY, *FIXED_SWEEP, VECTOR)

@njit(RUNGE_KUTTA_SWEEP, cache=True, error_model="numpy", nogil=True)
def runge_kutta_sweep(rhs, project, constraint_residual, energy, Y0, P, projecting, t0, dt, n_steps, t_end,
                      save_every, final, t_final, status, counts, dense, energy_stats, A, C, weights, denominator):
    """Trajectory k from (t0, Y0[k]) with parameters P[k]: ``n_steps`` steps of `fixed_step.runge_kutta_run`."""
    n2 = Y0.shape[1]
    for k in range(Y0.shape[0]):
        y, p = Y0[k].copy(), P[k]
        clock, counters, residual = np.array([t0, 0.0]), np.zeros(COUNTER_SLOTS, dtype=np.int64), np.zeros(1)
        ts, ys = np.empty(SWEEP_ROWS), np.empty((SWEEP_ROWS, n2))
        e0, deviation, row = energy(t0, y, p), 0.0, first_row(Y0, dense, k)
        while True:
            code, n_saved = runge_kutta_run(rhs, project, constraint_residual, y, clock, counters, p, projecting,
                                            residual, t0, dt, n_steps, NO_PAUSE, t_end, save_every, ts, ys,
                                            A, C, weights, denominator)
            deviation, row = fold_rows(energy, ts, ys, n_saved, p, e0, deviation, dense, k, row)
            if code != Status.BUFFER_FULL:
                break
        record_end(k, y, clock, counters, code, e0, deviation, final, t_final, status, counts, energy_stats)


@njit(COMPOSITION_SWEEP, cache=True, error_model="numpy", nogil=True)
def composition_sweep(rhs, energy, Y0, P, projecting, t0, dt, n_steps, t_end, save_every, final, t_final, status,
                      counts, dense, energy_stats, weights):
    """Trajectory k from (t0, Y0[k]) with parameters P[k]: ``n_steps`` steps of `fixed_step.composition_run`."""
    n2 = Y0.shape[1]
    for k in range(Y0.shape[0]):
        y, p = Y0[k].copy(), P[k]
        clock, counters, residual = np.array([t0, 0.0]), np.zeros(COUNTER_SLOTS, dtype=np.int64), np.zeros(1)
        ts, ys = np.empty(SWEEP_ROWS), np.empty((SWEEP_ROWS, n2))
        e0, deviation, row = energy(t0, y, p), 0.0, first_row(Y0, dense, k)
        while True:
            code, n_saved = composition_run(rhs, y, clock, counters, p, projecting, residual, t0, dt, n_steps,
                                            NO_PAUSE, t_end, save_every, ts, ys, weights)
            deviation, row = fold_rows(energy, ts, ys, n_saved, p, e0, deviation, dense, k, row)
            if code != Status.BUFFER_FULL:
                break
        record_end(k, y, clock, counters, code, e0, deviation, final, t_final, status, counts, energy_stats)
