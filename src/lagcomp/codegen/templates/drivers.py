"""Integration drivers: a *template*, appended verbatim to every generated module.

This file is not imported as part of lagcomp.  Its text is appended to each
generated kernel module, after the kernels.  The module it is appended to
provides three names:

* ``np`` and ``njit`` (``import numpy as np`` / ``from numba import njit`` in
  the generated header; they are imported again below so that this file is
  also valid on its own, and the duplicate imports are harmless);
* ``rhs(t, y, p, out) -> int``: the right-hand-side kernel, which writes
  ``y' = f(t, y)`` into ``out`` and returns 0, or ``k > 0`` when the mass
  matrix was singular at pivot ``k``.

Why a template rather than generic drivers taking ``rhs`` as an argument:
numba's on-disk cache misses for a cached function that receives a jitted
function as an argument, so each module gets its own copy of the drivers,
calling ``rhs`` as a module-level global.  Every function here is
``@njit(cache=True)``; the step loops run entirely in compiled code and do not
allocate (work arrays are allocated once at the start of each driver call).

Public drivers (the calling convention is shared by all three):

* ``rk4_run(y, clock, counters, p, t0, dt, n_steps, t_end, save_every, ts, ys)``
* ``dopri5_run(y, clock, counters, p, t_end, rtol, atol, max_step, max_steps,
  save_every, t_eval, ts, ys, A, B, C, E, P)``
* ``dop853_run(y, clock, counters, p, t_end, rtol, atol, max_step, max_steps,
  save_every, t_eval, ts, ys, A, B, C, E3, E5, D, A_EXTRA, C_EXTRA)``

The trailing tableau arrays are ``lagcomp.integrate.tableaux.driver_arguments``
of the corresponding tableau.  State is kept in the in/out arrays so that a
run can be resumed, chunk by chunk, when the output buffer fills:

* ``y``        float64[N], current state (last accepted state on return);
* ``clock``    float64[2] = [t, h]: current time and next step size to try
  (adaptive drivers; h == 0 selects the initial step automatically);
* ``counters`` int64[5] = [nfev, nsteps, nrejected, i_eval, since_save];
* ``ts``, ``ys`` float64[cap], float64[cap, N]: output rows written from 0;
  the initial point is never written (the caller does that).

Every driver returns ``(status, n_saved)``: status 0 = reached ``t_end``;
1 = output buffer full (call again with a fresh buffer; the continuation is
identical to an uninterrupted run except for one extra ``f`` evaluation per
call of the adaptive drivers; with ``t_eval`` the buffer may hold fewer than
``cap`` rows, see ``_ode_adaptive_run``); -1 = non-finite state or derivative; -2 = ``rhs`` returned a non-zero
status; -3 = step size too small; -4 = maximum number of steps reached.  On
failure ``y`` and ``clock[0]`` hold the last good state and its time.

The adaptive drivers implement the standard explicit Runge-Kutta step-size
control of Hairer, Norsett & Wanner, *Solving Ordinary Differential
Equations I* (2nd ed., Springer 1993), sec. II.4 (automatic step size
control, initial step selection) and II.6 (dense output), with the same
constants as scipy's ``solve_ivp`` explicit RK solvers, so that at equal
tolerances they take the same steps:

* DOPRI5: Dormand & Prince, "A family of embedded Runge-Kutta formulae",
  J. Comput. Appl. Math. 6 (1980) 19-26; quartic dense output (HNW II.6).
* DOP853: Hairer's DOP853 (HNW II.5 and II.6; Fortran code ``dop853.f``):
  8th-order method, error estimate combining 5th- and 3rd-order embedded
  formulas, 7th-order dense output from three extra stages.
"""

import numpy as np
from numba import njit

# Step-size controller constants (HNW I, sec. II.4, eqs. (4.12)-(4.13); the
# same values as scipy's explicit Runge-Kutta solvers).
_ODE_SAFETY = 0.9       # safety factor "fac" applied to the optimal step
_ODE_MIN_FACTOR = 0.2   # never shrink the step by more than this factor
_ODE_MAX_FACTOR = 10.0  # never grow the step by more than this factor

# Method identifiers for the shared adaptive core (the number is the order).
_ODE_METHOD_DOPRI5 = 5
_ODE_METHOD_DOP853 = 8

