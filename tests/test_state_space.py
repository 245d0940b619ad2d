"""State-space models for control (issue 37, part 5): A, B of a cart-pole against the closed form derived here,
B against central differences of Model.rhs, a constrained cart-pole's transfer function against the
unconstrained one, and an LQR design (scipy's Riccati solver) that balances the nonlinear model in simulation.

The cart-pole: cart mass M at x, a point mass m at distance l on the pole, θ from the upright, a force F on
the cart.  T = ½(M + m)ẋ² + m l ẋ θ̇ cos θ + ½ m l² θ̇², V = m g l cos θ.  About θ = 0 (q̇ = 0):
M₀ = [[M + m, m l], [m l, m l²]] (det M m l²), −∂V/∂θ ≈ m g l θ, so
    ẍ = (F − m g θ) / M,        θ̈ = ((M + m) g θ − F) / (M l),
A = [[0, I], [[0, −m g / M], [0, (M + m) g / (M l)]], 0]], B = [0, 0, 1/M, −1/(M l)]ᵀ.
"""

from __future__ import annotations

import numba
import numpy as np
import pytest
import sympy as sp
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import linalg, signal

import lagcomp as lc
from lagcomp import analysis as an
from lagcomp.model import t

x, th, px, py = lc.coordinates("x th px py")
M, m, l, g = sp.symbols("M m l g", positive=True)
DEFAULTS = {"M": 1.0, "m": 0.1, "l": 0.5, "g": 9.81}


def cart_pole() -> lc.System:
    T = (M + m) * x.diff(t) ** 2 / 2 + m * l * x.diff(t) * th.diff(t) * sp.cos(th) + m * l**2 * th.diff(t) ** 2 / 2
    return lc.System([x, th], T=T, V=m * g * l * sp.cos(th), forces=[lc.Input("F"), 0], name="ss_cart_pole",
                     defaults=DEFAULTS)


@pytest.fixture(scope="module")
def model(cache_dir):
    return lc.compile(cart_pole(), cache_dir=cache_dir)


def closed_form(M_, m_, l_, g_):
    A = np.zeros((4, 4))
    A[0, 2] = A[1, 3] = 1.0
    A[2, 1], A[3, 1] = -m_ * g_ / M_, (M_ + m_) * g_ / (M_ * l_)
    return A, np.array([[0.0], [0.0], [1 / M_], [-1 / (M_ * l_)]])


def test_linearize_steady_with_an_input(model):
    # was: NameError: name 'F' is not defined (the form's lambdified functions met the input F(t))
    system = cart_pole()
    A, B = closed_form(1.0, 0.1, 0.5, 9.81)
    for source in (model, system):
        steady = an.linearize_steady(source, [0.0, 0.0], inputs={"F": 0.0})
        assert steady.states == ("x", "th", "x_dot", "th_dot") and steady.inputs == ("F",)
        assert np.allclose(steady.A, A, rtol=1e-13, atol=1e-13) and np.allclose(steady.B, B, rtol=1e-13, atol=0)
    sweep = an.stability_sweep(system, "m", [0.1, 0.2, 0.3], [0.0, 0.0], inputs={"F": 0.0})
    assert sweep.unstable.all()      # the inverted pendulum, for every mass
    # θ̈ = ((M + m) g θ − F)/(M l): the growth rate √((M + m) g/(M l)) at m = 0.3
    assert sweep.growth[-1] == pytest.approx(np.sqrt(1.3 * 9.81 / 0.5), rel=1e-12)
    with pytest.raises(lc.OptionError, match=r"input\(s\) \['F'\]"):
        an.linearize_steady(system, [0.0, 0.0])
    with pytest.raises(lc.OptionError, match=r"input\(s\) \['F'\]"):
        an.stability_sweep(system, "m", [0.1, 0.2], [0.0, 0.0])


@settings(max_examples=20, deadline=None)
@given(st.floats(0.5, 5.0), st.floats(0.05, 2.0), st.floats(0.2, 3.0), st.floats(1.0, 20.0))
def test_cart_pole_closed_form(model, M_, m_, l_, g_):
    params = {"M": M_, "m": m_, "l": l_, "g": g_}
    space = an.linearize(model, [0.0, 0.0], params, inputs={"F": 0.0}).state_space()
    A, B = closed_form(M_, m_, l_, g_)
    assert np.allclose(space.A, A, rtol=1e-12, atol=1e-12 * np.max(np.abs(A)))
    assert np.allclose(space.B, B, rtol=1e-12, atol=1e-12 * np.max(np.abs(B)))
    assert space.states == ("x", "th", "x_dot", "th_dot") and space.inputs == ("F",)


