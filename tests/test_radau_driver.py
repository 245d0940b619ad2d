"""The Radau IIA driver (`lagcomp.integrate.drivers.radau`) called directly with hand-written kernels.

Kernels: tests/stiff_kernels.py (problems selected by p[0]; exact Jacobians) and the event functions of
tests/driver_kernels.py (g0 = y[0], g1 = t - p[1]).  Reference: scipy's ``solve_ivp(method="Radau")`` on
the same kernels with the same Jacobian, and closed forms.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.linalg import expm

from lagcomp.integrate.drivers.radau import new_carry, radau_run
from lagcomp.integrate.drivers.run_state import RunState
from lagcomp.integrate.radau import RADAU5
from lagcomp.integrate.status import Status
from tests import driver_kernels, stiff_kernels

OSCILLATOR, VAN_DER_POL, ROBERTSON, SPRING, NAN_RHS, SINGULAR_RHS, FAILING_JACOBIAN = range(7)
#: A stiff, critically damped spring-damper: eigenvalues -1000 (double), k/m = 1e6.
SPRING_P = [SPRING, 1e6, 2e3]
NO_EVENTS = np.zeros(0, dtype=np.int64)


class Run:
    """A run of `radau_run` from (t0, y0), driven call after call like `lagcomp.integrate.simulate` drives it;
    `kernels` (rhs, rhs_jacobian) and `differential` (None: all components, an ODE) for a DAE."""

    def __init__(self, p, y0, t_end, rtol, atol, *, t_eval=(), save_every=1, max_step=np.inf, first_step=0.0,
                 max_steps=10**9, events=None, kernels=(stiff_kernels.rhs, stiff_kernels.rhs_jacobian),
                 differential=None):
        self.p, self.t_end, self.rtol, self.atol = np.array(p, dtype=float), t_end, rtol, atol
        self.kernels, self.differential = kernels, len(y0) if differential is None else differential
        self.state = RunState(np.array(y0, dtype=float), 0.0, first_step)
        self.carry = new_carry(len(y0))
        self.t_eval = np.array(t_eval, dtype=float)
        self.save_every, self.max_step, self.max_steps = save_every, max_step, max_steps
        self.directions, self.actions = events if events is not None else (NO_EVENTS, NO_EVENTS)
        self.ts, self.ys, self.events = [], [], []
        self.calls = 0

    def call(self, cap=100_000, pause_at=10**9):
        """One driver call with an output buffer of `cap` rows; returns its status."""
        n = self.state.y.size
        ts, ys = np.empty(cap), np.empty((cap, n))
        ev = np.empty(16), np.empty((16, n)), np.empty(16, dtype=np.int64)
        self.state.new_event_buffer()
        status, n_saved = radau_run(
            *self.kernels, driver_kernels.event_values,
            self.state.y, self.state.clock, self.state.counters, self.p, 0, np.zeros(1), self.t_end, self.rtol,
            np.full(n, self.atol), self.max_step, self.max_steps, pause_at, self.save_every, self.t_eval, ts, ys,
            self.directions, self.actions, *ev, *RADAU5.driver_arguments(), self.differential, *self.carry)
        self.calls += 1
        self.ts.append(ts[:n_saved].copy())
        self.ys.append(ys[:n_saved].copy())
        rows = self.state.event_rows
        self.events.append((ev[0][:rows].copy(), ev[1][:rows].copy(), ev[2][:rows].copy()))
        return Status(status)

    def solve(self, cap=100_000, pause_every=None):
        """Call until the run ends (after BUFFER_FULL and PAUSED); returns (status, ts, ys)."""
        while True:
            pause_at = 10**9 if pause_every is None else self.state.nsteps + pause_every
            status = self.call(cap, pause_at)
            if not status.call_again:
                return status, np.concatenate(self.ts), np.concatenate(self.ys)


def scipy_radau(p, y0, t_end, rtol, atol, **options):
    """scipy's Radau on the same kernels and Jacobian."""
    fun, jac = stiff_kernels.scipy_functions(p)
    return solve_ivp(fun, (0.0, t_end), np.array(y0, dtype=float), method="Radau", rtol=rtol, atol=atol, jac=jac,
                     **options)


