"""Friction on kinematic trees pressed by an expression (`lc.Friction(..., normal=N)` among an `lc.Tree`'s events,
N a normal force written in the tree's coordinates, not a contact's name; issue 39): the slip force −μk |N| s ∂v/∂q̇
in the recursions' joint forces, the sticking element a held row.

Closed forms derived here: a block on a spring released beyond the static limit (its half swings and where it
stops), a block pushed by c t (breakaway at c t = μs N), a ball spinning down under a friction moment about a body
axis (the ball joint's MRPs: τ = Bᵀ Q_σ / 4); and the Lagrangian twin of a cart-pole with two friction elements, one
pressed by a state-dependent N: stick–slip times to 1e-9, kernels to 1e-12.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
import sympy as sp
from multibody_models import cart_pole, lagrangian_system
from test_contact_friction import breakaway_slide

import lagcomp as lc
from lagcomp.multibody import mrp

t = lc.t
G = 9.81


@pytest.fixture(scope="module")
def spring_block(cache_dir):
    """A block (mass m) on a prismatic joint along x with a spring k to x = 0, pushed by c t, on a table whose
    friction element on ẋ is pressed by N = m g (μs, μk)."""
    x, = lc.coordinates("x")
    m, k, g, c, mu_s, mu_k = sp.symbols("m k g c mu_s mu_k", positive=True)
    tree = lc.Tree([lc.Link("block", lc.Prismatic(x, axis="x", stiffness=k, torque=c * t), mass=m)],
                   name="tree_spring_block", defaults={"m": 1.5, "k": 40.0, "g": G, "c": 0.0, "mu_s": 0.3,
                                                       "mu_k": 0.2},
                   events=[lc.Friction("table", x.diff(t), normal=m * g, static=mu_s, kinetic=mu_k)])
    return lc.compile(tree, cache_dir=cache_dir)


def test_a_block_on_a_spring_swings_down_to_rest_at_the_closed_form_times(spring_block):
    """Released at rest from x_0 with k x_0 > μs m g, it slips: each half swing is x = ±δ + (x_n ∓ δ) cos ω(t −
    t_n), δ = μk m g / k, ω = √(k/m), ending at rest at t_n+1 = t_n + π/ω with |x_n+1| = |x_n| − 2δ; it sticks at
    the first turning point where k |x_n| ≤ μs m g, the friction then holding the spring's pull k x_n."""
    m, k, mu_s, mu_k, x0 = 1.5, 40.0, 0.3, 0.2, 0.5
    delta, omega, limit = mu_k * m * G / k, math.sqrt(k / m), mu_s * m * G / k
    turning = [x0]
    while abs(turning[-1]) > limit:
        turning.append(-np.sign(turning[-1]) * (abs(turning[-1]) - 2 * delta))
    swings = len(turning) - 1
    assert swings == 3          # (these numbers: 0.5, −0.353, 0.206, −0.059)
    end = (swings + 1) * math.pi / omega
    sol = spring_block.simulate((0.0, end), [x0], [0.0], rtol=1e-12, atol=1e-12, t_eval=np.linspace(0, end, 401))
    assert spring_block.frictions == ("table",) and spring_block.contacts == ()
    switches = sol.friction_switches
    modes = [int(-np.sign(turning[n])) for n in range(1, swings)] + [0]   # slip towards the spring's rest, then stick
    assert [(s.friction, s.mode) for s in switches] == [("table", mode) for mode in modes]
    np.testing.assert_allclose([s.t for s in switches], np.arange(1, swings + 1) * math.pi / omega, rtol=0, atol=1e-9)
    for n in range(swings):   # each half swing against the closed form
        inside = (sol.t > n * math.pi / omega) & (sol.t < (n + 1) * math.pi / omega)
        centre = np.sign(turning[n]) * delta
        expected = centre + (turning[n] - centre) * np.cos(omega * (sol.t[inside] - n * math.pi / omega))
        np.testing.assert_allclose(sol.q[inside, 0], expected, rtol=0, atol=1e-9)
    resting = sol.t > swings * math.pi / omega + 1e-6
    np.testing.assert_allclose(sol.q[resting, 0], turning[-1], rtol=0, atol=1e-9)
    np.testing.assert_allclose(sol.friction_forces[resting, 0], k * turning[-1], rtol=1e-9)


