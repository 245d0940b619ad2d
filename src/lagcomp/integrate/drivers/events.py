"""Events located on a step's dense output: shared by the adaptive drivers (embedded Runge-Kutta, Taylor).

After each accepted step a driver evaluates the model's ``event_values`` kernel at the step's end;
`event_crossings` flags the events whose sign changed in their direction, `record_events` locates
each crossing on the step's interpolant (`dense_state`) by Brent's method (`event_root`) and
records them in time order; a terminal event cuts the step short at its time.

These are helpers of the drivers, typed at their call sites: numba compiles them into each
driver that calls them, and caches them with it.
"""

from __future__ import annotations

import numpy as np
from numba import njit

#: How a driver's dense output ``F`` is laid out (`dense_state`): the Taylor series, powers of the
#: step fraction (DOPRI5, Tsit5, BS3), DOP853's ``contd8`` rows.
DENSE_SERIES, DENSE_POWERS, DENSE_CONTD8 = 0, 1, 2
#: ``actions[e]``: 0 ignores event e, 1 records its crossings, 2 records them and stops the run.
ACTION_IGNORE, ACTION_RECORD, ACTION_TERMINAL = 0, 1, 2


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


@njit(cache=True, error_model="numpy", nogil=True)
def event_root(event_values, kind, F, y, t, h, p, e, a, fa, b, fb, ywork, gwork):
    """Zero of event ``e`` on the dense output between times a and b (fa, fb of opposite signs).

    Brent's method (R. P. Brent, *Algorithms for Minimization without
    Derivatives*, 1973, ch. 4: inverse quadratic interpolation and secant
    steps, safeguarded by bisection), to 2 eps |tau| + 2 eps in time:
    a few units of rounding.
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
        tol = 2.0 * eps * abs(b) + 2.0 * eps
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
    after the first terminal one are dropped.  Returns the new row count and
    the time of the terminal event (inf when none fired).
    """
    n_events = g_old.shape[0]
    for e in range(n_events):
        times[e] = np.inf
        if crossed[e]:
            times[e] = event_root(event_values, kind, F, y, t, h, p, e, t, g_old[e], t + h, g_new[e], ywork, gwork)
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
        if actions[first] == ACTION_TERMINAL:
            t_stop = times[first]
        times[first] = np.inf
    return n_recorded, t_stop