def derived_constants() -> dict[str, np.ndarray]:
    """RADAU5's constants from the Radau IIA tableau in 40-digit arithmetic, rounded once to float64
    (the derivation `lagcomp.integrate.radau` documents)."""
    import mpmath

    with mpmath.workdps(40):
        s6 = mpmath.sqrt(6)
        c = [(4 - s6) / 10, (4 + s6) / 10, mpmath.mpf(1)]
        a = mpmath.matrix(3, 3)         # a_ij = integral of the Lagrange polynomial l_j over [0, c_i]
        for j in range(3):
            m, k = (c[i] for i in range(3) if i != j)
            scale = (c[j] - m) * (c[j] - k)
            for i in range(3):
                x = c[i]
                a[i, j] = (x ** 3 / 3 - (m + k) * x ** 2 / 2 + m * k * x) / scale
        a_inv = a ** -1
        values, vectors = mpmath.eig(a_inv)
        real = min(range(3), key=lambda i: abs(mpmath.im(values[i])))
        pair = max(range(3), key=lambda i: mpmath.im(values[i]))
        gamma = mpmath.re(values[real])
        v_real = [mpmath.re(vectors[i, real] / vectors[2, real]) for i in range(3)]
        v_pair = [vectors[i, pair] / vectors[2, pair] for i in range(3)]
        t = mpmath.matrix([[v_real[i], mpmath.re(v_pair[i]), mpmath.im(v_pair[i])] for i in range(3)])
        mu_complex = mpmath.conj(values[pair])
        vander = mpmath.matrix([[1, 1, 1], c, [ci ** 2 for ci in c]])
        b_hat = vander ** -1 * mpmath.matrix([1 - 1 / gamma, mpmath.mpf(1) / 2, mpmath.mpf(1) / 3])
        error = [gamma * sum((b_hat[k] - a[2, k]) * a_inv[k, j] for k in range(3)) for j in range(3)]
        dense = (mpmath.matrix([[ci ** (k + 1) for k in range(3)] for ci in c]) ** -1).T

        def as_floats(m, shape):
            return np.array(m.tolist() if hasattr(m, "tolist") else m, dtype=float).reshape(shape)

        return dict(C=as_floats(c, 3), T=as_floats(t, (3, 3)), TI=as_floats(t ** -1, (3, 3)),
                    MU=np.array([float(gamma), float(mpmath.re(mu_complex)), float(mpmath.im(mu_complex))]),
                    ERROR_WEIGHTS=as_floats(error, 3), DENSE_WEIGHTS=as_floats(dense, (3, 3)))


def test_constants_are_derived_from_the_tableau_and_are_scipys():
    """The stored constants are the derivation's, bit for bit; they match scipy's literals to round-off;
    A⁻¹ T = T Λ with Hairer's normalisation (T's last row (1, 1, 0))."""
    from scipy.integrate._ivp import radau as reference

    for name, value in derived_constants().items():
        assert np.array_equal(getattr(RADAU5, name), value), name
    assert np.allclose(RADAU5.C, reference.C, rtol=1e-15, atol=0)
    assert np.allclose(RADAU5.T, reference.T, rtol=1e-14, atol=1e-16)
    assert np.allclose(RADAU5.TI, reference.TI, rtol=1e-14, atol=1e-15)
    assert np.allclose(RADAU5.ERROR_WEIGHTS, reference.E, rtol=1e-14, atol=0)
    assert np.allclose(RADAU5.DENSE_WEIGHTS, reference.P, rtol=1e-14, atol=0)
    assert RADAU5.MU[0] == pytest.approx(reference.MU_REAL, rel=1e-15, abs=0)
    assert complex(RADAU5.MU[1], RADAU5.MU[2]) == pytest.approx(reference.MU_COMPLEX, rel=1e-15, abs=0)
    assert np.array_equal(RADAU5.T[2], [1.0, 1.0, 0.0])
    assert np.allclose(RADAU5.T @ RADAU5.TI, np.eye(3), atol=1e-14)


def test_order_five_with_forced_steps():
    """The oscillator over [0, 2] with steps forced to h = 2^-k: the error at t = 2 falls as h^5.

    Forced by max_step = first_step = h and rtol = atol = 1 (every step passes the error test and the
    controller may only propose larger steps, clamped back to h); the problem is linear and J exact,
    so the Newton iteration solves the stage equations to round-off whatever its tolerance.
    """
    exact = np.array([np.cos(2.0), -np.sin(2.0)])
    errors = []
    for k in range(3, 7):
        h = 2.0 ** -k
        run = Run([OSCILLATOR], [1.0, 0.0], 2.0, 1.0, 1.0, max_step=h, first_step=h)
        status, ts, ys = run.solve()
        assert status == Status.DONE and run.state.nsteps == 2 / h and run.state.nrejected == 0
        errors.append(np.abs(ys[-1] - exact).max())
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all((orders > 4.8) & (orders < 5.2)), orders


