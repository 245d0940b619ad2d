"""Equilibria of kinematic trees (`lagcomp.Tree`, issue 39): `lagcomp.analysis.find_equilibrium` and
`find_equilibria` solve F(q, 0, t) = 0 from the tree's ``forcing`` kernel with ∂F/∂q from its ``rest_partials``,
as for a System, and `normal_modes` judges their stability.

References: closed forms derived here (a double pendulum's four equilibria and their stability, the spring-loaded
joints' balance), the Lagrangian twin of the same double pendulum (`multibody_models.lagrangian_system`, compiled
through T and V), the phase portrait of a sprung hinge (the energy integral from the tree's energy function), and the
refusals of what a tree cannot give (the equilibria of closed loops; the portrait of a damped joint).
"""

from __future__ import annotations

import math

import multibody_models as mm
import numpy as np
import pytest
import sympy as sp
from hypothesis import given, settings
from hypothesis import strategies as st

import lagcomp as lc
from lagcomp.analysis import find_equilibria, find_equilibrium, normal_modes, phase_portrait
from lagcomp.errors import ModelError
from lagcomp.examples.trees import cart_pole, planar_chain

#: Equilibria agree with the closed forms to this (rad or m; the closed forms are O(1) and exact to rounding).
TOLERANCE = 1e-12


@pytest.fixture(scope="module")
def double_pendulum(cache_dir):
    """(the two-link planar chain as a tree model, its Lagrangian twin's model)."""
    tree = planar_chain(2)
    return lc.compile(tree, cache_dir=cache_dir), lc.compile(mm.lagrangian_system(tree), cache_dir=cache_dir)


def pendulum_parameters(m0, m1, c0, d0, c1, d1, l0, g) -> dict:
    return {"m0": m0, "m1": m1, "c0": c0, "d0": d0, "c1": c1, "d1": d1, "l0": l0, "g": g,
            "J0": 0.3 * m0, "J1": 0.2 * m1}


def closed_form_equilibria(p) -> dict:
    """{(s0, s1): (θ0, θ1)}: link 0's joint and link 1's centre of mass each straight below (s = −1) or above (+1).

    With gravity −g along y, V = g [R0 sin(θ0 + α0) + m1 r1 sin(θ0 + θ1 + α1)], where m0 (c0, d0) + m1 (l0, 0) =
    R0 (cos α0, sin α0) is the first moment of the links about joint 0 with link 1 lumped at joint 1 and
    (c1, d1) = r1 (cos α1, sin α1); in (θ0, θ0 + θ1) V separates, so ∇V = 0 where θ0 + α0 = s0 π/2 and
    θ0 + θ1 + α1 = s1 π/2, and the Hessian there is diag(−g R0 s0, −g m1 r1 s1): a minimum only at s0 = s1 = −1
    (hanging), a maximum inverted, saddles mixed.
    """
    alpha0 = math.atan2(p["m0"] * p["d0"], p["m0"] * p["c0"] + p["m1"] * p["l0"])
    alpha1 = math.atan2(p["d1"], p["c1"])
    found = {}
    for s0 in (-1, 1):
        for s1 in (-1, 1):
            theta0 = s0 * math.pi / 2 - alpha0
            found[(s0, s1)] = (theta0, s1 * math.pi / 2 - alpha1 - theta0)
    return found


def nudged(q, size=0.2):
    """A guess near `q` (not on it), so that the root finder has work to do."""
    return np.asarray(q) + size * np.array([1.0, -0.7])


lengths = st.floats(0.2, 1.5)
offsets = st.floats(-0.3, 0.3)
masses = st.floats(0.2, 5.0)


@settings(max_examples=15, deadline=None)
@given(m0=masses, m1=masses, c0=lengths, d0=offsets, c1=lengths, d1=offsets, l0=lengths, g=st.floats(1.0, 20.0))
def test_double_pendulum_equilibria_match_closed_form(double_pendulum, m0, m1, c0, d0, c1, d1, l0, g):
    tree_model, _ = double_pendulum
    p = pendulum_parameters(m0, m1, c0, d0, c1, d1, l0, g)
    for (s0, s1), q in closed_form_equilibria(p).items():
        e = find_equilibrium(tree_model, nudged(q, 0.05), p)
        assert e.success and e.steady, (s0, s1, e)
        assert np.max(np.abs(e.q - q)) <= TOLERANCE, (s0, s1, e.q, q)
        assert e.coordinates == ("th0", "th1")
        modes = normal_modes(tree_model, e.q, p)
        assert modes.stability == ("stable" if (s0, s1) == (-1, -1) else "unstable"), (s0, s1, modes)