# Status codes returned by the drivers.
_ODE_DONE = 0
_ODE_BUFFER_FULL = 1
_ODE_NONFINITE = -1
_ODE_RHS_FAILED = -2
_ODE_STEP_TOO_SMALL = -3
_ODE_MAX_STEPS = -4


# ---------------------------------------------------------------------------
# Small helpers
# ---------------------------------------------------------------------------

@njit(cache=True)
def _ode_all_finite(x):
    """True when every entry of the 1-D array ``x`` is finite (no NaN/inf)."""
    for i in range(x.shape[0]):
        if not np.isfinite(x[i]):
            return False
    return True


@njit(cache=True)
def _ode_rms_norm(v, scale):
    """Scaled root-mean-square norm sqrt(mean((v_i / scale_i)^2)).

    This is the norm used throughout HNW sec. II.4 (eq. (4.11)) for step
    control; each component is measured relative to its own tolerance.
    """
    n = v.shape[0]
    if n == 0:
        return 0.0
    acc = 0.0
    for i in range(n):
        r = v[i] / scale[i]
        acc += r * r
    return np.sqrt(acc / n)


@njit(cache=True)
def _ode_eval_stages(t, y, h, p, A, C, row0, first, last, K, ytmp, counters):
    """Evaluate explicit Runge-Kutta stages ``first .. last-1`` into ``K``.

    Stage s is ``K[s] = f(t + c h, y + h * sum_{j<s} a_j K[j])`` where
    ``(a, c) = (A[s - row0], C[s - row0])``.  ``row0`` lets the same helper
    evaluate the main stages (``A``, ``C``, row0 = 0) and DOP853's extra
    dense-output stages (``A_EXTRA``, ``C_EXTRA``, row0 = n_stages + 1).
    Zero coefficients are skipped, which matters for the sparse DOP853 tableau.

    Returns 0 on success, the rhs status if ``rhs`` failed, or -1 if a stage
    derivative is not finite.  Every ``rhs`` call is counted in counters[0].
    """
    n = y.shape[0]
    for s in range(first, last):
        row = s - row0
        for i in range(n):
            ytmp[i] = 0.0
        for j in range(s):
            a = A[row, j]
            if a != 0.0:
                for i in range(n):
                    ytmp[i] += a * K[j, i]
        for i in range(n):
            ytmp[i] = y[i] + h * ytmp[i]
        status = rhs(t + C[row] * h, ytmp, p, K[s])
        counters[0] += 1
        if status != 0:
            return status
        if not _ode_all_finite(K[s]):
            return -1
    return 0


@njit(cache=True)
def _ode_rk_step(t, y, h, p, A, B, C, K, y_new, ytmp, counters):
    """One explicit RK step of size ``h`` from ``(t, y)``; FSAL layout.

    On entry ``K[0] = f(t, y)``.  Computes stages ``K[1 .. s-1]``,
    ``y_new = y + h * sum_j B_j K[j]`` and the FSAL stage
    ``K[s] = f(t + h, y_new)`` which both the embedded error estimate and the
    next step (as its first stage) use.  Returns as ``_ode_eval_stages``.
    """
    n = y.shape[0]
    n_stages = B.shape[0]
    status = _ode_eval_stages(t, y, h, p, A, C, 0, 1, n_stages, K, ytmp,
                              counters)
    if status != 0:
        return status
    for i in range(n):
        ytmp[i] = 0.0
    for j in range(n_stages):
        b = B[j]
        if b != 0.0:
            for i in range(n):
                ytmp[i] += b * K[j, i]
    for i in range(n):
        y_new[i] = y[i] + h * ytmp[i]
    if not _ode_all_finite(y_new):
        return -1
    status = rhs(t + h, y_new, p, K[n_stages])
    counters[0] += 1
    if status != 0:
        return status
    if not _ode_all_finite(K[n_stages]):
        return -1
    return 0


