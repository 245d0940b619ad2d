"""The energy balance of kinematic trees (issue 39): the ``power`` kernel of a tree (`lagcomp.codegen.tree_power`).

References nobody here wrote: the Lagrangian path's ``power`` kernel (`lagcomp.codegen.power`, sympy's
derivatives of T and V) on the same chains as lc.System twins (`multibody_models.lagrangian_system`: the dampers
among the generalized forces there, so its "forces" term is the tree's "forces" + "dissipation"); the closed forms
−Σ c q̇² of the dampers and ω·τ − c|ω|² of a ball joint, ω from σ̇ by the MRP kinematics σ̇ = ¼ B(σ) ω solved in
numpy; and the balance itself: h(t) − h(0) against the integrated power, whose residual is the integration's error.
"""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp
from multibody_models import cart_pole, lagrangian_system

import lagcomp as lc

RTOL = 1e-10
#: The saved rows: dense enough that the quadrature of the power is not the residual (`quadrature_error`).
DENSE = np.linspace(0.0, 5.0, 2501)
CART_POLE = {"M": 1.3, "m": 0.7, "c": 0.4, "J": 0.05, "g": 9.81, "k": 2.0, "b": 0.3, "F": 1.5, "w": 2.0, "e": 0.1}


def _swinging_chain() -> lc.Tree:
    """Three links on unrotated joints (a revolute about y, a prismatic with a spring along y, a revolute about x),
    dampers, and torques that read t, q and q̇."""
    a, b, g = sp.symbols("a b g")
    q0, q1, q2 = lc.coordinates("q0 q1 q2")
    links = [
        lc.Link("l0", lc.Revolute(q0, axis="y", damping=0.2, torque=a * sp.cos(2 * lc.t)), mass=1.2,
                com=(0.3, 0.1, -0.2), inertia=(0.1, 0.2, 0.15)),
        lc.Link("l1", lc.Prismatic(q1, axis="y", origin=(0.5, 0, 0), stiffness=3.0, damping=b,
                                   torque=-0.4 * q1.diff(lc.t)), parent="l0", mass=0.8, com=(0, 0.2, 0.1),
                inertia=(0.05, 0.04, 0.06)),
        lc.Link("l2", lc.Revolute(q2, axis="x", origin=(0, 0.4, -0.1), damping=0.05, torque=0.3 * sp.sin(q0)),
                parent="l1", mass=0.5, com=(0, 0, -0.3), inertia=(0.02, 0.03, 0.01)),
    ]
    return lc.Tree(links, gravity=(0, 0, -g), name="power_chain")


CHAIN = {"a": 0.7, "b": 0.35, "g": 9.81}


@pytest.mark.parametrize(("build", "params"), [(cart_pole, CART_POLE), (_swinging_chain, CHAIN)])
def test_power_is_the_lagrangian_twins(cache_dir, build, params):
    tree = build()
    model = lc.compile(tree, cache_dir=cache_dir)
    twin = lc.compile(lagrangian_system(tree), cache_dir=cache_dir)
    p, p_twin = model.parameter_vector(params), twin.parameter_vector(params)
    dampers = np.array([float(sp.sympify(node.joint.damping).subs(params)) for node in tree.nodes])
    rng = np.random.default_rng(7)
    got, expected = np.empty(4), np.empty(4)
    for _ in range(20):
        y, time = rng.normal(size=2 * model.n), float(rng.uniform(-3, 3))
        assert model.kernels.power(time, y, p, np.empty(0), got) == 0
        twin.kernels.power(time, y, p_twin, np.empty(0), expected)
        scale = 1 + np.abs(expected).max()
        assert got[0] + got[1] == pytest.approx(expected[0], abs=1e-12 * scale)   # (the twin's dampers are forces)
        assert got[1] == pytest.approx(-np.sum(dampers * y[model.n:] ** 2), abs=1e-12 * scale)
        assert got[2] == pytest.approx(expected[2], abs=1e-12 * scale) and got[3] == expected[3] == 0


@pytest.mark.parametrize(("build", "params"), [(cart_pole, CART_POLE), (_swinging_chain, CHAIN)])
def test_a_damped_forced_tree_balances_to_the_integration_error(cache_dir, build, params):
    model = lc.compile(build(), cache_dir=cache_dir)
    q0 = np.linspace(0.1, 0.5, model.n)

    def balance(rtol):
        sol = model.simulate((0, 5), q0=q0, qd0=np.zeros(model.n), params=params, rtol=rtol, atol=rtol * 1e-2,
                             t_eval=DENSE)
        return sol.energy_balance()

    b = balance(RTOL)
    assert b.quantity == "T + V"
    assert b.work["dissipation"][-1] < -0.05 and np.max(np.abs(b.work["forces"])) > 0.05   # (not a first integral)
    assert b.relative_residual < 10 * RTOL and b.quadrature_error < RTOL * b.scale
    assert balance(1e-6).relative_residual > 100 * b.relative_residual   # (the residual is the integration's)


def _ball_tree() -> lc.Tree:
    """A link on a ball joint (damper c, a body-frame moment that reads t and σ̇) under gravity."""
    c = sp.Symbol("c")
    sx, sy, sz = lc.coordinates("sx sy sz")
    joint = lc.Spherical((sx, sy, sz), damping=c, torque=(0.3 * sp.cos(lc.t), -0.2, 0.1 * sz.diff(lc.t)))
    link = lc.Link("body", joint, mass=1.5, com=(0.1, 0.0, -0.4), inertia=(0.2, 0.3, 0.25))
    return lc.Tree([link], gravity=(0, 0, -9.81), name="power_ball")


