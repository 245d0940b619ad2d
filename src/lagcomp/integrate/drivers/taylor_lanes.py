"""Batched Taylor sweeps: the loop `sweep_taylor_lanes` around the model's unrolled lane kernels.

`lagcomp.codegen.taylor_lanes` writes, for one Taylor order p, the model's ``taylor_lanes``
(the Taylor program unrolled at order p over L lanes: straight-line code, which LLVM vectorizes
across the lanes only when it is inlined into its loop; that is why it stays emitted) and
``taylor_lanes_advance`` (every lane's Horner sum), with ``TAYLOR_ORDER`` = p and
``TAYLOR_LANES`` = L.  The loop here takes them as function values.

`sweep_taylor_lanes` runs the trajectories (Y0[k], P[k]) through the lanes.  Each lane takes the
steps `lagcomp.integrate.drivers.taylor.taylor_run` takes from its own state: the series with the
periodic coordinates reduced as there, the step from the last two coefficients, the new state by
Horner's rule and compensated summation, with the same arithmetic in the same order, so a lane
differs from the scalar driver only by the rounding of the coefficients themselves (LLVM may fuse
another product of a sum into a multiply-add in the unrolled kernel).  Lanes do not wait for each
other: a lane whose trajectory ends (or fails) takes the next trajectory of the batch at once, so a
batch costs the sum of its trajectories' steps over the lanes, not the longest one times the
lanes.  Outputs as the other batched sweeps (final states, statuses, counts, energy errors),
nrejected always 0.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, types

from lagcomp.integrate.drivers.kernel_types import (
    ENERGY,
    FLOAT,
    INDICES,
    INT,
    MATRIX,
    TAYLOR_ADVANCE,
    TAYLOR_LANES,
    VECTOR,
)
from lagcomp.integrate.status import Status

#: sweep_taylor_lanes(taylor_lanes, taylor_lanes_advance, order, lanes, energy, Y0, P, t0, t_end, rtol, atol,
#: max_step, max_steps, save_every, final, t_final, status, counts, dense, energy_stats)
SIGNATURE = types.none(TAYLOR_LANES, TAYLOR_ADVANCE, INT, INT, ENERGY, MATRIX, MATRIX, FLOAT, FLOAT, FLOAT, FLOAT,
                       FLOAT, INT, INT, MATRIX, VECTOR, INDICES, types.int64[:, ::1], types.float64[:, :, ::1], MATRIX)


@njit(SIGNATURE, cache=True, error_model="numpy", nogil=True)
def sweep_taylor_lanes(taylor_lanes, taylor_lanes_advance, order, lanes, energy, Y0, P, t0, t_end, rtol, atol,
                       max_step, max_steps, save_every, final, t_final, status, counts, dense, energy_stats):
    """The Taylor method of `order` over the trajectories (Y0[k], P[k]) in `lanes` lanes; see the module docstring.

    ``taylor_lanes`` and ``taylor_lanes_advance`` are the model's lane kernels of this order and lane
    count (its ``TAYLOR_ORDER`` and ``TAYLOR_LANES``); ``dense`` is not written (no rows).
    """
    n_traj = Y0.shape[0]
    n2 = Y0.shape[1]
    n_p = P.shape[1]
    # X[norms + lane]: the max norm of y in that lane; then |y[order]|, |y[order-1]|, the pivot test
    norms = n2 * (order + 1) * lanes
    rho_factor = math.exp(-0.7 / (order - 1)) / (math.e * math.e)

    # Lanes' data, flat with the lane last (the layout of the lane kernels).
    S = np.zeros(2 * n2 * lanes)        # states, then carries of the compensated sums
    S_new = np.zeros(2 * n2 * lanes)
    Pl = np.empty(n_p * lanes)
    for lane in range(lanes):
        for c in range(n_p):
            Pl[c * lanes + lane] = P[0, c]   # idle lanes compute on harmless values
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
        for lane in range(lanes):
            while trajectory[lane] < 0 and taken < n_traj:
                k = taken
                taken += 1
                e0[lane] = energy(t0, Y0[k], P[k])
                if t0 >= t_end:
                    for c in range(n2):
                        final[k, c] = Y0[k, c]
                    t_final[k] = t0
                    status[k] = Status.DONE
                    energy_stats[k, 0] = e0[lane]
                    energy_stats[k, 1] = 0.0
                    continue
                trajectory[lane] = k
                T[lane] = t0
                for c in range(n2):
                    S[c * lanes + lane] = Y0[k, c]
                    S[(n2 + c) * lanes + lane] = 0.0
                for c in range(n_p):
                    Pl[c * lanes + lane] = P[k, c]
                steps[lane] = 0
                since_save[lane] = 0
                deviation[lane] = 0.0
            if trajectory[lane] >= 0:
                busy += 1
        if busy == 0:
            return

        # The series of every lane, then each lane's step as taylor_run takes it.
        taylor_lanes(T, S, Pl, X)
        for lane in range(lanes):
            H[lane] = 0.0
            code[lane] = 0
            if trajectory[lane] < 0:
                continue
            t = T[lane]
            norm_y = X[norms + lane]
            norm_last = X[norms + lanes + lane]
            norm_before = X[norms + 2 * lanes + lane]
            if X[norms + 3 * lanes + lane] != 0.0:
                code[lane] = Status.RHS_FAILED
            elif steps[lane] >= max_steps:
                code[lane] = Status.MAX_STEPS
            elif not (norm_last < np.inf and norm_before < np.inf):     # (also false for NaN)
                code[lane] = Status.NONFINITE
            else:
                scale = 1.0 if rtol * norm_y <= atol else norm_y
                rho = min((scale / norm_last) ** (1.0 / order), (scale / norm_before) ** (1.0 / (order - 1)))
                h = min(rho * rho_factor, max_step)
                min_step = 10.0 * abs(np.nextafter(t, np.inf) - t)
                if not h >= min_step:                                   # (true for NaN)
                    code[lane] = Status.STEP_TOO_SMALL if h < min_step else Status.NONFINITE
                else:
                    t_new = t + h
                    if t_new > t_end:
                        t_new = t_end
                    T_new[lane] = t_new
                    H[lane] = t_new - t

        # The new states (Horner, compensated sums) of all lanes at once; then commit, per lane.
        taylor_lanes_advance(H, X, S, S_new)
        for lane in range(lanes):
            k = trajectory[lane]
            if k < 0:
                continue
            if code[lane] == 0:
                finite = True
                for i in range(n2):
                    finite = finite and np.isfinite(S_new[i * lanes + lane])
                if not finite:
                    code[lane] = Status.NONFINITE
                else:
                    for i in range(2 * n2):
                        S[i * lanes + lane] = S_new[i * lanes + lane]
                    t_new = T_new[lane]
                    T[lane] = t_new
                    steps[lane] += 1
                    since_save[lane] += 1
                    if since_save[lane] >= save_every or t_new >= t_end:
                        since_save[lane] = 0
                        for i in range(n2):
                            y_row[i] = S[i * lanes + lane]
                        deviation[lane] = max(deviation[lane], abs(energy(t_new, y_row, P[k]) - e0[lane]))
                    if t_new < t_end:
                        continue
            # The lane's trajectory ends here: at t_end, or failed with `code` (its last good state kept).
            for c in range(n2):
                final[k, c] = S[c * lanes + lane]
            t_final[k] = T[lane]
            status[k] = code[lane]
            failed = code[lane] != 0 and code[lane] != Status.MAX_STEPS   # a failed series counts, as in taylor_run
            counts[k, 0] = steps[lane] + (1 if failed else 0)
            counts[k, 1] = steps[lane]
            counts[k, 2] = 0
            energy_stats[k, 0] = e0[lane]
            energy_stats[k, 1] = deviation[lane]
            trajectory[lane] = -1
