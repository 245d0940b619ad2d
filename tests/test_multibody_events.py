"""Events and contacts on kinematic trees (``lc.Tree(..., events=)``, issue 39).

References: the Lagrangian path (the same systems written with lc.RigidBody and lc.rotated,
`multibody_models.lagrangian_system`: derived from T and V by sympy, sharing no code with the recursions), closed
forms derived here (a uniformly turning link's crossing times, a torque-free isotropic ball's half turns, a free
rod's impact on a floor), and Newton's restitution's energy balance.
"""

from __future__ import annotations

import math
import pickle
from dataclasses import replace

import multibody_models as mm
import numpy as np
import pytest
import sympy as sp
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from test_contact_friction import check_breakaway
from test_resting_contacts import check_ladder_leaves_the_wall

import lagcomp as lc
from lagcomp.examples.constrained import four_bar_linkage
from lagcomp.multibody import link_point, mrp

t = lc.t
DOUBLE = {"m0": 1.3, "m1": 0.8, "c0": 0.45, "c1": 0.35, "d0": 0.02, "d1": -0.03, "J0": 0.07, "J1": 0.04,
          "l0": 0.9, "l1": 0.7, "g": 9.81}


def _double_pendulum(name: str, events) -> lc.Tree:
    """The planar double pendulum of `multibody_models.planar_chain(2)` with `events` (a function of the links)."""
    links = mm.planar_chain(2).links
    return lc.Tree(links, gravity=(0, -sp.Symbol("g", positive=True), 0), name=name, events=events(links),
                   defaults=DOUBLE)


def _pair(tree: lc.Tree, cache_dir):
    """(the tree's model, the Lagrangian path's model of the same system with the same events)."""
    system = replace(mm.lagrangian_system(tree), events=tree.user_events, defaults=tree.defaults,
                     parameters=None)
    return lc.compile(tree, cache_dir=cache_dir), lc.compile(system, cache_dir=cache_dir)


def _watched(links):
    """The tip's height crossing −1 m (both ways), the first link passing the vertical upwards with a kick (the
    second joint's rate reversed and halved), and a stop at t = 2.9 s."""
    th0, th1 = lc.coordinates("th0 th1")
    tip = link_point(links, "link1", (sp.Symbol("l1"), 0, 0))
    return [lc.Event("tip_low", tip[1] + 1, direction=0),
            lc.Event("kick", th0 + sp.pi / 2, direction=1, reset={th1.diff(t): -th1.diff(t) / 2}),
            lc.Event("stop", t - 2.9, direction=1, terminal=True)]


@pytest.fixture(scope="module")
def watched(cache_dir):
    return _pair(_double_pendulum("tree_watched", _watched), cache_dir)


def test_link_point_is_the_tip_of_the_chain():
    th0, th1 = lc.coordinates("th0 th1")
    l0, l1 = sp.symbols("l0 l1")
    tip = link_point(mm.planar_chain(2).links, "link1", (l1, 0, 0))
    expected = [l0 * sp.cos(th0) + l1 * sp.cos(th0 + th1), l0 * sp.sin(th0) + l1 * sp.sin(th0 + th1), 0]
    assert [sp.simplify(sp.expand_trig(a - b)) for a, b in zip(tip, expected)] == [0, 0, 0]


def _state(data, n=2, scale=1.0):
    return np.array([data.draw(st.floats(-3.0, 3.0)) * scale for _ in range(2 * n)])


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.data())
def test_event_kernels_agree_with_the_lagrangian_path(watched, data):
    tree, lagrange = watched
    y, time = _state(data), data.draw(st.floats(0.0, 5.0))
    p_tree, p_lagrange = tree.parameter_vector(), lagrange.parameter_vector()
    assert tree.parameters == lagrange.parameters and tree.event_names == lagrange.event_names
    g_tree, g_lagrange = np.empty(3), np.empty(3)
    tree.kernels.event_values(time, y, p_tree, g_tree)
    lagrange.kernels.event_values(time, y, p_lagrange, g_lagrange)
    np.testing.assert_allclose(g_tree, g_lagrange, rtol=1e-13, atol=1e-13)
    width = 4 + 1 + len(tree.parameters)
    d_tree, d_lagrange = np.empty((3, width)), np.empty((3, width))
    tree.kernels.event_gradients(time, y, p_tree, d_tree)
    lagrange.kernels.event_gradients(time, y, p_lagrange, d_lagrange)
    np.testing.assert_allclose(d_tree, d_lagrange, rtol=1e-13, atol=1e-13)
    for e, after in enumerate(([*y], [*y[:3], -y[3] / 2], [*y])):
        out_tree, out_lagrange = np.empty(4), np.empty(4)
        if e < 2:   # (a terminal event has no reset: the drivers never call it)
            assert tree.kernels.event_reset(time, y, p_tree, e, out_tree) == 0
            assert lagrange.kernels.event_reset(time, y, p_lagrange, e, out_lagrange) == 0
            np.testing.assert_array_equal(out_tree, after)
            np.testing.assert_array_equal(out_lagrange, after)