@njit(cache=True)
def _ode_error_norm(method, K, E_main, E_aux, h, y, y_new, rtol, atol):
    """Scaled norm of the local error estimate of an accepted/rejected trial.

    The scale is ``atol + max(|y|, |y_new|) * rtol`` per component.

    * DOPRI5: RMS norm of ``h * sum_j E_j K[j]`` (difference of the 5th- and
      4th-order solutions), HNW sec. II.4.
    * DOP853 (``E_main = E5``, ``E_aux = E3``): Hairer's combined estimate
      ``|h| e5 / sqrt(n (e5 + 0.01 e3))`` with ``e5``/``e3`` the squared
      2-norms of the scaled 5th- and 3rd-order estimates
      ``sum_j E5_j K[j] / scale`` and ``sum_j E3_j K[j] / scale``
      (Hairer's ``dop853.f``; HNW sec. II.5, the 8(5,3) pair): it behaves like
      an estimate of order 7 (error order q = 7) while staying robust when the
      5th-order estimate happens to be small.

    A NaN/inf result means the trial step must be rejected.
    """
    n = y.shape[0]
    n_k = E_main.shape[0]
    if n == 0:
        return 0.0
    if method == _ODE_METHOD_DOP853:
        sum5 = 0.0
        sum3 = 0.0
        for i in range(n):
            sc = atol + max(abs(y[i]), abs(y_new[i])) * rtol
            e5 = 0.0
            e3 = 0.0
            for j in range(n_k):
                e5 += E_main[j] * K[j, i]
                e3 += E_aux[j] * K[j, i]
            e5 /= sc
            e3 /= sc
            sum5 += e5 * e5
            sum3 += e3 * e3
        if sum5 == 0.0 and sum3 == 0.0:
            return 0.0
        return abs(h) * sum5 / np.sqrt((sum5 + 0.01 * sum3) * n)
    acc = 0.0
    for i in range(n):
        sc = atol + max(abs(y[i]), abs(y_new[i])) * rtol
        e = 0.0
        for j in range(n_k):
            e += E_main[j] * K[j, i]
        e = h * e / sc
        acc += e * e
    return np.sqrt(acc / n)


@njit(cache=True)
def _ode_initial_step(t0, y0, f0, p, t_end, max_step, error_order, rtol,
                      atol, y1, f1, scale, counters):
    """Choose the first step size (HNW sec. II.4, "Starting Step Size").

    With ``scale = atol + |y0| rtol`` and the RMS norm:
    ``d0 = ||y0||``, ``d1 = ||f0||``; a probe step ``h0 = 0.01 d0/d1``
    (1e-6 if either is tiny, and at most the interval length); an explicit
    Euler step gives ``f1 = f(t0 + h0, y0 + h0 f0)`` and the second-derivative
    estimate ``d2 = ||f1 - f0|| / h0``; then
    ``h1 = (0.01 / max(d1, d2)) ** (1 / (error_order + 1))`` (or
    ``max(1e-6, 1e-3 h0)`` when both are negligible) and the result is
    ``min(100 h0, h1, t_end - t0, max_step)``.

    ``y1``, ``f1``, ``scale`` are work arrays.  Returns ``(h, status)`` with
    status 0, or the positive rhs status if ``rhs`` failed at the probe point.
    A non-finite probe derivative falls back to ``h0`` and lets the step
    controller's rejection logic handle the trouble.
    """
    n = y0.shape[0]
    interval = t_end - t0
    if n == 0:
        return min(interval, max_step), 0
    for i in range(n):
        scale[i] = atol + abs(y0[i]) * rtol
    d0 = _ode_rms_norm(y0, scale)
    d1 = _ode_rms_norm(f0, scale)
    if d0 < 1e-5 or d1 < 1e-5:
        h0 = 1e-6
    else:
        h0 = 0.01 * d0 / d1
    h0 = min(h0, interval)
    for i in range(n):
        y1[i] = y0[i] + h0 * f0[i]
    status = rhs(t0 + h0, y1, p, f1)
    counters[0] += 1
    if status != 0:
        return h0, status
    if not _ode_all_finite(f1):
        return min(h0, max_step), 0
    for i in range(n):
        f1[i] = f1[i] - f0[i]
    d2 = _ode_rms_norm(f1, scale) / h0
    if d1 <= 1e-15 and d2 <= 1e-15:
        h1 = max(1e-6, h0 * 1e-3)
    else:
        h1 = (0.01 / max(d1, d2)) ** (1.0 / (error_order + 1))
    return min(100.0 * h0, h1, interval, max_step), 0


# ---------------------------------------------------------------------------
# Dense output (HNW sec. II.6)
# ---------------------------------------------------------------------------

