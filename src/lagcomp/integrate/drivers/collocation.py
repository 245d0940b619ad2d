"""Implicit Gauss-Legendre collocation on the canonical equations in (q, p): gauss1, gauss2, gauss3.

Symplectic for any unconstrained Lagrangian (HLW, *Geometric Numerical Integration*, sec. II.1 and
VI.4): the method integrates x = (q, p), where the flow is symplectic, with the canonical vector
field of `lagcomp.integrate.drivers.canonical`, while its saved rows and ``y`` stay in (q, q̇) like
every other driver's.  The coefficients A, B, C and the extrapolation E of the first guess come
from `lagcomp.integrate.collocation`.

`collocation_run` is the resumable driver (the protocol of `lagcomp.integrate.drivers`), fixed-step
like RK4: step k goes from ``t0 + k dt`` to ``t0 + (k+1) dt``, the last step landing exactly on
``t_end``; `collocation_sweep` runs it over many trajectories.

Chart switches.  A ball joint's MRPs σ change to their shadow σ' = −σ/|σ|² past half a turn (an event with a reset,
`lagcomp.multibody.shadow`), which is a change of coordinates, not a jump of the motion: the same orientation and
angular velocity in the other chart.  In (q, p) it is the cotangent lift of the map σ → σ', a symplectic map, and it
may be made anywhere the two charts overlap, so it needs no locating: after a step that leaves the chart (its event
function g > 0), the driver applies the event's reset to y = (q, q̇) and rebuilds p = ``momenta`` there (the momenta
of the new chart, p' = Dφ⁻ᵀ p), then goes on from the new x with neither extrapolated stages nor a summation carry of
the old chart.  ``actions`` (one per event, `lagcomp.integrate.drivers.events`) marks the chart switches with
ACTION_RESET; no other event is located or reset here (`lagcomp.integrate.options.event_arguments` refuses them).
Each switch is an event row, as the adaptive drivers write theirs (`Solution.events`, a sweep's ``output="events"``):
its time is the step's end, where the chart changed (within one step after the crossing g = 0 that dop853 locates),
with the state there before the switch (g > 0) and after it.

The carry.  What the step loop keeps from one step to the next besides (y, clock, counters) is held by the caller
(`new_carry`, `lagcomp.integrate.methods.Method.carry`) and passed to each call, so that a run cut into calls (by
`lagcomp.integrate.simulate`'s call budgets, a sweep's row buffers) takes the steps one call would, bit for bit:

* ``x`` (2n,): the canonical state (q, p) as continued; p rebuilt from (q, q̇) by ``momenta`` would differ from it in
  its last bits;
* ``compensation`` (2n,): the Kahan compensation of the sum x ← x + h Σ b_i K_i;
* ``stages`` (s, 2n): the last step's stage derivatives K, extrapolated (E) to the next step's first guess;
* ``control`` int64 (2,): [STARTED] 0 until the first step of the run (which then builds x from y), [EXTRAPOLATE]
  whether ``stages`` hold a guess (not at the start, nor after a chart switch).
"""

from __future__ import annotations

import numpy as np
from numba import njit, types