def test_double_pendulum_against_lagrangian_twin(double_pendulum):
    """Same equilibria, force scales (what "F = 0" is judged against) and modes as the model compiled from T and V."""
    tree_model, twin = double_pendulum
    p = pendulum_parameters(1.3, 0.7, 0.6, 0.1, 0.45, -0.05, 1.1, 9.81)
    for q in closed_form_equilibria(p).values():
        e_tree = find_equilibrium(tree_model, nudged(q), p)
        e_twin = find_equilibrium(twin, nudged(q), p)
        assert e_tree.success and e_twin.success
        assert np.max(np.abs(e_tree.q - e_twin.q)) <= TOLERANCE
        tree_modes, twin_modes = normal_modes(tree_model, e_tree.q, p), normal_modes(twin, e_twin.q, p)
        assert np.allclose(tree_modes.linearization.force_scale, twin_modes.linearization.force_scale, rtol=1e-10,
                           atol=0)
        assert tree_modes.stability == twin_modes.stability
        assert np.allclose(np.sort_complex(tree_modes.eigenvalues), np.sort_complex(twin_modes.eigenvalues),
                           rtol=1e-10, atol=0)


def test_double_pendulum_find_equilibria_gets_all_four(double_pendulum):
    """The multistart over a box holding one copy of each equilibrium finds exactly those."""
    tree_model, _ = double_pendulum
    p = pendulum_parameters(1.0, 2.0, 0.5, 0.0, 0.4, 0.0, 1.0, 9.81)   # (α0 = α1 = 0: θ0, θ1 ∈ {±π/2}, {0, π})
    found = find_equilibria(tree_model, [(-2.0, 2.0), (-0.5, 3.5)], p)
    expected = sorted(closed_form_equilibria(p).values())
    expected = [(a, b % (2 * math.pi)) for a, b in expected]   # (θ1 = −π for the mixed ones: into the box)
    assert len(found) == 4, found
    assert np.max(np.abs(np.array([e.q for e in found]) - np.array(sorted(expected)))) <= TOLERANCE


@pytest.fixture(scope="module")
def spring_trees(cache_dir):
    """(a bob on a vertical slider with a spring, a pendulum with a torsional spring at its hinge), compiled."""
    k, r, m, g, c = sp.symbols("k r m g c")
    slider = lc.Tree([lc.Link("bob", lc.Prismatic("y", axis="y", stiffness=k, rest=r), mass=m)],
                     gravity=(0, -g, 0), name="sprung_slider")
    hinge = lc.Tree([lc.Link("arm", lc.Revolute("th", axis="z", stiffness=k, rest=r), mass=m, com=(c, 0, 0),
                             inertia=(0.01, 0.01, 0.01))], gravity=(0, -g, 0), name="sprung_hinge")
    return lc.compile(slider, cache_dir=cache_dir), lc.compile(hinge, cache_dir=cache_dir)


@settings(max_examples=15, deadline=None)
@given(k=st.floats(1.0, 1e4), r=st.floats(-2.0, 2.0), m=masses, g=st.floats(1.0, 20.0))
def test_sprung_slider_balances_weight(spring_trees, k, r, m, g):
    """m g = k (r − y*): a weight against a spring's pre-load (where ∂F/∂q q alone is no force scale at y* ≈ 0)."""
    slider, _ = spring_trees
    p = {"k": k, "r": r, "m": m, "g": g}
    y = r - m * g / k
    e = find_equilibrium(slider, [y + 0.3], p)
    assert e.success and e.steady
    assert abs(e.q[0] - y) <= TOLERANCE * max(1.0, abs(r), m * g / k)
    (only,) = find_equilibria(slider, (y - 1.0, y + 2.0), p)
    assert abs(only.q[0] - y) <= TOLERANCE * max(1.0, abs(r), m * g / k)
    assert normal_modes(slider, e.q, p).frequencies == pytest.approx([math.sqrt(k / m)], rel=1e-12)


