"""method="rattle" (lagcomp.integrate.drivers.rattle) on the spherical pendulum in Cartesian coordinates.

The reference is the same pendulum in spherical angles (`examples.spherical_pendulum`, no constraint),
integrated by scipy's DOP853 at rtol = atol = 1e-13 and mapped to Cartesian coordinates
(`spherical_to_cartesian`).  Checked: order 2, agreement with the reference at the accuracy order 2
gives (states and the rod's multiplier), the energy error bounded (no drift), both constraint levels
held to round-off at every step, refusal of the systems RATTLE does not apply to, and a run cut into
driver calls by small buffers and step budgets equal bitwise to one call.
"""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from lagcomp.errors import OptionError
from lagcomp.examples.constrained import spherical_to_cartesian
from lagcomp.integrate.drivers.run_state import RunState
from lagcomp.integrate.methods import METHODS
from lagcomp.integrate.status import Status

CARTESIAN, ANGLES = "spherical_pendulum_cartesian", "spherical_pendulum"
#: Both examples start at θ = 1, φ = 0, θ̇ = 0, φ̇ = 2 with m = l = 1, g = 9.81.
START, M, L, G = (1.0, 0.0, 0.0, 2.0), 1.0, 1.0, 9.81
#: Reference rows every 0.1 over [0, 2].
T_END, ROWS = 2.0, 21
STEPS = (0.02, 0.01, 0.005)


@pytest.fixture(scope="module")
def cartesian(compiled):
    return compiled(CARTESIAN)


@pytest.fixture(scope="module")
def reference(compiled):
    """(Cartesian states (ROWS, 6), the rod's multiplier λ (ROWS,)) from the angles' model, DOP853 at 1e-13."""
    angles = compiled(ANGLES)
    p = angles.parameter_vector()

    def f(t, y):
        out = np.empty(4)
        angles.kernels.rhs(t, y, p, out)
        return out

    times = np.linspace(0.0, T_END, ROWS)
    solution = solve_ivp(f, (0.0, T_END), START, method="DOP853", rtol=1e-13, atol=1e-13, t_eval=times)
    theta, theta_dot, phi_dot = solution.y[0], solution.y[2], solution.y[3]
    states = np.array([np.concatenate(spherical_to_cartesian(*row, L)) for row in solution.y.T])
    # tension N = m (l (θ̇² + sin²θ φ̇²) + g cos θ) (θ from the downward vertical); λ = −N / (2 l)
    tension = M * (L * (theta_dot**2 + np.sin(theta) ** 2 * phi_dot**2) + G * np.cos(theta))
    return states, -tension / (2 * L)


def _rattle(model, t_end, dt, **options):
    return model.simulate((0.0, t_end), method="rattle", dt=dt, throw=True, **options)


def test_rattle_is_of_order_2_and_agrees_with_the_spherical_model(cartesian, reference):
    states, lam = reference
    errors, reaction_errors = [], []
    for h in STEPS:
        s = _rattle(cartesian, T_END, h, save_every=round(0.1 / h))
        assert s.t.size == ROWS
        errors.append(np.abs(np.hstack([s.q, s.qd]) - states).max())
        reaction_errors.append(np.abs(s.reactions["rod"] - lam).max())
    for e in (errors, reaction_errors):
        orders = np.log2(np.array(e[:-1]) / np.array(e[1:]))
        assert np.all(np.abs(orders - 2.0) < 0.05), (orders, e)
    # order 2 with the constants measured (15.9 h² for the states, 38.2 h² for λ over [0, 2])
    assert all(e < 20 * h**2 for e, h in zip(errors, STEPS, strict=True)), errors
    assert all(e < 50 * h**2 for e, h in zip(reaction_errors, STEPS, strict=True)), reaction_errors


def _residuals(model, s) -> np.ndarray:
    """|Φ| and |Λ q̇| at every saved row, shape (rows, 2)."""
    p, out = model.parameter_vector(), np.empty(2)
    rows = []
    for t, y in zip(s.t, np.hstack([s.q, s.qd]), strict=True):
        model.kernels.constraint_residuals(t, y, p, out)
        rows.append(np.abs(out))
    return np.array(rows)