def test_event_times_agree_with_the_lagrangian_path(watched):
    a, b = (model.simulate((0.0, 10.0), q0=[-0.3, 0.8], qd0=[1.5, -2.0], rtol=1e-12, atol=1e-12)
            for model in watched)
    assert a.t[-1] == pytest.approx(2.9, abs=1e-12) and b.t[-1] == pytest.approx(2.9, abs=1e-12)
    assert len(a.events["tip_low"].t) >= 2 and len(a.events["kick"].t) >= 1
    for name in ("tip_low", "kick", "stop"):
        np.testing.assert_allclose(a.events[name].t, b.events[name].t, rtol=0, atol=1e-9)
        np.testing.assert_allclose(a.events[name].qd_after, b.events[name].qd_after, rtol=0, atol=1e-8)
    kick = a.events["kick"]
    np.testing.assert_allclose(kick.qd_after[:, 1], -kick.qd[:, 1] / 2, rtol=1e-15)


# -- a ball joint's shadow switches beside the user's events: the event indices -----------------------------------


@pytest.fixture(scope="module")
def spinner(cache_dir):
    """Two roots, no gravity: an isotropic ball on a spherical joint (torque-free: constant ω, half turns at
    |ω| t = π + 2πk) and a link on a revolute joint turning at a constant rate (a mark at angle a, where its rate is
    reversed: once)."""
    a = sp.Symbol("a")
    th, = lc.coordinates("th")
    links = [lc.Link("ball", lc.Spherical(("s1", "s2", "s3")), mass=2.0, inertia=(0.3, 0.3, 0.3)),
             lc.Link("arm", lc.Revolute(th, axis="z"), mass=1.0, com=(0.5, 0, 0), inertia=(0.1, 0.1, 0.1))]
    tree = lc.Tree(links, name="tree_spinner", defaults={"a": 2.0},
                   events=[lc.Event("mark", th - a, direction=1, reset={th.diff(t): -th.diff(t)})])
    return lc.compile(tree, cache_dir=cache_dir)


