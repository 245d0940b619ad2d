"""The symplectic Gauss–Legendre methods (gauss1/2/3) on kinematic trees: the tree's "canonical" kernels
(`lagcomp.codegen.tree_canonical`: q̇ = M⁻¹ p by CRBA, ṗ = F + (∂P/∂q) q̇ by forward mode over the momenta's
recursion, their partials by forward mode) and runs.

References nobody here wrote: the same systems on the Lagrangian path (`multibody_models.lagrangian_system`: sympy
derives ṗ = ∂L/∂q + Q and its partials from the expanded T and V), Richardson-extrapolated central differences of
the tree's own kernels, the chain rule through the articulated-body algorithm (ṗ = dP/dt along f, for the ball joint
that has no Lagrangian twin), dop853 at tight tolerance, and the closed form E = const of a conservative tree.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import lagcomp as lc
from lagcomp.examples.trees import spherical_chain

PAIRS = ("rigid_double_pendulum", "universal_chain_2", "cart_pole")


def _relative(a, b) -> float:
    return float(np.max(np.abs(a - b)) / max(np.max(np.abs(b)), 1e-300))


def _draw(data, model):
    """Random parameters (0.5 to 2, by name), a state y = (q, q̇) and momenta (within ±2) for `model`."""
    values = st.floats(0.5, 2.0, allow_nan=False)
    params = {name: data.draw(values, label=name) for name in model.parameters}
    numbers = st.lists(st.floats(-2.0, 2.0, allow_nan=False), min_size=3 * model.n, max_size=3 * model.n)
    drawn = np.array(data.draw(numbers, label="y, momenta"))
    return params, drawn[:2 * model.n], drawn[2 * model.n:]


def _canonical(model, t, y, momenta, p):
    """(q̇ at x = (q, momenta), ṗ at y, the partials at y) from `model`'s canonical kernels."""
    n, k = model.n, model.kernels
    v, rate, partials = np.empty(n), np.empty(n), np.empty((4, n, n))
    assert k.velocities(t, np.concatenate([y[:n], momenta]), p, v) == 0
    k.momentum_rate(t, y, p, rate)
    k.canonical_partials(t, y, p, partials)
    return v, rate, partials


@pytest.fixture(scope="module")
def ball(cache_dir):
    """A rigid body on a ball joint (MRPs, `lc.Spherical`), unequal principal moments: no Lagrangian twin."""
    return lc.compile(spherical_chain(1), cache_dir=cache_dir)


BALL_PARAMETERS = {"m0": 1.3, "c0": 0.7, "A0": 0.4, "B0": 0.3, "C0": 0.2, "g": 9.81}


# -- the kernels ---------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("name", PAIRS)
@settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.data())
def test_canonical_kernels_agree_with_the_lagrangian_path(tree_pair, name, data):
    """q̇(q, p), ṗ(q, q̇) and the four blocks of canonical_partials of the tree against the Lagrangian twin's, to
    1e-13 relative (normwise per block); the cart-pole brings a spring, dampers and a torque in t."""
    tree_model, lagrange_model = tree_pair(name)
    params, y, momenta = _draw(data, tree_model)
    t = data.draw(st.floats(0.0, 10.0), label="t")
    ours = _canonical(tree_model, t, y, momenta, tree_model.parameter_vector(params))
    theirs = _canonical(lagrange_model, t, y, momenta, lagrange_model.parameter_vector(params))
    assert _relative(ours[0], theirs[0]) <= 1e-13
    assert _relative(ours[1], theirs[1]) <= 1e-13
    for k in range(4):
        assert _relative(ours[2][k], theirs[2][k]) <= 1e-13, k


def _extrapolated(f, x, j, h):
    """∂f/∂x_j by central differences Richardson-extrapolated twice (error O(h⁶))."""
    def central(step):
        e = np.zeros_like(x)
        e[j] = step
        return (f(x + e) - f(x - e)) / (2 * step)
    d1, d2, d4 = central(h), central(h / 2), central(h / 4)
    return (16 * ((4 * d4 - d2) / 3) - ((4 * d2 - d1) / 3)) / 15


