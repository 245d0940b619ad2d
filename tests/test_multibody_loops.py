"""Closed kinematic loops in trees (`lc.Loop`): a cut joint's closure as holonomic constraints, through the public API.

The four-bar linkage as a tree (crank and coupler a chain from O, the rocker from D, the pin at B cut) against
today's four-bar example (`four_bar_linkage`, absolute angles, its constraints written by hand): the tree's
coordinates are (θ1, φ2 = θ2 − θ1, θ3), so q̈_tree = T q̈ with T the map of the coordinates, and both models'
multipliers are the force the rocker exerts on the coupler at B.  A slider-crank against the same mechanism
written as a `lc.System` with its closure by hand, and a spatial loop (a telescopic arm on a universal joint, joined
to a leg on another by a ball joint) against the Lagrangian path with Φ from sympy's rotation matrices.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
import sympy as sp
from hypothesis import given, settings
from hypothesis import strategies as st
from multibody_models import _rodrigues, lagrangian_system, planar_chain

import lagcomp as lc
from lagcomp.examples.constrained import four_bar_closure, four_bar_linkage

a, b, c, d, m1, m2, m3, g = sp.symbols("a b c d m1 m2 m3 g", positive=True)
#: The tree's coordinates (θ1, φ2, θ3) from the example's (θ1, θ2, θ3).
TO_TREE = np.array([[1.0, 0.0, 0.0], [-1.0, 1.0, 0.0], [0.0, 0.0, 1.0]])


def rod(mass, length):
    """A uniform thin rod along x of its frame, from the origin."""
    return {"mass": mass, "com": (length / 2, 0, 0), "inertia": (0, mass * length**2 / 12, mass * length**2 / 12)}


def four_bar_tree(directions="xy") -> lc.Tree:
    """`four_bar_linkage` as a tree: crank O→A (θ1), coupler A→B on it (φ2, relative), rocker D→B (θ3), B cut."""
    example = four_bar_linkage()
    return lc.Tree([
        lc.Link("crank", lc.Revolute("theta1"), **rod(m1, a)),
        lc.Link("coupler", lc.Revolute("phi2", origin=(a, 0, 0)), parent="crank", **rod(m2, b)),
        lc.Link("rocker", lc.Revolute("theta3", origin=(d, 0, 0)), **rod(m3, c)),
    ], gravity=(0, -g, 0), name="four_bar_tree", defaults=example.defaults,
        q0=TO_TREE @ example.q0, qd0=TO_TREE @ example.qd0, t_end=example.t_end,
        loops=[lc.Loop("loop", ("coupler", (b, 0, 0)), ("rocker", (c, 0, 0)), directions=directions)])


@pytest.fixture(scope="module")
def four_bars(cache_dir):
    """(the tree's model, the example's model)."""
    return lc.compile(four_bar_tree(), cache_dir=cache_dir), lc.compile(four_bar_linkage(), cache_dir=cache_dir)


def motion(model, y, gains=(0.0, 0.0), params=None, kernels=None):
    """(q̈, λ) of `model` at the state `y`, by its numba kernels or the plain-Python `kernels` (`random_systems.python_kernels`)."""
    p = model.parameter_vector(params, baumgarte=gains)
    out, lam = np.zeros(y.size), np.zeros(model.k)
    rhs_and_reactions = model.kernels.rhs_and_reactions if kernels is None else kernels["rhs_and_reactions"]
    assert rhs_and_reactions(0.0, y, p, out, lam) == 0
    return out[model.n:], lam


def relative(x, reference) -> float:
    return float(np.max(np.abs(x - reference)) / np.max(np.abs(reference)))


#: Parameters of the four-bar drawn around the example's: |AD| in [d − a, d + a] ⊂ [0.3, 0.9] stays inside
#: (|b − c|, b + c) ⊃ (0.2, 1.0), so the linkage assembles at every crank angle, away from singular positions.
FOUR_BAR_PARAMETERS = st.fixed_dictionaries({
    "a": st.floats(0.15, 0.25), "b": st.floats(0.55, 0.65), "c": st.floats(0.45, 0.55), "d": st.floats(0.55, 0.65),
    "m1": st.floats(0.2, 2.0), "m2": st.floats(0.2, 2.0), "m3": st.floats(0.2, 2.0), "g": st.floats(1.0, 20.0)})


@settings(max_examples=40, deadline=None)
@given(theta1=st.floats(0.0, 2 * math.pi), rate=st.floats(-20.0, 20.0), off=st.tuples(*[st.floats(-0.05, 0.05)] * 2),
       rates=st.tuples(*[st.floats(-3.0, 3.0)] * 2), gains=st.tuples(*[st.floats(0.0, 5.0)] * 2),
       params=FOUR_BAR_PARAMETERS)
def test_four_bar_tree_matches_the_example(four_bars, theta1, rate, off, rates, gains, params):
    """q̈ and λ agree to 1e-12 relative, on the loop and off it (Φ ≠ 0, Λ q̇ ≠ 0, with Baumgarte terms): Φ, Λ and
    γ of the tree's kinematics are the example's functions in other coordinates."""
    tree, example = four_bars
    q, qd = (np.array(v) for v in four_bar_closure(params, theta1, rate))
    q[1:] += off
    qd[1:] += rates
    qdd_tree, lam_tree = motion(tree, np.concatenate([TO_TREE @ q, TO_TREE @ qd]), gains, params)
    qdd, lam = motion(example, np.concatenate([q, qd]), gains, params)
    assert relative(qdd_tree, TO_TREE @ qdd) <= 1e-12
    assert relative(lam_tree, lam) <= 1e-12


def test_four_bar_tree_runs_as_the_example(four_bars):
    """A 5 s run (the crank turns about 10 times): the trajectories agree, so do the reactions; projection keeps
    the loop closed at rounding level and the energy is conserved."""
    tree, example = four_bars
    ts = np.linspace(0.0, 5.0, 101)
    options = {"t_eval": ts, "method": "dop853", "rtol": 1e-12, "atol": 1e-12, "projection": True,
               "max_residual": 1e-12}
    run_tree, run = tree.simulate((0.0, 5.0), **options), example.simulate((0.0, 5.0), **options)
    assert run_tree.success and run.success
    assert tree.constraints == example.constraints == ("loop_x", "loop_y")
    assert np.max(np.abs(run_tree.q - run.q @ TO_TREE.T)) <= 1e-9
    assert np.max(np.abs(run_tree.qd - run.qd @ TO_TREE.T)) <= 1e-8
    for name in ("loop_x", "loop_y"):
        assert relative(run_tree.reactions[name], run.reactions[name]) <= 1e-8
    assert run_tree.constraint_residual <= 1e-12
    assert run_tree.energy_drift() <= 1e-11
    assert run.q[-1, 0] > 20 * math.pi / 2   # (the crank went round: the run is not a trivial one)


def test_a_start_off_the_loop_is_projected_onto_it(four_bars):
    """q0, q̇0 off the loop (by 0.02 rad and 0.1 rad/s) with ``project_initial=True``: the first saved state
    closes the loop at rounding level (Φ and Λ q̇, from the model's own `constraint_residuals`)."""
    tree, _ = four_bars
    q0, qd0 = np.array(tree.q0) + [0.0, 0.02, -0.03], np.array(tree.qd0) + [0.0, 0.1, 0.0]
    sol = tree.simulate((0.0, 0.5), q0=q0, qd0=qd0, project_initial=True, projection=True, rtol=1e-11, atol=1e-11)
    assert sol.success, sol.message
    residuals = np.zeros(4)
    tree.kernels.constraint_residuals(0.0, sol.y[0], tree.parameter_vector(), residuals)
    assert np.max(np.abs(residuals)) <= 1e-14
    assert np.max(np.abs(sol.y[0] - np.concatenate([q0, qd0]))) >= 1e-3   # (it was off: projection moved it)


def test_directions_as_vectors_rotate_the_reactions(four_bars, cache_dir):
    """The pin closed along (1, 1, 0) and (1, −1, 0) instead of x and y: the same motion, and the multipliers are
    the same pin force's components along the (normalised) directions, named by position."""
    tree, _ = four_bars
    turned = lc.compile(four_bar_tree(((1, 1, 0), (1, -1, 0))), cache_dir=cache_dir)
    assert turned.constraints == ("loop_0", "loop_1")
    y = tree.initial_state() + np.array([0.0, 0.01, -0.02, 0.0, 0.3, -0.1])   # (off the loop: Φ and Λ q̇ too)
    qdd, lam = motion(tree, y, (1.0, 2.0))
    qdd_turned, lam_turned = motion(turned, y, (1.0, 2.0))
    assert relative(qdd_turned, qdd) <= 1e-13
    expected = np.array([lam[0] + lam[1], lam[0] - lam[1]]) / math.sqrt(2)
    assert relative(lam_turned, expected) <= 1e-13


def test_four_bar_tree_reaction_is_the_pin_force(four_bars):
    """λ is the force the rocker exerts on the coupler at B: the rocker's own Newton–Euler equation about D
    (its angular momentum balance, the pin force −λ at B, gravity at its centre) holds with the tree's θ̈3."""
    tree, _ = four_bars
    y = tree.initial_state()
    qdd, lam = motion(tree, y)
    p = tree.defaults
    th3 = y[2]
    e3 = np.array([math.cos(th3), math.sin(th3)])
    moment_of_pin = p["c"] * (e3[0] * -lam[1] - e3[1] * -lam[0])            # (c e3) × (−λ)
    moment_of_gravity = p["c"] / 2 * e3[0] * -p["m3"] * p["g"]               # (c/2 e3) × (0, −m3 g)
    assert p["m3"] * p["c"] ** 2 / 3 * qdd[2] == pytest.approx(moment_of_pin + moment_of_gravity, rel=1e-13)


# -- a slider-crank against the same mechanism by hand ---------------------------------------------------------------

r, l, M, m, J = sp.symbols("r l M m J", positive=True)


def slider_crank_tree() -> lc.Tree:
    """Crank (θ, uniform rod of length r) and connecting rod (φ relative to the crank, length l, mass m, inertia J
    about its centre) from O; the slider (mass M) on a rail along x from O (s); the pin between rod and slider cut."""
    return lc.Tree([
        lc.Link("crank", lc.Revolute("theta", torque=0.3), **rod(m, r)),
        lc.Link("rod", lc.Revolute("phi", origin=(r, 0, 0)), parent="crank", mass=m, com=(l / 2, 0, 0),
                inertia=(J, J, J)),
        lc.Link("slider", lc.Prismatic("s", axis="x", damping=0.2), mass=M),
    ], gravity=(0, -g, 0), name="slider_crank_tree",
        defaults={"r": 0.1, "l": 0.35, "M": 0.7, "m": 0.4, "J": 0.005, "g": 9.81},
        loops=[lc.Loop("pin", ("rod", (l, 0, 0)), ("slider", (0, 0, 0)), directions="xy")])


def slider_crank_system() -> lc.System:
    """The same mechanism, written by hand: the rod at angle θ + φ, its end at (r cos θ + l cos(θ + φ), ...)."""
    theta, phi, s = lc.coordinates("theta phi s")
    w, u = theta.diff(lc.t), (theta + phi).diff(lc.t)
    crank = m * r**2 / 3 * w**2 / 2
    G = (r * sp.cos(theta) + l / 2 * sp.cos(theta + phi), r * sp.sin(theta) + l / 2 * sp.sin(theta + phi))
    rod_ = m * (G[0].diff(lc.t) ** 2 + G[1].diff(lc.t) ** 2) / 2 + J * u**2 / 2
    T = crank + rod_ + M * s.diff(lc.t) ** 2 / 2
    V = g * (m * r * sp.sin(theta) / 2 + m * G[1])
    end = (r * sp.cos(theta) + l * sp.cos(theta + phi), r * sp.sin(theta) + l * sp.sin(theta + phi))
    return lc.System([theta, phi, s], T=T, V=V, forces={theta: 0.3, s: -0.2 * s.diff(lc.t)},
                     constraints=[lc.Holonomic("pin_x", end[0] - s), lc.Holonomic("pin_y", end[1])],
                     name="slider_crank_by_hand", defaults=slider_crank_tree().defaults)


def test_slider_crank_matches_the_hand_written_system(cache_dir):
    tree = lc.compile(slider_crank_tree(), cache_dir=cache_dir)
    system = lc.compile(slider_crank_system(), cache_dir=cache_dir)
    rng = np.random.default_rng(4)
    for _ in range(20):
        y = np.concatenate([rng.uniform(-math.pi, math.pi, 2), rng.uniform(0.2, 0.4, 1), rng.uniform(-3, 3, 3)])
        gains = tuple(rng.uniform(0, 4, 2))
        qdd_tree, lam_tree = motion(tree, y, gains)
        qdd, lam = motion(system, y, gains)
        assert relative(qdd_tree, qdd) <= 1e-12
        assert relative(lam_tree, lam) <= 1e-12


def test_slider_crank_stays_closed_and_conserves_energy(cache_dir):
    """Without its torque and damper (a conservative run): the pin stays closed and T + V stays."""
    tree = slider_crank_tree()
    free = lc.Tree(
        [dataclasses.replace(link, joint=dataclasses.replace(link.joint, torque=0, damping=0)) for link in tree.links],
        gravity=tree.gravity, name="slider_crank_free", defaults=tree.defaults,
        loops=[lc.Loop("pin", ("rod", (l, 0, 0)), ("slider", (0, 0, 0)), directions="xy")])
    model = lc.compile(free, cache_dir=cache_dir)
    theta, rate = 0.3, 15.0
    p = free.defaults
    y_end = p["r"] * math.sin(theta)
    phi = -math.asin(y_end / p["l"]) - theta
    s = p["r"] * math.cos(theta) + p["l"] * math.cos(theta + phi)
    # velocities on the loop: rod angle ψ = θ + φ with r cos θ θ̇ + l cos ψ ψ̇ = 0, ṡ = −r sin θ θ̇ − l sin ψ ψ̇
    psi = theta + phi
    psi_dot = -p["r"] * math.cos(theta) * rate / (p["l"] * math.cos(psi))
    qd0 = [rate, psi_dot - rate, -p["r"] * math.sin(theta) * rate - p["l"] * math.sin(psi) * psi_dot]
    sol = model.simulate((0.0, 3.0), q0=[theta, phi, s], qd0=qd0, method="dop853", rtol=1e-11, atol=1e-11,
                         projection=True, max_residual=1e-12)
    assert sol.success, sol.message
    assert sol.constraint_residual <= 1e-12
    assert sol.energy_drift() <= 1e-10
    assert np.ptp(sol.q[:, 2]) == pytest.approx(2 * p["r"], rel=1e-3)   # the slider's stroke: twice the crank


# -- a spatial loop against the Lagrangian path ------------------------------------------------------------------

def spatial_tree() -> lc.Tree:
    """An arm on a universal joint at O with a telescopic slide along it (a prismatic joint on a turning link:
    Coriolis terms), and a leg on a universal joint at (D, 0, 0), their ends joined by a ball joint (xyz)."""
    mA, mS, mL, cA, cL, D, L, IA, IB, IC, K = sp.symbols("mA mS mL cA cL D L IA IB IC K", positive=True)
    return lc.Tree([
        lc.Link("arm", lc.Universal(("a1", "b1")), mass=mA, com=(0, 0, -cA), inertia=(IA, IB, IC)),
        lc.Link("slide", lc.Prismatic("s", axis="z", stiffness=K), parent="arm", mass=mS, com=(0.1, 0, 0),
                inertia=(IB, IA, IC)),
        lc.Link("leg", lc.Universal(("a2", "b2"), origin=(D, 0, 0)), mass=mL, com=(0, 0, -cL), inertia=(IC, IB, IA)),
    ], gravity=(0, 0, -g), name="spatial_loop",
        defaults={"mA": 1.0, "mS": 0.5, "mL": 0.8, "cA": 0.3, "cL": 0.4, "D": 0.5, "L": 0.8, "IA": 0.02, "IB": 0.03,
                  "IC": 0.01, "K": 20.0, "g": 9.81},
        loops=[lc.Loop("ball", ("slide", (0, 0, -L)), ("leg", (0.2, 0.1, -0.7)))])


def _position(tree: lc.Tree, link: str, point) -> sp.Matrix:
    """A point fixed in `link` in base axes, by sympy: R = R_parent R(axis, q), origin + q·axis for a slider."""
    R, o = {-1: sp.eye(3)}, {-1: sp.zeros(3, 1)}
    for i, node in enumerate(tree.nodes):
        j = node.joint
        Rp, op = R[node.parent], o[node.parent]
        if j.kind == "revolute":
            R[i], o[i] = Rp * _rodrigues(j.axis, j.coordinate), op + Rp * sp.Matrix(j.origin)
        else:
            R[i], o[i] = Rp, op + Rp * (sp.Matrix(j.origin) + j.coordinate * sp.Matrix(j.axis))
    last = max(i for i, node in enumerate(tree.nodes) if node.link == link)
    return o[last] + R[last] * sp.Matrix(point)


def lagrangian_with_loops(tree: lc.Tree) -> lc.System:
    """`tree` on the Lagrangian path (`multibody_models.lagrangian_system`) with its loops' constraints written
    from sympy's rotation matrices: d·(P_first − P_second) = 0 for each direction d."""
    constraints = []
    for closure in tree.closures:
        gap = _position(tree, closure.first, closure.first_point) - (
            sp.Matrix(closure.second_point) if closure.second is None
            else _position(tree, closure.second, closure.second_point))
        constraints += [lc.Holonomic(name, (sp.Matrix(d).T * gap)[0]) for d, name in zip(closure.directions,
                                                                                           closure.names)]
    return dataclasses.replace(lagrangian_system(tree), constraints=tuple(constraints), parameters=tree.parameters)


def agree_with_the_lagrangian_path(tree: lc.Tree, cache_dir, states, seed: int) -> None:
    """q̈ and λ of `tree` and of `lagrangian_with_loops(tree)` agree to 1e-12 relative at the states `states()`
    draws (numpy Generator → y), random Baumgarte gains and parameters (±50 % about the defaults)."""
    tree_model = lc.compile(tree, cache_dir=cache_dir)
    lagrange = lc.compile(lagrangian_with_loops(tree), cache_dir=cache_dir)
    assert tree_model.constraints == lagrange.constraints
    rng = np.random.default_rng(seed)
    for _ in range(20):
        y, gains = states(rng), tuple(rng.uniform(0, 4, 2))
        params = {name: value * rng.uniform(0.5, 1.5) for name, value in tree.defaults.items()}
        qdd_tree, lam_tree = motion(tree_model, y, gains, params)
        qdd, lam = motion(lagrange, y, gains, params)
        assert relative(qdd_tree, qdd) <= 1e-12
        assert relative(lam_tree, lam) <= 1e-12


def test_spatial_loop_matches_the_lagrangian_path(cache_dir):
    agree_with_the_lagrangian_path(
        spatial_tree(), cache_dir, lambda rng: np.concatenate([rng.uniform(-1, 1, 2), rng.uniform(-0.3, 0.3, 1),
                                                               rng.uniform(-1, 1, 2), rng.uniform(-2, 2, 5)]), 7)


def test_a_loop_within_one_branch_matches_the_lagrangian_path(cache_dir):
    """A planar chain of four links whose last tip is pinned back to the first link's middle: the two ends share
    the first joint (its columns of Λ cancel in part), and a second loop holds the third joint on a rail y = h
    of the base."""
    chain = planar_chain(4)
    l0, l1, l3, h = sp.symbols("l0 l1 l3 h")
    values = {"g": 9.81, "h": 0.2, "l0": 1.0, "l1": 0.8, "l2": 0.9, "l3": 0.7}
    for i in range(4):
        values.update({f"m{i}": 1.0 + i / 4, f"c{i}": 0.4, f"d{i}": 0.05 * i, f"J{i}": 0.1})
    tree = lc.Tree(chain.links, gravity=chain.gravity, name="pinned_chain", defaults=values, loops=[
        lc.Loop("back", ("link3", (l3, 0, 0)), ("link0", (l0 / 2, 0, 0)), directions="xy"),
        lc.Loop("rail", ("link1", (l1, 0, 0)), (None, (0, h, 0)), directions="y")])
    agree_with_the_lagrangian_path(
        tree, cache_dir, lambda rng: np.concatenate([rng.uniform(-math.pi, math.pi, 4), rng.uniform(-2, 2, 4)]), 11)


# -- what is refused --------------------------------------------------------------------------------------------

def test_a_direction_the_tree_cannot_open_is_refused(cache_dir):
    """z of the planar four-bar: its row of Λ is identically zero, the augmented matrix singular everywhere."""
    with pytest.raises(lc.ModelError, match="'loop_z'.*identically zero"):
        lc.compile(four_bar_tree("xyz"), cache_dir=cache_dir)


@pytest.mark.parametrize(("loop", "culprit"), [
    (lc.Loop("pin", ("coupler", (1, 0, 0)), ("rocker_", (0, 0, 0))), "'rocker_', which is not a link"),
    (lc.Loop("pin", (None, (1, 0, 0)), ("rocker", (0, 0, 0))), "`first` must name a link"),
    (lc.Loop("pin", ("rocker", (1, 0, 0)), ("rocker", (0, 0, 0))), "joins link 'rocker' to itself"),
    (lc.Loop("pin", ("coupler", (1, 0, 0)), ("rocker", (0, 0, 0)), directions="xx"), "not independent"),
    (lc.Loop("pin", ("coupler", (1, 0, 0)), ("rocker", (0, 0, 0)), directions=("x", (1, 1, 0), (0, 1, 0))),
     "not independent"),
    (lc.Loop("pin", ("coupler", (1, 0)), ("rocker", (0, 0, 0))), "three expressions"),
    (lc.Loop("pin", "coupler", ("rocker", (0, 0, 0))), "pair (link name"),
    (lc.Loop("pin", ("coupler", (1, 0, 0)), ("rocker", (0, 0, 0)), directions=""), "one to three"),
    (lc.Loop("pin", ("coupler", (1, 0, 0)), ("rocker", (0, 0, lc.t))), "depends on t"),
])
def test_bad_loops_are_refused(loop, culprit):
    links = four_bar_tree().links
    with pytest.raises(lc.ModelError) as error:
        lc.Tree(links, loops=[loop])
    assert culprit in str(error.value)


def test_two_loops_of_one_name_are_refused():
    links = four_bar_tree().links
    loop = lc.Loop("pin", ("coupler", (1, 0, 0)), ("rocker", (0, 0, 0)), directions="x")
    with pytest.raises(lc.ModelError, match="taken by another loop"):
        lc.Tree(links, loops=[loop, dataclasses.replace(loop, directions="y")])


def test_a_loop_to_the_base_closes_a_slider_on_its_rail(cache_dir):
    """A uniform rod hinged at O, its tip held in a rail along x at height −h (a loop to the base, direction y):
    the rod is locked at l sin θ = −h, so q̈ = 0 at rest, and the rail carries half its weight: from
    M θ̈ = −m g (l/2) cos θ + λ l cos θ, λ = m g / 2 (upward, the base's force on the rod)."""
    h = sp.Symbol("h", positive=True)
    tree = lc.Tree([lc.Link("rod", lc.Revolute("theta"), **rod(m, l))], gravity=(0, -g, 0), name="railed_rod",
                   defaults={"m": 2.0, "l": 1.0, "g": 9.81, "h": 0.6},
                   loops=[lc.Loop("rail", ("rod", (l, 0, 0)), (None, (0, -h, 0)), directions="y")])
    model = lc.compile(tree, cache_dir=cache_dir)
    theta = -math.asin(0.6)
    qdd, lam = motion(model, np.array([theta, 0.0]))
    assert qdd[0] == pytest.approx(0.0, abs=1e-14)
    assert lam[0] == pytest.approx(2.0 * 9.81 / 2, rel=1e-14)