def test_input_jacobian_against_differences_of_rhs(model, rng):
    for _ in range(5):
        y, F, time = rng.normal(size=4), float(rng.normal()), float(rng.uniform(0, 3))
        exact = model.rhs_input_jacobian(time, y, inputs={"F": F})[:, 0]
        h = 1e-5
        central = (model.rhs(time, y, inputs={"F": F + h}) - model.rhs(time, y, inputs={"F": F - h})) / (2 * h)
        # the rhs is affine in F: central differences are exact up to rounding
        assert np.allclose(exact, central, rtol=1e-8, atol=1e-9)
        assert exact[0] == exact[1] == 0.0


def test_constrained_cart_pole_has_the_same_transfer_function(model, cache_dir):
    # the pole's mass at (px, py) on a rod of length l from the cart: (px − x)² + py² = l²
    rod = lc.System([x, px, py], T=M * x.diff(t) ** 2 / 2 + m * (px.diff(t) ** 2 + py.diff(t) ** 2) / 2, V=m * g * py,
                    forces=[lc.Input("F"), 0, 0], constraints=[lc.Holonomic("rod", (px - x) ** 2 + py**2 - l**2)],
                    name="ss_cart_pole_rod", defaults=DEFAULTS)
    steady = an.linearize_steady(lc.compile(rod, cache_dir=cache_dir), [0.0, 0.0, 0.5], inputs={"F": 0.0},
                                 independent=["x", "px", "x_dot", "px_dot"])
    plain = an.linearize(model, [0.0, 0.0], inputs={"F": 0.0}).state_space(outputs=["x"])
    rodded = steady.state_space(outputs=["x"])
    for s in (0.3, 1.0 + 2.0j, 7.0j):
        G = [(sys.C @ linalg.solve(s * np.eye(sys.A.shape[0]) - sys.A, sys.B))[0, 0] for sys in (plain, rodded)]
        assert G[1] == pytest.approx(G[0], rel=1e-10)


def test_lqr_balances_the_nonlinear_cart_pole(model):
    space = an.linearize(model, [0.0, 0.0], inputs={"F": 0.0}).state_space()
    Q, R = np.diag([1.0, 10.0, 1.0, 1.0]), np.array([[0.1]])
    P = linalg.solve_continuous_are(space.A, space.B, Q, R)
    gains = linalg.solve(R, space.B.T @ P)[0]
    assert np.all(linalg.eigvals(space.A - space.B @ gains[None, :]).real < 0)
    k0, k1, k2, k3 = (float(k) for k in gains)

    @numba.njit
    def feedback(time, y, p):
        return -(k0 * y[0] + k1 * y[1] + k2 * y[2] + k3 * y[3])

    start = ([0.1, 0.25], [0.0, 0.0])      # 0.25 rad ≈ 14° off the upright
    closed = model.simulate((0.0, 15.0), *start, inputs={"F": feedback}, rtol=1e-9, atol=1e-11)
    opened = model.simulate((0.0, 15.0), *start, inputs={"F": 0.0}, rtol=1e-9, atol=1e-11)
    assert closed.success and np.max(np.abs(closed.y[-1])) < 1e-4
    assert np.max(np.abs(opened.q[:, 1])) > 3.0    # without the controller it falls over


def test_conversions(model):
    space = an.linearize(model, [0.0, 0.0], inputs={"F": 0.0}).state_space(outputs=["x", "th"])
    scipy_system = space.to_scipy()
    assert isinstance(scipy_system, signal.StateSpace)
    assert np.array_equal(scipy_system.A, space.A) and np.array_equal(scipy_system.C, [[1, 0, 0, 0], [0, 1, 0, 0]])
    assert np.array_equal(space.D, np.zeros((2, 1)))
    control = pytest.importorskip("control")
    converted = space.to_control()
    assert isinstance(converted, control.StateSpace) and np.array_equal(converted.B, space.B)