@pytest.mark.parametrize("which", ["ball", "universal_chain_2"])
def test_canonical_partials_are_the_derivatives_of_the_kernels(tree_pair, ball, which):
    """canonical_partials against extrapolated central differences of the tree's own ``momenta`` (M = ∂P/∂q̇,
    ∂P/∂q) and ``momentum_rate`` (∂ṗ/∂q, ∂ṗ/∂q̇), to 1e-9 of each block's largest entry; the ball joint's σ near
    the shadow's edge (|σ| = 0.9), where J(σ) is far from the identity."""
    model = ball if which == "ball" else tree_pair(which)[0]
    n, k = model.n, model.kernels
    rng = np.random.default_rng(7)
    params = BALL_PARAMETERS if which == "ball" else {name: rng.uniform(0.5, 2.0) for name in model.parameters}
    p = model.parameter_vector(params)
    y = rng.uniform(-1.5, 1.5, 2 * n)
    if which == "ball":
        y[:3] *= 0.9 / np.linalg.norm(y[:3])

    def momenta(x):
        out = np.empty(n)
        k.momenta(0.3, x, p, out)
        return out

    def rate(x):
        out = np.empty(n)
        k.momentum_rate(0.3, x, p, out)
        return out

    blocks = np.empty((4, n, n))
    k.canonical_partials(0.3, y, p, blocks)
    expected = np.empty((4, n, n))
    for j in range(n):
        expected[0][:, j] = _extrapolated(momenta, y, n + j, 1e-2)
        expected[1][:, j] = _extrapolated(momenta, y, j, 1e-2)
        expected[2][:, j] = _extrapolated(rate, y, j, 1e-2)
        expected[3][:, j] = _extrapolated(rate, y, n + j, 1e-2)
    for b in range(4):
        assert _relative(blocks[b], expected[b]) <= 1e-9, b


def test_the_ball_joints_momentum_rate_is_dp_dt_along_the_motion(ball):
    """No Lagrangian twin for MRPs: ṗ = d/dt P(y(t)) = ∂P/∂y · f(y), f the articulated-body rhs (a recursion ṗ does
    not use), by an extrapolated central difference along f, to 1e-10; and q̇ = velocities(q, P(q, q̇)) to 1e-13
    (the Legendre map and its inverse, through J(σ))."""
    n, k = ball.n, ball.kernels
    p = ball.parameter_vector(BALL_PARAMETERS)
    rng = np.random.default_rng(3)
    for _ in range(5):
        y = rng.uniform(-1.0, 1.0, 2 * n)
        f, momenta, rate, v = np.empty(2 * n), np.empty(n), np.empty(n), np.empty(n)
        assert k.rhs(0.0, y, p, f) == 0

        def along(s, y=y, f=f):
            out = np.empty(n)
            k.momenta(0.0, y + s[0] * f, p, out)
            return out
        k.momentum_rate(0.0, y, p, rate)
        expected = _extrapolated(along, np.zeros(1), 0, 1e-3)
        assert _relative(rate, expected) <= 1e-10
        k.momenta(0.0, y, p, momenta)
        assert k.velocities(0.0, np.concatenate([y[:n], momenta]), p, v) == 0
        assert _relative(v, y[n:]) <= 1e-13


# -- runs -------------------------------------------------------------------------------------------------------------


@pytest.mark.parametrize(("name", "method"), [("rigid_double_pendulum", "gauss1"), ("rigid_double_pendulum", "gauss2"),
                                              ("rigid_double_pendulum", "gauss3"), ("universal_chain_2", "gauss2"),
                                              ("cart_pole", "gauss2")])
def test_gauss_on_a_tree_takes_the_twins_steps(tree_pair, name, method):
    """The same method and steps on the tree and on its Lagrangian twin: the same collocation equations, so the
    runs agree to round-off (1e-12 of the largest |q|, 400 steps); the cart-pole is driven and damped."""
    tree_model, lagrange_model = tree_pair(name)
    rng = np.random.default_rng(11)
    params = {k: rng.uniform(0.5, 2.0) for k in tree_model.parameters}
    q0, qd0 = rng.uniform(-1, 1, tree_model.n), rng.uniform(-1, 1, tree_model.n)
    ours = tree_model.simulate((0, 4), q0, qd0, params, method=method, dt=0.01)
    theirs = lagrange_model.simulate((0, 4), q0, qd0, params, method=method, dt=0.01)
    assert ours.status == theirs.status == 0
    assert np.array_equal(ours.t, theirs.t)
    assert _relative(ours.q, theirs.q) <= 1e-12
    assert _relative(ours.qd, theirs.qd) <= 1e-12


