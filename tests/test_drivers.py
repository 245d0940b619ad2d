"""Tests of the embedded Runge-Kutta driver of the library (`lagcomp.integrate.drivers.embedded`).

The driver takes the model's kernels as values: here hand-written njit kernels
(tests/driver_kernels.py) instead of a generated module's.  Results are checked against closed-form
solutions and against scipy's ``solve_ivp``, which implements the same algorithms (RK45 = dopri5,
DOP853, RK23 = bs3), and every check runs on each of the registry's embedded pairs.  The fixed-step
drivers have their own tests (tests/test_fixed_step_drivers.py).
"""


import numpy as np
import pytest
import scipy.integrate
from scipy.integrate import solve_ivp

from lagcomp.integrate.drivers.run_state import CLOCK_SLOTS, COUNTER_SLOTS
from lagcomp.integrate.methods import METHODS as REGISTRY
from lagcomp.integrate.status import Status
from tests import driver_kernels

# -- harness ------------------------------------------------------------------

#: The embedded pairs of the registry, and scipy's name of those scipy has.
EMBEDDED = [name for name, m in REGISTRY.items() if m.driver.endswith(":embedded_run")]
SCIPY = {"dopri5": "RK45", "dop853": "DOP853", "bs3": "RK23"}
KERNELS = (driver_kernels.rhs, driver_kernels.project, driver_kernels.constraint_residual,
           driver_kernels.event_values, driver_kernels.event_reset)


def embedded_run(*args):
    """The library driver with the test kernels; a number for ``atol`` (args[8]) spread over the state, as
    `simulate` does (the driver takes one per component)."""
    from lagcomp.integrate.drivers.embedded import embedded_run as driver

    y, atol = args[0], args[8]
    args = (*args[:8], np.full(y.size, atol) if np.ndim(atol) == 0 else atol, *args[9:])
    return driver(*KERNELS, *args)


OSCILLATOR, KEPLER, NAN_AFTER, SINGULAR_AFTER, BLOWUP, REST = 0.0, 1.0, 2.0, 3.0, 4.0, 5.0
ECC = 0.5
Y0 = {
    OSCILLATOR: np.array([1.0, 0.0]),
    KEPLER: np.array([1.0 - ECC, 0.0, 0.0, np.sqrt((1.0 + ECC) / (1.0 - ECC))]),
}
T_END = {OSCILLATOR: 10.0, KEPLER: 20.0}


def exact(kind, t):
    """Closed-form solutions; Kepler via Newton on Kepler's equation."""
    t = np.asarray(t, dtype=float)
    if kind == OSCILLATOR:
        return np.stack([np.cos(t), -np.sin(t)], axis=-1)
    E = t.copy()
    for _ in range(60):
        E = E - (E - ECC * np.sin(E) - t) / (1.0 - ECC * np.cos(E))
    b = np.sqrt(1.0 - ECC**2)
    den = 1.0 - ECC * np.cos(E)
    return np.stack([np.cos(E) - ECC, b * np.sin(E), -np.sin(E) / den, b * np.cos(E) / den], axis=-1)


def f_numpy(kind):
    """The same right-hand sides for scipy."""
    if kind == OSCILLATOR:
        return lambda t, y: np.array([y[1], -y[0]])

    def kepler(t, y):
        r3 = (y[0] ** 2 + y[1] ** 2) ** 1.5
        return np.array([y[2], y[3], -y[0] / r3, -y[1] / r3])

    return kepler


NO_PAUSE = np.iinfo(np.int64).max
NO_EVENTS = (np.empty(0, np.int64), np.empty(0, np.int64), np.empty(0), np.empty((0, 0)), np.empty(0, np.int64),
             np.empty((0, 0)), np.empty(0, np.int64))


class Run:
    """Outcome of one or more driver calls: concatenated output and final state."""

    def __init__(self, status, ts, ys, y, clock, counters, calls):
        self.status, self.ts, self.ys = status, ts, ys
        self.y, self.clock, self.counters, self.calls = y, clock, counters, calls