def test_refusals(model, cache_dir):
    support = lc.System([x], T=m * (x.diff(t) + lc.Input("s").diff(t)) ** 2 / 2, V=g * x**2 / 2,
                        name="ss_support", defaults={"m": 1.0, "g": 4.0})
    shaken = lc.compile(support, cache_dir=cache_dir)
    with pytest.raises(lc.LinearizationError, match=r"\['s'\]"):
        an.linearize(shaken, [0.0], inputs={"s": 0.0}).state_space()
    with pytest.raises(lc.LinearizationError, match=r"\['s'\]"):
        an.linearize_steady(support, [0.0], inputs={"s": 0.0}).state_space()
    with pytest.raises(lc.OptionError, match="Unknown output"):
        an.linearize(model, [0.0, 0.0], inputs={"F": 0.0}).state_space(outputs=["y"])
    with pytest.raises(lc.OptionError, match="inputs="):
        model.rhs(0.0, np.zeros(4))


def test_reaction_outputs_of_a_pendulum_held_aside():
    # a bob on a rod (x² + y² = l²) held at θ0 by a horizontal force F0 = m g tan θ0.  Along the rod the
    # tension is T = m g cos θ + F sin θ + m l θ̇², and λ = −T/(2l) (Λ = 2(x, y)), so about θ0:
    # δT = (F0 cos θ0 − m g sin θ0) δθ + sin θ0 δF = sin θ0 δF: C = 0, D = −sin θ0/(2l)
    x_, y_ = lc.coordinates("x y")
    bob = lc.System([x_, y_], T=m * (x_.diff(t) ** 2 + y_.diff(t) ** 2) / 2, V=m * g * y_,
                    forces=[lc.Input("F"), 0], constraints=[lc.Holonomic("rod", x_**2 + y_**2 - l**2)],
                    name="ss_held_bob", defaults={"m": 0.7, "g": 9.81, "l": 1.3})
    th0 = 0.5
    steady = an.linearize_steady(bob, [1.3 * np.sin(th0), -1.3 * np.cos(th0)], inputs={"F": 0.7 * 9.81 * np.tan(th0)},
                                 independent=["x", "x_dot"])
    assert steady.residual < 1e-12
    assert steady.reactions["rod"][2] == pytest.approx(-0.7 * 9.81 / np.cos(th0) / 2.6, rel=1e-13)
    space = steady.state_space(outputs=["x", "rod"])
    assert space.outputs == ("x", "rod") and np.array_equal(space.C[0], [1.0, 0.0]) and space.D[0, 0] == 0.0
    assert np.allclose(space.C[1], 0.0, atol=1e-13) and space.D[1, 0] == pytest.approx(-np.sin(th0) / 2.6, rel=1e-13)


# -- points of bodies as outputs: C rows against differences of the geometry kernel's positions ------------------

a, W = sp.symbols("a W", positive=True)


@pytest.fixture(scope="module")
def shaken_arm(cache_dir):
    """A cart at x with an arm of two bodies: a bob at angle th, and a tip whose pivot is shaken, x + a sin(W t):
    positions that depend on q and t (∂²r/∂q∂t ≠ 0 through the tip's rotating offset)."""
    cart = lc.Particle(M, (x, 0, 0), name="cart")
    bob = lc.Particle(m, (x + l * sp.sin(th), l * sp.cos(th), 0), name="bob")
    tip = lc.Particle(m, (x + a * sp.sin(W * t) + l * sp.sin(th + W * t), l * sp.cos(th + W * t), 0), name="tip")
    system = lc.System([x, th], bodies=[cart, bob, tip], loads=[lc.Gravity((0, -g, 0))], forces=[lc.Input("F"), 0],
                       name="ss_shaken_arm", defaults={**DEFAULTS, "a": 0.3, "W": 1.7})
    return lc.compile(system, cache_dir=cache_dir)


def _positions(model, t_, q, p):
    out = np.empty(model.kernels.GEOMETRY_SIZE)
    model.kernels.geometry(float(t_), np.concatenate([q, np.zeros(2)]), p, out)
    return out