@njit(cache=True)
def _ode_dopri5_dense_prepare(K, P, Q):
    """Coefficients of the DOPRI5 quartic continuous extension.

    ``Q[m, i] = sum_j P[j, m] K[j, i]`` over all stages including the FSAL
    row ``K[s] = f(t_new, y_new)`` (Dormand & Prince 1980; HNW II.6), so that
    ``y(t_old + x h) = y_old + h * sum_m Q[m] x^(m+1)``.
    """
    n = K.shape[1]
    n_k = P.shape[0]
    for m in range(P.shape[1]):
        for i in range(n):
            Q[m, i] = 0.0
        for j in range(n_k):
            w = P[j, m]
            if w != 0.0:
                for i in range(n):
                    Q[m, i] += w * K[j, i]


@njit(cache=True)
def _ode_dopri5_dense_eval(Q, n_power, y_old, h, x, out):
    """Evaluate the DOPRI5 interpolant at ``x = (t - t_old) / h`` into out.

    Horner form of ``y_old + h * sum_{m=0}^{n_power-1} Q[m] x^(m+1)``.
    """
    n = y_old.shape[0]
    for i in range(n):
        acc = 0.0
        for m in range(n_power - 1, -1, -1):
            acc = (acc + Q[m, i]) * x
        out[i] = y_old[i] + h * acc


@njit(cache=True)
def _ode_dop853_dense_prepare(t, y, y_new, h, p, A_EXTRA, C_EXTRA, D, K,
                              F, ytmp, counters):
    """Hairer's 7th-order DOP853 dense output for the step t -> t + h.

    Evaluates the three extra stages ``K[s+1 .. s+3]`` (``A_EXTRA``,
    ``C_EXTRA``; ``K[s]`` is the FSAL stage) and fills the interpolation
    coefficients (``dop853.f`` routine ``contd8``; HNW sec. II.6)::

        F0 = dy = y_new - y
        F1 = h f_old - dy
        F2 = 2 dy - h (f_new + f_old)
        F3..F6 = h * D @ K_extended

    Returns 0, a positive rhs status, or -1 for non-finite extra stages.
    """
    n = y.shape[0]
    n_main = A_EXTRA.shape[1] - A_EXTRA.shape[0]   # stages + FSAL row
    n_all = A_EXTRA.shape[1]
    status = _ode_eval_stages(t, y, h, p, A_EXTRA, C_EXTRA, n_main, n_main,
                              n_all, K, ytmp, counters)
    if status != 0:
        return status
    f_new_row = n_main - 1
    for i in range(n):
        dy = y_new[i] - y[i]
        F[0, i] = dy
        F[1, i] = h * K[0, i] - dy
        F[2, i] = 2.0 * dy - h * (K[f_new_row, i] + K[0, i])
    for r in range(D.shape[0]):
        for i in range(n):
            F[3 + r, i] = 0.0
        for j in range(n_all):
            w = D[r, j]
            if w != 0.0:
                for i in range(n):
                    F[3 + r, i] += w * K[j, i]
        for i in range(n):
            F[3 + r, i] *= h
    return 0


@njit(cache=True)
def _ode_dop853_dense_eval(F, n_rows, y_old, x, out):
    """Evaluate the DOP853 interpolant at ``x = (t - t_old) / h`` into out.

    Nested product with alternating factors ``x`` and ``1 - x``:
    ``y_old + x (F0 + (1-x) (F1 + x (F2 + (1-x) (F3 + ...))))``.
    """
    n = y_old.shape[0]
    one_minus_x = 1.0 - x
    for i in range(n):
        acc = 0.0
        for r in range(n_rows - 1, -1, -1):
            acc += F[r, i]
            if r % 2 == 0:
                acc *= x
            else:
                acc *= one_minus_x
        out[i] = y_old[i] + acc


# ---------------------------------------------------------------------------
# Fixed-step classic Runge-Kutta
# ---------------------------------------------------------------------------

@njit(cache=True)
def _ode_rk4_step(t, y, h, p, K, ytmp, y_new, counters):
    """One step of the classic 4th-order Runge-Kutta method (HNW II.1).

    Returns 0 or the rhs status; ``y_new`` receives the new state.
    """
    n = y.shape[0]
    half = 0.5 * h
    status = rhs(t, y, p, K[0])
    counters[0] += 1
    if status != 0:
        return status
    for i in range(n):
        ytmp[i] = y[i] + half * K[0, i]
    status = rhs(t + half, ytmp, p, K[1])
    counters[0] += 1
    if status != 0:
        return status
    for i in range(n):
        ytmp[i] = y[i] + half * K[1, i]
    status = rhs(t + half, ytmp, p, K[2])
    counters[0] += 1
    if status != 0:
        return status
    for i in range(n):
        ytmp[i] = y[i] + h * K[2, i]
    status = rhs(t + h, ytmp, p, K[3])
    counters[0] += 1
    if status != 0:
        return status
    sixth = h / 6.0
    for i in range(n):
        y_new[i] = y[i] + sixth * (K[0, i] + 2.0 * K[1, i] + 2.0 * K[2, i]
                                   + K[3, i])
    return 0