def test_a_block_pushed_harder_and_harder_breaks_away_at_the_static_limit(spring_block):
    """Without the spring, pushed by c t from rest: it sticks (the friction force −c t) until c t_s = μs m g, then
    slides with m ẍ = c t − μk m g: x = (c (t³ − t_s³)/6 − c t_s² (t − t_s)/2 − μk m g (t − t_s)²/2) / m."""
    m, c, mu_s, mu_k = 1.5, 3.0, 0.3, 0.2
    sol = spring_block.simulate((0.0, 3.0), [0.0], [0.0], params={"k": 0.0, "c": c}, rtol=1e-12, atol=1e-12,
                                t_eval=np.linspace(0, 3.0, 301))
    t_s, after, x = breakaway_slide(sol.t, m, c, mu_s, mu_k)
    assert [(s.friction, s.mode) for s in sol.friction_switches] == [("table", 1)]
    assert abs(sol.friction_switches[0].t - t_s) < 1e-9
    np.testing.assert_allclose(sol.q[after, 0], x[after], rtol=1e-9, atol=1e-12)
    assert np.abs(sol.q[~after, 0]).max() < 1e-12
    holding = sol.t < t_s
    np.testing.assert_allclose(sol.friction_forces[holding, 0], -c * sol.t[holding], rtol=1e-10, atol=1e-12)


def test_a_ball_spins_down_under_a_friction_moment_about_its_body_axis(cache_dir):
    """An isotropic ball (moment I) on a ball joint, no gravity, spinning with body rates ω_0 = (a, b, w): a friction
    element on v = ω_z(σ, σ̇) (`mrp.angular_velocity`) pressed by N gives the moment −μk N s about the body's z,
    so I ω̇_z = −μk N while ω_x, ω_y stay (Euler's equations of an isotropic body): ω_z reaches 0 at t = I w / (μk
    N) and stays there (nothing pulls it from rest)."""
    sigma = lc.coordinates("s1 s2 s3")
    I, N, mu = 0.4, 2.5, 0.3
    omega_z = mrp.angular_velocity(list(sigma), [s.diff(t) for s in sigma])[2]
    tree = lc.Tree([lc.Link("ball", lc.Spherical(sigma), mass=1.0, inertia=(I, I, I))], name="tree_spinning_ball",
                   events=[lc.Friction("spin", sp.simplify(omega_z), normal=N, static=mu)])
    model = lc.compile(tree, cache_dir=cache_dir)
    w0 = np.array([0.7, -0.4, 3.0])
    t_stop = I * w0[2] / (mu * N)
    sol = model.simulate((0.0, 1.5 * t_stop), [0.0, 0.0, 0.0], mrp.mrp_rate([0.0, 0.0, 0.0], w0), rtol=1e-12,
                         atol=1e-12, t_eval=np.linspace(0, 1.5 * t_stop, 61))
    assert [(s.friction, s.mode) for s in sol.friction_switches] == [("spin", 0)]
    assert abs(sol.friction_switches[0].t - t_stop) < 1e-9
    rates = np.array([mrp.angular_velocity(q, qd) for q, qd in zip(sol.q, sol.qd, strict=True)], dtype=float)
    np.testing.assert_allclose(rates[:, :2], np.broadcast_to(w0[:2], (len(sol.t), 2)), rtol=0, atol=1e-9)
    np.testing.assert_allclose(rates[:, 2], np.maximum(w0[2] - mu * N * sol.t / I, 0.0), rtol=0, atol=1e-9)


# -- against the Lagrangian twin ------------------------------------------------------------------------------------


def _frictions():
    """A friction element on the cart's slide pressed by N = (M + m) g − m c θ̇² cos θ (the track's load, state
    dependent), one on the pole's hinge (pin radius r) pressed by a constant N_0."""
    x, th = lc.coordinates("x th")
    M, m, c, g, r, N0 = sp.symbols("M m c g r N0")
    return [lc.Friction("slide", x.diff(t), normal=(M + m) * g - m * c * th.diff(t) ** 2 * sp.cos(th),
                        static=sp.Symbol("mu_s"), kinetic=sp.Symbol("mu_k")),
            lc.Friction("hinge", r * th.diff(t), normal=N0, static=0.4, kinetic=0.3)]


DEFAULTS = {"M": 2.0, "m": 0.8, "c": 0.5, "J": 0.05, "g": G, "k": 6.0, "b": 0.1, "F": 4.0, "w": 1.3, "e": 0.02,
            "r": 0.05, "N0": 15.0, "mu_s": 0.08, "mu_k": 0.06}


@pytest.fixture(scope="module")
def twins(cache_dir):
    """The cart-pole (spring, damper, forcing F sin(w t)) with `_frictions`, as a tree and as its Lagrangian twin."""
    tree = cart_pole()
    pair = (lc.Tree(tree.links, gravity=tree.gravity, name="cart_pole_friction", defaults=DEFAULTS,
                    events=_frictions()),
            replace(lagrangian_system(tree), name="cart_pole_friction_lagrange", defaults=DEFAULTS, parameters=None,
                    events=_frictions()))
    return tuple(lc.compile(model, cache_dir=cache_dir) for model in pair)