def test_rattle_holds_both_constraint_levels_to_round_off_at_every_step(cartesian):
    s = _rattle(cartesian, 100.0, 0.01)
    residuals = _residuals(cartesian, s)
    assert s.nsteps == 10_000 and residuals.shape == (10_001, 2)
    assert residuals[:, 0].max() <= 1e-12 and residuals[:, 1].max() <= 1e-12, residuals.max(axis=0)
    assert s.constraint_residual <= 1e-12


def _bounded_energy_error(model, t_end, dt, rows):
    """The largest relative energy error over the run, and over its first and last tenths of saved rows."""
    s = _rattle(model, t_end, dt, save_every=round(t_end / dt / rows))
    error = np.abs(s.energy - s.energy[0]) / abs(s.energy[0])
    tenth = error.size // 10
    return error.max(), error[:tenth].max(), error[-tenth:].max()


def test_rattle_energy_error_stays_bounded_over_1e5_steps(cartesian):
    largest, first, last = _bounded_energy_error(cartesian, 1000.0, 0.01, 10_000)
    assert largest < 5e-4            # 2.9e-4 measured: O(h²), no drift
    assert last <= 1.5 * first, (first, last)


def test_rattle_energy_error_is_of_order_2(cartesian):
    errors = [_bounded_energy_error(cartesian, 100.0, h, 1000)[0] for h in (0.02, 0.01)]
    assert abs(np.log2(errors[0] / errors[1]) - 2.0) < 0.1, errors


@pytest.mark.slow
def test_rattle_energy_error_stays_bounded_over_1e6_steps(cartesian):
    largest, first, last = _bounded_energy_error(cartesian, 10_000.0, 0.01, 10_000)
    assert largest < 5e-4
    assert last <= 1.5 * first, (first, last)
    summary = _rattle(cartesian, 10_000.0, 0.01, record="summary")
    assert summary.nsteps == 1_000_000 and summary.summary.energy_error < 5e-4
    assert summary.constraint_residual <= 1e-12


def test_holonomic_separable_names_the_systems_rattle_applies_to(compiled):
    assert compiled(CARTESIAN).holonomic_separable and not compiled(CARTESIAN).separable
    assert not compiled(ANGLES).holonomic_separable      # no constraints: `separable` covers it
    assert not compiled("chaplygin_sleigh").holonomic_separable


@pytest.mark.parametrize("name, needle", [
    ("chaplygin_sleigh", "are nonholonomic"),
    ("simple_pendulum", "has no constraints: use verlet (RATTLE without constraints is Störmer-Verlet)"),
    (ANGLES, "has no constraints: use gauss2"),
])
def test_rattle_refuses_other_systems_and_says_why(compiled, name, needle):
    with pytest.raises(OptionError, match="rattle") as caught:
        compiled(name).simulate((0.0, 1.0), method="rattle", dt=0.01)
    assert needle in str(caught.value)


def test_rattle_refuses_projection(cartesian):
    with pytest.raises(OptionError, match="without projection"):
        cartesian.simulate((0.0, 1.0), method="rattle", dt=0.01, projection=True)


def test_the_explicit_symplectic_methods_point_a_holonomic_separable_system_to_rattle(cartesian):
    with pytest.raises(OptionError, match="Use rattle"):
        cartesian.simulate((0.0, 1.0), method="verlet", dt=0.01)


def _driver_rows(model, n_steps, dt, cap, pause_every=None):
    """Rows, final state and counters of a RATTLE run cut by a `cap`-row buffer (BUFFER_FULL) and budgets."""
    m = METHODS["rattle"]
    driver = m.bound_driver(model.kernels)
    p = model.parameter_vector()
    state = RunState(model.initial_state(), 0.0)
    ts_all, ys_all = [], []
    while True:
        pause_at = n_steps if pause_every is None else state.nsteps + pause_every
        ts, ys = np.empty(cap), np.empty((cap, 6))
        status, n_saved = driver(state.y, state.clock, state.counters, p, 1, np.zeros(1), 0.0, dt, n_steps,
                                 pause_at, n_steps * dt, 1, ts, ys, *m.driver_arguments())
        ts_all.append(ts[:n_saved].copy())
        ys_all.append(ys[:n_saved].copy())
        if not Status(status).call_again:
            assert status == Status.DONE
            return np.concatenate(ts_all), np.concatenate(ys_all), state.y.copy(), state.counters.copy()