def _collect(call, y, clock, counters, cap, max_calls):
    n = y.shape[0]
    ts_all, ys_all = [], []
    for calls in range(1, max_calls + 1):
        ts = np.full(cap, np.nan)
        ys = np.full((cap, n), np.nan)
        status, n_saved = call(ts, ys)
        assert 0 <= n_saved <= cap
        ts_all.append(ts[:n_saved].copy())
        ys_all.append(ys[:n_saved].copy())
        if status != Status.BUFFER_FULL:
            break
    return Run(status, np.concatenate(ts_all), np.concatenate(ys_all), y, clock, counters, calls)


def run_adaptive(method, kind, tol, *, atol=None, t_end=None, p_extra=(), t_eval=(),
                 cap=100_000, save_every=1, max_steps=10**7, max_step=np.inf, max_calls=1,
                 first_step=0.0):
    base = KEPLER if kind == KEPLER else OSCILLATOR
    y = Y0[base].copy()
    t_end = T_END[base] if t_end is None else t_end
    atol = tol if atol is None else atol
    clock = np.array([0.0, first_step, 0.0])
    counters = np.zeros(COUNTER_SLOTS, dtype=np.int64)
    p = np.array([kind, *p_extra], dtype=float)
    t_eval = np.asarray(t_eval, dtype=float)
    args = REGISTRY[method].driver_arguments()

    def call(ts, ys):
        return embedded_run(y, clock, counters, p, 0, np.zeros(1), t_end, tol, atol, max_step, max_steps, NO_PAUSE,
                            save_every, t_eval, ts, ys, *NO_EVENTS, *args)

    return _collect(call, y, clock, counters, cap, max_calls)


# -- accuracy against scipy and closed forms -----------------------------------

#: scipy's pairs at two tolerances (BS3, of order 3, at 1e-9 only on the oscillator: tens of thousands of scipy steps)
CASES = [(m, k, tol) for m in SCIPY for k in (OSCILLATOR, KEPLER) for tol in (1e-6, 1e-9)
         if not (m == "bs3" and k == KEPLER and tol < 1e-6)]
CASE_IDS = [f"{m}-{'osc' if k == OSCILLATOR else 'kepler'}-{tol:g}" for m, k, tol in CASES]


@pytest.mark.parametrize("method, kind, tol", CASES, ids=CASE_IDS)
def test_steps_and_error_match_scipy(method, kind, tol):
    run = run_adaptive(method, kind, tol)
    t_end = T_END[kind]
    ref = solve_ivp(f_numpy(kind), (0.0, t_end), Y0[kind], method=SCIPY[method], rtol=tol, atol=tol)

    assert run.status == 0
    assert run.clock[0] == t_end and run.ts[-1] == t_end
    n_steps = run.counters[1]
    assert len(run.ts) == n_steps  # save_every = 1: every step, initial point excluded
    assert abs(n_steps - (len(ref.t) - 1)) <= 1
    if n_steps == len(ref.t) - 1:
        # Same rejections too: f(t0), the initial-step probe, s stages per trial.
        assert run.counters[0] == ref.nfev
    assert np.all(np.diff(run.ts) > 0)
    np.testing.assert_array_equal(run.y, run.ys[-1])

    err = np.abs(run.y - exact(kind, t_end)).max()
    err_ref = np.abs(ref.y[:, -1] - exact(kind, t_end)).max()
    assert err <= 1.5 * err_ref


@pytest.mark.parametrize("method, kind, tol", CASES, ids=CASE_IDS)
def test_dense_output_matches_scipy(method, kind, tol):
    t_end = T_END[kind]
    t_eval = np.linspace(0.0, t_end, 241)[1:]
    run = run_adaptive(method, kind, tol, t_eval=t_eval)
    ref = solve_ivp(f_numpy(kind), (0.0, t_end), Y0[kind], method=SCIPY[method],
                    rtol=tol, atol=tol, t_eval=t_eval)

    assert run.status == 0 and run.counters[3] == len(t_eval)
    np.testing.assert_array_equal(run.ts, t_eval)
    # Same algorithm: the interpolants agree far below the tolerance.
    assert np.abs(run.ys - ref.y.T).max() <= 0.01 * tol
    err = np.abs(run.ys - exact(kind, t_eval)).max()
    err_ref = np.abs(ref.y.T - exact(kind, t_eval)).max()
    assert err <= 1.5 * err_ref
    # The last point is t_end itself: it is the final state, not interpolated.
    np.testing.assert_array_equal(run.ys[-1], run.y)