@njit(cache=True)
def rk4_run(y, clock, counters, p, t0, dt, n_steps, t_end, save_every, ts,
            ys):
    """Integrate with classic RK4 and a fixed step ``dt``; resumable.

    Step k (0-based, ``k = counters[1]``) goes from ``t0 + k dt`` to
    ``min(t0 + (k+1) dt, t_end)``, the last one (k = n_steps - 1) ending
    exactly at ``t_end``.  Times are computed from k rather than accumulated,
    so there is no drift.  A row is saved after a step when
    ``counters[4]`` (steps since the last save) reaches ``save_every`` or it
    is the last step.  Returns ``(status, n_saved)``; status 1 is returned
    before a step whose row would not fit into ``ts``/``ys``.  The new state
    is checked for finiteness every step (-1: state not updated); a non-zero
    rhs status gives -2.  ``clock[0]`` always holds the time of ``y``.
    """
    n = y.shape[0]
    cap = ts.shape[0]
    K = np.empty((4, n))
    ytmp = np.empty(n)
    y_new = np.empty(n)
    n_saved = 0
    while True:
        k = counters[1]
        if k >= n_steps:
            return _ODE_DONE, n_saved
        last = k == n_steps - 1
        if last or counters[4] + 1 >= save_every:
            if n_saved >= cap:
                return _ODE_BUFFER_FULL, n_saved
        t_a = min(t0 + k * dt, t_end)
        if last:
            t_b = t_end
        else:
            t_b = min(t0 + (k + 1) * dt, t_end)
        status = _ode_rk4_step(t_a, y, t_b - t_a, p, K, ytmp, y_new, counters)
        if status != 0:
            return _ODE_RHS_FAILED, n_saved
        if not _ode_all_finite(y_new):
            return _ODE_NONFINITE, n_saved
        for i in range(n):
            y[i] = y_new[i]
        clock[0] = t_b
        counters[1] = k + 1
        counters[4] += 1
        if last or counters[4] >= save_every:
            ts[n_saved] = t_b
            for i in range(n):
                ys[n_saved, i] = y[i]
            n_saved += 1
            counters[4] = 0


# ---------------------------------------------------------------------------
# Adaptive embedded Runge-Kutta (shared core of DOPRI5 and DOP853)
# ---------------------------------------------------------------------------

@njit(cache=True)
def _ode_outputs_needed(t_reach, t_end, save_every, t_eval, counters,
                        limit):
    """How many output rows the next step, which ends at or before
    ``t_reach``, may write (counting stops at ``limit``).

    With ``t_eval``: the points in ``(t, t_reach]`` not yet emitted.
    Without: 1 if the step will be saved by decimation or may end at t_end.
    Step rejections only shorten a step, so this is an upper bound.
    """
    if t_eval.shape[0] > 0:
        count = 0
        j = counters[3]
        while j < t_eval.shape[0] and t_eval[j] <= t_reach and count < limit:
            count += 1
            j += 1
        return count
    if counters[4] + 1 >= save_every or t_reach >= t_end:
        return 1
    return 0


