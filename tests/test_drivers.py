"""Tests of the compiled integration drivers (codegen/templates/drivers.py).

The drivers are a source template appended to generated modules that define
``rhs``.  The harness below does the same with a hand-written ``rhs``: it
writes header + kernel + template to a temporary file and imports it (once per
test module, since numba compilation dominates the run time).  Results are
checked against closed-form solutions and against scipy's ``solve_ivp``,
which implements the same algorithms.  The harness kernel is compiled with
``error_model="numpy"``, as the generated kernels are, so that a division by
zero in it gives inf/NaN for the drivers to detect.
"""

import importlib.util
import re
import sys
import uuid

import numpy as np
import pytest
import scipy.integrate
from scipy.integrate import solve_ivp

from lagcomp.integrate.tableaux import DOP853, DOPRI5, driver_arguments
from lagcomp.integrate.status import Status

# -- harness ------------------------------------------------------------------

HEADER = "import numpy as np\nfrom numba import njit\n\n"

# Test problems, selected by p[0]:
#   0  harmonic oscillator  y0' = y1, y1' = -y0                     (N = 2)
#   1  Kepler problem       q'' = -q / |q|^3, y = (q, q')            (N = 4)
#   2  oscillator whose derivative is NaN for t > p[1]
#   3  oscillator whose rhs returns status 3 (singular) for t > p[1]
#   4  y0' = 1 / (1 - t), y1' = 0: a division by zero at t = 1  (N = 2)
#   5  at rest: y' = 0, so that every norm of f vanishes          (N = 2)
RHS_SOURCE = '''
@njit(cache=True, error_model="numpy")
def rhs(t, y, p, out):
    kind = int(p[0])
    if kind == 4:
        out[0] = 1.0 / (1.0 - t)
        out[1] = 0.0
        return 0
    if kind == 5:
        out[0] = 0.0
        out[1] = 0.0
        return 0
    if kind == 1:
        r2 = y[0] * y[0] + y[1] * y[1]
        r3 = r2 * np.sqrt(r2)
        out[0] = y[2]
        out[1] = y[3]
        out[2] = -y[0] / r3
        out[3] = -y[1] / r3
        return 0
    out[0] = y[1]
    out[1] = -y[0]
    if kind == 2 and t > p[1]:
        out[1] = np.nan
    if kind == 3 and t > p[1]:
        return 3
    return 0


@njit(cache=True, error_model="numpy")
def project(t, y, p):
    return 0


@njit(cache=True, error_model="numpy")
def constraint_residual(t, y, p):
    return 0.0


@njit(cache=True, error_model="numpy")
def event_values(t, y, p, out):
    # event 0: y[0] (the oscillator's position); event 1: t - p[1]
    if out.shape[0] > 0:
        out[0] = y[0]
    if out.shape[0] > 1:
        out[1] = t - p[1]

'''


def _template_text():
    spec = importlib.util.find_spec("lagcomp")
    package_dir = spec.submodule_search_locations[0]
    with open(f"{package_dir}/codegen/templates/drivers.py", encoding="utf-8") as fh:
        return fh.read()


@pytest.fixture(scope="module")
def mod(tmp_path_factory):
    """The compiled harness module (header + rhs + driver template)."""
    name = f"lagcomp_test_drivers_{uuid.uuid4().hex}"
    path = tmp_path_factory.mktemp("drivers") / f"{name}.py"
    path.write_text(HEADER + RHS_SOURCE + _template_text(), encoding="utf-8")
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module  # numba's cache locator needs the module registered
    try:
        spec.loader.exec_module(module)
        yield module
    finally:
        sys.modules.pop(name, None)


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


METHODS = {"RK45": ("dopri5_run", DOPRI5), "DOP853": ("dop853_run", DOP853)}
NO_PAUSE = np.iinfo(np.int64).max
NO_EVENTS = (np.empty(0, np.int64), np.empty(0, np.int64), np.empty(0), np.empty((0, 0)), np.empty(0, np.int64))


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