def test_gauss2_on_a_tree_converges_at_order_four_to_dop853(tree_pair):
    """The 3D universal pendulum: gauss2's error at t = 4 against dop853 at rtol = atol = 1e-13 falls 16-fold
    when the step halves (order 4: the ratio within [12, 20]), and is below 1e-8 at dt = 0.01."""
    model, _ = tree_pair("universal_chain_2")
    params = {k: 1.0 + 0.1 * i for i, k in enumerate(model.parameters)}
    q0, qd0 = [0.4, -0.3, 0.2, 0.5], [0.3, 0.1, -0.2, 0.4]
    reference = model.simulate((0, 4), q0, qd0, params, method="dop853", rtol=1e-13, atol=1e-13).q[-1]
    errors = [np.max(np.abs(model.simulate((0, 4), q0, qd0, params, method="gauss2", dt=dt).q[-1] - reference))
              for dt in (0.02, 0.01)]
    assert 12.0 <= errors[0] / errors[1] <= 20.0
    assert errors[1] <= 1e-8


def test_gauss2_keeps_a_ball_jointed_bodys_energy_without_drift(ball):
    """A conservative rigid body on a ball joint (no closed form for its motion; E = T + V is constant): 40,000
    gauss2 steps, the energy error bounded (≤ 1e-7 of |E|) and not drifting (its largest over the last tenth of the
    run within 1.5× the first tenth's): a symplectic method's
    signature."""
    q0, qd0 = [0.3, 0.1, 0.0], [0.0, 0.0, 0.0]
    run = ball.simulate((0, 400), q0, qd0, BALL_PARAMETERS, method="gauss2", dt=0.01)
    assert run.status == 0 and np.max(np.linalg.norm(run.q, axis=1)) < 0.5   # (one chart: no shadow switch due)
    error = np.abs(run.energy - run.energy[0])
    tenth = error.size // 10
    assert error.max() <= 1e-7 * abs(run.energy[0])
    assert error[-tenth:].max() <= 1.5 * error[:tenth].max()


def _rotation(sigma):
    """The rotation matrix of the MRPs σ (the same for σ and its shadow −σ/|σ|²)."""
    S = np.array([[0, -sigma[2], sigma[1]], [sigma[2], 0, -sigma[0]], [-sigma[1], sigma[0], 0]])
    s = sigma @ sigma
    return np.eye(3) + (8 * S @ S - 4 * (1 - s) * S) / (1 + s) ** 2


TUMBLING = ([0.3, 0.1, 0.0], [1.0, -0.5, 2.0])   # (a spin about the vertical: a shadow switch every ~0.7 s)


def test_gauss2_switches_a_tumbling_bodys_mrps_and_follows_dop853(ball):
    """Across the shadow switches (seven in 5 s, which dop853 locates): gauss2 switches at the first step end past
    |σ| = 1 (the collocation driver's chart switch), so every row has |σ| ≤ 1, and the body's rotation matrix at
    t = 5 (chart-free) converges to dop853's (rtol 1e-13) at order 4: its error falls at least 12-fold when the step
    halves, to below 1e-7."""
    reference = ball.simulate((0, 5), *TUMBLING, BALL_PARAMETERS, method="dop853", rtol=1e-13, atol=1e-13)
    assert reference.events["link0_shadow"].t.size >= 5
    errors = []
    for dt in (0.01, 0.005):
        run = ball.simulate((0, 5), *TUMBLING, BALL_PARAMETERS, method="gauss2", dt=dt)
        assert run.status == 0 and np.max(np.linalg.norm(run.q, axis=1)) <= 1.0
        errors.append(np.max(np.abs(_rotation(run.q[-1]) - _rotation(reference.q[-1]))))
    assert errors[0] / errors[1] >= 12.0 and errors[1] <= 1e-7