@njit(cache=True)
def _ode_adaptive_run(method, y, clock, counters, p, t_end, rtol, atol,
                      max_step, max_steps, save_every, t_eval, ts, ys,
                      A, B, C, E_main, E_aux, P, D, A_EXTRA, C_EXTRA):
    """Adaptive explicit RK integration with FSAL, step control and dense
    output; the common body of ``dopri5_run`` and ``dop853_run``.

    Step control follows HNW sec. II.4 exactly as scipy's explicit RK
    solvers do: the trial step is clamped to ``max_step`` (or raised to the
    minimum step ``10 ulp(t)``) and clipped to land on ``t_end``; it is
    accepted when the scaled error norm ``err < 1`` and the next step is
    ``h * min(MAX_FACTOR, SAFETY err^(-1/(q+1)))`` (q the error order;
    capped at ``h`` if this step had a rejection); otherwise ``h`` is
    multiplied by ``max(MIN_FACTOR, SAFETY err^(-1/(q+1)))`` and the step
    retried.  A trial with NaN/inf stages or error is rejected with
    ``h *= MIN_FACTOR``; if ``h`` then falls below the minimum step the run
    stops with -1 (last trouble non-finite) or -3.

    Output buffer: before each step the number of rows it may write is
    bounded (from the trial step, which rejections only shorten); if they do
    not fit, status 1 is returned before the step.  With ``t_eval`` this can
    happen while the buffer still has free rows (``n_saved < cap``): the
    rows written are always ``ts[:n_saved]``.  Only if a single step holds
    more ``t_eval`` points than an empty buffer, the points that fit are
    written and the step is *not* committed; the next call redoes the same
    (deterministic) step and continues with the remaining points, so the
    trajectory is unchanged but that step's f evaluations and rejections
    are counted twice.

    ``method`` selects the error norm and dense output (``_ODE_METHOD_*``);
    arrays a method does not use are passed empty.
    """
    n = y.shape[0]
    cap = ts.shape[0]
    n_eval = t_eval.shape[0]
    use_t_eval = n_eval > 0
    n_stages = B.shape[0]
    n_extra = C_EXTRA.shape[0]
    if method == _ODE_METHOD_DOP853:
        error_order = 7
    else:
        error_order = 4
    exponent = -1.0 / (error_order + 1)

    # Work arrays, allocated once per call.
    K = np.empty((n_stages + 1 + n_extra, n))
    y_new = np.empty(n)
    ytmp = np.empty(n)
    ytmp2 = np.empty(n)
    n_dense = max(P.shape[1], 3 + D.shape[0])
    dense = np.empty((n_dense, n))

    n_saved = 0
    t = clock[0]
    if t >= t_end:
        return _ODE_DONE, n_saved
    # Output points at or before the current time are never emitted here.
    while counters[3] < n_eval and t_eval[counters[3]] <= t:
        counters[3] += 1

    # First stage of the first step (FSAL thereafter).
    status = rhs(t, y, p, K[0])
    counters[0] += 1
    if status != 0:
        return _ODE_RHS_FAILED, n_saved
    if not (_ode_all_finite(y) and _ode_all_finite(K[0])):
        return _ODE_NONFINITE, n_saved

    h_abs = clock[1]
    if h_abs <= 0.0:
        h_abs, status = _ode_initial_step(t, y, K[0], p, t_end, max_step,
                                          error_order, rtol, atol, ytmp,
                                          ytmp2, dense[0], counters)
        if status != 0:
            return _ODE_RHS_FAILED, n_saved
        clock[1] = h_abs

    while True:
        if t >= t_end:
            return _ODE_DONE, n_saved
        if counters[1] >= max_steps:
            return _ODE_MAX_STEPS, n_saved

        min_step = 10.0 * abs(np.nextafter(t, np.inf) - t)
        if h_abs > max_step:
            h_abs = max_step
        elif h_abs < min_step:
            h_abs = min_step

        # Stop before a step whose outputs would not fit (never lose one).
        room = cap - n_saved
        t_reach = min(t + h_abs, t_end)
        need = _ode_outputs_needed(t_reach, t_end, save_every, t_eval,
                                   counters, room + 1)
        if need > room and (n_saved > 0 or not use_t_eval):
            return _ODE_BUFFER_FULL, n_saved

        # Trial loop: shrink until the error estimate is acceptable.
        step_rejected = False
        nonfinite = False
        while True:
            if h_abs < min_step:
                if nonfinite:
                    return _ODE_NONFINITE, n_saved
                return _ODE_STEP_TOO_SMALL, n_saved
            t_new = t + h_abs
            if t_new > t_end:
                t_new = t_end
            h = t_new - t
            h_abs = abs(h)
            status = _ode_rk_step(t, y, h, p, A, B, C, K, y_new, ytmp,
                                  counters)
            if status > 0:
                return _ODE_RHS_FAILED, n_saved
            err = np.inf
            if status == 0:
                err = _ode_error_norm(method, K, E_main, E_aux, h, y, y_new,
                                      rtol, atol)
            if np.isfinite(err) and err < 1.0:
                if err == 0.0:
                    factor = _ODE_MAX_FACTOR
                else:
                    factor = min(_ODE_MAX_FACTOR, _ODE_SAFETY * err ** exponent)
                if step_rejected:
                    factor = min(1.0, factor)
                h_abs *= factor
                break
            if np.isfinite(err):
                h_abs *= max(_ODE_MIN_FACTOR, _ODE_SAFETY * err ** exponent)
                nonfinite = False
            else:
                h_abs *= _ODE_MIN_FACTOR
                nonfinite = True
            step_rejected = True
            counters[2] += 1

        # Outputs of the accepted step t -> t_new.
        if use_t_eval:
            j = counters[3]
            if j < n_eval and t_eval[j] < t_new:
                # A point strictly inside the step: build the interpolant.
                if method == _ODE_METHOD_DOP853:
                    status = _ode_dop853_dense_prepare(
                        t, y, y_new, h, p, A_EXTRA, C_EXTRA, D, K, dense,
                        ytmp, counters)
                    if status > 0:
                        return _ODE_RHS_FAILED, n_saved
                    if status < 0:
                        return _ODE_NONFINITE, n_saved
                else:
                    _ode_dopri5_dense_prepare(K, P, dense)
            while j < n_eval and t_eval[j] <= t_new and n_saved < cap:
                te = t_eval[j]
                ts[n_saved] = te
                if te == t_new:
                    for i in range(n):
                        ys[n_saved, i] = y_new[i]
                else:
                    x = (te - t) / h
                    if method == _ODE_METHOD_DOP853:
                        _ode_dop853_dense_eval(dense, 3 + D.shape[0], y,
                                               x, ys[n_saved])
                    else:
                        _ode_dopri5_dense_eval(dense, P.shape[1], y, h, x,
                                               ys[n_saved])
                n_saved += 1
                j += 1
            counters[3] = j
            if j < n_eval and t_eval[j] <= t_new:
                # Only when one step holds more points than a whole buffer:
                # do not commit; the next call redoes this (deterministic)
                # step and emits the remaining points.
                return _ODE_BUFFER_FULL, n_saved
        else:
            counters[4] += 1
            if counters[4] >= save_every or t_new >= t_end:
                ts[n_saved] = t_new
                for i in range(n):
                    ys[n_saved, i] = y_new[i]
                n_saved += 1
                counters[4] = 0

        # Commit the step; the FSAL stage becomes the next first stage.
        for i in range(n):
            y[i] = y_new[i]
            K[0, i] = K[n_stages, i]
        t = t_new
        clock[0] = t
        clock[1] = h_abs
        counters[1] += 1


