"""Batched sweeps of kinematic trees (``sweep(..., batched=True)``, issue 39): the lane kernel ``rhs_lanes`` of a tree
is its articulated-body ``rhs`` evaluated per lane (`lagcomp.codegen.tree_lanes`), so a batched sweep gives bitwise
the unbatched sweep's trajectories, as a System's does (tests/test_sweep.py), and agrees with the same system on the
Lagrangian path (`multibody_models.lagrangian_system`: derived from T and V by sympy, no code shared with the
recursion) to rounding.  A tree whose motion is more than that ``rhs`` (closed loops) and a ball joint's shadow
switches (events that reset the state) are refused by name.
"""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import lagcomp as lc
from lagcomp.examples.trees import spherical_chain
from lagcomp.integrate.drivers.lanes import DOP853_LANES, RK4_LANES

#: What a sweep returns per trajectory; all of it must be the unbatched sweep's, bit for bit.
KEYS = ("final", "t_final", "status", "nfev", "nsteps", "nrejected", "energy_error")
RK4 = dict(method="rk4", dt=0.01, output="energy", save_every=10)
DOP853 = dict(rtol=1e-10, atol=1e-10, output="energy")


def _params(model, seed: int) -> dict:
    rng = np.random.default_rng(seed)
    return {name: rng.uniform(0.5, 2.0) for name in model.parameters}


def _same(lanes, scalar, keys=KEYS) -> None:
    for key in keys:
        np.testing.assert_array_equal(getattr(lanes, key), getattr(scalar, key), err_msg=key)


@pytest.fixture(scope="module")
def ball_chain(cache_dir):
    """Two links on ball joints (six MRPs), compiled once."""
    return lc.compile(spherical_chain(2), cache_dir=cache_dir)


@pytest.mark.parametrize("name", ["planar_chain_4", "universal_chain_2", "cart_pole"])
@pytest.mark.parametrize("options", [RK4, DOP853], ids=["rk4", "dop853"])
def test_a_batched_tree_sweep_is_the_unbatched_sweep_bitwise(tree_pair, name, options):
    """A grid over the first coordinate and a parameter (each lane its own P column), more trajectories than one block
    of lanes (a full block and a partial one); the cart-pole's joint torque reads t (each lane its own time) and its
    dampers make the energy output the energy balance's."""
    model, _ = tree_pair(name)
    rng = np.random.default_rng(7)
    q0, qd0 = rng.uniform(-1.0, 1.0, model.n), rng.uniform(-1.0, 1.0, model.n)
    parameter = model.parameters[0]
    count = (RK4_LANES if options is RK4 else DOP853_LANES) // 10 + 1
    grid = {model.coordinates[0]: np.linspace(-1.0, 1.0, count), parameter: [0.7, 1.3]}
    run = dict(params=_params(model, 1), q0=q0, qd0=qd0, workers=1, **options)
    scalar = model.sweep((0.0, 2.0), grid, **run)
    lanes = model.sweep((0.0, 2.0), grid, batched=True, **run)
    assert np.all(scalar.status == 0) and np.all(scalar.t_final == 2.0)
    _same(lanes, scalar)


def test_the_batched_sweep_keeps_its_dense_rows_bitwise(tree_pair):
    """RK4's saved rows (the only dense output of the lanes) are the unbatched sweep's."""
    model, _ = tree_pair("planar_chain_4")
    grid = {"th1": np.linspace(-0.5, 0.5, 9)}
    run = dict(params=_params(model, 2), q0=[0.3, -0.2, 0.1, 0.4], qd0=[0.0, 0.5, -0.5, 0.0], method="rk4",
               dt=0.01, output="dense", save_every=25)
    scalar = model.sweep((0.0, 1.0), grid, **run)
    lanes = model.sweep((0.0, 1.0), grid, batched=True, **run)
    assert lanes.dense.shape == (9, 5, 8)
    np.testing.assert_array_equal(lanes.dense, scalar.dense)


@pytest.mark.parametrize("options", [RK4, DOP853], ids=["rk4", "dop853"])
def test_a_batched_ball_chain_sweep_is_the_unbatched_sweep_bitwise(ball_chain, options):
    """Six MRPs, rational kinematics, no trigonometry; without the shadow switches (``events=False`` in both: a
    batched sweep applies no reset), which the motion here (well under half a turn) never reaches."""
    rng = np.random.default_rng(3)
    grid = {"s0x": np.linspace(-0.2, 0.2, 5), "s1y": np.linspace(-0.2, 0.2, 5)}
    run = dict(params=_params(ball_chain, 3), q0=rng.uniform(-0.2, 0.2, 6), qd0=rng.uniform(-0.5, 0.5, 6),
               events=False, workers=1, **options)
    scalar = ball_chain.sweep((0.0, 1.0), grid, **run)
    lanes = ball_chain.sweep((0.0, 1.0), grid, batched=True, **run)
    assert np.all(scalar.status == 0) and np.max(np.abs(scalar.final[..., :6])) < 1.0
    _same(lanes, scalar)
    if options is DOP853:    # (a conservative chain: the run keeps its energy to its tolerance)
        assert np.max(np.abs(lanes.energy_error)) < 1e-9


