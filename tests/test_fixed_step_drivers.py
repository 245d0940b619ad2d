"""The library's explicit fixed-step drivers and their sweep loops (lagcomp.integrate.drivers.fixed_step, fixed_sweeps).

The drivers take the kernels as function values, so the tests hand them small hand-written njit
kernels (tests/driver_kernels.py), selected by ``p[0]``, and check them against closed forms,
against the textbook formula computed in Python, and against themselves (a run cut into calls by
a small buffer or a step budget is the uninterrupted run).
"""

import numpy as np
import pytest

from lagcomp.integrate import compositions, tableaux
from lagcomp.integrate.drivers import fixed_step, fixed_sweeps
from lagcomp.integrate.status import Status
from tests.driver_kernels import circle_projection as project
from tests.driver_kernels import circle_residual as constraint_residual
from tests.driver_kernels import oscillator_energy as energy
from tests.driver_kernels import rhs

# Test problems, selected by p[0]:
#   0  harmonic oscillator  y0' = y1, y1' = -y0 (separable: q = y0, q̇ = y1)
#   2  the oscillator, its acceleration NaN for t > p[1]
#   3  the oscillator, rhs status 3 (singular) for t > p[1]
#   4  y0' = 1 / (1 - t), y1' = 0: a division by zero at t = 1
OSCILLATOR, NAN_AFTER, SINGULAR_AFTER, BLOWUP = 0.0, 2.0, 3.0, 4.0
NO_PAUSE = np.iinfo(np.int64).max
COMPOSITIONS = {c.name: c for c in (compositions.VERLET, compositions.YOSHIDA4, compositions.YOSHIDA6)}


def exact(t):
    return np.array([np.cos(t), -np.sin(t)])


def _steps(dt, t_end):
    return int(np.ceil(t_end / dt - 1e-9))


class Run:
    """Outcome of one or more driver calls: the rows of all calls, the final state and the last status."""

    def __init__(self, status, ts, ys, y, clock, counters, calls):
        self.status, self.ts, self.ys, self.y, self.clock, self.counters, self.calls = (
            status, ts, ys, y, clock, counters, calls)


def run(method, kind, dt, t_end, *, p_extra=(), save_every=1, cap=100_000, pause_every=None, projecting=0,
        residual_bound=None, tableau=tableaux.RK4):
    """Integrate from (1, 0) at t = 0; a new buffer after BUFFER_FULL, a later budget after PAUSED."""
    y, clock, counters = np.array([1.0, 0.0]), np.zeros(2), np.zeros(6, dtype=np.int64)
    p = np.array([kind, *p_extra])
    residual = np.array([0.0] if residual_bound is None else [0.0, residual_bound])
    n_steps = _steps(dt, t_end)
    if method == "rk":
        driver = fixed_step.runge_kutta_run
        kernels, coefficients = (rhs, project, constraint_residual), tableaux.driver_arguments(tableau)
    else:
        driver = fixed_step.composition_run
        kernels, coefficients = (rhs,), COMPOSITIONS[method].driver_arguments()
    ts_all, ys_all, calls = [], [], 0
    while True:
        calls += 1
        pause_at = NO_PAUSE if pause_every is None else counters[1] + pause_every
        ts, ys = np.full(cap, np.nan), np.full((cap, 2), np.nan)
        status, n_saved = driver(*kernels, y, clock, counters, p, projecting, residual, 0.0, dt, n_steps, pause_at,
                                 t_end, save_every, ts, ys, *coefficients)
        assert 0 <= n_saved <= cap
        ts_all.append(ts[:n_saved].copy())
        ys_all.append(ys[:n_saved].copy())
        if status not in (Status.BUFFER_FULL, Status.PAUSED):
            break
    return Run(status, np.concatenate(ts_all), np.concatenate(ys_all), y, clock, counters, calls)


# -- the tableau as the driver reads it ------------------------------------------