def test_across_shadow_switches_the_energy_error_grows_by_a_fifth_order_term_per_switch(ball):
    """What a chart switch costs a symplectic method: Gauss–Legendre is not covariant under the (nonlinear) shadow
    map, so each switch moves the run to another chart's modified Hamiltonian and the energy error, bounded within
    one chart (above), grows with the number of switches.  Measured: over 400 s (≈ 560 switches) it grows steadily,
    by a term that falls ≥ 16-fold (measured ~30, O(h⁵)) when the step halves, to ≤ 1e-7 of |E| at dt = 0.005; it
    is no blow-up (|σ| ≤ 1 throughout)."""
    finals = []
    for dt in (0.01, 0.005):
        run = ball.simulate((0, 400), *TUMBLING, BALL_PARAMETERS, method="gauss2", dt=dt)
        assert run.status == 0 and np.max(np.linalg.norm(run.q, axis=1)) <= 1.0
        switches = np.count_nonzero(np.einsum("ij,ij->i", run.q[1:], run.q[:-1]) < 0)   # σ' = −σ/|σ|²
        assert switches >= 400
        finals.append(np.max(np.abs(run.energy - run.energy[0])) / abs(run.energy[0]))
    assert finals[0] / finals[1] >= 16.0 and finals[1] <= 1e-7


def test_a_gauss2_sweep_switches_charts_as_a_run_does(ball):
    """The sweep loop takes the chart switches too (about 28 in 20 s): each trajectory's final state is its own
    run's, bit for bit (both carry (q, p) from call to call: tests/test_collocation_resume.py)."""
    sweep = ball.sweep((0, 20), {"m0": [1.0, 1.3]}, q0=TUMBLING[0], qd0=TUMBLING[1], params=BALL_PARAMETERS,
                       method="gauss2", dt=0.01)
    for k, mass in enumerate((1.0, 1.3)):
        run = ball.simulate((0, 20), *TUMBLING, {**BALL_PARAMETERS, "m0": mass}, method="gauss2", dt=0.01)
        assert sweep.status[k] == 0
        np.testing.assert_array_equal(sweep.final[k], run.y[-1])


# -- refusals -------------------------------------------------------------------------------------------------------


def test_gauss_refuses_a_tree_with_loops(cache_dir):
    """An arm whose tip rides a rail (a closed loop): its momenta do not determine its velocities, so the gauss
    methods refuse it as they refuse a constrained System, naming the loop's constraint and what to use."""
    arm = lc.Link("arm", lc.Revolute("th"), mass=1.0, com=(0.5, 0, 0), inertia=(0.01, 0.1, 0.1))
    tree = lc.Tree([arm], gravity=(0, -9.81, 0), name="arm_on_a_rail",
                   loops=[lc.Loop("rail", ("arm", (1, 0, 0)), (None, (0, -0.5, 0)), directions="y")])
    model = lc.compile(tree, cache_dir=cache_dir)
    for method in ("gauss1", "gauss2", "gauss3"):
        with pytest.raises(lc.OptionError, match=rf"`{method}` does not handle constraints yet; 'arm_on_a_rail' has "
                                                  r"\['rail_y'\].*radau"):
            model.simulate((0, 1), [0.0], [0.0], method=method, dt=0.01)


def test_gauss_applies_a_trees_chart_switches_only(cache_dir):
    """A chart switch is applied without locating it, which only a change of coordinates allows: a tree's own event
    with a reset (a hinge's stop) is still refused for the gauss methods by name (`resets-method`), and
    ``events=False`` runs without it."""
    (th,) = lc.coordinates("th")
    arm = lc.Link("arm", lc.Revolute(th), mass=1.0, com=(0.5, 0, 0), inertia=(0.01, 0.1, 0.1))
    stop = lc.Event("stop", th + 1, direction=-1, reset={th.diff(lc.t): -0.5 * th.diff(lc.t)})
    model = lc.compile(lc.Tree([arm], gravity=(0, -9.81, 0), name="arm_with_a_stop", events=[stop]),
                       cache_dir=cache_dir)
    with pytest.raises(lc.OptionError, match=r"Event\(s\) \['stop'\] of 'arm_with_a_stop' reset the state, which "
                                             r"`gauss2` cannot do"):
        model.simulate((0, 1), [0.0], [0.0], method="gauss2", dt=0.01)
    assert model.simulate((0, 1), [0.0], [0.0], method="gauss2", dt=0.01, events=False).status == 0