def test_the_kernels_agree_with_the_lagrangian_twins_in_every_mode(twins):
    """rhs, event_values and friction_limits at random states, each element sticking or slipping either way."""
    tree, twin = twins
    assert sorted(tree.parameters) == sorted(twin.parameters)
    assert tree.frictions == twin.frictions == ("slide", "hinge")
    rng = np.random.default_rng(39)
    p_tree, p_twin = tree.parameter_vector(DEFAULTS), twin.parameter_vector(DEFAULTS)
    slots = [row[2] for row in tree.kernels.FRICTIONS]
    assert slots == [row[2] for row in twin.kernels.FRICTIONS]
    worst = 0.0
    for slide, hinge in [(0, 0), (1, 1), (-1, 1), (1, -1), (0, -1), (-1, 0)]:
        for p in (p_tree, p_twin):
            p[slots[0]], p[slots[1]] = slide, hinge
        for _ in range(4):
            y = rng.uniform(-1.5, 1.5, 4)
            for kernel in ("rhs", "event_values", "friction_limits"):
                size = {"rhs": 4, "event_values": 2, "friction_limits": 2}[kernel]
                a, b = np.empty(size), np.empty(size)
                assert getattr(tree.kernels, kernel)(0.7, y, p_tree, a) == getattr(twin.kernels, kernel)(0.7, y,
                                                                                                        p_twin, b)
                worst = max(worst, float(np.max(np.abs(a - b)) / max(np.max(np.abs(b)), 1.0)))
    assert worst <= 1e-12


def test_the_stick_slip_motion_is_the_lagrangian_twins(twins):
    """Forced from rest, the cart and the pole stick and slip several times: the same switches (element, mode) at the
    same times (1e-9), the same states."""
    runs = [model.simulate((0.0, 6.0), [0.3, 0.2], [0.0, 0.0], rtol=1e-12, atol=1e-12, t_eval=np.linspace(0, 6, 121))
            for model in twins]
    a, b = ([(s.friction, s.mode) for s in run.friction_switches] for run in runs)
    assert len(a) >= 10 and {name for name, _ in a} == {"slide", "hinge"} and {mode for _, mode in a} == {-1, 0, 1}
    assert a == b
    np.testing.assert_allclose([s.t for s in runs[0].friction_switches], [s.t for s in runs[1].friction_switches],
                               rtol=0, atol=1e-9)
    np.testing.assert_allclose(runs[0].y, runs[1].y, rtol=0, atol=1e-8)
    np.testing.assert_allclose(runs[0].friction_forces, runs[1].friction_forces, rtol=0, atol=1e-7)




def _differences(kernel, t0, y, p, h=1e-3) -> np.ndarray:
    """∂f/∂y of `kernel` (an rhs) by fourth-order central differences: error ~h⁴ f⁽⁵⁾/30 + ε |f| / h ≈ 1e-13."""
    columns = []
    for j in range(len(y)):
        values = []
        for step in (2, 1, -1, -2):
            shifted, out = y.copy(), np.empty(len(y))
            shifted[j] += step * h
            assert kernel(t0, shifted, p, out) == 0
            values.append(out)
        columns.append((-values[0] + 8 * values[1] - 8 * values[2] + values[3]) / (12 * h))
    return np.array(columns).T


def test_the_on_demand_jacobian_sees_the_slip_forces(twins):
    """``rhs_jacobian`` (on demand: the tree's recursions differentiated in forward mode) while the elements slip:
    the slip forces, their modes read from p, are differentiated too (|N| of the state-dependent N included),
    against differences of the twin's rhs (the Lagrangian path)."""
    tree, twin = twins
    rng = np.random.default_rng(8)
    p_tree, p_twin = tree.parameter_vector(DEFAULTS), twin.parameter_vector(DEFAULTS)
    slots = [row[2] for row in tree.kernels.FRICTIONS]
    for slide, hinge in [(1, -1), (-1, 1)]:
        for p in (p_tree, p_twin):
            p[slots[0]], p[slots[1]] = slide, hinge
        for _ in range(3):
            y, got = rng.uniform(-1.5, 1.5, 4), np.empty((4, 4))
            assert tree.kernels.rhs_jacobian(0.4, y, p_tree, got) == 0
            expected = _differences(twin.kernels.rhs, 0.4, y, p_twin)
            assert np.max(np.abs(got - expected)) <= 1e-9 * np.max(np.abs(expected))


