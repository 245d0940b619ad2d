"""Events located on a step's dense output: shared by the adaptive drivers (embedded Runge-Kutta, Taylor).

After each accepted step a driver evaluates the model's ``event_values`` kernel at the step's end;
`event_crossings` flags the events whose sign changed in their direction, `record_events` locates
each crossing on the step's interpolant (`dense_state`) by Brent's method (`event_root`) and
records them in time order; a terminal event cuts the step short at its time, and so does an event with a
reset (`reset_state` then moves the state, and the run goes on from there).

These are helpers of the drivers, typed at their call sites: numba compiles them into each
driver that calls them, and caches them with it.
"""

from __future__ import annotations

import numpy as np
from numba import njit

#: How a driver's dense output ``F`` is laid out (`dense_state`): the Taylor series, powers of the
#: step fraction (DOPRI5, Tsit5, BS3), DOP853's ``contd8`` rows.
DENSE_SERIES, DENSE_POWERS, DENSE_CONTD8 = 0, 1, 2
#: ``actions[e]``: 0 ignores event e, 1 records its crossings, 2 records them and stops the run, 3 records
#: them and applies its reset (the model's ``event_reset``) at the first, after which the run goes on.
ACTION_IGNORE, ACTION_RECORD, ACTION_TERMINAL, ACTION_RESET = 0, 1, 2, 3
#: ``actions[e]`` 4: a reset that is a contact's impact (`lagcomp.model.contacts`): g is the gap, and the reset
#: sends it away from its zero, never through it, so g found past its zero just after the impact is a return
#: (`return_before`), never a departure.
ACTION_IMPACT = 4


@njit(cache=True, error_model="numpy", nogil=True)
def dense_state(kind, F, y, t, h, tau, out):
    """State at time ``tau`` inside the step (t, t + h) from its dense output, into ``out``.

    ``kind`` DENSE_POWERS: ``F`` holds Q with ``y(t + x h) = y + h sum_m Q[m] x^(m+1)`` (DOPRI5 and the
    other pairs with a polynomial interpolant);
    ``kind`` DENSE_CONTD8: ``F`` holds the rows of DOP853's ``contd8``;
    ``kind`` DENSE_SERIES: the Taylor method, ``F`` holds the series, ``y(t + u) = sum_m F[i, m] u^m``.
    """
    n = y.shape[0]
    rows = F.shape[0]
    x = (tau - t) / h
    if kind == DENSE_SERIES:
        u = tau - t
        for i in range(n):
            acc = 0.0
            for m in range(F.shape[1] - 1, -1, -1):
                acc = acc * u + F[i, m]
            out[i] = acc
    elif kind == DENSE_POWERS:
        for i in range(n):
            acc = 0.0
            for m in range(rows - 1, -1, -1):
                acc = (acc + F[m, i]) * x
            out[i] = y[i] + h * acc
    else:
        one_minus_x = 1.0 - x
        for i in range(n):
            acc = 0.0
            for r in range(rows - 1, -1, -1):
                acc += F[r, i]
                if r % 2 == 0:
                    acc *= x
                else:
                    acc *= one_minus_x
            out[i] = y[i] + acc


@njit(cache=True, error_model="numpy", nogil=True)
def event_crossings(g_old, g_new, directions, actions, crossed):
    """Flag in ``crossed`` the active events whose sign change over the step matches their direction.

    Up: g_old < 0 <= g_new; down: g_old > 0 >= g_new (a zero at the step's
    start does not count: it was the previous step's end).  Returns the count.
    """
    count = 0
    for e in range(g_old.shape[0]):
        up = g_old[e] < 0.0 and g_new[e] >= 0.0
        down = g_old[e] > 0.0 and g_new[e] <= 0.0
        hit = actions[e] > 0 and ((up and directions[e] >= 0) or (down and directions[e] <= 0))
        crossed[e] = hit
        if hit:
            count += 1
    return count


#: The absolute part of `event_root`'s tolerance, only so that a root at t = 0 ends the search: far below any
#: time a model's unit makes meaningful (1e-300 s is 1e-297 ms), unlike Brent's 2 eps.
TINY_TIME = 1e-300