@settings(max_examples=15, deadline=None)
@given(theta=st.floats(-3.0, 3.0), m=masses, c=lengths, g=st.floats(1.0, 20.0), stiffer=st.floats(1.5, 20.0))
def test_sprung_hinge_equilibrium(spring_trees, theta, m, c, g, stiffer):
    """k (θ* − r) = −m g c cos θ*: with the spring's rest angle r = θ* + m g c cos θ* / k, θ* is the equilibrium,
    the only one since k > m g c makes F strictly decreasing in θ."""
    _, hinge = spring_trees
    k = stiffer * m * g * c
    p = {"k": k, "r": theta + m * g * c * math.cos(theta) / k, "m": m, "g": g, "c": c}
    (only,) = find_equilibria(hinge, (-math.pi - 1.0, math.pi + 1.0), p)
    assert only.success and abs(only.q[0] - theta) <= TOLERANCE
    assert normal_modes(hinge, only.q, p).stability == "stable"


@pytest.fixture(scope="module")
def driven_cart(cache_dir):
    return lc.compile(cart_pole(), cache_dir=cache_dir)


def test_driven_cart_balance_is_instantaneous(driven_cart):
    """The cart's drive F sin(w t) (the only way a tree reads t) shifts x* = F sin(w t) / k: solved at t, but not
    steady; without drive (F = 0) the same equilibrium is steady."""
    p = {"M": 2.0, "m": 0.5, "c": 0.3, "J": 0.02, "g": 9.81, "k": 40.0, "b": 0.4, "F": 3.0, "w": 1.7, "e": 0.1}
    t = 0.6
    for th, stability in ((0.0, "asymptotically stable"), (math.pi, "unstable")):
        e = find_equilibrium(driven_cart, [0.2, th + 0.1], p, t=t)
        assert e.success and not e.steady, e
        assert np.max(np.abs(e.q - [p["F"] * math.sin(p["w"] * t) / p["k"], th])) <= TOLERANCE
        assert normal_modes(driven_cart, e.q, p, t=t).stability == stability
        still = find_equilibrium(driven_cart, [0.2, th + 0.1], {**p, "F": 0.0}, t=t)
        assert still.success and still.steady and np.max(np.abs(still.q - [0.0, th])) <= TOLERANCE


def test_closed_loop_tree_is_refused(cache_dir):
    """A tree with a cut joint is constrained: the equilibria need the loop's reactions, which are refused with
    the constraints named (as for a constrained System)."""
    rod = {"mass": 1.0, "com": (0.5, 0, 0), "inertia": (0, 0.1, 0.1)}
    four_bar = lc.Tree([
        lc.Link("crank", lc.Revolute("q1"), **rod),
        lc.Link("coupler", lc.Revolute("q2", origin=(1, 0, 0)), parent="crank", **rod),
        lc.Link("rocker", lc.Revolute("q3", origin=(2, 0, 0)), **rod),
    ], gravity=(0, -9.81, 0), name="statics_four_bar",
        loops=[lc.Loop("pin", ("coupler", (1, 0, 0)), ("rocker", (1, 0, 0)), directions="xy")])
    model = lc.compile(four_bar, cache_dir=cache_dir)
    for find in (lambda: find_equilibrium(model, [1.0, -1.0, 2.0]), lambda: find_equilibria(model, [(0, 1)] * 3)):
        with pytest.raises(ModelError, match=r"statics_four_bar.*constraints"):
            find()


def test_energy_portrait_of_a_sprung_hinge(spring_trees):
    """The phase portrait of a conservative 1-DoF tree: U(θ) = m g c sin θ + k (θ − r)² / 2 (gravity and the
    joint's spring), m(θ) = J + m c², the one equilibrium of `test_sprung_hinge_equilibrium`, stable."""
    _, hinge = spring_trees
    k, m, g, c, theta = 30.0, 1.2, 9.81, 0.5, 0.4
    p = {"k": k, "r": theta + m * g * c * math.cos(theta) / k, "m": m, "g": g, "c": c}
    portrait = phase_portrait(hinge, [5.0, 20.0], (-2.0, 2.5), p, samples=201)
    U = m * g * c * np.sin(portrait.q) + k * (portrait.q - p["r"]) ** 2 / 2
    assert np.max(np.abs(portrait.potential - U)) <= 1e-13 * np.max(np.abs(U))
    assert np.allclose(portrait.inertia, 0.01 + m * c**2, rtol=1e-14, atol=0)
    assert [abs(e.q[0] - theta) <= TOLERANCE for e in portrait.equilibria] == [True]
    assert portrait.stable == (True,)