def test_the_lagrangian_jacobians_of_a_normal_force_over_symbols_without_assumptions(twins):
    """The twin's own ``rhs_jacobian`` and ``rhs_parameter_jacobian``: its N = (M + m) g − m c θ̇² cos θ is written
    over symbols declared without assumptions, which sympy takes as complex and differentiated |N| into derivatives
    of re N and im N that no kernel can print (a traceback from the printer); lagcomp's quantities are real, so
    ∂|N| = sign(N) ∂N.  Against the tree's forward-mode Jacobian (1e-12) and differences in the parameters."""
    tree, twin = twins
    rng = np.random.default_rng(9)
    p_tree, p_twin = tree.parameter_vector(DEFAULTS), twin.parameter_vector(DEFAULTS)
    slots = [row[2] for row in tree.kernels.FRICTIONS]
    names = list(twin.parameters)
    for slide, hinge in [(1, -1), (-1, 1)]:
        for p in (p_tree, p_twin):
            p[slots[0]], p[slots[1]] = slide, hinge
        y = rng.uniform(-1.5, 1.5, 4)
        expected, got = np.empty((4, 4)), np.empty((4, 4))
        assert tree.kernels.rhs_jacobian(0.4, y, p_tree, expected) == 0
        assert twin.kernels.rhs_jacobian(0.4, y, p_twin, got) == 0
        assert np.max(np.abs(got - expected)) <= 1e-12 * np.max(np.abs(expected))
        partials = np.empty((4, len(names)))
        assert twin.kernels.rhs_parameter_jacobian(0.4, y, p_twin, partials) == 0
        for j in (names.index("g"), names.index("c"), names.index("mu_k")):
            h, values = 1e-3 * abs(p_twin[j]), []
            for step in (2, 1, -1, -2):
                shifted, out = p_twin.copy(), np.empty(4)
                shifted[j] += step * h
                assert twin.kernels.rhs(0.4, y, shifted, out) == 0
                values.append(out)
            column = (-values[0] + 8 * values[1] - 8 * values[2] + values[3]) / (12 * h)
            assert np.max(np.abs(partials[:, j] - column)) <= 1e-9 * np.max(np.abs(column))


@pytest.fixture(scope="module")
def pressed_both_ways(cache_dir):
    """The frictional block of tests/test_multibody_events.py (a carriage along x pushed by P sin(w t), the block
    along y on it over a floor y = 0 whose normal force presses friction on ẋ) carrying a pendulum (hinge about z)
    whose hinge friction is pressed by the expression N_0 + m_p θ̇² l: one element pressed by a contact, one by an
    expression, in one tree; and its Lagrangian twin."""
    x, y, th = lc.coordinates("x y th")
    m, mp, l, J, g, P, w, e, N0 = sp.symbols("m m_p l J g P w e N0")
    links = [lc.Link("carriage", lc.Prismatic(x, axis="x", torque=P * sp.sin(w * t))),
             lc.Link("block", lc.Prismatic(y, axis="y"), parent="carriage", mass=m),
             lc.Link("bob", lc.Revolute(th, axis="z"), parent="block", mass=mp, com=(0, -l, 0), inertia=(J, J, J))]
    defaults = {"m": 2.0, "m_p": 0.5, "l": 0.6, "J": 0.02, "g": G, "P": 9.0, "w": 2.0, "e": 0.0, "N0": 5.0,
                "r": 0.04}
    events = [lc.Contact("floor", y, restitution=e),
              lc.Friction("ground", x.diff(t), normal="floor", static=0.4, kinetic=0.3),
              lc.Friction("pin", sp.Symbol("r") * th.diff(t), normal=N0 + mp * th.diff(t) ** 2 * l, static=0.5,
                          kinetic=0.4)]
    tree = lc.Tree(links, gravity=(0, -g, 0), name="tree_pressed_both_ways", defaults=defaults, events=events)
    twin = replace(lagrangian_system(tree), name="pressed_both_ways_lagrange", defaults=defaults, parameters=None,
                   events=events)
    return tuple(lc.compile(model, cache_dir=cache_dir) for model in (tree, twin))


def test_friction_pressed_by_a_contact_and_by_an_expression_in_one_tree_is_the_twins(pressed_both_ways):
    """Resting on the floor and pushed to and fro, the carriage and the pendulum stick and slip: the same switches at
    the same times (1e-9) as the Lagrangian twin, the same states and contact and friction forces."""
    runs = [model.simulate((0.0, 5.0), [0.0, 0.0, 0.4], [0.0, 0.0, 0.0], rtol=1e-12, atol=1e-12,
                           t_eval=np.linspace(0, 5, 101)) for model in pressed_both_ways]
    a, b = ([(s.friction, s.mode) for s in run.friction_switches] for run in runs)
    assert {name for name, _ in a} == {"ground", "pin"} and 0 in {mode for _, mode in a} and a == b
    np.testing.assert_allclose([s.t for s in runs[0].friction_switches], [s.t for s in runs[1].friction_switches],
                               rtol=0, atol=1e-9)
    np.testing.assert_allclose(runs[0].y, runs[1].y, rtol=0, atol=1e-8)
    np.testing.assert_allclose(runs[0].contact_forces, runs[1].contact_forces, rtol=0, atol=1e-7)
    np.testing.assert_allclose(runs[0].friction_forces, runs[1].friction_forces, rtol=0, atol=1e-7)