def test_rk4_weights_are_integers_over_their_common_denominator():
    A, C, weights, denominator = tableaux.driver_arguments(tableaux.RK4)
    np.testing.assert_array_equal(A, tableaux.RK4.A)
    np.testing.assert_array_equal(C, tableaux.RK4.C)
    np.testing.assert_array_equal(weights, [1.0, 2.0, 2.0, 1.0])
    assert denominator == 6.0
    irrational = np.array([np.sqrt(0.5), 1.0 - np.sqrt(0.5)])
    numerators, d = tableaux.over_common_denominator(irrational)
    assert d == 1.0
    np.testing.assert_array_equal(numerators, irrational)


def test_rk4_is_the_textbook_formula_bitwise():
    """y + h/6 (K1 + 2 K2 + 2 K3 + K4), stage by stage in Python floats: the same roundings."""
    dt, t_end = 0.1, 3.05
    y = np.array([1.0, 0.0])
    textbook = []
    for k in range(_steps(dt, t_end)):
        t = k * dt
        h = (t_end if k == _steps(dt, t_end) - 1 else min((k + 1) * dt, t_end)) - t
        f = lambda y: np.array([y[1], -y[0]])  # noqa: E731
        k1 = f(y)
        k2 = f(y + 0.5 * h * k1)
        k3 = f(y + 0.5 * h * k2)
        k4 = f(y + 1.0 * h * k3)
        y = y + h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
        textbook.append(y)
    driver = run("rk", OSCILLATOR, dt, t_end)
    np.testing.assert_array_equal(driver.ys, np.array(textbook))


def test_rk4_convergence_order():
    errors = []
    for dt in (0.1, 0.05, 0.025):
        r = run("rk", OSCILLATOR, dt, 2.0)
        assert r.status == Status.DONE and r.clock[0] == 2.0 and r.ts[-1] == 2.0
        assert r.counters[0] == 4 * r.counters[1] == 4 * round(2.0 / dt)
        errors.append(np.abs(r.y - exact(2.0)).max())
    ratios = [errors[0] / errors[1], errors[1] / errors[2]]
    assert all(15.0 <= r <= 17.0 for r in ratios), ratios


def test_another_tableau_runs_on_the_same_driver():
    """Kutta's 3/8 rule (HNW I, table II.1.2): a tableau is all the driver needs; its weights are 1 3 3 1 over 8."""
    three_eighths = tableaux.Tableau(
        name="3/8", order=4, error_order=None,
        A=[[0, 0, 0, 0], [1 / 3, 0, 0, 0], [-1 / 3, 1, 0, 0], [1, -1, 1, 0]],
        B=[1 / 8, 3 / 8, 3 / 8, 1 / 8], C=[0, 1 / 3, 2 / 3, 1])
    _, _, weights, denominator = tableaux.driver_arguments(three_eighths)
    np.testing.assert_array_equal(weights, [1.0, 3.0, 3.0, 1.0])
    assert denominator == 8.0
    errors = [np.abs(run("rk", OSCILLATOR, dt, 2.0, tableau=three_eighths).y - exact(2.0)).max() for dt in (0.1, 0.05)]
    assert 15.0 <= errors[0] / errors[1] <= 17.0


def test_step_times_are_on_the_grid_and_the_last_step_is_clipped():
    """Times are t0 + k dt (no accumulated drift); the last step ends on t_end."""
    r = run("rk", OSCILLATOR, 0.1, 1.05)
    assert r.status == Status.DONE and r.counters[1] == 11
    np.testing.assert_array_equal(r.ts[:-1], 0.1 * np.arange(1, 11))
    assert r.ts[-1] == 1.05


# -- the compositions --------------------------------------------------------------

@pytest.mark.parametrize("method, order", [("verlet", 2), ("yoshida4", 4), ("yoshida6", 6)])
def test_composition_convergence_order(method, order):
    errors = [np.abs(run(method, OSCILLATOR, dt, 2.0).y - exact(2.0)).max() for dt in (0.1, 0.05)]
    assert 2 ** order * 0.9 <= errors[0] / errors[1] <= 2 ** order * 1.1


