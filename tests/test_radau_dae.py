"""The Radau driver's DAE form (`lagcomp.integrate.drivers.radau`, "DAEs") on hand-written index-2 kernels.

Kernels: tests/dae_kernels.py — the planar pendulum in Cartesian coordinates as the stabilised (GGL)
index-2 DAE, z = (x, y, vx, vy, wx, wy, λ, μ), differential = 4, and a linear constrained oscillator of
the same shape.  References: the pendulum's angle ODE θ'' = −(g/L) sin θ by scipy's DOP853 at rtol 1e-13,
and closed forms.

The reaction, in the kernels' sign convention m q̈ = F + Λᵀλ with Λ = (x, y), F = (0, −m g):
m ẍ = λ x, m ÿ = −m g + λ y.  Differentiating the velocity constraint x ẋ + y ẏ = 0 once more,
ẋ² + ẏ² + x ẍ + y ÿ = 0, i.e. |v|² + (λ/m)(x² + y²) − g y = 0, so with x² + y² = L²

    λ = m (g y − |v|²) / L²        (μ = 0 on the exact solution).

Orders.  Forced steps (first_step = max_step = h) need stage equations solved far below the method's
error: the driver's Newton tolerance is tied to rtol (max(10 eps/rtol, min(0.03, √rtol)) of the
scaled norm), so on the nonlinear pendulum a step that passes the error test leaves a Newton error
above the method's own (measured: errors flat in h from 2^-4 to 2^-9 at rtol 1e-5 .. 1e-9).  So the
forced-step orders are measured on the linear DAE (kind 2), where the exact J makes the simplified
Newton iteration exact, and the pendulum's orders from adaptive runs, as the error against the number
of steps across rtol 1e-6, 1e-8, 1e-10.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from lagcomp.integrate.radau import RADAU5
from lagcomp.integrate.status import Status
from tests import dae_kernels, driver_kernels
from tests.test_radau_driver import Run

PENDULUM, REDUNDANT, LINE = 0.0, 1.0, 2.0
M, G, L = 1.3, 9.81, 0.8
#: p = (kind, event time, m, g, L); the event time far away unless a test sets it.
PENDULUM_P = np.array([PENDULUM, 1e9, M, G, L])
#: The line's p = (kind, event time, m, g, α, K11, K12, K22).
LINE_P = np.array([LINE, 1e9, 1.5, 9.81, 0.5, 40.0, 12.0, 25.0])
THETA0, OMEGA0 = 1.2, 0.0
DIFFERENTIAL = 4
KERNELS = (dae_kernels.rhs, dae_kernels.rhs_jacobian)


def dae_run(p, z0, t_end, rtol, atol=None, **options):
    return Run(p, z0, t_end, rtol, rtol if atol is None else atol, kernels=KERNELS, differential=DIFFERENTIAL,
               **options)


def angle_reference(t_end, **options):
    """θ'' = −(g/L) sin θ from (θ0, ω0) by DOP853 at rtol = atol = 1e-13, with its dense output."""
    return solve_ivp(lambda t, u: [u[1], -G / L * np.sin(u[0])], (0.0, t_end), [THETA0, OMEGA0], method="DOP853",
                     rtol=1e-13, atol=1e-13, dense_output=True, **options)


@pytest.mark.parametrize("p, n", [(PENDULUM_P, 8), (np.r_[REDUNDANT, PENDULUM_P[1:]], 10), (LINE_P, 8)])
def test_jacobian_is_the_central_differences_of_the_residual(p, n):
    z = np.random.default_rng(7).normal(size=n)
    jacobian, plus, minus = np.empty((n, n)), np.empty(n), np.empty(n)
    assert dae_kernels.rhs_jacobian(0.3, z, p, jacobian) == 0
    step = 1e-6
    differences = np.empty((n, n))
    for j in range(n):
        dz = np.zeros(n)
        dz[j] = step
        dae_kernels.rhs(0.3, z + dz, p, plus)
        dae_kernels.rhs(0.3, z - dz, p, minus)
        differences[:, j] = (plus - minus) / (2 * step)
    np.testing.assert_allclose(jacobian, differences, rtol=0, atol=1e-8)


def test_pendulum_against_the_angle_ode():
    """Over 30 s (15 periods of 1.97 s from θ0 = 1.2): positions within ten times the measured errors of the
    angle ODE's (measured with RADAU5's scales for the algebraic components 1.9e-6, 7.2e-9, 2.8e-11 at rtol
    1e-6, 1e-8, 1e-10, steps 1811, 5640, 17900; with `lagcomp.integrate.drivers.radau._algebraic_scales`
    1.1e-6, 7.0e-9, 1.8e-11 in 1827, 5689, 18059); error against steps of order 5 in q and 3 in λ between rtol
    1e-8 and 1e-10 (measured 5.17 and 3.03; from 1e-6 to 1e-8, 4.44 and 3.31: rtol 1e-6 is not yet asymptotic); at every accepted step, without
    projection, |Φ| and |Λ v| ≤ 1e-10 at rtol ≤ 1e-8 (measured 5.9e-13 and 8.3e-12 at 1e-8; at 1e-6 they follow
    the tolerance: 1.7e-9 and 9.1e-9); λ the closed form of the module docstring at the reference state and
    μ ≈ 0 (λ: 4.0e-4, 9.3e-6, 2.8e-7; μ: 1.9e-4, 6.5e-6, 2.1e-7)."""
    t_end = 30.0
    reference = angle_reference(t_end)
    bounds = {1e-6: (2e-5, 6e-3, 1.5e-3), 1e-8: (7e-8, 1.3e-4, 4e-5), 1e-10: (3e-10, 4e-6, 1.2e-6)}
    errors, lambda_errors, steps = [], [], []
    for rtol, (bound, lambda_bound, mu_bound) in bounds.items():
        run = dae_run(PENDULUM_P, dae_kernels.consistent_state(THETA0, OMEGA0, PENDULUM_P), t_end, rtol)
        status, ts, zs = run.solve()
        assert status == Status.DONE and ts[-1] == t_end
        theta, omega = reference.sol(ts)
        x, y, vx, vy, lam, mu = zs[:, 0], zs[:, 1], zs[:, 2], zs[:, 3], zs[:, 6], zs[:, 7]
        error = max(np.abs(x - L * np.sin(theta)).max(), np.abs(y + L * np.cos(theta)).max())
        assert error < bound, (rtol, error)
        if rtol <= 1e-8:
            assert np.abs((x * x + y * y - L * L) / 2).max() <= 1e-10
            assert np.abs(x * vx + y * vy).max() <= 1e-10
        exact_lambda = M * (G * -L * np.cos(theta) - (L * omega) ** 2) / L**2
        lambda_errors.append(np.abs(lam - exact_lambda).max())
        assert lambda_errors[-1] < lambda_bound, (rtol, lambda_errors[-1])
        assert np.abs(mu).max() < mu_bound, (rtol, np.abs(mu).max())
        errors.append(error)
        steps.append(run.state.nsteps)
    decade = np.log(steps[2] / steps[1])
    position_order = np.log(errors[1] / errors[2]) / decade
    lambda_order = np.log(lambda_errors[1] / lambda_errors[2]) / decade
    assert abs(position_order - 5.0) < 0.3, position_order
    assert lambda_order > 2.8, lambda_order


def test_orders_with_forced_steps_on_the_linear_dae():
    """The linear DAE (kind 2) over [0, 2] with h = 2^-3 .. 2^-7 forced (rtol = atol = 1: no rejection):
    q, v, w and λ converge with order 5 (measured 4.95-5.32; a linear constant-coefficient DAE shows no
    order reduction in λ, the pendulum's order 3 comes from its nonlinearity) and μ stays at round-off."""
    z0 = dae_kernels.line_solution([0.0], 0.3, 0.0, LINE_P)[0]
    exact = dae_kernels.line_solution([2.0], 0.3, 0.0, LINE_P)[0]
    errors = []
    for k in range(3, 8):
        h = 2.0**-k
        run = dae_run(LINE_P, z0, 2.0, 1.0, max_step=h, first_step=h)
        status, ts, zs = run.solve()
        assert status == Status.DONE and run.state.nsteps == 2 / h and run.state.nrejected == 0
        difference = np.abs(zs[-1] - exact)
        errors.append([difference[0:2].max(), difference[2:4].max(), difference[4:6].max(), difference[6]])
        assert difference[7] < 1e-14
    errors = np.array(errors)
    orders = np.log2(errors[:-1] / errors[1:])
    assert np.all((orders > 4.8) & (orders < 5.5)), orders


def test_events_on_the_dae_dense_output():
    """The pendulum's passes through the bottom (event g0 = x, both directions), located on the
    collocation polynomial, at the angle ODE's zeros of θ within six times the measured 1.9e-11 (rtol 1e-9);
    a terminal event at t = 10 stops the run there."""
    p = PENDULUM_P.copy()
    p[1] = 10.0
    run = dae_run(p, dae_kernels.consistent_state(THETA0, OMEGA0, p), 20.0, 1e-9,
                  events=(np.array([0, 0]), np.array([1, 2])))
    status, ts, zs = run.solve()
    te, ze, ie = (np.concatenate(part) for part in zip(*run.events, strict=True))
    assert status == Status.TERMINATED and run.state.t == ts[-1] and abs(run.state.t - 10.0) < 1e-13
    reference = angle_reference(10.0, events=lambda t, u: u[0]).t_events[0]
    crossings = ie == 0
    assert crossings.sum() == reference.size >= 9
    np.testing.assert_allclose(te[crossings], reference, rtol=0, atol=1.2e-10)
    assert np.abs(ze[crossings, 0]).max() < 1e-14
    assert list(ie[~crossings]) == [1]


def test_continuation_is_bitwise_the_same_dae_run():
    """Small output buffers and step budgets give the uninterrupted DAE run's rows bit for bit."""
    z0 = dae_kernels.consistent_state(THETA0, OMEGA0, PENDULUM_P)
    whole = dae_run(PENDULUM_P, z0, 3.0, 1e-7)
    reference = whole.solve()
    pieces = dae_run(PENDULUM_P, z0, 3.0, 1e-7)
    result = pieces.solve(cap=7, pause_every=5)
    assert pieces.calls > 10 and result[0] == reference[0] == Status.DONE
    assert np.array_equal(result[1], reference[1]) and np.array_equal(result[2], reference[2])
    assert (pieces.state.nsteps, pieces.state.njev) == (whole.state.nsteps, whole.state.njev)


def test_redundant_constraint_is_iteration_matrix_singular():
    """The pendulum's constraint stated twice (rank-deficient Λ: the iteration matrices are singular at every
    step): ITERATION_MATRIX_SINGULAR after halving the step down to the smallest (at t = 0, ~1000 halvings to
    10 ulp of 0), with the initial state kept."""
    p = np.r_[REDUNDANT, PENDULUM_P[1:]]
    z0 = dae_kernels.consistent_state(THETA0, OMEGA0, p)
    run = dae_run(p, z0, 1.0, 1e-6)
    status, ts, zs = run.solve()
    assert status == Status.ITERATION_MATRIX_SINGULAR
    assert run.state.t == 0.0 and run.state.nsteps == 0 and ts.size == 0
    assert np.array_equal(run.state.y, z0)


def test_sweep_passes_differential_to_each_run():
    """`sweep_radau` over two starting angles of the pendulum DAE: each row's final state and counts are those
    of the driver run alone (bitwise)."""
    from lagcomp.integrate.drivers.radau_sweep import sweep_radau

    angles = [0.4, 1.2]
    Y0 = np.array([dae_kernels.consistent_state(angle, 0.0, PENDULUM_P) for angle in angles])
    P = np.array([PENDULUM_P] * 2)
    final, t_final = np.empty((2, 8)), np.empty(2)
    status, counts = np.empty(2, dtype=np.int64), np.empty((2, 3), dtype=np.int64)
    dense, energy = np.empty((2, 0, 8)), np.empty((2, 2))
    event_count, event_t, event_y = np.empty((2, 0), np.int64), np.empty((2, 0, 1)), np.empty((2, 0, 1, 8))
    no_events = np.zeros(0, dtype=np.int64)
    sweep_radau(*KERNELS, driver_kernels.event_values, driver_kernels.oscillator_energy, Y0, P, 0, 0.0, 2.0, 1e-8,
                np.full(Y0.shape[1], 1e-8), np.inf, 10**9, 10**9, np.empty(0), False, no_events, no_events, final,
                t_final, status, counts, dense, energy, event_count, event_t, event_y, *RADAU5.driver_arguments(),
                DIFFERENTIAL)
    for row, z0 in enumerate(Y0):
        run = dae_run(PENDULUM_P, z0, 2.0, 1e-8)
        assert run.solve()[0] == status[row] == Status.DONE
        assert np.array_equal(final[row], run.state.y) and t_final[row] == 2.0
        assert list(counts[row]) == [run.state.nfev, run.state.nsteps, run.state.nrejected]