@pytest.mark.parametrize("problem, y0, t_end, rtol, atol", [
    (SPRING_P, [1.0, 0.0], 1.0, 1e-3, 1e-3),
    (SPRING_P, [1.0, 0.0], 1.0, 1e-7, 1e-7),
    ([ROBERTSON], [1.0, 0.0, 0.0], 1e5, 1e-7, 1e-10),
    ([OSCILLATOR], [1.0, 0.0], 10.0, 1e-9, 1e-9),
])
def test_takes_scipys_steps(problem, y0, t_end, rtol, atol):
    """The same accepted steps as scipy's Radau (times to 1e-5 relative, states to rtol from scipy's dense
    output at the same times; the counts of f and J evaluations and of LU factorisations equal), on problems
    whose step sequence round-off does not perturb."""
    run = Run(problem, y0, t_end, rtol, atol)
    status, ts, ys = run.solve()
    reference = scipy_radau(problem, y0, t_end, rtol, atol, dense_output=True)
    assert status == Status.DONE
    assert run.state.nsteps == reference.t.size - 1
    np.testing.assert_allclose(ts, reference.t[1:], rtol=1e-5, atol=0)
    assert (run.state.nfev, run.state.njev, run.state.nlu) == (reference.nfev, reference.njev, reference.nlu)
    np.testing.assert_allclose(ys, reference.sol(ts).T, rtol=0, atol=rtol * np.abs(reference.y).max())


def test_stiff_van_der_pol_close_to_scipy():
    """Van der Pol with ε = 1e-6 (stiff): step counts within 2% of scipy's at equal tolerances, where
    round-off steers the two runs apart (a Newton iteration converging one iteration later), and the
    state at t = 2 within 1e-5 of scipy's at rtol = 1e-10."""
    p, y0 = [VAN_DER_POL, 1e-6], [2.0, 0.0]
    for rtol in (1e-3, 1e-6):
        run = Run(p, y0, 2.0, rtol, rtol)
        assert run.solve()[0] == Status.DONE
        steps = scipy_radau(p, y0, 2.0, rtol, rtol).t.size - 1
        assert abs(run.state.nsteps - steps) <= 0.02 * steps
    run = Run(p, y0, 2.0, 1e-8, 1e-8)
    status, ts, ys = run.solve()
    reference = scipy_radau(p, y0, 2.0, 1e-10, 1e-10)
    assert np.abs(ys[-1] - reference.y[:, -1]).max() < 1e-5 * np.abs(reference.y[:, -1]).max()


def test_stiff_spring_against_closed_form():
    """The stiff spring-damper at t_eval points (dense output) within 10 rtol of expm(A t) y0."""
    k, c = SPRING_P[1:]
    matrix = np.array([[0.0, 1.0], [-k, -c]])
    t_eval = np.linspace(0.001, 0.02, 20)
    run = Run(SPRING_P, [1.0, 0.0], 0.02, 1e-8, 1e-8, t_eval=t_eval)
    status, ts, ys = run.solve()
    exact = np.array([expm(matrix * t) @ [1.0, 0.0] for t in t_eval])
    assert status == Status.DONE and np.array_equal(ts, t_eval)
    scale = np.abs(exact).max(axis=0)
    assert np.all(np.abs(ys - exact) <= 10 * 1e-8 * (scale + 1))


def test_continuation_is_bitwise_the_same_run():
    """Small output buffers (BUFFER_FULL) and step budgets (PAUSED) give the uninterrupted run's rows bit for bit."""
    p, y0 = [VAN_DER_POL, 1e-3], [2.0, 0.0]
    whole = Run(p, y0, 1.0, 1e-6, 1e-6)
    reference = whole.solve()
    for cap, pause_every in ((7, None), (1000, 13), (5, 3)):
        pieces = Run(p, y0, 1.0, 1e-6, 1e-6)
        result = pieces.solve(cap, pause_every)
        assert pieces.calls > 10
        assert result[0] == reference[0] == Status.DONE
        assert np.array_equal(result[1], reference[1]) and np.array_equal(result[2], reference[2])
        assert pieces.state.nsteps == whole.state.nsteps
        assert pieces.state.njev == whole.state.njev


def test_t_eval_continuation_through_a_step_holding_more_points_than_the_buffer():
    """t_eval points 1e-3 apart and 3-row buffers: each step holds more than one buffer; its remaining
    points come from the carried polynomial at the next call's start, the same as with one big buffer."""
    t_eval = np.linspace(0.0, 3.0, 3001)[1:]
    whole = Run([OSCILLATOR], [1.0, 0.0], 3.0, 1e-8, 1e-8, t_eval=t_eval)
    reference = whole.solve()
    pieces = Run([OSCILLATOR], [1.0, 0.0], 3.0, 1e-8, 1e-8, t_eval=t_eval)
    result = pieces.solve(cap=3)
    assert np.array_equal(result[1], t_eval) and np.array_equal(result[1], reference[1])
    assert np.array_equal(result[2], reference[2])
    assert np.abs(result[2][:, 0] - np.cos(t_eval)).max() < 1e-7