def test_composition_evaluates_once_per_substep():
    r = run("yoshida4", OSCILLATOR, 0.1, 2.0)
    assert r.counters[0] == 1 + 3 * r.counters[1]  # one more at the call's start


# -- runs cut into calls ---------------------------------------------------------------

@pytest.mark.parametrize("method", ["rk", "verlet", "yoshida4"])
@pytest.mark.parametrize("save_every", [1, 4])
def test_buffer_full_and_pauses_continue_the_run_exactly(method, save_every):
    whole = run(method, OSCILLATOR, 0.01, 3.05, save_every=save_every)
    for cut in (dict(cap=7), dict(pause_every=11), dict(cap=5, pause_every=3)):
        parts = run(method, OSCILLATOR, 0.01, 3.05, save_every=save_every, **cut)
        assert parts.status == whole.status == Status.DONE and parts.calls > 5
        np.testing.assert_array_equal(parts.ts, whole.ts)
        np.testing.assert_array_equal(parts.ys, whole.ys)
        np.testing.assert_array_equal(parts.y, whole.y)
        np.testing.assert_array_equal(parts.counters[1:], whole.counters[1:])
        # RK4 carries nothing over between steps; a composition evaluates f again at each call's start
        extra = 0 if method == "rk" else parts.calls - 1
        assert parts.counters[0] == whole.counters[0] + extra


@pytest.mark.parametrize("method", ["rk", "yoshida4"])
def test_save_every_keeps_every_kth_row_and_the_last(method):
    every = run(method, OSCILLATOR, 0.1, 3.05)
    k = 4  # 31 steps: the last step is an extra row
    decimated = run(method, OSCILLATOR, 0.1, 3.05, save_every=k)
    rows = [*range(k - 1, len(every.ts), k), len(every.ts) - 1]
    np.testing.assert_array_equal(decimated.ts, every.ts[rows])
    np.testing.assert_array_equal(decimated.ys, every.ys[rows])


# -- failures are statuses ----------------------------------------------------------------

# The step that first evaluates f past t = 1 (NaN) or t = 0.5 (singular), dt = 0.1: Yoshida's first
# substep (w = 1.35) reaches past the end of its step.
@pytest.mark.parametrize("method, good_steps", [("rk", 10), ("verlet", 10), ("yoshida4", 9)])
def test_non_finite_state_stops_with_the_last_good_state(method, good_steps):
    r = run(method, NAN_AFTER, 0.1, 5.0, p_extra=(1.0,))
    assert r.status == Status.NONFINITE
    assert r.counters[1] == good_steps and r.clock[0] == pytest.approx(0.1 * good_steps)
    assert np.all(np.isfinite(r.y)) and np.all(np.isfinite(r.ys))
    assert r.ts[-1] == r.clock[0]
    np.testing.assert_array_equal(r.ys[-1], r.y)


@pytest.mark.parametrize("method, good_steps", [("rk", 5), ("verlet", 5), ("yoshida4", 4)])
def test_rhs_failure_stops_with_rhs_failed(method, good_steps):
    r = run(method, SINGULAR_AFTER, 0.1, 5.0, p_extra=(0.5,))
    assert r.status == Status.RHS_FAILED
    assert r.counters[1] == good_steps and r.clock[0] == pytest.approx(0.1 * good_steps)
    np.testing.assert_array_equal(r.ys[-1], r.y)


def test_division_by_zero_in_rhs_is_a_status():
    """f = 1 / (1 - t) is inf at t = 1: the step 0.75 -> 1 meets it in its last stage."""
    r = run("rk", BLOWUP, 0.25, 2.0)
    assert r.status == Status.NONFINITE and r.counters[1] == 3 and r.clock[0] == 0.75 and r.counters[0] == 16
    np.testing.assert_allclose(r.y, [1.0 - np.log(0.25), 0.0], rtol=1e-3)