@settings(max_examples=8, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(seed=st.integers(0, 2**32 - 1), count=st.integers(1, RK4_LANES + 3),
       method=st.sampled_from(["rk4", "dop853"]))
def test_any_initial_states_in_any_number_of_lanes_give_the_unbatched_bits(tree_pair, seed, count, method):
    """Random initial states (an explicit grid over all of y) and parameters, any number of trajectories (blocks full,
    partial or one lane) on the rigid double pendulum as a tree."""
    model, _ = tree_pair("rigid_double_pendulum")
    rng = np.random.default_rng(seed)
    states = rng.uniform(-2.0, 2.0, (count, 2 * model.n))
    options = RK4 if method == "rk4" else DOP853
    run = dict(names=model.state_names, params=_params(model, seed % 1000), workers=1, **options)
    scalar = model.sweep((0.0, 0.5), states, **run)
    lanes = model.sweep((0.0, 0.5), states, batched=True, **run)
    _same(lanes, scalar)


@pytest.mark.parametrize("name", ["planar_chain_4", "universal_chain_2", "cart_pole"])
def test_the_batched_tree_sweep_agrees_with_the_lagrangian_path(tree_pair, name):
    """The same grid on the model derived from T and V (its own lanes): both are RK4 with the same steps on the same
    equations, so the final states differ by the rounding of two formulations of q̈ carried over 200 steps: measured
    1.5e-16 to 4.0e-16 relative to the largest component on these states.  1e-13 is far above that rounding and far
    below RK4's own error here (the change from dt = 0.005 to 0.0025: 2e-11 to 1.7e-10), which a wrong q̈ in some
    lane would show as."""
    tree_model, lagrange_model = tree_pair(name)
    rng = np.random.default_rng(11)
    run = dict(params=_params(tree_model, 4), q0=rng.uniform(-1.0, 1.0, tree_model.n),
               qd0=rng.uniform(-1.0, 1.0, tree_model.n), method="rk4", dt=0.005, batched=True, workers=1)
    grid = {tree_model.coordinates[-1]: np.linspace(-1.0, 1.0, 13)}
    tree = tree_model.sweep((0.0, 1.0), grid, **run)
    lagrange = lagrange_model.sweep((0.0, 1.0), grid, **run)
    assert tree_model.state_names == lagrange_model.state_names
    assert np.max(np.abs(tree.final - lagrange.final)) <= 1e-13 * np.max(np.abs(lagrange.final))


def test_a_ball_chain_sweep_names_its_shadow_switches(ball_chain):
    """dop853 applies the shadow switches by default: a batched sweep, which cannot reset, names them and says what
    ``events=False`` means for them."""
    with pytest.raises(lc.OptionError, match=r"\['link0_shadow', 'link1_shadow'\].*shadow switches.*full turn"):
        ball_chain.sweep((0.0, 1.0), {"s0x": [0.1, 0.2]}, params=_params(ball_chain, 5), q0=[0.0] * 6,
                         qd0=[0.0] * 6, batched=True)


def test_a_tree_with_a_loop_has_no_lanes_and_says_why(cache_dir):
    """A closed loop moves by an augmented solve, not by the articulated-body rhs: the tree's kind "lanes" is empty (so
    `Model.operations` and ``lagcomp precompile --all`` build it as any kind) and a batched sweep names the loop.  Two
    rods hinged about z at (0, 0) and (1, 0), their ends held at one x (a one-degree-of-freedom mechanism)."""
    m, l = sp.symbols("m l", positive=True)
    rod = {"mass": m, "com": (l / 2, 0, 0), "inertia": (0, m * l**2 / 12, m * l**2 / 12)}
    tree = lc.Tree([lc.Link("left", lc.Revolute("q1"), **rod), lc.Link("right", lc.Revolute("q2", origin=(1, 0, 0)),
                                                                          **rod)],
                   name="lanes_loop", defaults={"m": 1.0, "l": 1.0},
                   loops=[lc.Loop("pin", ("left", (l, 0, 0)), ("right", (l, 0, 0)), directions="x")])
    model = lc.compile(tree, cache_dir=cache_dir)
    assert model.on_demand_entry("lanes").path.exists() and not hasattr(model.kernels, "rhs_lanes")   # (empty kind)
    with pytest.raises(lc.ModelError, match=r"`rhs_lanes`.*'lanes_loop'.*closed loops \['pin'\].*`batched`"):
        model.sweep((0.0, 0.1), {"m": [1.0, 2.0]}, q0=[np.pi / 3, 2 * np.pi / 3], qd0=[0.0, 0.0], method="rk4",
                    dt=0.01, batched=True)