def run_adaptive(mod, method, kind, tol, *, atol=None, t_end=None, p_extra=(), t_eval=(),
                 cap=100_000, save_every=1, max_steps=10**7, max_step=np.inf, max_calls=1,
                 first_step=0.0):
    fname, tableau = METHODS[method]
    driver = getattr(mod, fname)
    base = KEPLER if kind == KEPLER else OSCILLATOR
    y = Y0[base].copy()
    t_end = T_END[base] if t_end is None else t_end
    atol = tol if atol is None else atol
    clock = np.array([0.0, first_step])
    counters = np.zeros(6, dtype=np.int64)
    p = np.array([kind, *p_extra], dtype=float)
    t_eval = np.asarray(t_eval, dtype=float)
    args = driver_arguments(tableau)

    def call(ts, ys):
        return driver(y, clock, counters, p, 0, np.zeros(1), t_end, tol, atol, max_step, max_steps, NO_PAUSE,
                      save_every, t_eval, ts, ys, *NO_EVENTS, *args)

    return _collect(call, y, clock, counters, cap, max_calls)


# -- accuracy against scipy and closed forms -----------------------------------

CASES = [(m, k, tol) for m in METHODS for k in (OSCILLATOR, KEPLER) for tol in (1e-6, 1e-9)]
CASE_IDS = [f"{m}-{'osc' if k == OSCILLATOR else 'kepler'}-{tol:g}" for m, k, tol in CASES]


@pytest.mark.parametrize("method, kind, tol", CASES, ids=CASE_IDS)
def test_steps_and_error_match_scipy(mod, method, kind, tol):
    run = run_adaptive(mod, method, kind, tol)
    t_end = T_END[kind]
    ref = solve_ivp(f_numpy(kind), (0.0, t_end), Y0[kind], method=method, rtol=tol, atol=tol)

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
def test_dense_output_matches_scipy(mod, method, kind, tol):
    t_end = T_END[kind]
    t_eval = np.linspace(0.0, t_end, 241)[1:]
    run = run_adaptive(mod, method, kind, tol, t_eval=t_eval)
    ref = solve_ivp(f_numpy(kind), (0.0, t_end), Y0[kind], method=method,
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


@pytest.mark.parametrize("method", METHODS)
def test_initial_step_matches_scipy(mod, method):
    """With max_steps = 0 the driver only selects the first step (clock[1])."""
    tol = 1e-7
    run = run_adaptive(mod, method, KEPLER, tol, max_steps=0)
    assert run.status == -4 and run.counters[1] == 0
    assert run.counters[0] == 2  # f(t0, y0) and the probe Euler step
    solver_class = getattr(scipy.integrate, method)
    solver = solver_class(f_numpy(KEPLER), 0.0, Y0[KEPLER], T_END[KEPLER], rtol=tol, atol=tol)
    assert run.clock[1] == pytest.approx(solver.h_abs, rel=1e-12)


def test_max_step_is_respected(mod):
    run = run_adaptive(mod, "RK45", OSCILLATOR, 1e-6, max_step=0.05)
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
    ("RK45", 0, 1, 7),
    ("RK45", 0, 3, 7),
    ("RK45", 100, 1, 7),
    ("DOP853", 0, 1, 7),
    ("DOP853", 100, 1, 7),
]