@njit(cache=True)
def dopri5_run(y, clock, counters, p, t_end, rtol, atol, max_step, max_steps,
               save_every, t_eval, ts, ys, A, B, C, E, P):
    """Dormand-Prince 5(4) with step control and quartic dense output.

    ``A`` (s, s) strictly lower triangular, ``B``/``C`` (s,), ``E`` (s+1,)
    error weights including the FSAL stage, ``P`` (s+1, 4) dense-output
    matrix.  Error order 4.  See the module docstring for the arguments and
    return value, and ``_ode_adaptive_run`` for the algorithm.
    """
    empty1 = np.empty(0)
    empty2 = np.empty((0, 0))
    return _ode_adaptive_run(_ODE_METHOD_DOPRI5, y, clock, counters, p,
                             t_end, rtol, atol, max_step, max_steps,
                             save_every, t_eval, ts, ys, A, B, C, E, empty1,
                             P, empty2, empty2, empty1)


@njit(cache=True)
def dop853_run(y, clock, counters, p, t_end, rtol, atol, max_step, max_steps,
               save_every, t_eval, ts, ys, A, B, C, E3, E5, D, A_EXTRA,
               C_EXTRA):
    """Hairer's DOP853: order 8 with the combined 5th/3rd-order error
    estimate (error order 7) and 7th-order dense output.

    ``A`` (s, s), ``B``/``C`` (s,), ``E3``/``E5`` (s+1,), ``D`` (4, s+4),
    ``A_EXTRA`` (3, s+4), ``C_EXTRA`` (3,).  See the module docstring for the
    arguments and return value, and ``_ode_adaptive_run`` for the algorithm.
    """
    empty2 = np.empty((0, 0))
    return _ode_adaptive_run(_ODE_METHOD_DOP853, y, clock, counters, p,
                             t_end, rtol, atol, max_step, max_steps,
                             save_every, t_eval, ts, ys, A, B, C, E5, E3,
                             empty2, D, A_EXTRA, C_EXTRA)