from lagcomp.integrate.drivers.canonical import canonical_jacobian
from lagcomp.integrate.drivers.events import ACTION_RESET
from lagcomp.integrate.drivers.fixed_step import fixed_step_window
from lagcomp.integrate.drivers.kernel_types import (
    CANONICAL_PARTIALS,
    ENERGY,
    EVENT_RESET,
    EVENTS,
    FLOAT,
    INDICES,
    INT,
    MATRIX,
    MOMENTA,
    MOMENTUM_RATE,
    OUTCOME,
    VECTOR,
    VELOCITIES,
)
from lagcomp.integrate.drivers.run_state import (
    COUNTER_SLOTS,
    EVENT_ROWS,
    NFEV,
    NSTEPS,
    SINCE_SAVE,
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
from lagcomp.kernel_support.linear_solvers import equilibrate, lu_factor, lu_substitute

#: Slots of the carry's ``control`` (module docstring): x has been built from y; ``stages`` hold a guess.
STARTED, EXTRAPOLATE = 0, 1
CONTROL_SLOTS = 2

#: The model kernels `collocation_run` takes first (`Method.kernels` of the gauss methods names them).
_KERNEL_TYPES = (VELOCITIES, MOMENTA, MOMENTUM_RATE, CANONICAL_PARTIALS, EVENTS, EVENT_RESET)
#: The method's arrays and settings after the common arguments: A (s, s), B (s,), C (s,), E (s, s),
#: the iteration limit, whether the stage equations are solved by simplified Newton, and the events' actions (the
#: chart switches: module docstring).
_COEFFICIENTS = (MATRIX, VECTOR, VECTOR, MATRIX, INT, types.boolean, INDICES)
#: The event rows the chart switches are recorded in (`_switch_charts`): times, states before, events, states after.
_EVENT_ROWS = (VECTOR, MATRIX, INDICES, MATRIX)
#: The carry (module docstring): x, compensation, stages, control.
_CARRY = (VECTOR, VECTOR, MATRIX, INDICES)

#: kernels, y, clock, counters, p, projecting, residual_max, t0, dt, n_steps, pause_at, t_end, save_every,
#: ts, ys, then the coefficients: the fixed-step driver protocol (as the RK4 driver's); then the event rows and the
#: carry.
_RUN = OUTCOME(*_KERNEL_TYPES, VECTOR, VECTOR, INDICES, VECTOR, INT, VECTOR, FLOAT, FLOAT, INT, INT, FLOAT, INT,
               VECTOR, MATRIX, *_COEFFICIENTS, *_EVENT_ROWS, *_CARRY)


@njit(cache=True, error_model="numpy", nogil=True)
def new_carry(n, s):
    """The carry of a new run of an ``n``-component state (q, q̇) by an ``s``-stage method: (x, compensation, stages,
    control), see the module docstring; the run's first step builds x from its y."""
    return np.zeros(n), np.zeros(n), np.zeros((s, n)), np.zeros(CONTROL_SLOTS, dtype=np.int64)


@njit(cache=True, error_model="numpy", nogil=True)
def _canonical_state(momenta, t, y, p, x, work, compensation, control):
    """x = (q, p) of y = (q, q̇) at t (``momenta``; ``work`` (n,)), with no compensation nor stages carried: the start
    of a run, or of a new chart."""
    n = work.shape[0]
    momenta(t, y, p, work)
    for c in range(n):
        x[c] = y[c]
        x[n + c] = work[c]
    compensation[:] = 0.0
    control[EXTRAPOLATE] = 0


@njit(cache=True, error_model="numpy", nogil=True)
def _switch_charts(event_values, event_reset, t, y, p, actions, g, counters, ev_t, ev_y, ev_i, ev_y_after):
    """Apply the reset of each chart switch (``actions`` ACTION_RESET) whose event function is positive at y (the
    state has left its chart) to ``y`` in place, and record it as an event row at ``t`` (the step's end, where the
    chart changes: module docstring): the event's index into ``ev_i``, the state before into ``ev_y`` and after into
    ``ev_y_after``, from row ``counters[EVENT_ROWS]`` on (`lagcomp.integrate.drivers.run_state`; the caller leaves
    a row per chart switch free).  ``g`` (E,) is work space.  Returns the number applied, or −1 when a reset could not
    be computed (its row is then not counted)."""
    event_values(t, y, p, g)
    switched = 0
    for e in range(actions.shape[0]):
        if actions[e] == ACTION_RESET and g[e] > 0.0:
            row = counters[EVENT_ROWS]
            if event_reset(t, y, p, e, ev_y_after[row]) != 0:
                return -1
            ev_t[row] = t
            ev_i[row] = e
            for c in range(y.shape[0]):
                ev_y[row, c] = y[c]
                y[c] = ev_y_after[row, c]
            counters[EVENT_ROWS] = row + 1
            switched += 1
    return switched


#: The stage iteration has converged when every component's change of h·K is below this fraction of the
#: component's own size (`_rounding_ratio`): about two ulps.
ROUNDING = 4e-16
#: ... or when that ratio, with the component's rounding noise in its scale (`_noise_floor`), no longer decreases
#: and is below this bound (the iteration has reached the noise of the terms that cancel in f).
NOISE = 1e-14


@njit(cache=True, error_model="numpy", nogil=True, inline="always")
def _rounding_ratio(change, size, floor, x, h):
    """max over the components c of change[c] / max(|x[c]|, h size[c], floor[c]): the stage iteration's change of
    h·K_c against component c's own size (0 for a component that did not change; NaN kept).

    Each component is compared with a size in its own unit (a length, an angle, a momentum) and of its own time
    scale (h K_c is x_c's increment), so the ratio is the same in any units: a change of units multiplies x_c,
    h K_c and ``floor[c]`` by the same factor, and the iteration itself is unchanged up to rounding."""
    ratio = 0.0
    for c in range(x.shape[0]):
        if change[c] != 0.0:  # np.maximum keeps a NaN, where max would drop it
            ratio = np.maximum(ratio, change[c] / max(abs(x[c]), h * size[c], floor[c]))
    return ratio


@njit(cache=True, error_model="numpy", nogil=True)
def _noise_floor(J, x, h, floor):
    """floor[c] = h Σ_d |J[c, d]| |x[d]|, J = ∂f/∂x at x: the size of the terms of h f_c that scale with the state
    (a stiff spring's k r in ṗ, which cancels against its k l0), whose rounding bounds how far h K_c can converge.
    Like x_c and h K_c it is in x_c's unit (J[c, d] x[d] is in that of f_c)."""
    for c in range(x.shape[0]):
        acc = 0.0
        for d in range(x.shape[0]):
            acc += abs(J[c, d]) * abs(x[d])
        floor[c] = h * acc


#: What `_stop_test` finds after a sweep of the stage iteration: go on, converged, diverged (non-finite), or stalled
#: above `NOISE` without the noise floor (the fixed point's: `_solve_stages` then evaluates it, once in a step).
GO_ON, CONVERGED, DIVERGED, STALLED = 0, 1, 2, 3


@njit(cache=True, error_model="numpy", nogil=True, inline="always")
def _stop_test(change, size, floor, x, h, previous, noise_known):
    """Whether the stage iteration stops after a sweep whose changes of h·K are in ``change``, ``size``, ``floor``
    (`_rounding_ratio`): (GO_ON, CONVERGED, DIVERGED or STALLED, the sweep's ratio).

    CONVERGED below `ROUNDING`, or, once the ratio no longer decreases (below ``previous``, the last sweep's), below
    `NOISE`; STALLED there above `NOISE` when the floor is not ``noise_known``; DIVERGED: the ratio is not finite.
    (It calls no kernel: numba then drops the reference counting of the arrays it is passed.)"""
    ratio = _rounding_ratio(change, size, floor, x, h)
    if not np.isfinite(ratio):
        return DIVERGED, ratio
    if ratio <= ROUNDING:
        return CONVERGED, ratio
    if ratio >= previous:  # no longer decreasing: at the noise of terms that cancel in f?
        if ratio >= NOISE and not noise_known:
            return STALLED, ratio
        if ratio < NOISE:
            return CONVERGED, ratio
    return GO_ON, ratio


@njit(cache=True, error_model="numpy", nogil=True, inline="always")
def _first_guess(K, K_previous, E, extrapolate):
    """The stages' first guess into ``K`` (s, 2n): the previous step's stages extrapolated by E if ``extrapolate``,
    else zero (the run's first step, after a chart switch, and the last, shorter step)."""
    for i in range(K.shape[0]):
        for c in range(K.shape[1]):
            guess = 0.0
            if extrapolate:
                for j in range(K.shape[0]):
                    guess += E[i, j] * K_previous[j, c]
            K[i, c] = guess


@njit(cache=True, error_model="numpy", nogil=True, inline="always")
def _factor_newton_matrix(h, A, J, matrix, pivots, rows, columns):
    """The simplified Newton iteration's matrix I − h A ⊗ J, J = ∂f/∂x (2n, 2n), equilibrated by powers of two
    (``equilibrate``: its blocks are in the units of q, p and their rates, and the pivot test must not depend on
    them) and LU-factored in place; the others are work space.  Returns whether the matrix was factored.  (It calls
    no kernel: numba then drops the reference counting of the arrays it is passed.)"""
    s, n2 = A.shape[0], J.shape[0]
    for i in range(s):
        for j in range(s):
            for a in range(n2):
                for b in range(n2):
                    unit = 1.0 if i == j and a == b else 0.0
                    matrix[i * n2 + a, j * n2 + b] = unit - h * A[i, j] * J[a, b]
    equilibrate(matrix, rows, columns)  # R (I − h A ⊗ J) C: its pivot test unit-free
    return lu_factor(matrix, pivots) == 0


@njit(cache=True, error_model="numpy", nogil=True, inline="always")
def _take_stage(i, h, qdot, pdot, K, newton, delta, change, size):
    """Stage i's f_i = (``qdot``, ``pdot``): the fixed point (``newton`` None) takes K_i ← f_i at once, into the next
    stage, and keeps the change of h·K and the size of K per component in ``change`` and ``size`` (2n,); Newton keeps
    the residual f_i − K_i in ``delta`` (s·2n,).  (It calls no kernel: numba then drops the reference counting of
    the arrays it is passed.)"""
    n = qdot.shape[0]
    n2 = 2 * n
    for c in range(n):
        if newton is not None:
            delta[i * n2 + c] = qdot[c] - K[i, c]
            delta[i * n2 + n + c] = pdot[c] - K[i, n + c]
        else:  # np.maximum keeps a NaN, where max would drop it
            change[c] = np.maximum(change[c], abs(h * (qdot[c] - K[i, c])))
            change[n + c] = np.maximum(change[n + c], abs(h * (pdot[c] - K[i, n + c])))
            size[c] = max(size[c], abs(qdot[c]), abs(K[i, c]))
            size[n + c] = max(size[n + c], abs(pdot[c]), abs(K[i, n + c]))
            K[i, c] = qdot[c]
            K[i, n + c] = pdot[c]


@njit(cache=True, error_model="numpy", nogil=True, inline="always")
def _newton_correction(matrix, pivots, rows, columns, delta, K, h, change, size):
    """K ← K + ΔK, ΔK solving (I − h A ⊗ J) ΔK = F(K) − K (the residuals in ``delta``, the matrix factored by
    `_factor_newton_matrix`); the change of h·K and the size of K per component into ``change`` and ``size``.  (It
    calls no kernel: numba then drops the reference counting of the arrays it is passed.)"""
    s, n2 = K.shape
    for c in range(s * n2):
        delta[c] *= rows[c]
    lu_substitute(matrix, pivots, delta)
    for c in range(s * n2):
        delta[c] *= columns[c]
    for i in range(s):
        for c in range(n2):
            change[c] = np.maximum(change[c], abs(h * delta[i * n2 + c]))
            size[c] = max(size[c], abs(K[i, c]))
            K[i, c] += delta[i * n2 + c]
            size[c] = max(size[c], abs(K[i, c]))


@njit(cache=True, error_model="numpy", nogil=True, inline="always")
def _solve_stages(velocities, momentum_rate, canonical_partials, t, h, x, p, A, C, K, max_iter, newton, counters,
                  xs, y_stage, qdot, pdot, J, matrix, pivots, delta, rows, columns, change, size, floor):
    """Solve the stage equations K_i = f(t + c_i h, x + h Σ_j a_ij K_j), i = 1..s, from the first guess in ``K``
    (s, 2n), by one of two iterations, chosen by ``newton``:

    * fixed point (``newton`` None): K_i ← f(t + c_i h, x + h Σ_j a_ij K_j), updating each stage as soon as it is
      computed (`_take_stage`); s evaluations of f per sweep, and it contracts only while h ‖∂f/∂x‖ ‖A‖ < 1
      (roughly);
    * simplified Newton (``newton`` True): with J = `canonical_jacobian` at the step's start (t, x), solve
      (I − h A ⊗ J) ΔK = F(K) − K, F_i(K) the right-hand side above, and K ← K + ΔK (`_newton_correction`); the
      (2ns)×(2ns) iteration matrix is factored once per step (`_factor_newton_matrix`).  It converges for steps far
      beyond the fixed point's reach (stiff or fast motions), at the price of one Jacobian and one factorization.

    ``newton`` is None or True, a compile-time constant to numba, so the fixed-point specialisation has no Newton
    branch in its inner loops, and the other way round.  Both stop when the change of h·K reaches rounding level,
    component by component and so in any units (`_stop_test`: ``change`` and ``size`` (2n,) per component, the
    noise floor ``floor``, which Newton has from its Jacobian).

    The stages' kernel calls are written out here, not in a function of their own: numba increfs and decrefs every
    array a call passes (inlined or not), and cannot drop the pairs around a call of a kernel (it may release
    anything); a call per sweep with its dozen arrays cost the double pendulum's gauss2 a fifth of its steps per
    second, measured when `_collocation_steps` was split.  The helpers called per stage, sweep and step
    (`_take_stage`, `_newton_correction`, `_stop_test`, ...) call no kernel, this one aside.

    The other arrays are work space (`_collocation_steps`).  Returns DONE; RHS_FAILED (M
    singular); or NOT_CONVERGED after ``max_iter`` sweeps, or when the iterates become non-finite or the iteration
    matrix singular (the step is too large for the iteration to converge).
    """
    status = 0
    sweeps = max_iter
    if newton is not None:
        status = canonical_jacobian(velocities, canonical_partials, t, x, p, J)
        if status != 0 or not _factor_newton_matrix(h, A, J, matrix, pivots, rows, columns):
            sweeps = 0  # M singular here (status > 0), or I − h A ⊗ J: not converged
    noise_known = newton is not None and status == 0
    if noise_known:
        _noise_floor(J, x, h, floor)
    else:
        for c in range(floor.shape[0]):
            floor[c] = 0.0
    previous = np.inf
    outcome = GO_ON
    for _ in range(sweeps):
        n2 = x.shape[0]
        n = n2 // 2
        for c in range(n2):
            change[c] = 0.0
            size[c] = 0.0
        for i in range(C.shape[0]):
            for c in range(n2):
                acc = x[c]
                for j in range(C.shape[0]):
                    acc += h * A[i, j] * K[j, c]
                xs[c] = acc
            t_stage = t + C[i] * h
            status = velocities(t_stage, xs, p, qdot)
            if status == 0:
                for c in range(n):
                    y_stage[c] = xs[c]
                    y_stage[n + c] = qdot[c]
                momentum_rate(t_stage, y_stage, p, pdot)
            counters[NFEV] += 1
            if status != 0:
                break
            _take_stage(i, h, qdot, pdot, K, newton, delta, change, size)
        if status != 0:
            break
        if newton is not None:
            _newton_correction(matrix, pivots, rows, columns, delta, K, h, change, size)
        outcome, previous = _stop_test(change, size, floor, x, h, previous, noise_known)
        if outcome == STALLED:  # the fixed point's floor, once in a step
            if canonical_jacobian(velocities, canonical_partials, t, x, p, J) != 0:
                J[:] = 0.0  # M singular at x (the stages' velocities were solved): no floor
            _noise_floor(J, x, h, floor)
            noise_known = True
            previous = _rounding_ratio(change, size, floor, x, h)
            outcome = CONVERGED if previous < NOISE else GO_ON
        if outcome != GO_ON:
            break
    if status > 0:
        return Status.RHS_FAILED
    return Status.DONE if outcome == CONVERGED else Status.NOT_CONVERGED


@njit(cache=True, error_model="numpy", nogil=True, inline="always")
def _step_end(h, x, B, K, compensation, new_compensation, xs):
    """The step's end x + h Σ b_i K_i into ``xs``, summed with Kahan's compensation: the increment's rounding
    (``new_compensation``) is carried to the next step instead of lost, which removes the systematic energy drift of
    long runs.  Returns 0, or −1 when it is not finite.  (It calls no kernel: numba then drops the reference counting
    of the arrays it is passed.)"""
    status = 0
    for c in range(x.shape[0]):
        increment = 0.0
        for i in range(B.shape[0]):
            increment += h * B[i] * K[i, c]
        increment -= compensation[c]
        acc = x[c] + increment
        new_compensation[c] = (acc - x[c]) - increment
        xs[c] = acc
        if not np.isfinite(acc):
            status = -1
    return status


@njit(cache=True, error_model="numpy", nogil=True, inline="always")
def _accept_step(x, y, compensation, new_compensation, K, K_previous, control, xs, qdot):
    """Take the step `_step_end` computed: x and y = (q, q̇) from ``xs`` and ``qdot``, its compensation,
    and its stages, which the next step extrapolates."""
    n = qdot.shape[0]
    for c in range(n):
        x[c] = xs[c]
        x[n + c] = xs[n + c]
        y[c] = xs[c]
        y[n + c] = qdot[c]
    for c in range(x.shape[0]):
        compensation[c] = new_compensation[c]
    for i in range(K.shape[0]):
        for c in range(K.shape[1]):
            K_previous[i, c] = K[i, c]
    control[EXTRAPOLATE] = 1


@njit(cache=True, error_model="numpy", nogil=True, inline="always")
def _record_step(clock, counters, t, last, save_every, ts, ys, y, n_saved):
    """Count the step that ended at ``t`` and save its row (every ``save_every``-th, and the ``last``); returns the
    rows now saved."""
    clock[TIME] = t
    counters[NSTEPS] += 1
    counters[SINCE_SAVE] += 1
    if last or counters[SINCE_SAVE] >= save_every:
        ts[n_saved] = t
        for c in range(y.shape[0]):
            ys[n_saved, c] = y[c]
        n_saved += 1
        counters[SINCE_SAVE] = 0
    return n_saved


@njit(cache=True, error_model="numpy", nogil=True)
def _collocation_steps(velocities, momenta, momentum_rate, canonical_partials, event_values, event_reset, y, clock,
                       counters, p, t0, dt, n_steps, pause_at, t_end, save_every, ts, ys, A, B, C, E, max_iter, newton,
                       actions, ev_t, ev_y, ev_i, ev_y_after, x, compensation, K_previous, control):
    """Implicit Runge-Kutta (Gauss-Legendre) on x = (q, p); fixed step ``dt``; resumable.

    The canonical equations are evaluated without a symbolic inverse: q̇ = ``velocities``(t, x) solves M q̇ = p − b,
    and ṗ = ``momentum_rate`` at (q, q̇) is ∂L/∂q + Q = −∂H/∂q + Q.  Saved rows and ``y`` stay in (q, q̇); x is
    carried from call to call (``x``, ``compensation``, ``K_previous``, ``control``: the carry of the module
    docstring) and built from y by ``momenta`` at the run's first step only.  A step: the stages' first guess
    (`_first_guess`), the stage equations solved (`_solve_stages`, by fixed point or simplified Newton as ``newton``
    says), the step's end summed (`_step_end`), its velocities, the step taken (`_accept_step`), the chart switches it calls for
    (`_switch_charts`), its row (`_record_step`).  Explicit time dependence is evaluated at the stage times
    t + c_i h, which is the method applied to the autonomous system extended by t' = 1 (HLW, sec. VI.4).  Step
    times, saving and chunking follow the RK4 driver.
    """
    n2, s = y.shape[0], B.shape[0]
    K = np.empty((s, n2))
    xs, y_stage, qdot, pdot = np.empty(n2), np.empty(n2), np.empty(n2 // 2), np.empty(n2 // 2)
    J, matrix, pivots = np.empty((n2, n2)), np.empty((s * n2, s * n2)), np.empty(s * n2, dtype=np.int64)
    delta, rows, columns = np.empty(s * n2), np.empty(s * n2), np.empty(s * n2)
    change, size, floor = np.empty(n2), np.empty(n2), np.empty(n2)
    new_compensation = np.zeros(n2)
    charts = 0      # the chart switches among the events (module docstring)
    for e in range(actions.shape[0]):
        charts += actions[e] == ACTION_RESET
    g = np.empty(actions.shape[0])
    n_saved = 0
    if control[STARTED] == 0:
        _canonical_state(momenta, clock[TIME], y, p, x, pdot, compensation, control)
        control[STARTED] = 1
    while True:
        k = counters[NSTEPS]
        stop, why, t_a, t_b = fixed_step_window(k, n_steps, pause_at, counters[SINCE_SAVE], save_every,
                                                n_saved, ts.shape[0], t0, dt, t_end)
        if stop:
            return why, n_saved
        if charts > 0 and counters[EVENT_ROWS] + charts > ev_t.shape[0]:
            return Status.BUFFER_FULL, n_saved     # no room for the step's chart switches: a fresh event buffer
        last = k == n_steps - 1
        h = t_b - t_a
        _first_guess(K, K_previous, E, control[EXTRAPOLATE] != 0 and not last)
        why = _solve_stages(velocities, momentum_rate, canonical_partials, t_a, h, x, p, A, C, K, max_iter, newton,
                            counters, xs, y_stage, qdot, pdot, J, matrix, pivots, delta, rows, columns, change, size,
                            floor)
        if why != Status.DONE:
            return why, n_saved
        status = _step_end(h, x, B, K, compensation, new_compensation, xs)
        if status == 0:
            status = velocities(t_b, xs, p, qdot)   # (q̇ at the step's end: y's)
            if status > 0:
                return Status.RHS_FAILED, n_saved
        if status != 0:
            return Status.NONFINITE, n_saved
        _accept_step(x, y, compensation, new_compensation, K, K_previous, control, xs, qdot)
        if charts > 0:
            switched = _switch_charts(event_values, event_reset, t_b, y, p, actions, g, counters, ev_t, ev_y, ev_i,
                                      ev_y_after)
            if switched < 0:
                return Status.RHS_FAILED, n_saved
            if switched > 0:    # the new chart's x; nothing carried over from the old one
                _canonical_state(momenta, t_b, y, p, x, pdot, compensation, control)
        n_saved = _record_step(clock, counters, t_b, last, save_every, ts, ys, y, n_saved)


@njit(_RUN, cache=True, error_model="numpy", nogil=True)
def collocation_run(velocities, momenta, momentum_rate, canonical_partials, event_values, event_reset, y, clock,
                    counters, p, projecting, residual_max, t0, dt, n_steps, pause_at, t_end, save_every, ts, ys, A, B,
                    C, E, max_iter, newton, actions, ev_t, ev_y, ev_i, ev_y_after, x, compensation, stages, control):
    """Gauss-Legendre collocation on x = (q, p); fixed step ``dt``; resumable (see `_collocation_steps`): ``x``,
    ``compensation``, ``stages`` and ``control`` are the run's carry (module docstring, `new_carry`); ``ev_t``,
    ``ev_y``, ``ev_i``, ``ev_y_after`` the event rows of its chart switches (`_switch_charts`), written from
    ``counters[EVENT_ROWS]`` on (the call returns BUFFER_FULL before a step that could overflow them).

    ``newton`` chooses how the stage equations are solved: simplified Newton (True) or fixed-point
    iteration (False).  Each runs its own specialisation of `_collocation_steps`, from which numba
    drops the other's branches (``projecting`` and ``residual_max`` are unused: unconstrained
    systems only).  ``actions`` marks the events that are chart switches (module docstring).
    """
    if newton:
        return _collocation_steps(velocities, momenta, momentum_rate, canonical_partials, event_values, event_reset,
                                  y, clock, counters, p, t0, dt, n_steps, pause_at, t_end, save_every, ts, ys, A, B,
                                  C, E, max_iter, True, actions, ev_t, ev_y, ev_i, ev_y_after, x, compensation,
                                  stages, control)
    return _collocation_steps(velocities, momenta, momentum_rate, canonical_partials, event_values, event_reset, y,
                              clock, counters, p, t0, dt, n_steps, pause_at, t_end, save_every, ts, ys, A, B, C, E,
                              max_iter, None, actions, ev_t, ev_y, ev_i, ev_y_after, x, compensation, stages, control)


_SWEEP = types.none(*_KERNEL_TYPES, ENERGY, MATRIX, MATRIX, INT, FLOAT, FLOAT, INT, FLOAT, INT, MATRIX, VECTOR,
                    INDICES, types.int64[:, ::1], types.float64[:, :, ::1], MATRIX, types.int64[:, ::1],
                    types.float64[:, :, ::1], types.float64[:, :, :, ::1], *_COEFFICIENTS)


@njit(_SWEEP, cache=True, error_model="numpy", nogil=True)
def collocation_sweep(velocities, momenta, momentum_rate, canonical_partials, event_values, event_reset, energy, Y0,
                      P, projecting, t0, dt, n_steps, t_end, save_every, final, t_final, status, counts, dense,
                      energy_stats, event_count, event_t, event_y, A, B, C, E, max_iter, newton, actions):
    """Trajectory k from (t0, Y0[k]) with parameters P[k], ``n_steps`` steps of ``dt`` by `collocation_run`, with a
    carry of its own (`new_carry`): its calls (one more each time the row buffer fills) make the run of one call.

    The outputs and their shapes are those of every fixed-step sweep loop (`lagcomp.integrate.sweep`):
    ``final`` (N, 2n), ``t_final`` (N,), ``status`` (N,), ``counts`` (N, 3) = [nfev, nsteps, nrejected],
    ``dense`` (N, m, 2n) the initial state and the saved rows (m = 0: none kept), ``energy_stats``
    (N, 2) = [E0, largest |E − E0| over the saved rows]; the chart switches as events, as the adaptive sweep loops
    record theirs (`lagcomp.integrate.drivers.sweep_rows.fold_events`): ``event_count`` (N, E), the first ``cap`` in
    ``event_t`` (N, E, cap) and ``event_y`` (N, E, cap, 4n: the states before and after).  Then the driver's
    trailing arguments (A, B, C, E, max_iter, newton, actions).
    """
    n_traj = Y0.shape[0]
    n2 = Y0.shape[1]
    for k in range(n_traj):
        y = Y0[k].copy()
        p = P[k]
        clock = np.zeros(2)
        clock[TIME] = t0
        counters = np.zeros(COUNTER_SLOTS, dtype=np.int64)
        residual = np.zeros(1)
        x, compensation, stages, control = new_carry(n2, B.shape[0])
        ts = np.empty(SWEEP_ROWS)
        ys = np.empty((SWEEP_ROWS, n2))
        rows_e = max(actions.shape[0], 1)
        ev_t, ev_y, ev_i, ev_y_after = (np.empty(rows_e), np.empty((rows_e, n2)), np.empty(rows_e, dtype=np.int64),
                                        np.empty((rows_e, n2)))
        e0 = energy(t0, y, p)
        deviation = 0.0
        row = 0
        if dense.shape[1] > 0:
            for c in range(n2):
                dense[k, 0, c] = y[c]
            row = 1
        for e in range(event_count.shape[1]):
            event_count[k, e] = 0
        while True:
            counters[EVENT_ROWS] = 0
            code, n_saved = collocation_run(velocities, momenta, momentum_rate, canonical_partials, event_values,
                                            event_reset, y, clock, counters, p, projecting, residual, t0, dt, n_steps,
                                            NO_PAUSE, t_end, save_every, ts, ys, A, B, C, E, max_iter, newton, actions,
                                            ev_t, ev_y, ev_i, ev_y_after, x, compensation, stages, control)
            deviation, row = fold_rows(energy, ts, ys, n_saved, p, e0, deviation, dense, k, row)
            fold_events(counters[EVENT_ROWS], ev_t, ev_y, ev_y_after, ev_i, event_count, event_t, event_y, k)
            if code != Status.BUFFER_FULL:
                break
        record_end(k, y, clock, counters, code, e0, deviation, final, t_final, status, counts, energy_stats)