@pytest.mark.parametrize("method, n_eval, save_every, cap", CHUNK_CASES)
def test_adaptive_chunked_equals_single_call(mod, method, n_eval, save_every, cap):
    t_eval = np.linspace(0.0, 20.0, n_eval + 1)[1:] if n_eval else ()
    kw = dict(t_eval=t_eval, save_every=save_every)
    whole = run_adaptive(mod, method, KEPLER, 1e-8, **kw)
    chunked = run_adaptive(mod, method, KEPLER, 1e-8, cap=cap, max_calls=10_000, **kw)
    _assert_same_trajectory(chunked, whole)
    assert chunked.calls >= -(-len(whole.ts) // cap) > 5
    # Identical steps; each extra call re-evaluates f at its starting state.
    np.testing.assert_array_equal(chunked.counters[1:], whole.counters[1:])
    assert chunked.counters[0] == whole.counters[0] + chunked.calls - 1


@pytest.mark.parametrize("method", METHODS)
def test_chunked_with_more_points_per_step_than_buffer(mod, method):
    """A step holding more t_eval points than a whole buffer is redone."""
    t_eval = np.linspace(0.0, 5.0, 1001)[1:]
    whole = run_adaptive(mod, method, OSCILLATOR, 1e-6, t_eval=t_eval)
    chunked = run_adaptive(mod, method, OSCILLATOR, 1e-6, t_eval=t_eval, cap=3, max_calls=10_000)
    _assert_same_trajectory(chunked, whole)
    assert chunked.counters[1] == whole.counters[1]


# -- save_every decimation ---------------------------------------------------------

def _expected_decimation(all_steps, k):
    idx = list(range(k - 1, len(all_steps.ts), k))
    if idx[-1] != len(all_steps.ts) - 1:
        idx.append(len(all_steps.ts) - 1)
    return idx


@pytest.mark.parametrize("method", METHODS)
def test_save_every(mod, method):
    every = run_adaptive(mod, method, KEPLER, 1e-7)
    # A k that does not divide the step count, so the final step is an extra row.
    k = next(k for k in (4, 5, 7, 11) if len(every.ts) % k != 0)
    decimated = run_adaptive(mod, method, KEPLER, 1e-7, save_every=k)
    idx = _expected_decimation(every, k)
    np.testing.assert_array_equal(decimated.ts, every.ts[idx])
    np.testing.assert_array_equal(decimated.ys, every.ys[idx])


# -- failures ---------------------------------------------------------------------

@pytest.mark.parametrize("method", METHODS)
def test_adaptive_nan_stops_just_before_blowup(mod, method):
    run = run_adaptive(mod, method, NAN_AFTER, 1e-6, p_extra=(1.0,))
    assert run.status in (-1, -3)
    assert 1.0 - 1e-6 < run.clock[0] <= 1.0
    assert np.all(np.isfinite(run.y)) and np.all(np.isfinite(run.ys))
    assert np.all(run.ts <= 1.0) and run.ts[-1] == run.clock[0]
    np.testing.assert_allclose(run.y, exact(OSCILLATOR, run.clock[0]), atol=1e-5)


@pytest.mark.parametrize("method", METHODS)
def test_rhs_failure_gives_status_minus_2(mod, method):
    run = run_adaptive(mod, method, SINGULAR_AFTER, 1e-6, p_extra=(0.5,))
    assert run.status == -2
    assert run.clock[0] <= 0.5
    if len(run.ts):
        assert run.ts[-1] == run.clock[0]
        np.testing.assert_array_equal(run.ys[-1], run.y)


@pytest.mark.parametrize("method", METHODS)
def test_max_steps_then_resume(mod, method):
    limited = run_adaptive(mod, method, OSCILLATOR, 1e-6, max_steps=5)
    assert limited.status == -4 and limited.counters[1] == 5 and len(limited.ts) == 5
    assert limited.clock[0] == limited.ts[-1] < T_END[OSCILLATOR]

    # The state in y/clock/counters lets a run continue after raising the limit.
    fname, tableau = METHODS[method]
    ts, ys = np.empty(10_000), np.empty((10_000, 2))
    status, n = getattr(mod, fname)(
        limited.y, limited.clock, limited.counters, np.array([OSCILLATOR]), 0, np.zeros(1), T_END[OSCILLATOR],
        1e-6, 1e-6, np.inf, 10**7, NO_PAUSE, 1, np.empty(0), ts, ys, *NO_EVENTS, *driver_arguments(tableau))
    whole = run_adaptive(mod, method, OSCILLATOR, 1e-6)
    assert status == 0
    np.testing.assert_array_equal(np.concatenate([limited.ts, ts[:n]]), whole.ts)
    np.testing.assert_array_equal(limited.y, whole.y)


# -- division by zero and other non-finite trouble: a status, never an exception --

def test_template_uses_the_numpy_error_model_everywhere():
    """Under numba's default error model a division by zero raises
    ZeroDivisionError out of the compiled loop; the drivers rely on inf/NaN."""
    decorators = re.findall(r"^@njit\((.*)\)$", _template_text(), flags=re.M)
    assert decorators and all('error_model="numpy"' in d for d in decorators)


def blowup_exact(t):
    return 1.0 - np.log(1.0 - t)


@pytest.mark.parametrize("method", METHODS)
def test_division_by_zero_in_rhs_stops_the_run_before_the_singularity(mod, method):
    """f = 1 / (1 - t) is inf at t = 1 (and finite but of the wrong sign past it)."""
    run = run_adaptive(mod, method, BLOWUP, 1e-8, t_end=2.0)
    assert run.status in (-1, -3)
    assert 1.0 - 1e-9 < run.clock[0] < 1.0
    assert run.ts[-1] == run.clock[0]
    rel = 1e-4
    assert np.all(np.isfinite(run.y)) and np.all(np.isfinite(run.ys))
    np.testing.assert_allclose(run.y, [blowup_exact(run.clock[0]), 0.0], rtol=rel)
    np.testing.assert_allclose(run.ys[:, 0], blowup_exact(run.ts), rtol=rel)


@pytest.mark.parametrize("method", METHODS)
def test_vanishing_norms_take_the_same_steps_as_scipy(mod, method):
    """y' = 0: ||f0|| = ||f1 - f0|| = 0 in the initial step (h0 = 1e-6,
    h1 = max(1e-6, 1e-3 h0)) and a zero error norm every step (growth by
    MAX_FACTOR): the guarded divisions of scipy's step control."""
    run = run_adaptive(mod, method, REST, 1e-6)
    ref = solve_ivp(lambda t, y: np.zeros(2), (0.0, T_END[OSCILLATOR]), Y0[OSCILLATOR],
                    method=method, rtol=1e-6, atol=1e-6)
    assert run.status == 0 and ref.status == 0
    np.testing.assert_allclose(run.ts, ref.t[1:], rtol=1e-12)
    assert run.counters[0] == ref.nfev and run.counters[2] == 0
    np.testing.assert_array_equal(run.y, Y0[OSCILLATOR])


@pytest.mark.parametrize("kind", [OSCILLATOR, REST], ids=["crossing-zero", "identically-zero"])
@pytest.mark.parametrize("method", METHODS)
def test_zero_error_scale_is_a_status_not_an_exception(mod, method, kind):
    """atol = 0 with a state component that is exactly 0 makes the error scale
    atol + |y| rtol zero: 0/0 in the norms (scipy divides by it too and goes on
    with NaN; numba's default error model would raise ZeroDivisionError).  The
    run must end with a status: here the very first trial has a NaN error."""
    run = run_adaptive(mod, method, kind, 1e-6, atol=0.0, t_end=1.0)
    assert run.status in (-1, -3)
    assert run.clock[0] == 0.0 and run.counters[1] == 0
    np.testing.assert_array_equal(run.y, Y0[OSCILLATOR])


@pytest.mark.parametrize("first_step", [np.nan, np.inf], ids=["nan", "inf"])
@pytest.mark.parametrize("method", METHODS)
def test_non_finite_step_size_ends_the_run(mod, method, first_step):
    """A NaN step (or an infinite one with t_end = inf) never shrinks below
    the minimum step; the step control must stop instead of looping forever."""
    run = run_adaptive(mod, method, OSCILLATOR, 1e-6, first_step=first_step, t_end=np.inf)
    assert run.status == -1 and run.counters[1] == 0 and run.clock[0] == 0.0
    # With a finite t_end an infinite first step is simply clipped.
    if first_step == np.inf:
        run = run_adaptive(mod, method, OSCILLATOR, 1e-6, first_step=first_step)
        assert run.status == 0 and run.clock[0] == T_END[OSCILLATOR]


# -- events and pausing -----------------------------------------------------------

def run_events(mod, method, directions, actions, *, tol=1e-10, t_end=10.0, switch_time=np.inf, ev_cap=64,
               pause_every=None):
    """Oscillator y = (cos t, −sin t) with events g0 = y[0], g1 = t − switch_time; collects every call's rows."""
    fname, tableau = METHODS[method]
    y, clock, counters = Y0[OSCILLATOR].copy(), np.zeros(2), np.zeros(6, dtype=np.int64)
    p = np.array([OSCILLATOR, switch_time])
    directions, actions = np.array(directions, dtype=np.int64), np.array(actions, dtype=np.int64)
    ts_all, ys_all, events = [], [], []
    for _ in range(100_000):
        ts, ys = np.empty(1000), np.empty((1000, 2))
        ev = (np.empty(ev_cap), np.empty((ev_cap, 2)), np.empty(ev_cap, dtype=np.int64))
        counters[5] = 0
        pause_at = NO_PAUSE if pause_every is None else counters[1] + pause_every
        status, n_saved = getattr(mod, fname)(
            y, clock, counters, p, 0, np.zeros(1), t_end, tol, tol, np.inf, 10**7, pause_at, 1, np.empty(0),
            ts, ys, directions, actions, *ev, *driver_arguments(tableau))
        ts_all.append(ts[:n_saved].copy())
        ys_all.append(ys[:n_saved].copy())
        events += [(ev[0][k], ev[1][k].copy(), ev[2][k]) for k in range(counters[5])]
        if not Status(status).call_again:
            break
    return status, np.concatenate(ts_all), np.concatenate(ys_all), events, counters, clock


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("direction, expected", [(0, [1, 3, 5]), (1, [3]), (-1, [1, 5])])
def test_event_directions_and_times(mod, method, direction, expected):
    """cos t vanishes at π/2, 3π/2, 5π/2 in [0, 10]: upwards at 3π/2, downwards at the others."""
    status, _, _, events, _, _ = run_events(mod, method, [direction, 0], [1, 0])
    assert status == 0
    times = np.array([e[0] for e in events])
    np.testing.assert_allclose(times, np.array(expected) * np.pi / 2, rtol=0, atol=1e-9)
    for t_event, state, index in events:
        assert index == 0 and abs(state[0]) < 1e-12          # the root of the interpolant, to rounding
        assert abs(state[1] + np.sin(t_event)) < 1e-9


@pytest.mark.parametrize("method", METHODS)
def test_terminal_event_ends_the_run_at_its_time(mod, method):
    """g1 = t − 2.5 is linear in t: the stop lands on 2.5 to rounding, the last row is the event's state,
    and the crossing of g0 at π/2 before it is still recorded, in time order."""
    status, ts, ys, events, counters, clock = run_events(mod, method, [0, 1], [1, 2], switch_time=2.5)
    assert status == Status.TERMINATED
    assert [e[2] for e in events] == [0, 1]
    assert abs(events[1][0] - 2.5) < 1e-15 and clock[0] == ts[-1] == events[1][0]
    np.testing.assert_array_equal(ys[-1], events[1][1])
    np.testing.assert_allclose(ys[-1], [np.cos(2.5), -np.sin(2.5)], atol=1e-9)


@pytest.mark.parametrize("method", METHODS)
def test_pausing_and_small_event_buffers_change_nothing(mod, method):
    """A run cut into one-step calls (pause_at) with event buffers of the minimum size gives the same
    saved rows and events as one call; only the FSAL re-evaluation per call adds to nfev."""
    whole = run_events(mod, method, [0, 0], [1, 1], switch_time=4.0, t_end=30.0)
    cut = run_events(mod, method, [0, 0], [1, 1], switch_time=4.0, t_end=30.0, ev_cap=2, pause_every=1)
    assert whole[0] == cut[0] == 0
    np.testing.assert_array_equal(whole[1], cut[1])
    np.testing.assert_array_equal(whole[2], cut[2])
    assert [(e[0], e[2]) for e in whole[3]] == [(e[0], e[2]) for e in cut[3]]
    np.testing.assert_array_equal(whole[4][1:5], cut[4][1:5])


@pytest.mark.parametrize("method", METHODS)
def test_terminal_event_row_has_room_with_decimated_output(mod, method):
    """With save_every > 1 a terminal event still writes its row: the driver keeps room for it."""
    fname, tableau = METHODS[method]
    y, clock, counters = Y0[OSCILLATOR].copy(), np.zeros(2), np.zeros(6, dtype=np.int64)
    ts, ys = np.full(1, np.nan), np.full((1, 2), np.nan)
    calls = 0
    rows = []
    while True:
        calls += 1
        ev = (np.empty(4), np.empty((4, 2)), np.empty(4, dtype=np.int64))
        counters[5] = 0
        status, n = getattr(mod, fname)(
            y, clock, counters, np.array([OSCILLATOR, 2.5]), 0, np.zeros(1), 10.0, 1e-8, 1e-8, np.inf, 10**7,
            NO_PAUSE, 10**6, np.empty(0), ts, ys, np.zeros(2, np.int64), np.array([0, 2]), *ev,
            *driver_arguments(tableau))
        rows += [(ts[k], ys[k].copy()) for k in range(n)]
        if status != Status.BUFFER_FULL:
            break
    assert status == Status.TERMINATED and len(rows) == 1 and rows[0][0] == 2.5 and calls <= 2