def test_a_run_cut_into_calls_is_bitwise_the_uninterrupted_run(cartesian):
    one = _driver_rows(cartesian, 500, 0.01, 1000)
    for cut in (dict(cap=7), dict(cap=1000, pause_every=33), dict(cap=5, pause_every=9)):
        other = _driver_rows(cartesian, 500, 0.01, **cut)
        for a, b in zip(one[:3], other[:3], strict=True):
            assert np.array_equal(a, b), cut
        assert one[3][1] == other[3][1] == 500


def test_a_rattle_sweep_is_bitwise_the_runs_it_sweeps(cartesian):
    speeds = [1.5, 2.0]
    swept = cartesian.sweep((0.0, 1.0), {"y_dot": speeds}, method="rattle", dt=0.01, workers=1, progress=False)
    assert np.all(swept.status == 0)
    for i, speed in enumerate(speeds):
        y0 = cartesian.initial_state()
        s = _rattle(cartesian, 1.0, 0.01, qd0=(y0[3], speed, y0[5]))
        assert np.array_equal(swept.final[i], np.concatenate([s.q[-1], s.qd[-1]]))


@pytest.fixture(scope="module")
def chain(cache_dir):
    """A planar double pendulum in Cartesian coordinates, unequal masses: two rods, k = 2, M ≠ m·I."""
    import sympy as sp

    import lagcomp as lc
    from lagcomp.model import t

    x1, y1, x2, y2 = lc.coordinates("x1 y1 x2 y2")
    m1, m2, l1, l2, g = sp.symbols("m1 m2 l1 l2 g", positive=True)
    speed2 = lambda x, y: x.diff(t) ** 2 + y.diff(t) ** 2  # noqa: E731
    system = lc.System(
        coordinates=(x1, y1, x2, y2), T=(m1 * speed2(x1, y1) + m2 * speed2(x2, y2)) / 2, V=g * (m1 * y1 + m2 * y2),
        constraints=(lc.Holonomic("rod1", x1**2 + y1**2 - l1**2),
                     lc.Holonomic("rod2", (x2 - x1) ** 2 + (y2 - y1) ** 2 - l2**2)),
        parameters=(m1, m2, l1, l2, g), name="rattle_cartesian_double_pendulum",
        defaults={"m1": 1.0, "m2": 0.5, "l1": 1.0, "l2": 0.7, "g": 9.81},
        q0=(np.sin(1.0), -np.cos(1.0), np.sin(1.0) + 0.7 * np.sin(2.0), -np.cos(1.0) - 0.7 * np.cos(2.0)),
        qd0=(np.cos(1.0), np.sin(1.0), np.cos(1.0), np.sin(1.0)),   # the first rod turning at 1 rad/s, rigidly
    )
    return lc.compile(system, cache_dir=cache_dir)


def test_rattle_on_two_constraints_and_unequal_masses(chain):
    """Order 2 against DOP853 at rtol 1e-12 on the same model (errors 7.1e-3, 1.8e-3, 4.4e-4 at h = 0.02, 0.01,
    0.005), both constraint levels at round-off (2.7e-15 over 1000 s), the energy error bounded."""
    assert chain.holonomic_separable
    reference = chain.simulate((0.0, 1.0), method="dop853", rtol=1e-12, atol=1e-12, t_eval=[1.0], throw=True)
    exact = np.concatenate([reference.q[-1], reference.qd[-1]])
    errors = [np.abs(np.concatenate([s.q[-1], s.qd[-1]]) - exact).max()
              for s in (_rattle(chain, 1.0, h) for h in (0.01, 0.005))]
    assert abs(np.log2(errors[0] / errors[1]) - 2.0) < 0.1, errors
    s = _rattle(chain, 100.0, 0.005, save_every=10)
    p, out = chain.parameter_vector(), np.empty(4)
    worst = 0.0
    for time, y in zip(s.t, np.hstack([s.q, s.qd]), strict=True):
        chain.kernels.constraint_residuals(time, y, p, out)
        worst = max(worst, np.abs(out).max())
    assert worst <= 1e-12 and s.constraint_residual <= 1e-12, (worst, s.constraint_residual)
    # O(h²) and bounded: 1.5e-3 measured over 1000 s.  The motion is chaotic, so the maxima over windows of the
    # run differ with the states visited: the drift test is the spherical pendulum's.
    assert np.abs(s.energy - s.energy[0]).max() / abs(s.energy[0]) < 3e-3