# -- constraints: projection and the residual bound -----------------------------------------

def test_projection_keeps_the_state_on_the_constraint():
    free = run("rk", OSCILLATOR, 0.5, 50.0)
    projected = run("rk", OSCILLATOR, 0.5, 50.0, projecting=1)
    assert constraint_residual(0.0, free.y, np.zeros(1)) > 1e-3
    assert constraint_residual(0.0, projected.y, np.zeros(1)) < 1e-14


def test_residual_above_the_bound_stops_after_committing_the_step():
    r = run("rk", OSCILLATOR, 0.5, 50.0, residual_bound=1e-3)
    assert r.status == Status.RESIDUAL_EXCEEDED and r.counters[1] < 100
    assert r.ts[-1] == r.clock[0] and np.array_equal(r.ys[-1], r.y)
    assert constraint_residual(0.0, r.ys[-2], np.zeros(1)) <= 1e-3 < constraint_residual(0.0, r.y, np.zeros(1))


# -- the sweep loops --------------------------------------------------------------------------

@pytest.mark.parametrize("method", ["rk", "yoshida4"])
def test_sweep_runs_each_trajectory_as_the_driver_does(method):
    Y0 = np.array([[1.0, 0.0], [0.5, 0.2], [0.0, -1.0]])
    P = np.zeros((3, 1))
    dt, t_end, save_every = 0.01, 2.0, 1   # 200 rows: the sweep's driver fills its buffer of SWEEP_ROWS 3 times
    n_steps = _steps(dt, t_end)
    rows = n_steps // save_every + 1
    final, t_final = np.empty((3, 2)), np.empty(3)
    status, counts = np.empty(3, dtype=np.int64), np.empty((3, 3), dtype=np.int64)
    dense, energy_stats = np.full((3, rows, 2), np.nan), np.empty((3, 2))
    outputs = (final, t_final, status, counts, dense, energy_stats)
    fixed = (Y0, P, 0, 0.0, dt, n_steps, t_end, save_every, *outputs)
    if method == "rk":
        fixed_sweeps.runge_kutta_sweep(rhs, project, constraint_residual, energy, *fixed,
                                       *tableaux.driver_arguments(tableaux.RK4))
    else:
        fixed_sweeps.composition_sweep(rhs, energy, *fixed, *compositions.YOSHIDA4.driver_arguments())
    for k in range(3):
        y, clock, counters = Y0[k].copy(), np.zeros(2), np.zeros(6, dtype=np.int64)
        ts, ys = np.empty(rows), np.empty((rows, 2))
        if method == "rk":
            code, n = fixed_step.runge_kutta_run(rhs, project, constraint_residual, y, clock, counters, P[k], 0,
                                                 np.zeros(1), 0.0, dt, n_steps, NO_PAUSE, t_end, save_every, ts, ys,
                                                 *tableaux.driver_arguments(tableaux.RK4))
        else:
            code, n = fixed_step.composition_run(rhs, y, clock, counters, P[k], 0, np.zeros(1), 0.0, dt, n_steps,
                                                 NO_PAUSE, t_end, save_every, ts, ys,
                                                 *compositions.YOSHIDA4.driver_arguments())
        assert code == status[k] == Status.DONE and t_final[k] == clock[0] == t_end
        np.testing.assert_array_equal(final[k], y)
        np.testing.assert_array_equal(counts[k, 1:], counters[1:3])
        calls = -(-n_steps // fixed_sweeps.SWEEP_ROWS)   # a composition evaluates f again at each call's start
        assert counts[k, 0] == counters[0] + (0 if method == "rk" else calls - 1)
        np.testing.assert_array_equal(dense[k], np.vstack([Y0[k], ys[:n]]))
        e = energy(0.0, Y0[k], P[k])
        assert energy_stats[k, 0] == e
        assert energy_stats[k, 1] == max(abs(energy(0.0, row, P[k]) - e) for row in ys[:n])