@njit(cache=True, error_model="numpy", nogil=True)
def event_root(event_values, kind, F, y, t, h, p, e, a, fa, b, fb, ywork, gwork):
    """Zero of event ``e`` on the dense output between times a and b (fa, fb of opposite signs).

    Brent's method (R. P. Brent, *Algorithms for Minimization without
    Derivatives*, 1973, ch. 4: inverse quadratic interpolation and secant
    steps, safeguarded by bisection), to 2 eps |tau| in time (+ `TINY_TIME`):
    a few units of its rounding.  (Brent's absolute term, 2 eps in the
    model's unit of time, made the location depend on that unit: in
    milliseconds a ball's bounces near t = 0.6 ms were located 1600 times
    less precisely than in seconds, and stopped as accumulated; issue #36.)
    """
    eps = 2.220446049250313e-16
    c = a
    fc = fa
    d = b - a
    step = d
    for _ in range(200):
        if (fb > 0.0) == (fc > 0.0):
            c = a
            fc = fa
            d = b - a
            step = d
        if abs(fc) < abs(fb):
            a = b
            b = c
            c = a
            fa = fb
            fb = fc
            fc = fa
        tol = 2.0 * eps * abs(b) + TINY_TIME
        half = 0.5 * (c - b)
        if abs(half) <= tol or fb == 0.0:
            break
        if abs(step) >= tol and abs(fa) > abs(fb):
            s = fb / fa
            if a == c:                           # secant
                num = 2.0 * half * s
                den = 1.0 - s
            else:                                # inverse quadratic
                qa = fa / fc
                r = fb / fc
                num = s * (2.0 * half * qa * (qa - r) - (b - a) * (r - 1.0))
                den = (qa - 1.0) * (r - 1.0) * (s - 1.0)
            if num > 0.0:
                den = -den
            else:
                num = -num
            if 2.0 * num < min(3.0 * half * den - abs(tol * den), abs(step * den)):
                step = d
                d = num / den
            else:
                d = half
                step = d
        else:
            d = half
            step = d
        a = b
        fa = fb
        if abs(d) > tol:
            b += d
        elif half > 0.0:
            b += tol
        else:
            b -= tol
        dense_state(kind, F, y, t, h, b, ywork)
        event_values(b, ywork, p, gwork)
        fb = gwork[e]
    return b


@njit(cache=True, error_model="numpy", nogil=True)
def record_events(event_values, kind, F, y, t, h, p, g_old, g_new, crossed, actions, times,
                   te, ye, ie, n_recorded, ywork, gwork):
    """Locate the flagged crossings of the step (t, t + h) and record them in time order.

    Writes times, states and event indices to ``te``/``ye``/``ie`` from row
    ``n_recorded`` (the caller made room for one row per event).  Events
    after the first terminal or resetting one are dropped (a reset changes
    what follows).  Returns the new row count and the time of that event
    (inf when none fired).
    """
    n_events = g_old.shape[0]
    return record_events_between(event_values, kind, F, y, t, h, p, np.full(n_events, t), g_old,
                                 np.full(n_events, t + h), g_new, crossed, actions, times, te, ye, ie, n_recorded,
                                 ywork, gwork)


@njit(cache=True, error_model="numpy", nogil=True)
def record_events_between(event_values, kind, F, y, t, h, p, starts, g_start, ends, g_end, crossed, actions, times,
                          te, ye, ie, n_recorded, ywork, gwork):
    """`record_events` with each flagged event's crossing bracketed by its own times inside the step: between
    ``starts[e]`` and ``ends[e]``, where g is ``g_start[e]`` and ``g_end[e]`` (of opposite signs)."""
    n_events = g_start.shape[0]
    for e in range(n_events):
        times[e] = np.inf
        if crossed[e]:
            times[e] = event_root(event_values, kind, F, y, t, h, p, e, starts[e], g_start[e], ends[e], g_end[e],
                                  ywork, gwork)
    t_stop = np.inf
    while True:
        first = -1
        for e in range(n_events):
            if times[e] < np.inf and (first < 0 or times[e] < times[first]):
                first = e
        if first < 0 or times[first] > t_stop:
            break
        te[n_recorded] = times[first]
        dense_state(kind, F, y, t, h, times[first], ye[n_recorded])
        ie[n_recorded] = first
        n_recorded += 1
        if actions[first] >= ACTION_TERMINAL:
            t_stop = times[first]
        times[first] = np.inf
    return n_recorded, t_stop


#: Points per step at which an event that starts the step at its zero is sampled (`restart_brackets`): at
#: h 2^-k, k = RESTART_SAMPLES - 1 .. 0, the first at h/2048.
RESTART_SAMPLES = 12
#: How far below h/2048 `return_before` looks for g's departure from its zero: h 2^-k up to k = this (or until
#: t + h 2^-k is t itself), below any time a double resolves next to t.
REFINED_SAMPLES = 80