@settings(max_examples=10, deadline=None)
@given(st.floats(-1.0, 1.0), st.floats(-3.0, 3.0), st.floats(0.0, 5.0))
def test_body_points_against_differences_of_positions(shaken_arm, x_, th_, t_):
    names = [f"{body}.{part}" for body in ("cart", "bob", "tip") for part in ("x", "y", "vx", "vy")]
    lin = an.linearize(shaken_arm, [x_, th_], t=t_, inputs={"F": 0.0}, outputs=["th", *names])
    space = lin.state_space()
    assert space.outputs == ("th", *names) and np.array_equal(space.C[0], [0, 1, 0, 0]) and not space.D.any()
    p, q, h = shaken_arm.parameter_vector(inputs={"F": 0.0}), np.array([x_, th_]), 1e-5
    offsets = {name: offset for name, _, offset in shaken_arm.kernels.GEOMETRY}

    def r(q_, time):
        return _positions(shaken_arm, time, q_, p)

    def v(q_, qd_, time):        # the velocity along the motion through (q_, qd_) at `time`: d r / dt
        return (r(q_ + h * qd_, time + h) - r(q_ - h * qd_, time - h)) / (2 * h)

    e = np.eye(2)
    dr_dq = np.stack([(r(q + h * e[j], t_) - r(q - h * e[j], t_)) / (2 * h) for j in range(2)], axis=1)
    dv_dq = np.stack([(v(q + 1e-3 * e[j], np.zeros(2), t_) - v(q - 1e-3 * e[j], np.zeros(2), t_)) / 2e-3
                      for j in range(2)], axis=1)
    dv_dqd = np.stack([v(q, e[j], t_) for j in range(2)], axis=1) - v(q, np.zeros(2), t_)[:, None]
    for row, name in zip(space.C[1:], names, strict=True):
        body, _, part = name.partition(".")
        i = offsets[body] + ("x", "y").index(part[-1])
        expected = (np.concatenate([dr_dq[i], [0, 0]]) if part in ("x", "y")
                    else np.concatenate([dv_dq[i], dv_dqd[i]]))
        assert row == pytest.approx(expected, abs=2e-6 * max(1.0, np.abs(expected).max()))


def test_body_point_outputs_of_the_cart_pole_closed_form(shaken_arm):
    # about the upright (x, θ) = 0 at t = 0 the bob is at (x + l sin θ, l cos θ): δx_bob = δx + l δθ, δy_bob = 0,
    # δvx_bob = δẋ + l δθ̇; the transfer function F → x_bob is C (sI − A)⁻¹ B of those rows
    lin = an.linearize(shaken_arm, [0.0, 0.0], inputs={"F": 0.0}, outputs=["bob.x", "bob.y", "bob.vx"])
    space = lin.state_space()
    assert np.array_equal(space.C, [[1, 0.5, 0, 0], [0, 0, 0, 0], [0, 0, 1, 0.5]])
    assert lin.state_space(["x", "bob.x"]).outputs == ("x", "bob.x")
    with pytest.raises(lc.OptionError, match=r"'pole.x'.*\['bob', 'cart', 'tip'\]"):
        an.linearize(shaken_arm, [0.0, 0.0], inputs={"F": 0.0}, outputs=["pole.x"])
    with pytest.raises(lc.OptionError, match="Unknown output"):
        lin.state_space(["tip.x"])     # (not asked of linearize: its row was not computed)
    pytest.importorskip("control")
    converted = space.to_control()      # (python-control refuses '.' in names)
    assert converted.output_labels == ["bob_x", "bob_y", "bob_vx"] and np.array_equal(converted.C, space.C)


def test_python_control_lqr_stabilises_the_cart_pole_of_bodies(shaken_arm):
    # the gallery's design (docs/gallery/workflows/plot_lqr_cart_pole.py): gains from control.lqr on to_control()
    control = pytest.importorskip("control")
    space = an.linearize(shaken_arm, [0.0, 0.0], params={"a": 0.0, "W": 0.0}, inputs={"F": 0.0},
                         outputs=["bob.x"]).state_space()
    gains, _, poles = control.lqr(space.to_control(), np.diag([1.0, 10.0, 1.0, 1.0]), np.array([[0.1]]))
    assert np.all(np.real(poles) < 0)
    k0, k1, k2, k3 = (float(k) for k in np.asarray(gains)[0])

    @numba.njit
    def feedback(t_, y_, p_):
        return -(k0 * y_[0] + k1 * y_[1] + k2 * y_[2] + k3 * y_[3])

    params = {"a": 0.0, "W": 0.0}
    held = shaken_arm.simulate((0.0, 8.0), [0.1, 0.25], [0.0, 0.0], params=params, inputs={"F": feedback})
    free = shaken_arm.simulate((0.0, 8.0), [0.1, 0.25], [0.0, 0.0], params=params, inputs={"F": 0.0})
    assert np.max(np.abs(held.q[-1])) < 1e-3 and np.max(np.abs(free.q[:, 1])) > 1.0