def test_the_shadow_switches_come_first_and_the_users_events_keep_their_resets(spinner):
    model = spinner
    assert model.event_names == ("ball_shadow", "mark")
    w, rate = np.array([0.4, -1.1, 0.7]), 0.8          # rad/s: the ball's ω (body = world, isotropic), the arm's
    sol = model.simulate((0.0, 20.0), q0=[0.0, 0.0, 0.0, 0.0], qd0=[*mrp.mrp_rate([0.0, 0.0, 0.0], w), rate],
                         rtol=1e-12, atol=1e-12)
    speed = np.linalg.norm(w)
    switches = sol.events["ball_shadow"].t
    expected = (math.pi + 2 * math.pi * np.arange(len(switches))) / speed
    assert len(switches) == int((20.0 * speed - math.pi) // (2 * math.pi)) + 1
    np.testing.assert_allclose(switches, expected, rtol=0, atol=1e-9)
    mark = sol.events["mark"]
    np.testing.assert_allclose(mark.t, [2.0 / rate], rtol=0, atol=1e-10)
    np.testing.assert_allclose(mark.qd_after[:, 3], [-rate], rtol=1e-13)
    shadow = sol.events["ball_shadow"]      # the arm's rate is the mark's business only
    np.testing.assert_array_equal(shadow.qd[:, 3], shadow.qd_after[:, 3])
    np.testing.assert_allclose(shadow.qd[:, 3], np.where(switches < 2.0 / rate, rate, -rate), rtol=1e-12)
    np.testing.assert_allclose(sol.q[-1, 3], 2.0 - rate * (20.0 - 2.0 / rate), rtol=1e-10)


@pytest.fixture(scope="module")
def ball_pendulum(cache_dir):
    """A body on a ball joint (mass m, centre of mass at (0, −c, 0), isotropic inertia J about it) under gravity −g
    along y, with an event on the x of the point (0, −l, 0): a point placed through the joint's MRPs."""
    links = [lc.Link("bob", lc.Spherical(("s1", "s2", "s3")), mass=sp.Symbol("m"), com=(0, -sp.Symbol("c"), 0),
                     inertia=(sp.Symbol("J"),) * 3)]
    tip = link_point(links, "bob", (0, -sp.Symbol("l"), 0))
    tree = lc.Tree(links, gravity=(0, -sp.Symbol("g"), 0), name="tree_ball_pendulum",
                   defaults={"m": 1.2, "c": 0.8, "J": 0.05, "l": 1.0, "g": G}, events=[lc.Event("bottom", tip[0])])
    return lc.compile(tree, cache_dir=cache_dir)


def test_a_point_through_a_ball_joint_crosses_the_vertical_at_the_elliptic_quarter_periods(ball_pendulum):
    """Released at rest at θ0 about z, the body swings in the x-y plane as a compound pendulum, ω0² = m g c /
    (J + m c²): the period is T = 4 K(sin²(θ0/2))/ω0 (K the complete elliptic integral of the first kind, parameter
    m = k²), and the point passes x = 0 at T/4, 3T/4, ..."""
    from scipy.special import ellipk

    theta0 = 1.2
    omega0 = math.sqrt(1.2 * G * 0.8 / (0.05 + 1.2 * 0.8**2))
    period = 4 * ellipk(math.sin(theta0 / 2) ** 2) / omega0
    sol = ball_pendulum.simulate((0.0, 2 * period), q0=mrp.mrp_from_axis_angle((0, 0, 1), theta0),
                                 qd0=[0.0, 0.0, 0.0], rtol=1e-13, atol=1e-13)
    assert ball_pendulum.event_names == ("bob_shadow", "bottom") and len(sol.events["bob_shadow"]) == 0
    np.testing.assert_allclose(sol.events["bottom"].t, period * np.array([0.25, 0.75, 1.25, 1.75]), rtol=1e-11)


def test_events_on_a_tree_with_a_closed_loop_agree_with_the_four_bar_example(cache_dir):
    """The four-bar as a tree plus a cut joint (tests/test_multibody_loops.py) with the pin B's height crossing
    0.42 m upwards and the rocker passing 2 rad downwards (B's height swings within 0.33–0.5 m, the rocker within
    1.52–2.42 rad, about ten times in 5 s), against `four_bar_linkage` (absolute angles)
    with the same events written in its coordinates: B = a e1 + b e2, θ3 the rocker's angle."""
    from test_multibody_loops import TO_TREE, four_bar_tree

    b, c = sp.symbols("b c", positive=True)
    base = four_bar_tree()
    pin = link_point(base, "coupler", (b, 0, 0))
    tree = lc.Tree(base.links, gravity=base.gravity, name="four_bar_events", defaults=base.defaults, q0=base.q0,
                   qd0=base.qd0, loops=[lc.Loop("loop", ("coupler", (b, 0, 0)), ("rocker", (c, 0, 0)),
                                                directions="xy")],
                   events=[lc.Event("pin_high", pin[1] - sp.Rational(42, 100), direction=1),
                           lc.Event("rocker_back", lc.coordinates("theta3")[0] - 2, direction=-1)])
    example = four_bar_linkage()
    a = sp.Symbol("a", positive=True)
    th1, th2, th3 = example.coordinates
    example = replace(example, name="four_bar_events_example",
                      events=[lc.Event("pin_high", a * sp.sin(th1) + b * sp.sin(th2) - sp.Rational(42, 100), direction=1),
                              lc.Event("rocker_back", th3 - 2, direction=-1)])
    options = {"method": "dop853", "rtol": 1e-12, "atol": 1e-12, "projection": True, "max_residual": 1e-12}
    run_tree = lc.compile(tree, cache_dir=cache_dir).simulate((0.0, 5.0), **options)
    run = lc.compile(example, cache_dir=cache_dir).simulate((0.0, 5.0), **options)
    assert len(run_tree.events["pin_high"]) >= 5 and len(run_tree.events["rocker_back"]) >= 5
    for name in ("pin_high", "rocker_back"):
        np.testing.assert_allclose(run_tree.events[name].t, run.events[name].t, rtol=0, atol=1e-9)
        np.testing.assert_allclose(run_tree.events[name].q, run.events[name].q @ TO_TREE.T, rtol=0, atol=1e-9)


# -- contacts -------------------------------------------------------------------------------------------------------

G = 9.81


@pytest.fixture(scope="module")
def rod(cache_dir):
    """A uniform rod (mass m, length L along its link's y axis, centre at the joint) on a planar joint (X, Y, θ)
    under gravity −g along y, with a smooth wall at X = 0 touched by its top end and a floor at Y = 0 by its bottom
    end, restitution e: the ladder of tests/test_resting_contacts.py, as a tree."""
    m, L, e = sp.symbols("m L e", positive=True)
    links = [lc.Link("rod", lc.Planar(("X", "Y", "theta")), mass=m, inertia=(m * L**2 / 12, 0, m * L**2 / 12))]
    top, bottom = link_point(links, "rod", (0, L / 2, 0)), link_point(links, "rod", (0, -L / 2, 0))
    tree = lc.Tree(links, gravity=(0, -sp.Symbol("g"), 0), name="tree_rod", defaults={"m": 3.0, "L": 2.0, "g": G},
                   events=[lc.Contact("wall", top[0], restitution=e), lc.Contact("floor", bottom[1], restitution=e)])
    return lc.compile(tree, cache_dir=cache_dir)


def test_the_contacts_take_the_lagrange_modules_kernels_and_constants(rod):
    assert rod.contacts == ("wall", "floor")
    assert rod.kernels.CONTACTS == (("wall", 0, "e"), ("floor", 1, "e"))
    assert rod.kernels.CONTACT_MODES == len(rod.parameters)
    for name in ("rhs_free", "closed_contacts", "contact_forces"):
        assert callable(getattr(rod.kernels, name))


@pytest.mark.parametrize("theta0", [0.2, 0.6])
def test_a_ladder_tree_leaves_the_wall_at_two_thirds_of_its_height(rod, theta0):
    """Released at rest against the wall, both contacts closed: the closed form of test_resting_contacts.py's
    ladder (the wall's force (3/4) m g sin θ (3 cos θ − 2 cos θ0) vanishes at cos θ = (2/3) cos θ0)."""
    m, L = 3.0, 2.0
    q0 = [L / 2 * np.sin(theta0), L / 2 * np.cos(theta0), theta0]
    sol = rod.simulate((0, 3.0), q0=q0, qd0=[0.0, 0.0, 0.0], params={"e": 0.0}, rtol=1e-12, atol=1e-12)
    check_ladder_leaves_the_wall(sol, m, theta0)


@pytest.mark.parametrize(("theta0", "e"), [(0.4, 0.0), (0.9, 0.6), (1.3, 1.0)])
def test_a_falling_rod_hits_the_floor_as_the_impulse_closed_form_says(rod, theta0, e):
    """The rod falls at rest from its centre's height Y0 at angle θ0 and its bottom end meets the floor after
    t1 = √(2 (Y0 − (L/2) cos θ0) / g) at speed v = g t1.  There G = ∂g/∂(X, Y, θ) = (0, 1, (L/2) sin θ0) and
    M = diag(m, m, m L²/12), so w = G M⁻¹ Gᵀ = (1 + 3 sin² θ0)/m and Newton's law (ġ⁺ = −e ġ⁻ = e v) takes the
    impulse P = (1 + e) v / w: Ẏ⁺ = −v + P/m, θ̇⁺ = 6 sin θ0 P/(m L), Ẋ⁺ = 0; the kinetic energy drops by
    (1 − e²) v²/(2 w)."""
    m, L, Y0 = 3.0, 2.0, 2.5
    t1 = math.sqrt(2 * (Y0 - L / 2 * math.cos(theta0)) / G)
    v = G * t1
    w = (1 + 3 * math.sin(theta0) ** 2) / m
    P = (1 + e) * v / w
    sol = rod.simulate((0, t1 + 1e-3), q0=[5.0, Y0, theta0], qd0=[0.0, 0.0, 0.0], params={"e": e}, rtol=1e-13,
                       atol=1e-13)
    floor = sol.events["floor"]
    assert floor.t[0] == pytest.approx(t1, rel=1e-12)
    np.testing.assert_allclose(floor.qd[0], [0.0, -v, 0.0], rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(floor.qd_after[0], [0.0, -v + P / m, 6 * math.sin(theta0) * P / (m * L)], rtol=1e-11,
                               atol=1e-11)
    np.testing.assert_allclose(floor.impulses[0], [0.0, P], rtol=1e-11, atol=1e-11)

    def kinetic(qd):
        return m * (qd[0] ** 2 + qd[1] ** 2) / 2 + m * L**2 / 24 * qd[2] ** 2

    assert kinetic(floor.qd[0]) - kinetic(floor.qd_after[0]) == pytest.approx((1 - e**2) * v**2 / (2 * w),
                                                                              rel=1e-11, abs=1e-11)


def test_a_sweep_over_e_gives_each_rod_its_own_impact(rod):
    """The falling rod of the test above, swept over e and θ0: each trajectory's first impact at its t1 with its
    closed-form post-impact velocities (the sweep loop, its contact modes appended to each trajectory's p)."""
    m, L, Y0 = 3.0, 2.0, 2.5
    e, theta0 = np.array([0.0, 0.5, 1.0]), np.array([0.3, 1.1])
    sweep = rod.sweep((0.0, 0.8), grid={"e": e, "theta": theta0}, q0=[5.0, Y0, 0.0], qd0=[0.0, 0.0, 0.0],
                      params={"e": 0.0},    # (a value the grid replaces: the sweep asks for one)
                      rtol=1e-13, atol=1e-13, output="events", event_cap=4, progress=False)
    floor = sweep.events["floor"]
    for i, ei in enumerate(e):
        for j, th in enumerate(theta0):
            t1 = math.sqrt(2 * (Y0 - L / 2 * math.cos(th)) / G)
            v, w = G * t1, (1 + 3 * math.sin(th) ** 2) / m
            P = (1 + ei) * v / w
            assert floor["t"][i, j, 0] == pytest.approx(t1, rel=1e-12)
            np.testing.assert_allclose(floor["y_after"][i, j, 0, 3:], [0.0, -v + P / m, 6 * math.sin(th) * P / (m * L)],
                                       rtol=1e-11, atol=1e-11)


def test_a_tree_with_contacts_loads_by_name_and_pickles_with_its_events(rod, cache_dir):
    loaded = lc.load("tree_rod", cache_dir=cache_dir)
    copy = pickle.loads(pickle.dumps(rod))
    runs = [model.simulate((0, 0.7), q0=[5.0, 2.5, 0.9], qd0=[0.0, 0.0, 0.0], params={"e": 0.6}, rtol=1e-12,
                           atol=1e-12) for model in (rod, loaded, copy)]
    assert loaded.event_names == copy.event_names == ("wall", "floor") and loaded.contacts == ("wall", "floor")
    for run in runs[1:]:
        np.testing.assert_array_equal(run.events["floor"].qd_after, runs[0].events["floor"].qd_after)


def _floored(links):
    """A floor at y = −h under the pivot, met by the second link's tip, restitution e."""
    tip = link_point(links, "link1", (sp.Symbol("l1"), 0, 0))
    return [lc.Contact("floor", tip[1] + sp.Symbol("h"), restitution=sp.Symbol("e"))]


@pytest.fixture(scope="module")
def floored(cache_dir):
    tree = _double_pendulum("tree_floored", _floored)
    tree = lc.Tree(tree.links, gravity=tree.gravity, name=tree.name, events=tree.user_events,
                   defaults={**DOUBLE, "h": 1.2, "e": 0.7})
    return _pair(tree, cache_dir)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.data())
def test_an_impact_of_the_chains_tip_agrees_with_the_lagrangian_path_and_loses_1_minus_e2(floored, data):
    """At a state whose tip touches the floor moving down: the tree's impact against the Lagrangian module's, and
    against Newton's restitution with G = ∂g/∂q from sympy and M from the Lagrangian path: the normal velocity
    v = G q̇ leaves at −e v, and T drops by (1 − e²) v² / (2 G M⁻¹ Gᵀ)."""
    tree, lagrange = floored
    e = data.draw(st.floats(0.0, 1.0))
    th0 = data.draw(st.floats(-1.5, -0.7))   # (where the tip can reach the floor)
    # the second angle that puts the tip on the floor: l0 sin th0 + l1 sin(th0 + th1) = −h
    s = (-1.2 - DOUBLE["l0"] * math.sin(th0)) / DOUBLE["l1"]
    th1 = math.asin(s) - th0
    qd = np.array([data.draw(st.floats(-3.0, 3.0)) for _ in range(2)])
    G = np.array([DOUBLE["l0"] * math.cos(th0) + DOUBLE["l1"] * math.cos(th0 + th1), DOUBLE["l1"] * math.cos(th0 + th1)])
    v = G @ qd
    if v > -1e-3:   # (moving up: the drivers never call the impact)
        qd = qd - (v + 1.0) * G / (G @ G)
        v = G @ qd
    y = np.array([th0, th1, *qd])
    params = {"e": e}
    out = {}
    for model in floored:
        p = model.parameter_vector(params)
        gap = np.empty(1)
        model.kernels.event_values(0.0, y, p, gap)
        assert abs(gap[0]) < 1e-14
        out[model] = np.empty(4)
        assert model.kernels.event_reset(0.0, y, p, 0, out[model]) == 0
    np.testing.assert_allclose(out[tree], out[lagrange], rtol=1e-12, atol=1e-12)
    after = out[tree]
    np.testing.assert_array_equal(after[:2], y[:2])
    assert G @ after[2:] == pytest.approx(-e * v, rel=1e-12, abs=1e-12)
    M = np.empty((2, 2))
    lagrange.kernels.mass_matrix(0.0, y, lagrange.parameter_vector(params), M)
    w = G @ np.linalg.solve(M, G)
    loss = qd @ M @ qd / 2 - after[2:] @ M @ after[2:] / 2
    assert loss == pytest.approx((1 - e**2) * v**2 / (2 * w), rel=1e-11, abs=1e-13)


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.data())
def test_a_closed_contact_of_the_chain_holds_as_the_lagrangian_paths(floored, data):
    """With the floor's mode closed (its slot of p at 1), at a touching state: rhs (q̈ with the normal force, or
    without it where it would pull), contact_forces and event_values (the normal force) of the tree equal the
    Lagrangian module's."""
    th0 = data.draw(st.floats(-1.5, -0.7))
    th1 = math.asin((-1.2 - DOUBLE["l0"] * math.sin(th0)) / DOUBLE["l1"]) - th0
    G = np.array([DOUBLE["l0"] * math.cos(th0) + DOUBLE["l1"] * math.cos(th0 + th1), DOUBLE["l1"] * math.cos(th0 + th1)])
    qd = np.array([data.draw(st.floats(-2.0, 2.0)) for _ in range(2)])
    y = np.array([th0, th1, *(qd - (G @ qd) * G / (G @ G))])      # sliding along the floor: ġ = 0
    found = []
    for model in floored:
        p = model.parameter_vector({"e": 0.3})
        p[model.kernels.CONTACT_MODES] = 1.0
        rhs, forces, values = np.empty(4), np.empty(1), np.empty(1)
        assert model.kernels.rhs(0.0, y, p, rhs) == 0
        assert model.kernels.contact_forces(0.0, y, p, forces) == 0
        model.kernels.event_values(0.0, y, p, values)
        assert values[0] == forces[0]
        found.append(np.concatenate([rhs, forces]))
    np.testing.assert_allclose(found[0], found[1], rtol=1e-11, atol=1e-11)
    qdd, force = found[0][2:4], found[0][4]
    w0, w01 = y[2], y[2] + y[3]
    tip_acceleration = G @ qdd - DOUBLE["l0"] * math.sin(th0) * w0**2 - DOUBLE["l1"] * math.sin(th0 + th1) * w01**2
    assert force >= 0.0
    if force > 0.0:     # held: the tip does not leave the floor
        assert abs(tip_acceleration) < 1e-10
    else:               # it would pull: released, the tip accelerates upwards
        assert tip_acceleration >= -1e-10


