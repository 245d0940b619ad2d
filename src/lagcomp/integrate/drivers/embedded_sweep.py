"""The sweep of the embedded Runge-Kutta driver: `embedded_run` over many trajectories (`lagcomp.integrate.sweep`).

A module of its own, apart from `lagcomp.integrate.drivers.embedded`: numba loads a function with an
explicit signature from its cache when its module is imported, and a single run (`simulate`) needs
only `embedded_run`; loading the sweep (and `fold_rows`) as well cost a warm start some 30 ms.
"""

from __future__ import annotations

import warnings

import numpy as np
from numba import njit, types
from numba.core.errors import NumbaExperimentalFeatureWarning

from lagcomp.integrate.drivers.embedded import TABLEAU, embedded_run
from lagcomp.integrate.drivers.kernel_types import (
    ENERGY,
    EVENT_RESET,
    EVENTS,
    FLOAT,
    INDICES,
    INT,
    MATRIX,
    PROJECT,
    RESIDUAL,
    RHS,
    VECTOR,
)
from lagcomp.integrate.drivers.run_state import (
    CLOCK_SLOTS,
    COUNTER_SLOTS,
    EVENT_ROWS,
    STIFF_AT_STEP,
    TIME,
)
from lagcomp.integrate.drivers.sweep_rows import (
    NO_PAUSE,
    SWEEP_ROWS,
    fold_events,
    fold_rows,
    record_end,
)
from lagcomp.integrate.status import Status

#: The column of ``counts`` that holds the step at which a trajectory was declared stiff.
STIFF_COLUMN = 3

SWEEP_SIGNATURE = types.none(RHS, PROJECT, RESIDUAL, EVENTS, EVENT_RESET, ENERGY,
                             MATRIX, MATRIX, INT, FLOAT, FLOAT, FLOAT, VECTOR, FLOAT, INT, INT, VECTOR, types.boolean,
                             INDICES, INDICES, MATRIX, VECTOR, INDICES, types.int64[:, ::1], types.float64[:, :, ::1],
                             MATRIX, types.int64[:, ::1], types.float64[:, :, ::1], types.float64[:, :, :, ::1],
                             *TABLEAU)


def sweep_embedded(rhs, project, constraint_residual, event_values, event_reset, energy,
                   Y0, P, projecting, t0, t_end, rtol, atol, max_step, max_steps, save_every, t_eval, save_initial,
                   directions, actions, final, t_final, status, counts, dense, energy_stats,
                   event_count, event_t, event_y,
                   A, B, C, error_weights, error_norm, error_exponent, dense_kind, dense_weights, extra_A, extra_C,
                   stiffness_bound):
    """Trajectory k from (t0, Y0[k]) with parameters P[k] to t_end by `embedded_run`, for every row k.

    Each trajectory runs the resumable driver with a small row buffer (`SWEEP_ROWS`) and folds the
    rows of every call into its outputs (`fold_rows`).  It releases the GIL: the caller runs disjoint
    row ranges on several threads (`lagcomp.integrate.sweep`), and the result does not depend on how
    many (trajectories share only the read-only inputs and write their own rows).  Outputs, per k:

    * ``final[k]`` (2n,), ``t_final[k]``, ``status[k]``, ``counts[k]`` = [nfev, nsteps, nrejected,
      the step at which the stiffness test declared the trajectory stiff (0: not)] (the sweeps of the
      other methods leave the last column alone);
    * ``dense[k]`` (m, 2n): the saved rows in order (the ``t_eval`` rows, which hold the times after t0,
      with the initial state first when ``save_initial``); m = 0 when not wanted;
    * ``energy_stats[k]`` = [E0, largest |E - E0| over the saved rows], E = ``energy`` (T + V);
    * ``event_count[k]`` (E,) occurrences of each event, the first ``cap`` of them in
      ``event_t[k]`` (E, cap) and ``event_y[k]`` (E, cap, 2n) (the states just before them; with 4n columns, the
      states after them in the last 2n: `fold_events`).

    Each trajectory runs with a copy of its row of ``P``: a contact's reset writes mode slots of its p.
    """
    n_traj = Y0.shape[0]
    n2 = Y0.shape[1]
    n_events = directions.shape[0]
    for k in range(n_traj):
        y = Y0[k].copy()
        p = P[k].copy()
        clock = np.zeros(CLOCK_SLOTS)
        clock[TIME] = t0
        counters = np.zeros(COUNTER_SLOTS, dtype=np.int64)
        residual = np.zeros(1)
        ts = np.empty(SWEEP_ROWS)
        ys = np.empty((SWEEP_ROWS, n2))
        rows_e = max(n_events, 1)
        ev_t = np.empty(rows_e)
        ev_y = np.empty((rows_e, n2))
        ev_i = np.empty(rows_e, dtype=np.int64)
        ev_y_after = np.empty((rows_e, n2))
        at_zero = np.zeros(n_events, dtype=np.int64)
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
            code, n_saved = embedded_run(rhs, project, constraint_residual, event_values, event_reset,
                                         y, clock, counters, p, projecting, residual, t_end, rtol, atol, max_step,
                                         max_steps, NO_PAUSE, save_every, t_eval, ts, ys,
                                         directions, actions, ev_t, ev_y, ev_i, ev_y_after, at_zero,
                                         A, B, C, error_weights, error_norm, error_exponent, dense_kind,
                                         dense_weights, extra_A, extra_C, stiffness_bound)
            deviation, row = fold_rows(energy, ts, ys, n_saved, p, e0, deviation, dense, k, row)
            fold_events(counters[EVENT_ROWS], ev_t, ev_y, ev_y_after, ev_i, event_count, event_t, event_y, k)
            if code != Status.BUFFER_FULL:
                break
        record_end(k, y, clock, counters, code, e0, deviation, final, t_final, status, counts, energy_stats)
        counts[k, STIFF_COLUMN] = counters[STIFF_AT_STEP]


# Passing the kernels on to `embedded_run` is numba's first-class function feature, which it labels
# experimental with a warning at this compile (once per installation); the drivers rely on it by design.
with warnings.catch_warnings():
    warnings.simplefilter("ignore", NumbaExperimentalFeatureWarning)
    sweep_embedded = njit(SWEEP_SIGNATURE, cache=True, error_model="numpy", nogil=True)(sweep_embedded)