@pytest.mark.parametrize("method", SCIPY)
def test_initial_step_matches_scipy(method):
    """With max_steps = 0 the driver only selects the first step (clock[1])."""
    tol = 1e-7
    run = run_adaptive(method, KEPLER, tol, max_steps=0)
    assert run.status == -4 and run.counters[1] == 0
    assert run.counters[0] == 2  # f(t0, y0) and the probe Euler step
    solver_class = getattr(scipy.integrate, SCIPY[method])
    solver = solver_class(f_numpy(KEPLER), 0.0, Y0[KEPLER], T_END[KEPLER], rtol=tol, atol=tol)
    assert run.clock[1] == pytest.approx(solver.h_abs, rel=1e-12, abs=0)


@pytest.mark.parametrize("method", EMBEDDED)
def test_max_step_is_respected(method):
    run = run_adaptive(method, OSCILLATOR, 1e-6, max_step=0.05)
    assert run.status == 0
    assert np.diff(np.concatenate([[0.0], run.ts])).max() <= 0.05 * (1 + 1e-12)


# -- chunked output buffers ----------------------------------------------------

def _assert_same_trajectory(chunked, whole):
    assert chunked.status == whole.status == 0
    np.testing.assert_array_equal(chunked.ts, whole.ts)
    assert np.abs(chunked.ys - whole.ys).max() <= 1e-14
    np.testing.assert_array_equal(chunked.y, whole.y)
    np.testing.assert_array_equal(chunked.clock, whole.clock)


CHUNK_CASES = [
    # method, t_eval points, save_every, cap
    *[(method, 0, 1, 7) for method in EMBEDDED],
    ("dopri5", 0, 3, 7),
    *[(method, 100, 1, 7) for method in EMBEDDED],
]