def test_the_chain_meets_the_floor_when_the_lagrangian_path_does(floored):
    a, b = (model.simulate((0.0, 4.0), q0=[0.0, 0.0], qd0=[0.0, 0.0], rtol=1e-12, atol=1e-12) for model in floored)
    impacts, reference = a.events["floor"], b.events["floor"]
    assert len(impacts) >= 2 and len(impacts) == len(reference)
    np.testing.assert_allclose(impacts.t, reference.t, rtol=0, atol=1e-9)
    np.testing.assert_allclose(impacts.qd, reference.qd, rtol=0, atol=1e-8)
    np.testing.assert_allclose(impacts.qd_after, reference.qd_after, rtol=0, atol=1e-8)
    np.testing.assert_allclose(impacts.impulses, reference.impulses, rtol=0, atol=1e-8)
    np.testing.assert_allclose(a.energy[-1], b.energy[-1], rtol=1e-8)


@pytest.fixture(scope="module")
def bouncer(cache_dir):
    """Two roots under gravity −g along z: an isotropic ball on a spherical joint about its centre (gravity exerts
    no moment: constant ω) and a block on a prismatic joint along z over a floor at z = 0 (restitution e)."""
    z, = lc.coordinates("z")
    links = [lc.Link("ball", lc.Spherical(("s1", "s2", "s3")), mass=2.0, inertia=(0.3, 0.3, 0.3)),
             lc.Link("block", lc.Prismatic(z, axis="z"), mass=1.5)]
    tree = lc.Tree(links, gravity=(0, 0, -G), name="tree_bouncer", defaults={"e": 0.8},
                   events=[lc.Contact("floor", link_point(links, "block")[2], restitution=sp.Symbol("e"))])
    return lc.compile(tree, cache_dir=cache_dir)