def test_energy_portrait_of_a_damped_tree_is_refused(cache_dir):
    """A joint's damper makes the energy function not conserved: refused by name, as a System with dissipation."""
    damped = lc.Tree([lc.Link("arm", lc.Revolute("th", axis="z", damping=0.1), mass=1.0, com=(0.5, 0, 0),
                              inertia=(0.01, 0.01, 0.01))], gravity=(0, -9.81, 0), name="damped_arm")
    model = lc.compile(damped, cache_dir=cache_dir)
    with pytest.raises(ModelError, match=r"damped_arm.*dissipation"):
        phase_portrait(model, [1.0], (-1.0, 1.0))
    assert find_equilibrium(model, [-1.0]).q == pytest.approx([-math.pi / 2], abs=TOLERANCE)


def test_steady_motion_analyses_of_a_tree_are_refused(double_pendulum):
    """linearize_steady and stability_sweep reduce a System's symbolic equations: refused for a tree, by name,
    where before a tree model was called no Model; `normal_modes` at the equilibrium is what applies."""
    from lagcomp.analysis import linearize_steady, stability_sweep

    tree_model, _ = double_pendulum
    p = pendulum_parameters(1.0, 2.0, 0.5, 0.0, 0.4, 0.0, 1.0, 9.81)
    hanging = [-math.pi / 2, 0.0]
    with pytest.raises(ModelError, match=r"linearize_steady.*'planar_chain_2'"):
        linearize_steady(tree_model, hanging, [0.0, 0.0], p)
    with pytest.raises(ModelError, match=r"stability_sweep.*'planar_chain_2'"):
        stability_sweep(tree_model, "g", [1.0, 2.0], hanging, [0.0, 0.0], p)


@pytest.fixture(scope="module")
def universal_pendulum(cache_dir):
    """A link hanging from a universal joint (x, then y), centre of mass at (0, 0, −c), under gravity in any
    direction (gx, gy, gz): a 3D tree whose equilibria have a closed form."""
    gx, gy, gz, m, c = sp.symbols("gx gy gz m c")
    tree = lc.Tree([lc.Link("bob", lc.Universal(("a", "b")), mass=m, com=(0, 0, -c), inertia=(0.02, 0.03, 0.01))],
                   gravity=(gx, gy, gz), name="universal_pendulum")
    return lc.compile(tree, cache_dir=cache_dir)


@settings(max_examples=15, deadline=None)
@given(polar=st.floats(0.05, 1.2), quadrant=st.integers(0, 3), within=st.floats(0.1, 1.47), g=st.floats(1.0, 20.0),
       m=masses, c=lengths)
def test_universal_pendulum_hangs_along_gravity(universal_pendulum, polar, quadrant, within, g, m, c):
    """The centre of mass R_x(a) R_y(b) (0, 0, −c) = −c (sin b, −sin a cos b, cos a cos b) points along gravity ĝ
    at b* = −asin ĝx, a* = atan2(ĝy, −ĝz) (cos b* > 0): a minimum of V, stable; the opposite branch, pointing
    against gravity, unstable.

    (Gravity off the coordinate planes: where gx or gy is exactly 0, an equilibrium angle is exactly 0, F_i there
    is K a alone, and a converged a of 1e-47 leaves |F_i| equal to its own force scale: judged no equilibrium, as
    for a System: a limit of `lagcomp.analysis._common.force_scale`, not of the tree.)"""
    azimuth = quadrant * math.pi / 2 + within
    direction = np.array([math.sin(polar) * math.cos(azimuth), math.sin(polar) * math.sin(azimuth), -math.cos(polar)])
    p = {"gx": g * direction[0], "gy": g * direction[1], "gz": g * direction[2], "m": m, "c": c}
    hanging = np.array([math.atan2(direction[1], -direction[2]), -math.asin(direction[0])])
    upright = np.array([math.atan2(-direction[1], direction[2]), math.asin(direction[0])])
    for q, stability in ((hanging, "stable"), (upright, "unstable")):
        e = find_equilibrium(universal_pendulum, q + 0.05, p)
        assert e.success and e.steady
        assert np.max(np.abs(e.q - q)) <= TOLERANCE, (e.q, q)
        assert normal_modes(universal_pendulum, e.q, p).stability == stability