def test_events_on_the_dense_output():
    """The oscillator's zeros of y0 (recorded) at π/2 + kπ to the interpolant's accuracy, with y0 = 0 to
    round-off on the dense output; a terminal event t = p[1] stops the run there."""
    events = (np.array([0, 0]), np.array([1, 2]))
    run = Run([OSCILLATOR, 7.0], [1.0, 0.0], 10.0, 1e-9, 1e-9, events=events)
    status, ts, ys = run.solve()
    te, ye, ie = (np.concatenate(part) for part in zip(*run.events, strict=True))
    assert status == Status.TERMINATED and abs(run.state.t - 7.0) < 1e-13 and ts[-1] == run.state.t
    zeros = ie == 0
    np.testing.assert_allclose(te[zeros], np.pi / 2 + np.pi * np.arange(zeros.sum()), atol=1e-8)
    assert np.abs(ye[zeros, 0]).max() < 1e-15
    assert list(ie[~zeros]) == [1] and te[~zeros][0] == run.state.t
    np.testing.assert_allclose(ys[-1], [np.cos(7.0), -np.sin(7.0)], atol=1e-8)


@pytest.mark.parametrize("kind, expected", [
    (NAN_RHS, Status.NONFINITE),
    (SINGULAR_RHS, Status.RHS_FAILED),
])
def test_failing_rhs_stops_with_its_status_and_the_last_good_state(kind, expected):
    run = Run([kind, 1.0], [1.0, 0.0], 5.0, 1e-6, 1e-6)
    status, ts, ys = run.solve()
    assert status == expected
    assert 0.5 < run.state.t <= 1.0 and ts[-1] == run.state.t
    np.testing.assert_allclose(run.state.y, [np.cos(run.state.t), -np.sin(run.state.t)], atol=1e-5)


def test_failing_jacobian_is_rhs_failed_and_a_budget_is_max_steps():
    assert Run([FAILING_JACOBIAN, -1.0], [1.0, 0.0], 5.0, 1e-6, 1e-6).solve()[0] == Status.RHS_FAILED
    run = Run([OSCILLATOR], [1.0, 0.0], 5.0, 1e-6, 1e-6, max_steps=4)
    assert run.solve()[0] == Status.MAX_STEPS and run.state.nsteps == 4


def test_singular_iteration_matrix_is_detected():
    """γ/h I − J with J = γ/h I is singular: the factorisation reports it instead of dividing by zero."""
    from lagcomp.integrate.drivers.radau import _factor

    h = 0.5
    jacobian = RADAU5.MU[0] / h * np.eye(2)
    lu_real, lu_complex = np.empty((2, 2)), np.empty((2, 2), dtype=np.complex128)
    pivots = np.empty(2, dtype=np.int64), np.empty(2, dtype=np.int64)
    rows, columns = np.empty(2), np.empty(2)
    assert _factor(jacobian, h, RADAU5.MU.copy(), 2, lu_real, pivots[0], lu_complex, pivots[1], rows, columns) > 0
    assert _factor(np.zeros((2, 2)), h, RADAU5.MU.copy(), 2, lu_real, pivots[0], lu_complex, pivots[1], rows,
                   columns) == 0


def test_sweep_loop_gives_each_trajectory_of_the_driver():
    """`sweep_radau` over three spring-damper stiffnesses: each row's final state and counts are those of the
    driver run alone (bitwise), with its own carry."""
    from lagcomp.integrate.drivers.radau_sweep import sweep_radau

    stiffness = [1e4, 1e6, 1e8]
    P = np.array([[SPRING, k, 2 * np.sqrt(k)] for k in stiffness])
    Y0 = np.array([[1.0, 0.0]] * 3)
    final, t_final = np.empty((3, 2)), np.empty(3)
    status, counts = np.empty(3, dtype=np.int64), np.empty((3, 3), dtype=np.int64)
    dense, energy = np.empty((3, 0, 2)), np.empty((3, 2))
    event_count, event_t, event_y = np.empty((3, 0), np.int64), np.empty((3, 0, 1)), np.empty((3, 0, 1, 2))
    sweep_radau(stiff_kernels.rhs, stiff_kernels.rhs_jacobian, driver_kernels.event_values,
                driver_kernels.oscillator_energy, Y0, P, 0, 0.0, 0.01, 1e-8, np.full(2, 1e-8), np.inf, 10**9, 10**9,
                np.empty(0), False, NO_EVENTS, NO_EVENTS, final, t_final, status, counts, dense, energy, event_count,
                event_t, event_y, *RADAU5.driver_arguments(), 2)
    for row, p in enumerate(P):
        run = Run(p, [1.0, 0.0], 0.01, 1e-8, 1e-8)
        assert run.solve()[0] == status[row] == Status.DONE
        assert np.array_equal(final[row], run.state.y) and t_final[row] == 0.01
        assert list(counts[row]) == [run.state.nfev, run.state.nsteps, run.state.nrejected]