def test_a_contact_beside_a_ball_joint_bounces_at_the_closed_form_times(bouncer):
    """The block falls from h and bounces: impacts at t_1 = √(2h/g), t_k+1 = t_k + 2 e^k v_1/g, v⁺ = e v⁻; the
    ball's shadow switches at |ω| t = π + 2πk all the while (event 0), the floor's impacts are event 1."""
    assert bouncer.event_names == ("ball_shadow", "floor") and bouncer.kernels.CONTACTS == (("floor", 1, "e"),)
    h, e, w = 1.25, 0.8, np.array([3.3, 0.5, -2.1])
    v1 = math.sqrt(2 * G * h)
    times = [v1 / G]
    for k in range(1, 5):
        times.append(times[-1] + 2 * e**k * v1 / G)
    sol = bouncer.simulate((0.0, times[-1] + 0.01), q0=[0.0, 0.0, 0.0, h], qd0=[*mrp.mrp_rate([0, 0, 0], w), 0.0],
                           rtol=1e-13, atol=1e-13)
    floor = sol.events["floor"]
    np.testing.assert_allclose(floor.t, times, rtol=1e-11)
    np.testing.assert_allclose(floor.qd_after[:, 3], v1 * e ** np.arange(1, 6), rtol=1e-10)
    np.testing.assert_array_equal(floor.qd_after[:, :3], floor.qd[:, :3])     # the impact leaves the ball alone
    switches = sol.events["ball_shadow"].t
    assert len(switches) >= 2
    np.testing.assert_allclose(switches, (math.pi + 2 * math.pi * np.arange(len(switches))) / np.linalg.norm(w),
                               rtol=0, atol=1e-9)