def _body_rates(sigma, sigma_dot) -> np.ndarray:
    """ω from σ̇ = ¼ ((1 − σ·σ) 1 + 2 [σ]× + 2 σ σᵀ) ω."""
    skew = np.array([[0, -sigma[2], sigma[1]], [sigma[2], 0, -sigma[0]], [-sigma[1], sigma[0], 0]])
    B = (1 - sigma @ sigma) * np.eye(3) + 2 * skew + 2 * np.outer(sigma, sigma)
    return np.linalg.solve(B / 4, sigma_dot)


def test_a_ball_joints_power_is_omega_dot_tau(cache_dir):
    model = lc.compile(_ball_tree(), cache_dir=cache_dir)
    p = model.parameter_vector({"c": 0.15})
    rng = np.random.default_rng(3)
    got = np.empty(4)
    for _ in range(20):
        sigma, sigma_dot, time = rng.uniform(-0.6, 0.6, 3), rng.normal(size=3), float(rng.uniform(-3, 3))
        model.kernels.power(time, np.concatenate([sigma, sigma_dot]), p, np.empty(0), got)
        w = _body_rates(sigma, sigma_dot)
        tau = np.array([0.3 * np.cos(time), -0.2, 0.1 * sigma_dot[2]])
        assert got[0] == pytest.approx(w @ tau, abs=1e-12 * (1 + abs(w @ tau)))
        assert got[1] == pytest.approx(-0.15 * w @ w, abs=1e-12 * (1 + w @ w))
        assert got[2] == got[3] == 0
    sol = model.simulate((0, 5), q0=[0.2, -0.1, 0.3], qd0=[0.5, 0.0, -0.4], params={"c": 0.15}, rtol=RTOL,
                         atol=RTOL * 1e-2, t_eval=DENSE)
    b = sol.energy_balance()
    assert b.work["dissipation"][-1] < -0.01 and b.relative_residual < 10 * RTOL
    assert b.quadrature_error < RTOL * b.scale


def test_a_sweep_of_a_damped_tree_reports_the_balance(cache_dir):
    model = lc.compile(cart_pole(), cache_dir=cache_dir)
    options = {"q0": [0.1, 0.5], "qd0": [0.0, 0.0], "rtol": RTOL, "atol": RTOL * 1e-2}
    sweep = model.sweep((0, 4), {"b": [0.0, 0.3, 1.0]}, params=CART_POLE, output="energy", **options)
    assert sweep.energy_balance and np.all(sweep.energy_error < 1e-8)



def _damped_four_bar() -> lc.Tree:
    """A four-bar linkage as a tree with its pin at B cut (`lc.Loop`): crank O→A driven and damped, coupler A→B
    damped, rocker D→B; uniform thin rods along x, gravity −y."""
    def rod(mass, length):
        return {"mass": mass, "com": (length / 2, 0, 0), "inertia": (0, mass * length**2 / 12, mass * length**2 / 12)}

    a, b, c, d = 0.6, 1.4, 1.1, 1.5
    return lc.Tree([
        lc.Link("crank", lc.Revolute("theta1", damping=0.3, torque=0.5 * sp.cos(2 * lc.t)), **rod(1.0, a)),
        lc.Link("coupler", lc.Revolute("phi2", origin=(a, 0, 0), damping=0.1), parent="crank", **rod(1.5, b)),
        lc.Link("rocker", lc.Revolute("theta3", origin=(d, 0, 0)), **rod(1.2, c)),
    ], gravity=(0, -9.81, 0), name="power_four_bar",
        loops=[lc.Loop("pin", ("coupler", (b, 0, 0)), ("rocker", (c, 0, 0)), directions="xy")])


def _closed_angles(theta1: float) -> list:
    """(θ1, φ2, θ3) with the pin closed: B where the circles of radius b about A and c about D meet (above AD)."""
    a, b, c, d = 0.6, 1.4, 1.1, 1.5
    A, D = a * np.array([np.cos(theta1), np.sin(theta1)]), np.array([d, 0.0])
    gap = np.linalg.norm(D - A)
    along = (b**2 - c**2 + gap**2) / (2 * gap)
    unit = (D - A) / gap
    B = A + along * unit + np.sqrt(b**2 - along**2) * np.array([-unit[1], unit[0]])
    theta2 = np.arctan2(*(B - A)[::-1])
    return [theta1, theta2 - theta1, np.arctan2(*(B - D)[::-1])]


def test_a_loops_constraint_forces_do_no_work(cache_dir):
    """The balance of a damped, driven four-bar closes with the torques and dampers alone: the loop's reactions
    λ do no work (b = 0, Λ q̇ = 0 along the motion), so their term is zero and the residual the integration's."""
    model = lc.compile(_damped_four_bar(), cache_dir=cache_dir)
    sol = model.simulate((0, 5), q0=_closed_angles(1.0), qd0=[0.0, 0.0, 0.0], rtol=RTOL, atol=RTOL * 1e-2,
                         t_eval=DENSE)
    b = sol.energy_balance()
    assert b.work["dissipation"][-1] < -0.1 and not np.any(b.work["constraints"])
    assert b.relative_residual < 10 * RTOL and b.quadrature_error < RTOL * b.scale
