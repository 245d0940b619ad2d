"""The sweep of the Radau driver: `radau_run` over many trajectories (`lagcomp.integrate.sweep`).

A module of its own, apart from `lagcomp.integrate.drivers.radau`, as `embedded_sweep` is apart from
`embedded`: a single run (`simulate`) then loads only the driver from numba's cache.  The loop is
`sweep_embedded`'s with Radau's kernels and constants; each trajectory has its own carry (Jacobian,
last collocation polynomial, controller memory: `lagcomp.integrate.drivers.radau`), allocated here.
"""

from __future__ import annotations

import warnings

import numpy as np
from numba import njit, types
from numba.core.errors import NumbaExperimentalFeatureWarning

from lagcomp.integrate.drivers.kernel_types import (
    ENERGY,
    EVENTS,
    FLOAT,
    INDICES,
    INT,
    MATRIX,
    RHS,
    RHS_JACOBIAN,
    VECTOR,
)
from lagcomp.integrate.drivers.radau import CONSTANTS, CONTROL_SLOTS, radau_run
from lagcomp.integrate.drivers.run_state import COUNTER_SLOTS, EVENT_ROWS, TIME
from lagcomp.integrate.drivers.sweep_rows import NO_PAUSE, SWEEP_ROWS, fold_events, fold_rows, record_end
from lagcomp.integrate.status import Status

SWEEP_SIGNATURE = types.none(RHS, RHS_JACOBIAN, EVENTS, ENERGY,
                             MATRIX, MATRIX, INT, FLOAT, FLOAT, FLOAT, VECTOR, FLOAT, INT, INT, VECTOR, types.boolean,
                             INDICES, INDICES, MATRIX, VECTOR, INDICES, types.int64[:, ::1], types.float64[:, :, ::1],
                             MATRIX, types.int64[:, ::1], types.float64[:, :, ::1], types.float64[:, :, :, ::1],
                             *CONSTANTS, INT)


def sweep_radau(rhs, rhs_jacobian, event_values, energy,
                Y0, P, projecting, t0, t_end, rtol, atol, max_step, max_steps, save_every, t_eval, save_initial,
                directions, actions, final, t_final, status, counts, dense, energy_stats,
                event_count, event_t, event_y,
                C, T, TI, MU, ERROR_WEIGHTS, DENSE_WEIGHTS, differential):
    """Trajectory k from (t0, Y0[k]) with parameters P[k] to t_end by `radau_run`, for every row k.

    ``differential``: `radau_run`'s (the count of differential components; the state size for an ODE).
    The outputs are `lagcomp.integrate.drivers.embedded_sweep.sweep_embedded`'s (its docstring).
    """
    n_traj = Y0.shape[0]
    n2 = Y0.shape[1]
    n_events = directions.shape[0]
    for k in range(n_traj):
        y = Y0[k].copy()
        p = P[k]
        clock = np.zeros(2)
        clock[TIME] = t0
        counters = np.zeros(COUNTER_SLOTS, dtype=np.int64)
        residual = np.zeros(1)
        jacobian = np.zeros((n2, n2))
        previous = np.zeros((4, n2))
        control = np.zeros(CONTROL_SLOTS)
        ts = np.empty(SWEEP_ROWS)
        ys = np.empty((SWEEP_ROWS, n2))
        rows_e = max(n_events, 1)
        ev_t = np.empty(rows_e)
        ev_y = np.empty((rows_e, n2))
        ev_i = np.empty(rows_e, dtype=np.int64)
        e0 = energy(t0, y, p)
        deviation = 0.0
        row = 0
        if dense.shape[1] > 0 and save_initial:
            for c in range(n2):
                dense[k, 0, c] = y[c]
            row = 1
        for e in range(n_events):
            event_count[k, e] = 0
        while True:
            counters[EVENT_ROWS] = 0
            code, n_saved = radau_run(rhs, rhs_jacobian, event_values,
                                      y, clock, counters, p, projecting, residual, t_end, rtol, atol, max_step,
                                      max_steps, NO_PAUSE, save_every, t_eval, ts, ys,
                                      directions, actions, ev_t, ev_y, ev_i,
                                      C, T, TI, MU, ERROR_WEIGHTS, DENSE_WEIGHTS, differential, jacobian, previous,
                                      control)
            deviation, row = fold_rows(energy, ts, ys, n_saved, p, e0, deviation, dense, k, row)
            fold_events(counters[EVENT_ROWS], ev_t, ev_y, ev_y, ev_i, event_count, event_t, event_y, k)
            if code != Status.BUFFER_FULL:
                break
        record_end(k, y, clock, counters, code, e0, deviation, final, t_final, status, counts, energy_stats)


# Passing the kernels on to `radau_run` is numba's first-class function feature, which it labels
# experimental with a warning at this compile (once per installation); the drivers rely on it by design.
with warnings.catch_warnings():
    warnings.simplefilter("ignore", NumbaExperimentalFeatureWarning)
    sweep_radau = njit(SWEEP_SIGNATURE, cache=True, error_model="numpy", nogil=True)(sweep_radau)