@pytest.fixture(scope="module")
def block(cache_dir):
    """A block (mass m) on a massless carriage: the carriage slides along x (pushed by c t), the block along y on it,
    over a floor y = 0 (restitution e) whose normal force presses a friction element on ẋ (μs, μk): the frictional
    block of tests/test_contact_friction.py, as a tree."""
    x, y = lc.coordinates("x y")
    m, g, c, e, mu_s, mu_k = sp.symbols("m g c e mu_s mu_k", positive=True)
    links = [lc.Link("carriage", lc.Prismatic(x, axis="x", torque=c * t)),
             lc.Link("block", lc.Prismatic(y, axis="y"), parent="carriage", mass=m)]
    tree = lc.Tree(links, gravity=(0, -g, 0), name="tree_block",
                   defaults={"m": 2.0, "g": G, "c": 3.0, "e": 0.0, "mu_s": 0.5, "mu_k": 0.3},
                   events=[lc.Contact("floor", link_point(links, "block")[1], restitution=e),
                           lc.Friction("ground", x.diff(t), normal="floor", static=mu_s, kinetic=mu_k)])
    return lc.compile(tree, cache_dir=cache_dir)


def test_a_block_tree_pushed_harder_and_harder_breaks_away_at_the_static_limit(block):
    """Resting on the floor, pushed by c t: it sticks until c t_s = μs m g, then slides with m ẍ = c t − μk m g."""
    m, c, mu_s, mu_k = 2.0, 3.0, 0.5, 0.3
    sol = block.simulate((0.0, 5.0), [0.0, 0.0], [0.0, 0.0], rtol=1e-12, atol=1e-12)
    assert block.frictions == ("ground",) and block.contacts == ("floor",)
    check_breakaway(sol, m, c, mu_s, mu_k)


