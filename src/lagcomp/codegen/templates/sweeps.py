"""Sweep drivers: a *template*, appended to every generated module after the other drivers.

A sweep integrates N trajectories, one per row of ``Y0`` (initial states,
(N, 2n)) and ``P`` (parameter vectors, (N, n_p)), in a compiled loop that
releases the GIL (``nogil``): the caller runs disjoint row ranges on several
Python threads at once (`lagcomp.integrate.sweep`).  Trajectories share
nothing but the read-only inputs and write disjoint rows of the outputs, so
the result does not depend on the number of threads (bitwise).  Threads
rather than ``parallel=True``/``prange``: the parallel compilation of a
sweep function took 1.7 times as long (DOP853 sweep of the double pendulum,
first call: 8.4 s against 4.9 s), for the same loop.  Each trajectory runs the ordinary resumable driver (see
``drivers.py``) with a small row buffer of ``_SWEEP_ROWS`` rows, and after
every call folds the rows into the outputs the caller asked for:

``projecting`` is passed to the driver (constrained systems).  Outputs:

* ``final`` (N, 2n), ``t_final`` (N,), ``status`` (N,), ``counts`` (N, 3)
  = [nfev, nsteps, nrejected]: always;
* ``dense`` (N, m, 2n): the saved rows in order (the ``t_eval`` rows of an
  adaptive method (``t_eval`` holds those after t0, ``save_initial`` says
  whether t0 is one too), every ``save_every``-th step of a fixed-step one,
  the initial state first); m = 0 when not wanted;
* ``energy_stats`` (N, 2): the initial energy T + V and the largest |E − E₀| over
  the saved rows;
* events (adaptive methods): ``event_count`` (N, E) occurrences of each
  event and the first ``cap`` of them in ``event_t`` (N, E, cap) and
  ``event_y`` (N, E, cap, 2n).

The text holds two functions, ``sweep_adaptive`` and ``sweep_fixed``,
written against placeholder drivers ``ADAPTIVE_DRIVER`` and
``FIXED_DRIVER``.  The emitter copies them once per driver, renaming them
``sweep_<driver>`` (e.g. ``sweep_dop853_run`` calls ``dop853_run``): numba
caches a function only when its callees are module globals, not arguments.
numba compiles a function at its first call, so a model pays for the sweep
of a method only when it sweeps with it.  The trailing ``coefficients`` tuple
is the driver's tableau arguments, passed through.
"""

# ruff: noqa: F821  (energy, the drivers and _ODE_* are defined by the module this text is appended to)

import numpy as np
from numba import njit

_SWEEP_ROWS = 64            # rows of each trajectory's output buffer
_SWEEP_NO_PAUSE = np.iinfo(np.int64).max


@njit(cache=True, error_model="numpy", nogil=True)
def sweep_adaptive(Y0, P, projecting, t0, t_end, rtol, atol, max_step, max_steps, save_every, t_eval, save_initial,
                   directions, actions, final, t_final, status, counts, dense, energy_stats,
                   event_count, event_t, event_y, coefficients):
    """Trajectory k from (t0, Y0[k]) with parameters P[k] to t_end by ``ADAPTIVE_DRIVER``; see the module docstring."""
    n_traj = Y0.shape[0]
    n2 = Y0.shape[1]
    n_events = directions.shape[0]
    cap = event_t.shape[2]
    for k in range(n_traj):
        y = Y0[k].copy()
        p = P[k]
        clock = np.zeros(2)
        clock[0] = t0
        counters = np.zeros(6, dtype=np.int64)
        residual = np.zeros(1)
        ts = np.empty(_SWEEP_ROWS)
        ys = np.empty((_SWEEP_ROWS, n2))
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
            counters[5] = 0
            code, n_saved = ADAPTIVE_DRIVER(y, clock, counters, p, projecting, residual, t_end, rtol, atol, max_step,
                                            max_steps, _SWEEP_NO_PAUSE, save_every, t_eval, ts, ys,
                                            directions, actions, ev_t, ev_y, ev_i, *coefficients)
            for r in range(n_saved):
                deviation = max(deviation, abs(energy(ts[r], ys[r], p) - e0))
                if row < dense.shape[1]:
                    for c in range(n2):
                        dense[k, row, c] = ys[r, c]
                    row += 1
            for r in range(counters[5]):
                e = ev_i[r]
                j = event_count[k, e]
                if j < cap:
                    event_t[k, e, j] = ev_t[r]
                    for c in range(n2):
                        event_y[k, e, j, c] = ev_y[r, c]
                event_count[k, e] = j + 1
            if code != _ODE_BUFFER_FULL:
                break
        for c in range(n2):
            final[k, c] = y[c]
        t_final[k] = clock[0]
        status[k] = code
        counts[k, 0] = counters[0]
        counts[k, 1] = counters[1]
        counts[k, 2] = counters[2]
        energy_stats[k, 0] = e0
        energy_stats[k, 1] = deviation


@njit(cache=True, error_model="numpy", nogil=True)
def sweep_fixed(Y0, P, projecting, t0, dt, n_steps, t_end, save_every, final, t_final, status, counts, dense, energy_stats,
                coefficients):
    """Trajectory k from (t0, Y0[k]) with parameters P[k], ``n_steps`` steps of ``dt`` by ``FIXED_DRIVER``."""
    n_traj = Y0.shape[0]
    n2 = Y0.shape[1]
    for k in range(n_traj):
        y = Y0[k].copy()
        p = P[k]
        clock = np.zeros(2)
        clock[0] = t0
        counters = np.zeros(6, dtype=np.int64)
        residual = np.zeros(1)
        ts = np.empty(_SWEEP_ROWS)
        ys = np.empty((_SWEEP_ROWS, n2))
        e0 = energy(t0, y, p)
        deviation = 0.0
        row = 0
        if dense.shape[1] > 0:
            for c in range(n2):
                dense[k, 0, c] = y[c]
            row = 1
        while True:
            code, n_saved = FIXED_DRIVER(y, clock, counters, p, projecting, residual, t0, dt, n_steps, _SWEEP_NO_PAUSE,
                                         t_end, save_every, ts, ys, *coefficients)
            for r in range(n_saved):
                deviation = max(deviation, abs(energy(ts[r], ys[r], p) - e0))
                if row < dense.shape[1]:
                    for c in range(n2):
                        dense[k, row, c] = ys[r, c]
                    row += 1
            if code != _ODE_BUFFER_FULL:
                break
        for c in range(n2):
            final[k, c] = y[c]
        t_final[k] = clock[0]
        status[k] = code
        counts[k, 0] = counters[0]
        counts[k, 1] = counters[1]
        counts[k, 2] = counters[2]
        energy_stats[k, 0] = e0
        energy_stats[k, 1] = deviation