@pytest.mark.parametrize("method, n_eval, save_every, cap", CHUNK_CASES)
def test_adaptive_chunked_equals_single_call(method, n_eval, save_every, cap):
    t_eval = np.linspace(0.0, 20.0, n_eval + 1)[1:] if n_eval else ()
    kw = dict(t_eval=t_eval, save_every=save_every)
    whole = run_adaptive(method, KEPLER, 1e-8, **kw)
    chunked = run_adaptive(method, KEPLER, 1e-8, cap=cap, max_calls=10_000, **kw)
    _assert_same_trajectory(chunked, whole)
    assert chunked.calls >= -(-len(whole.ts) // cap) > 5
    # Identical steps; each extra call re-evaluates f at its starting state.
    np.testing.assert_array_equal(chunked.counters[1:], whole.counters[1:])
    assert chunked.counters[0] == whole.counters[0] + chunked.calls - 1


@pytest.mark.parametrize("method", EMBEDDED)
def test_chunked_with_more_points_per_step_than_buffer(method):
    """A step holding more t_eval points than a whole buffer is redone."""
    t_eval = np.linspace(0.0, 5.0, 1001)[1:]
    whole = run_adaptive(method, OSCILLATOR, 1e-6, t_eval=t_eval)
    chunked = run_adaptive(method, OSCILLATOR, 1e-6, t_eval=t_eval, cap=3, max_calls=10_000)
    _assert_same_trajectory(chunked, whole)
    assert chunked.counters[1] == whole.counters[1]


# -- save_every decimation ---------------------------------------------------------

def _expected_decimation(all_steps, k):
    idx = list(range(k - 1, len(all_steps.ts), k))
    if idx[-1] != len(all_steps.ts) - 1:
        idx.append(len(all_steps.ts) - 1)
    return idx


@pytest.mark.parametrize("method", EMBEDDED)
def test_save_every(method):
    every = run_adaptive(method, KEPLER, 1e-7)
    # A k that does not divide the step count, so the final step is an extra row.
    k = next(k for k in (4, 5, 7, 11) if len(every.ts) % k != 0)
    decimated = run_adaptive(method, KEPLER, 1e-7, save_every=k)
    idx = _expected_decimation(every, k)
    np.testing.assert_array_equal(decimated.ts, every.ts[idx])
    np.testing.assert_array_equal(decimated.ys, every.ys[idx])


# -- failures ---------------------------------------------------------------------

@pytest.mark.parametrize("method", EMBEDDED)
def test_adaptive_nan_stops_just_before_blowup(method):
    run = run_adaptive(method, NAN_AFTER, 1e-6, p_extra=(1.0,))
    assert run.status in (-1, -3)
    assert 1.0 - 1e-6 < run.clock[0] <= 1.0
    assert np.all(np.isfinite(run.y)) and np.all(np.isfinite(run.ys))
    assert np.all(run.ts <= 1.0) and run.ts[-1] == run.clock[0]
    np.testing.assert_allclose(run.y, exact(OSCILLATOR, run.clock[0]), atol=1e-5)


@pytest.mark.parametrize("method", EMBEDDED)
def test_rhs_failure_gives_status_minus_2(method):
    run = run_adaptive(method, SINGULAR_AFTER, 1e-6, p_extra=(0.5,))
    assert run.status == -2
    assert run.clock[0] <= 0.5
    if len(run.ts):
        assert run.ts[-1] == run.clock[0]
        np.testing.assert_array_equal(run.ys[-1], run.y)


@pytest.mark.parametrize("method", EMBEDDED)
def test_max_steps_then_resume(method):
    limited = run_adaptive(method, OSCILLATOR, 1e-6, max_steps=5)
    assert limited.status == -4 and limited.counters[1] == 5 and len(limited.ts) == 5
    assert limited.clock[0] == limited.ts[-1] < T_END[OSCILLATOR]

    # The state in y/clock/counters lets a run continue after raising the limit.
    ts, ys = np.empty(10_000), np.empty((10_000, 2))
    status, n = embedded_run(
        limited.y, limited.clock, limited.counters, np.array([OSCILLATOR]), 0, np.zeros(1), T_END[OSCILLATOR],
        1e-6, 1e-6, np.inf, 10**7, NO_PAUSE, 1, np.empty(0), ts, ys, *NO_EVENTS, *REGISTRY[method].driver_arguments())
    whole = run_adaptive(method, OSCILLATOR, 1e-6)
    assert status == 0
    np.testing.assert_array_equal(np.concatenate([limited.ts, ts[:n]]), whole.ts)
    np.testing.assert_array_equal(limited.y, whole.y)


# -- division by zero and other non-finite trouble: a status, never an exception --

def test_drivers_use_the_numpy_error_model_everywhere():
    """Under numba's default error model a division by zero raises
    ZeroDivisionError out of the compiled loop; the drivers rely on inf/NaN."""
    from lagcomp.integrate.drivers import embedded, embedded_sweep, events, fixed_step, fixed_sweeps, sweep_rows

    library = [embedded.embedded_run, embedded_sweep.sweep_embedded, sweep_rows.fold_rows, events.dense_state,
               events.event_crossings, events.event_root, events.record_events, fixed_step.runge_kutta_run,
               fixed_step.composition_run, fixed_sweeps.runge_kutta_sweep, fixed_sweeps.composition_sweep]
    assert all(f.targetoptions.get("error_model") == "numpy" for f in library)


def blowup_exact(t):
    return 1.0 - np.log(1.0 - t)


@pytest.mark.parametrize("method", EMBEDDED)
def test_division_by_zero_in_rhs_stops_the_run_before_the_singularity(method):
    """f = 1 / (1 - t) is inf at t = 1 (and finite but of the wrong sign past it)."""
    run = run_adaptive(method, BLOWUP, 1e-8, t_end=2.0)
    assert run.status in (-1, -3)
    assert 1.0 - 1e-9 < run.clock[0] < 1.0
    assert run.ts[-1] == run.clock[0]
    rel = 1e-4
    assert np.all(np.isfinite(run.y)) and np.all(np.isfinite(run.ys))
    np.testing.assert_allclose(run.y, [blowup_exact(run.clock[0]), 0.0], rtol=rel)
    np.testing.assert_allclose(run.ys[:, 0], blowup_exact(run.ts), rtol=rel)


@pytest.mark.parametrize("method", SCIPY)
def test_vanishing_norms_take_the_same_steps_as_scipy(method):
    """y' = 0: ||f0|| = ||f1 - f0|| = 0 in the initial step (h0 = 1e-6,
    h1 = max(1e-6, 1e-3 h0)) and a zero error norm every step (growth by
    MAX_FACTOR): the guarded divisions of scipy's step control."""
    run = run_adaptive(method, REST, 1e-6)
    ref = solve_ivp(lambda t, y: np.zeros(2), (0.0, T_END[OSCILLATOR]), Y0[OSCILLATOR],
                    method=SCIPY[method], rtol=1e-6, atol=1e-6)
    assert run.status == 0 and ref.status == 0
    np.testing.assert_allclose(run.ts, ref.t[1:], rtol=1e-12)
    assert run.counters[0] == ref.nfev and run.counters[2] == 0
    np.testing.assert_array_equal(run.y, Y0[OSCILLATOR])


@pytest.mark.parametrize("kind", [OSCILLATOR, REST], ids=["crossing-zero", "identically-zero"])
@pytest.mark.parametrize("method", EMBEDDED)
def test_zero_error_scale_is_a_status_not_an_exception(method, kind):
    """atol = 0 with a state component that is exactly 0 makes the error scale
    atol + |y| rtol zero: 0/0 in the norms (scipy divides by it too and goes on
    with NaN; numba's default error model would raise ZeroDivisionError).  The
    run must end with a status: here the very first trial has a NaN error."""
    run = run_adaptive(method, kind, 1e-6, atol=0.0, t_end=1.0)
    assert run.status in (-1, -3)
    assert run.clock[0] == 0.0 and run.counters[1] == 0
    np.testing.assert_array_equal(run.y, Y0[OSCILLATOR])


@pytest.mark.parametrize("first_step", [np.nan, np.inf], ids=["nan", "inf"])
@pytest.mark.parametrize("method", EMBEDDED)
def test_non_finite_step_size_ends_the_run(method, first_step):
    """A NaN step (or an infinite one with t_end = inf) never shrinks below
    the minimum step; the step control must stop instead of looping forever."""
    run = run_adaptive(method, OSCILLATOR, 1e-6, first_step=first_step, t_end=np.inf)
    assert run.status == -1 and run.counters[1] == 0 and run.clock[0] == 0.0
    # With a finite t_end an infinite first step is simply clipped.
    if first_step == np.inf:
        run = run_adaptive(method, OSCILLATOR, 1e-6, first_step=first_step)
        assert run.status == 0 and run.clock[0] == T_END[OSCILLATOR]


# -- events and pausing -----------------------------------------------------------

def run_events(method, directions, actions, *, tol=1e-10, t_end=10.0, switch_time=np.inf, ev_cap=64,
               pause_every=None):
    """Oscillator y = (cos t, −sin t) with events g0 = y[0], g1 = t − switch_time; collects every call's rows."""
    y, clock, counters = Y0[OSCILLATOR].copy(), np.zeros(CLOCK_SLOTS), np.zeros(COUNTER_SLOTS, dtype=np.int64)
    p = np.array([OSCILLATOR, switch_time])
    directions, actions = np.array(directions, dtype=np.int64), np.array(actions, dtype=np.int64)
    ts_all, ys_all, events = [], [], []
    for _ in range(100_000):
        ts, ys = np.empty(1000), np.empty((1000, 2))
        ev = (np.empty(ev_cap), np.empty((ev_cap, 2)), np.empty(ev_cap, dtype=np.int64), np.empty((ev_cap, 2)),
              np.zeros(directions.size, dtype=np.int64))
        counters[5] = 0
        pause_at = NO_PAUSE if pause_every is None else counters[1] + pause_every
        status, n_saved = embedded_run(
            y, clock, counters, p, 0, np.zeros(1), t_end, tol, tol, np.inf, 10**7, pause_at, 1, np.empty(0),
            ts, ys, directions, actions, *ev, *REGISTRY[method].driver_arguments())
        ts_all.append(ts[:n_saved].copy())
        ys_all.append(ys[:n_saved].copy())
        events += [(ev[0][k], ev[1][k].copy(), ev[2][k]) for k in range(counters[5])]
        if not Status(status).call_again:
            break
    return status, np.concatenate(ts_all), np.concatenate(ys_all), events, counters, clock


@pytest.mark.parametrize("method", EMBEDDED)
@pytest.mark.parametrize("direction, expected", [(0, [1, 3, 5]), (1, [3]), (-1, [1, 5])])
def test_event_directions_and_times(method, direction, expected):
    """cos t vanishes at π/2, 3π/2, 5π/2 in [0, 10]: upwards at 3π/2, downwards at the others."""
    status, _, _, events, _, _ = run_events(method, [direction, 0], [1, 0])
    assert status == 0
    times = np.array([e[0] for e in events])
    np.testing.assert_allclose(times, np.array(expected) * np.pi / 2, rtol=0, atol=1e-9)
    for t_event, state, index in events:
        assert index == 0 and abs(state[0]) < 1e-12          # the root of the interpolant, to rounding
        assert abs(state[1] + np.sin(t_event)) < (1e-9 if REGISTRY[method].order >= 5 else 1e-8)  # global error


@pytest.mark.parametrize("method", EMBEDDED)
def test_terminal_event_ends_the_run_at_its_time(method):
    """g1 = t − 2.5 is linear in t: the stop lands on 2.5 to rounding, the last row is the event's state,
    and the crossing of g0 at π/2 before it is still recorded, in time order."""
    status, ts, ys, events, counters, clock = run_events(method, [0, 1], [1, 2], switch_time=2.5)
    assert status == Status.TERMINATED
    assert [e[2] for e in events] == [0, 1]
    assert abs(events[1][0] - 2.5) < 1e-15 and clock[0] == ts[-1] == events[1][0]
    np.testing.assert_array_equal(ys[-1], events[1][1])
    np.testing.assert_allclose(ys[-1], [np.cos(2.5), -np.sin(2.5)], atol=1e-9)


@pytest.mark.parametrize("method", EMBEDDED)
def test_pausing_and_small_event_buffers_change_nothing(method):
    """A run cut into one-step calls (pause_at) with event buffers of the minimum size gives the same
    saved rows and events as one call; only the FSAL re-evaluation per call adds to nfev."""
    whole = run_events(method, [0, 0], [1, 1], switch_time=4.0, t_end=30.0)
    cut = run_events(method, [0, 0], [1, 1], switch_time=4.0, t_end=30.0, ev_cap=2, pause_every=1)
    assert whole[0] == cut[0] == 0
    np.testing.assert_array_equal(whole[1], cut[1])
    np.testing.assert_array_equal(whole[2], cut[2])
    assert [(e[0], e[2]) for e in whole[3]] == [(e[0], e[2]) for e in cut[3]]
    np.testing.assert_array_equal(whole[4][1:5], cut[4][1:5])


@pytest.mark.parametrize("method", EMBEDDED)
def test_terminal_event_row_has_room_with_decimated_output(method):
    """With save_every > 1 a terminal event still writes its row: the driver keeps room for it."""
    y, clock, counters = Y0[OSCILLATOR].copy(), np.zeros(CLOCK_SLOTS), np.zeros(COUNTER_SLOTS, dtype=np.int64)
    ts, ys = np.full(1, np.nan), np.full((1, 2), np.nan)
    calls = 0
    rows = []
    while True:
        calls += 1
        ev = (np.empty(4), np.empty((4, 2)), np.empty(4, dtype=np.int64), np.empty((4, 2)), np.zeros(2, np.int64))
        counters[5] = 0
        status, n = embedded_run(
            y, clock, counters, np.array([OSCILLATOR, 2.5]), 0, np.zeros(1), 10.0, 1e-8, 1e-8, np.inf, 10**7,
            NO_PAUSE, 10**6, np.empty(0), ts, ys, np.zeros(2, np.int64), np.array([0, 2]), *ev,
            *REGISTRY[method].driver_arguments())
        rows += [(ts[k], ys[k].copy()) for k in range(n)]
        if status != Status.BUFFER_FULL:
            break
    assert status == Status.TERMINATED and len(rows) == 1 and rows[0][0] == 2.5 and calls <= 2


# -- each pair's order, and BS3 step for step with scipy's RK23 ----------------------

#: Steps 2^-k of the measured orders (measured slopes: dopri5 5.26, dop853 8.12, tsit5 5.08, bs3 3.02).
ORDER_STEPS = {"dopri5": (5, 8), "dop853": (2, 5), "tsit5": (4, 7), "bs3": (5, 8)}


@pytest.mark.parametrize("method", EMBEDDED)
def test_measured_convergence_order(method):
    """Fixed steps h = 2^-k (first_step = max_step = h, a tolerance no step fails) on the Kepler problem
    to t = 2: the global error falls as h^p, p the pair's order (a wrong coefficient drops p by one or more).

    The slope of log(error) against log(h) is fitted over four halvings of h."""
    lo, hi = ORDER_STEPS[method]
    steps, errors = [], []
    for k in range(lo, hi + 1):
        h = 2.0**-k
        run = run_adaptive(method, KEPLER, 1e6, t_end=2.0, first_step=h, max_step=h)
        assert run.status == 0 and run.counters[1] == 2 * 2**k and run.counters[2] == 0
        steps.append(h)
        errors.append(np.abs(run.y - exact(KEPLER, 2.0)).max())
    slope = np.polyfit(np.log(steps), np.log(errors), 1)[0]
    assert abs(slope - REGISTRY[method].order) <= 0.3, (slope, errors)


def test_bs3_takes_the_steps_of_scipys_rk23():
    """At equal rtol/atol BS3 accepts the steps of scipy's RK23 (same times to rounding, same counts and
    evaluations) on the Kepler problem, whose step sizes vary by a factor of ten over the orbit."""
    tol = 1e-7
    run = run_adaptive("bs3", KEPLER, tol)
    ref = solve_ivp(f_numpy(KEPLER), (0.0, T_END[KEPLER]), Y0[KEPLER], method="RK23", rtol=tol, atol=tol)
    assert run.status == 0 and ref.status == 0
    assert run.counters[1] == len(ref.t) - 1 and run.counters[0] == ref.nfev
    np.testing.assert_allclose(run.ts, ref.t[1:], rtol=1e-12, atol=0)
    steps = np.diff(ref.t)
    assert steps.max() > 10 * steps.min()
    np.testing.assert_allclose(run.y, ref.y[:, -1], rtol=1e-9, atol=1e-12)


def test_tsit5_error_follows_the_tolerance():
    """Tsit5 (no scipy counterpart): a thousandfold tighter tolerance gives an error smaller by at least
    a hundred, and the error stays within a few tolerances, on the Kepler problem."""
    errors = []
    for tol in (1e-6, 1e-9):
        run = run_adaptive("tsit5", KEPLER, tol)
        assert run.status == 0
        errors.append(np.abs(run.y - exact(KEPLER, T_END[KEPLER])).max())
        assert errors[-1] < 1000 * tol
    assert errors[1] < errors[0] / 100