@pytest.mark.parametrize("v_t", [1.0, 5.0])
def test_a_block_tree_hitting_the_frictional_floor_obliquely_loses_tangential_speed_by_coulombs_law(block, v_t):
    """Falling from h with ẋ = v_t: the impact takes P_n = (1 + e) m v_n; slipping through it (|v_t| > μs P_n/m),
    friction takes μk P_n from m v_t, else the block sticks."""
    h, e, mu_s, mu_k = 1.0, 0.5, 0.5, 0.3
    v_n = np.sqrt(2 * G * h)
    sol = block.simulate((0.0, 0.5), [0.0, h], [v_t, 0.0], params={"c": 0.0, "e": e}, rtol=1e-12, atol=1e-12)
    impact = sol.events["floor"]
    assert len(impact) == 1
    slipping = abs(v_t) > mu_s * (1 + e) * v_n
    expected = v_t - mu_k * (1 + e) * v_n * np.sign(v_t) if slipping else 0.0
    np.testing.assert_allclose(impact.qd_after[0], [expected, e * v_n], rtol=1e-12, atol=1e-15)


# -- refusals -------------------------------------------------------------------------------------------------------


def _ball_and_stick():
    return [lc.Link("ball", lc.Spherical(("a", "b", "c")), mass=1.0, inertia=(1, 1, 1)),
            lc.Link("stick", lc.Revolute("q"), parent="ball", mass=1.0, inertia=(1, 1, 1))]