@njit(cache=True, error_model="numpy", nogil=True)
def return_before(event_values, kind, F, y, t, h, p, e, direction, tau, g_tau, starts, g_start, ends, g_end,
                  ywork, gwork):
    """Whether event ``e``, at its zero at t after its reset (the state ``y``; g zero within rounding) and
    found past it at ``tau`` (g = ``g_tau`` on the side the event fires into: below 0 for direction −1), came
    back to it before ``tau`` rather than left it that way; a return's bracket goes to starts/ends[e].

    g is sampled at t + (tau − t) 2^-k, k = `REFINED_SAMPLES`, ..., 1 (from the deepest that t can tell from t,
    outwards), then at ``tau``.  The first sample where g differs from its value at t says which way g left its
    zero: the way the event fires (a kick that carries on: False), or the other way (a bounce), and then g came
    back: the bracket is [a sample on the other side, the next sample, past the zero], or, when no sample is on
    the other side (g turned back within the rounding of t), [t, t], which the driver reports as accumulated
    events.  ``gwork`` and ``ywork`` are overwritten.
    """
    event_values(t, y, p, gwork)
    g_restart = gwork[e]                # (the drivers' g_old holds 0 for an event at its zero)
    departed = 0.0                      # the sign g left its zero with (0: no sample told yet)
    other_side = False                  # some sample on the side g left to
    for k in range(REFINED_SAMPLES, -1, -1):
        if k > 0:
            inner = t + (tau - t) * 2.0 ** -k
            if inner == t:
                continue
            dense_state(kind, F, y, t, h, inner, ywork)
            event_values(inner, ywork, p, gwork)
            g_inner = gwork[e]
        else:
            inner, g_inner = tau, g_tau
        if departed == 0.0 and g_inner != g_restart:
            departed = 1.0 if g_inner > g_restart else -1.0
            if (departed < 0.0) == (direction < 0):
                return False
        if (g_inner > 0.0) if direction < 0 else (g_inner < 0.0):
            other_side = True
            starts[e] = inner
            g_start[e] = g_inner
        elif other_side:
            ends[e] = inner
            g_end[e] = g_inner
            return True
    if departed == 0.0:
        return False
    starts[e] = ends[e] = t
    g_start[e] = g_end[e] = 0.0
    return True


@njit(cache=True, error_model="numpy", nogil=True)
def step_brackets(t, h, g_old, g_new, starts, g_start, ends, g_end):
    """Every event's bracket: the whole step (t, t + h), g from ``g_old`` to ``g_new``."""
    for e in range(g_old.shape[0]):
        starts[e] = t
        g_start[e] = g_old[e]
        ends[e] = t + h
        g_end[e] = g_new[e]


@njit(cache=True, error_model="numpy", nogil=True)
def restart_brackets(event_values, kind, F, y, t, h, p, at_zero, g_new, directions, actions, crossed, starts,
                     g_start, ends, g_end, side, ywork, gwork):
    """Crossings of the events that start the step (t, t + h) at their zero (``at_zero[e]``: the state just after
    their reset), flagged in ``crossed`` with their brackets; returns their count.

    That zero does not count, but g may leave it and come back within the step (a bouncing ball's whole flight,
    in one step of a method whose step the flight does not limit: a parabola is a Taylor series' best case), a
    crossing the signs at the step's ends do not show.  g is sampled on the dense output at `RESTART_SAMPLES`
    points, dense near the start (t + h 2^-k: the step after a reset is the step before it, kept, often long
    against the motion that follows): the first sign change after g left 0 in the event's direction is bracketed
    by the samples around it.  A return to 0 before the first sample (h/2048) shows as a first sample already
    past the zero in the event's direction; `return_before` tells it from a departure that way (a kick that
    carries on) by the way g left its zero, and brackets it.  After an impact (``ACTION_IMPACT``), whose gap
    the impact sends away from its zero, a departure past it means the impacts accumulate at t.
    ``side`` (E,) is work space.
    """
    n_events = g_new.shape[0]
    count = 0
    for e in range(n_events):
        side[e] = 0.0                   # the sign of g once it left its zero (0: not yet)
    for j in range(RESTART_SAMPLES - 1, -1, -1):
        if j > 0:
            tau = t + h * 2.0 ** -j
            if tau == t:                # below the resolution of t: the state at t, not a sample after it
                continue
            dense_state(kind, F, y, t, h, tau, ywork)
            event_values(tau, ywork, p, gwork)
        else:
            tau = t + h
            for e in range(n_events):
                gwork[e] = g_new[e]
        for e in range(n_events):
            if at_zero[e] == 0 or actions[e] == ACTION_IGNORE or crossed[e]:
                continue
            v = gwork[e]
            if side[e] != 0.0 and (v <= 0.0 if side[e] > 0.0 else v >= 0.0):
                up = side[e] < 0.0
                if (up and directions[e] >= 0) or (not up and directions[e] <= 0):
                    crossed[e] = True
                    ends[e] = tau
                    g_end[e] = v
                    count += 1
                    continue
            if v != 0.0 and side[e] == 0.0 and directions[e] != 0 and (v < 0.0) == (directions[e] < 0):
                # g's first sample after its reset is already past its zero: a return before it, or a departure
                # that way, which an impact's gap never makes (the impacts then accumulate at t)
                returned = return_before(event_values, kind, F, y, t, h, p, e, directions[e], tau, v, starts, g_start,
                                         ends, g_end, ywork, gwork)
                if returned or actions[e] == ACTION_IMPACT:
                    if not returned:            # [t, t]: the impacts accumulate at t
                        starts[e] = ends[e] = t
                        g_start[e] = g_end[e] = 0.0
                    crossed[e] = True
                    count += 1
                if j > 0:       # the other events' values at tau again (return_before used gwork)
                    event_values(tau, ywork_at(kind, F, y, t, h, tau, ywork), p, gwork)
                else:
                    for other in range(n_events):
                        gwork[other] = g_new[other]
                if crossed[e]:
                    continue
            if v != 0.0:
                side[e] = 1.0 if v > 0.0 else -1.0
                starts[e] = tau
                g_start[e] = v
    return count


