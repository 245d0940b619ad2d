"""Batched Taylor sweeps: a *template*, appended after a ``taylor_lanes`` kernel of one order.

`lagcomp.codegen.taylor_lanes` writes a module for one Taylor order p: the
model's module, the constants ``_TAYLOR_ORDER`` and ``_TAYLOR_LANES``,
``taylor_lanes`` (the program unrolled at order p over the lanes) and
``taylor_lanes_advance`` (every lane's Horner sum), then this text.

``sweep_taylor_lanes`` runs the trajectories (Y0[k], P[k]) through the lanes.
Each lane takes the steps ``taylor_run`` (``taylor.py``) takes from its own
state: the series with the periodic coordinates reduced as there, the step
from the last two coefficients, the new state by Horner's rule and
compensated summation, with the same arithmetic in the same order,
so a lane differs from the scalar driver only by the rounding of the
coefficients themselves (LLVM may fuse another product of a sum into a
multiply-add in the unrolled kernel).  Lanes do not wait for each other:
a lane whose trajectory ends (or fails) takes the next trajectory of the
batch at once, so a batch costs the sum of its trajectories' steps over the
lanes, not the longest one times the lanes.  Outputs as ``sweep_dop853_lanes``
(final states, statuses, counts, energy errors), nrejected always 0.
"""

# ruff: noqa: F821  (taylor_lanes, taylor_lanes_advance, _TAYLOR_*, energy, _ODE_* come from the module)

import math

import numpy as np
from numba import njit


@njit(cache=True, error_model="numpy", nogil=True)
def sweep_taylor_lanes(Y0, P, t0, t_end, rtol, atol, max_step, max_steps, save_every, final, t_final, status,
                       counts, dense, energy_stats):
    """Taylor method of order ``_TAYLOR_ORDER`` over the trajectories (Y0[k], P[k]); see the module docstring."""
    n_traj = Y0.shape[0]
    n2 = Y0.shape[1]
    n_p = P.shape[1]
    lanes = _TAYLOR_LANES
    order = _TAYLOR_ORDER
    norms = n2 * (order + 1) * lanes    # X[norms + l]: max norm of y in lane l; then |y[order]|, |y[order-1]|, pivots
    rho_factor = math.exp(-0.7 / (order - 1)) / (math.e * math.e)

    # Lanes' data, flat with the lane last (the layout of the generated functions).
    S = np.zeros(2 * n2 * lanes)        # states, then carries of the compensated sums
    S_new = np.zeros(2 * n2 * lanes)
    Pl = np.empty(n_p * lanes)
    for l in range(lanes):
        for c in range(n_p):
            Pl[c * lanes + l] = P[0, c]   # idle lanes compute on harmless values
    X = np.empty(norms + 4 * lanes)
    T = np.zeros(lanes)
    H = np.zeros(lanes)
    T_new = np.zeros(lanes)
    y_row = np.empty(n2)
    trajectory = np.full(lanes, -1)    # the trajectory each lane runs, -1 when idle
    steps = np.zeros(lanes, dtype=np.int64)
    since_save = np.zeros(lanes, dtype=np.int64)
    code = np.zeros(lanes, dtype=np.int64)
    deviation = np.zeros(lanes)
    e0 = np.zeros(lanes)
    taken = 0                          # trajectories handed to lanes so far

    while True:
        # Hand the next trajectories to idle lanes (one that starts at its end finishes at once).
        busy = 0
        for l in range(lanes):
            while trajectory[l] < 0 and taken < n_traj:
                k = taken
                taken += 1
                e0[l] = energy(t0, Y0[k], P[k])
                if t0 >= t_end:
                    for c in range(n2):
                        final[k, c] = Y0[k, c]
                    t_final[k] = t0
                    status[k] = _ODE_DONE
                    energy_stats[k, 0] = e0[l]
                    energy_stats[k, 1] = 0.0
                    continue
                trajectory[l] = k
                T[l] = t0
                for c in range(n2):
                    S[c * lanes + l] = Y0[k, c]
                    S[(n2 + c) * lanes + l] = 0.0
                for c in range(n_p):
                    Pl[c * lanes + l] = P[k, c]
                steps[l] = 0
                since_save[l] = 0
                deviation[l] = 0.0
            if trajectory[l] >= 0:
                busy += 1
        if busy == 0:
            return

        # The series of every lane, then each lane's step as taylor_run takes it.
        taylor_lanes(T, S, Pl, X)
        for l in range(lanes):
            H[l] = 0.0
            code[l] = 0
            if trajectory[l] < 0:
                continue
            t = T[l]
            norm_y = X[norms + l]
            norm_last = X[norms + lanes + l]
            norm_before = X[norms + 2 * lanes + l]
            if X[norms + 3 * lanes + l] != 0.0:
                code[l] = _ODE_RHS_FAILED
            elif steps[l] >= max_steps:
                code[l] = _ODE_MAX_STEPS
            elif not (norm_last < np.inf and norm_before < np.inf):     # (also false for NaN)
                code[l] = _ODE_NONFINITE
            else:
                scale = 1.0 if rtol * norm_y <= atol else norm_y
                rho = min((scale / norm_last) ** (1.0 / order), (scale / norm_before) ** (1.0 / (order - 1)))
                h = min(rho * rho_factor, max_step)
                min_step = 10.0 * abs(np.nextafter(t, np.inf) - t)
                if not h >= min_step:                                   # (true for NaN)
                    code[l] = _ODE_STEP_TOO_SMALL if h < min_step else _ODE_NONFINITE
                else:
                    t_new = t + h
                    if t_new > t_end:
                        t_new = t_end
                    T_new[l] = t_new
                    H[l] = t_new - t

        # The new states (Horner, compensated sums) of all lanes at once; then commit, per lane.
        taylor_lanes_advance(H, X, S, S_new)
        for l in range(lanes):
            k = trajectory[l]
            if k < 0:
                continue
            if code[l] == 0:
                finite = True
                for i in range(n2):
                    finite = finite and np.isfinite(S_new[i * lanes + l])
                if not finite:
                    code[l] = _ODE_NONFINITE
                else:
                    for i in range(2 * n2):
                        S[i * lanes + l] = S_new[i * lanes + l]
                    t_new = T_new[l]
                    T[l] = t_new
                    steps[l] += 1
                    since_save[l] += 1
                    if since_save[l] >= save_every or t_new >= t_end:
                        since_save[l] = 0
                        for i in range(n2):
                            y_row[i] = S[i * lanes + l]
                        deviation[l] = max(deviation[l], abs(energy(t_new, y_row, P[k]) - e0[l]))
                    if t_new < t_end:
                        continue
            # The lane's trajectory ends here: at t_end, or failed with `code` (its last good state kept).
            for c in range(n2):
                final[k, c] = S[c * lanes + l]
            t_final[k] = T[l]
            status[k] = code[l]
            counts[k, 0] = steps[l] + (1 if code[l] != 0 and code[l] != _ODE_MAX_STEPS else 0)   # as taylor_run
            counts[k, 1] = steps[l]
            counts[k, 2] = 0
            energy_stats[k, 0] = e0[l]
            energy_stats[k, 1] = deviation[l]
            trajectory[l] = -1