@pytest.mark.parametrize(("build", "culprit"), [
    (lambda: lc.Tree(_ball_and_stick(), events=[lc.Event("ball_shadow", lc.coordinates("q")[0])]), "'ball_shadow'"),
    (lambda: lc.Tree(_ball_and_stick(), events=[lc.Event("a", lc.coordinates("q")[0]),
                                                lc.Event("a", lc.coordinates("q")[0] - 1)]), "'a'"),
    (lambda: lc.Tree(_ball_and_stick(), events=[lc.Event("kick", lc.coordinates("q")[0],
                                                         reset={lc.coordinates("z")[0]: 0})]), "z(t)"),
    (lambda: lc.Tree(_ball_and_stick(), events=["q"]), "'q'"),
    (lambda: lc.Tree(_ball_and_stick(), events=[lc.Event("late", lc.coordinates("w")[0])]), "w(t)"),
    (lambda: link_point(_ball_and_stick(), "arm"), "'arm'"),
    (lambda: lc.Tree(_ball_and_stick(), events=[lc.Contact("floor", lc.coordinates("q")[0]), lc.Friction(
        "rub", lc.coordinates("q")[0].diff(t), normal="flor", static=0.5)]), "'flor'"),
    (lambda: lc.Tree(_ball_and_stick(), events=[lc.Contact("floor", lc.coordinates("q")[0]), lc.Friction(
        "rub", lc.coordinates("q")[0].diff(t) ** 2, normal="floor", static=0.5)]), "`rub`"),
    (lambda: link_point(mm.planar_chain(2).links, "link1", (1, 0)), "'link1'"),
])
def test_bad_events_are_refused_naming_the_culprit(build, culprit):
    with pytest.raises(lc.ModelError) as caught:
        build()
    assert culprit in str(caught.value)


def test_a_point_of_a_link_moves_with_the_links_frame():
    # the rod's top end of `rod`, at a state: the centre plus the rotated (0, L/2)
    X, Y, th = lc.coordinates("X Y theta")
    L = sp.Symbol("L")
    links = [lc.Link("rod", lc.Planar((X, Y, th)), mass=1.0, inertia=(1, 0, 1))]
    top = link_point(links, "rod", (0, L / 2, 0))
    values = {X: 0.3, Y: -1.2, th: 0.7, L: 2.0}
    np.testing.assert_allclose(np.array(top.subs(values), dtype=float).ravel(),
                               [0.3 - math.sin(0.7), -1.2 + math.cos(0.7), 0.0], rtol=1e-15)


@pytest.mark.parametrize("method", ["radau", "rk4"])
def test_a_method_that_cannot_apply_impacts_is_refused_naming_those_that_can(rod, method):
    # as for a System with contacts: an OptionError naming the capable methods (listing them asks whether the
    # Taylor method has mode programs, a kernel a tree does not have: no, rather than a ModelError about Taylor)
    with pytest.raises(lc.OptionError, match=f"which `{method}` cannot do; use dopri5, dop853"):
        rod.simulate((0, 0.1), q0=[5.0, 2.5, 0.5], qd0=[0.0, 0.0, 0.0], method=method, dt=1e-3)


def test_which_contact_presses_a_friction_element_is_part_of_the_trees_key():
    x, y = lc.coordinates("x y")
    links = [lc.Link("carriage", lc.Prismatic(x, axis="x")), lc.Link("block", lc.Prismatic(y, axis="y"),
                                                                     parent="carriage", mass=1.0)]

    def tree(normal):
        return lc.Tree(links, name="pressed", events=[lc.Contact("low", y), lc.Contact("high", 1 - y),
                                                      lc.Friction("rub", x.diff(t), normal=normal, static=0.5)])

    assert tree("low").fingerprint() != tree("high").fingerprint()
    assert tree("low").fingerprint() == tree("low").fingerprint()