@njit(cache=True, error_model="numpy", nogil=True)
def ywork_at(kind, F, y, t, h, tau, ywork):
    """``ywork`` holding the state at ``tau`` on the step's dense output (`dense_state`), returned."""
    dense_state(kind, F, y, t, h, tau, ywork)
    return ywork


@njit(cache=True, error_model="numpy", nogil=True)
def resetting_event(te, ie, actions, first_row, n_rows, t_stop):
    """The event whose reset acts at ``t_stop``, from the rows ``first_row`` to ``n_rows`` a step recorded: the
    first at that time with a reset; -1 when a terminal event fired then too (the run stops instead)."""
    found = -1
    for r in range(first_row, n_rows):
        if te[r] == t_stop:
            action = actions[ie[r]]
            if action == ACTION_TERMINAL:
                return -1
            if action >= ACTION_RESET and found < 0:
                found = ie[r]
    return found


@njit(cache=True, error_model="numpy", nogil=True)
def reset_state(event_reset, event_values, t, y, p, e, work, g_old, g_work, te, ie, ye_after, first_row, n_rows,
                at_zero):
    """Apply the reset of event ``e`` at time ``t`` to ``y`` in place; the events' values there into ``g_old``.

    The rows ``first_row`` to ``n_rows`` the step recorded get their state after the event in ``ye_after``:
    the state after the reset for the rows at ``t``, their own state (``ye``, already copied there) for the
    others.  An event recorded at ``t`` whose g the reset leaves as it was starts the next step at 0 exactly
    (``at_zero[e]`` = 1, which the caller keeps across its calls until the next step is committed), so that its
    zero there, a few roundings off 0 on either side, does not count again (the bouncing ball's height after
    an impact: ±1e-17, growing); `restart_brackets` then watches it.  Returns 0; the kernel's status k > 0;
    or -1 when the state after the reset is not finite (``y`` is then left as it was).
    """
    n = y.shape[0]
    event_values(t, y, p, g_work)
    status = event_reset(t, y, p, e, work)
    if status != 0:
        return status
    for i in range(n):
        if not np.isfinite(work[i]):
            return -1
    for i in range(n):
        y[i] = work[i]
    for r in range(first_row, n_rows):
        if te[r] == t:
            for i in range(n):
                ye_after[r, i] = y[i]
    event_values(t, y, p, g_old)
    for ev in range(g_old.shape[0]):
        at_zero[ev] = 0
    for r in range(first_row, n_rows):
        if te[r] == t and g_old[ie[r]] == g_work[ie[r]]:
            g_old[ie[r]] = 0.0
            at_zero[ie[r]] = 1
    return 0


@njit(cache=True, error_model="numpy", nogil=True)
def unchanged_state(t, y, p, e, out):
    """An ``event_reset`` kernel for models none of whose events resets the state: ``out`` = ``y``, 0.  The
    drivers take it instead of the module's own (`lagcomp.integrate.methods.Method.bound_driver`), so that a new
    model's first run does not wait for numba to compile a kernel that no event uses."""
    for i in range(y.shape[0]):
        out[i] = y[i]
    return 0


@njit(cache=True, error_model="numpy", nogil=True)
def copy_rows(source, target, first_row, n_rows):
    """``target[r] = source[r]`` for the rows ``first_row`` to ``n_rows`` (the state after an event without a reset
    is the state at it)."""
    for r in range(first_row, n_rows):
        for i in range(source.shape[1]):
            target[r, i] = source[r, i]
