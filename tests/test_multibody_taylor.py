"""The Taylor method on kinematic trees (lc.Tree, issue 39): the articulated-body recursion in series arithmetic
(`lagcomp.codegen.tree_taylor`).

References that share no code with the tree's Taylor program: the tree's q̈ in 40 digits from its description alone
(`lagcomp.accuracy.tree_reference`, d'Alembert's principle over forward kinematics), whose time derivatives along the
series give the coefficients of every order; the same system on the Lagrangian path (derived by sympy from T and V,
`multibody_models.lagrangian_system`) with its own Taylor program; dop853 at tight tolerance; and the invariants of a
conservative top on a ball joint (E, and the angular momentum about the vertical through the fixed point).
"""

from __future__ import annotations

import mpmath
import multibody_models as mm
import numpy as np
import pytest
import sympy as sp

import lagcomp as lc
from lagcomp.accuracy.tree_reference import tree_reference
from lagcomp.codegen.taylor import Unsupported
from lagcomp.codegen.tree_locals import tree_locals
from lagcomp.codegen.tree_taylor import tree_taylor_decomposition
from lagcomp.errors import OptionError
from lagcomp.multibody.mrp import (
    angular_velocity,
    mrp_from_rotation,
    mrp_rate,
    rotation,
)

#: Parameters of the tree_pair models used here (the examples' trees have free symbols, no defaults).
PARAMS = {
    "rigid_double_pendulum": dict(m0=1.0, c0=0.5, d0=0.1, J0=0.02, m1=0.7, c1=0.4, d1=-0.05, J1=0.03, l0=1.0, g=9.81),
    "cart_pole": dict(M=1.3, m=0.4, c=0.6, J=0.05, g=9.81, k=2.0, b=0.3, F=1.5, w=2.2, e=0.05),
}
STATES = {"rigid_double_pendulum": ([1.0, -0.5], [0.2, 0.1]), "cart_pole": ([0.1, 2.5], [-0.3, 1.0])}
ORDER = 30


def _top() -> lc.Tree:
    """An asymmetric heavy top on a ball joint (lc.Spherical: modified Rodrigues parameters, shadow switches)."""
    m, l, A, B, C, g = 2.0, 0.3, 0.03, 0.04, 0.05, 9.81
    return lc.Tree([lc.Link("top", lc.Spherical(("s1", "s2", "s3")), mass=m, com=(0, 0, l), inertia=(A, B, C))],
                   gravity=(0, 0, -g), name="taylor_top")


@pytest.fixture(scope="module")
def top(cache_dir):
    return lc.compile(_top(), cache_dir=cache_dir)


def _top_state(spin: float) -> np.ndarray:
    """The top tilted 0.5 rad about x, spinning at `spin` rad/s about its axis (and 0.3 rad/s about x)."""
    tilt = np.array([[1, 0, 0], [0, np.cos(0.5), -np.sin(0.5)], [0, np.sin(0.5), np.cos(0.5)]])
    sigma = mrp_from_rotation(tilt)
    return np.concatenate([sigma, mrp_rate(sigma, np.array([0.3, 0.0, spin]))])


def _coefficients(model, t: float, y, p) -> np.ndarray:
    X, W = np.empty((len(y), ORDER + 1)), np.empty((model.kernels.TAYLOR_WORK, ORDER + 1))
    assert model.kernels.taylor_coefficients(t, np.asarray(y, dtype=float), p, X, W) == 0
    return X


def _reference_coefficients(model, params: dict, tree: lc.Tree, t0: float, X: np.ndarray, orders: int,
                            degree: int = 40) -> np.ndarray:
    """(k + 1) X[n:, k + 1], k < `orders`, from the 40-digit q̈ of `tree_reference`: the Taylor coefficients of
    s ↦ q̈(t0 + s, c(s)), c the series X summed (which is y(t0 + s) to O(s^ORDER) if X is right), by interpolation at
    `degree` + 1 Chebyshev points within a quarter of the series' radius of convergence (estimated from the growth of
    its coefficients from order 15 to 30), in 60 digits.

    The reference reads the time and state as floats: (t0 + s, c(s)) rounded by (δt, δ) (known exactly) is corrected
    to first order, q̈(c) = q̈(ĉ) − J δ − ∂q̈/∂t δt, J and ∂q̈/∂t by central differences of the model's rhs (the
    correction is ~1e-16 |J|: its error is far below 1e-30).
    """
    n, reference = model.n, tree_reference(tree)
    half = ORDER // 2
    radius = 0.25 * (np.max(np.abs(X[:, ORDER])) / np.max(np.abs(X[:, half]))) ** (-1 / (ORDER - half))
    p = [*model.parameter_vector(params), 0.0, 0.0]       # (the reference reads Baumgarte's gains after them)
    with mpmath.workdps(60):
        nodes = [radius * mpmath.cos(mpmath.pi * (j + mpmath.mpf(0.5)) / (degree + 1)) for j in range(degree + 1)]
        samples = []
        for s in nodes:
            exact = [sum(mpmath.mpf(X[i, k]) * s**k for k in range(ORDER + 1)) for i in range(2 * n)]
            c = np.array([float(x) for x in exact])
            delta = np.array([float(mpmath.mpf(ci) - e) for ci, e in zip(c, exact)])
            ts, h = float(t0 + s), 1e-6
            delta_t = float(mpmath.mpf(ts) - (t0 + s))
            J = np.array([(model.rhs(ts, c + h * u, params) - model.rhs(ts, c - h * u, params)) / (2 * h)
                          for u in np.eye(2 * n)]).T
            rate = (model.rhs(ts + h, c, params) - model.rhs(ts - h, c, params)) / (2 * h)    # ∂f/∂t
            accelerations, _, _ = reference.evaluate(ts, c, p, 40)
            correction = J[n:] @ delta + rate[n:] * delta_t
            samples.append([mpmath.mpf(a) - mpmath.mpf(x) for a, x in zip(accelerations, correction)])
        V = mpmath.matrix([[s**k for k in range(degree + 1)] for s in nodes])
        fits = [mpmath.lu_solve(V, mpmath.matrix([sample[i] for sample in samples])) for i in range(n)]
        return np.array([[float(fit[k]) for k in range(orders)] for fit in fits])


def _relative_by_order(got: np.ndarray, want: np.ndarray) -> np.ndarray:
    """Per column (order): max |got − want| over the components, relative to max |want|."""
    return np.max(np.abs(got - want), axis=0) / np.max(np.abs(want), axis=0)


# -- the coefficients ------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("name", ["rigid_double_pendulum", "cart_pole"])
def test_coefficients_are_the_lagrangian_twins(tree_pair, name):
    """The same ODE in the same coordinates: the tree's series and the Lagrangian path's agree to every order
    (normwise per order, 1e-13 relative; the twin's q̈ is an LDLᵀ solve of sympy's M q̈ = F)."""
    tree_model, lagrange_model = tree_pair(name)
    q0, qd0 = STATES[name]
    y = np.array([*q0, *qd0])
    p = tree_model.parameter_vector(PARAMS[name])
    got = _coefficients(tree_model, 0.7, y, p)
    want = _coefficients(lagrange_model, 0.7, y, lagrange_model.parameter_vector(PARAMS[name]))
    assert np.all(_relative_by_order(got[:, 1:], want[:, 1:]) <= 1e-13)


@pytest.mark.parametrize("name", ["rigid_double_pendulum", "cart_pole", "top"])
def test_coefficients_against_the_40_digit_reference(tree_pair, top, name):
    """Orders 1 to 10 of q̈'s series against the derivatives of the 40-digit q̈ along the series (interpolated
    in 60 digits; measured agreement ≤ 2e-13 normwise per order): revolute joints, a ball joint's rational MRP
    functions, a prismatic joint with a time-dependent force."""
    if name == "top":
        model, tree, params, y, t0 = top, _top(), None, _top_state(6.0), 0.0
    else:
        model, tree, params, t0 = tree_pair(name)[0], mm.PAIRS[name](), PARAMS[name], 0.7
        y = np.array([*STATES[name][0], *STATES[name][1]])
    X = _coefficients(model, t0, y, model.parameter_vector(params))
    want = _reference_coefficients(model, params, tree, t0, X, orders=10)
    got = X[model.n:, 1:11] * np.arange(1, 11)
    assert np.all(_relative_by_order(got, want) <= 1e-12)


# -- runs ------------------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("name", ["rigid_double_pendulum", "cart_pole"])
def test_a_run_agrees_with_dop853_and_with_the_lagrangian_twins_taylor(tree_pair, name):
    """5 s of the double pendulum and of the cart-pole (prismatic cart, spring, damper, force F sin(w t), pendulum
    with a damper) at rtol = atol = 1e-13: Taylor's final state against dop853's on the same tree, and against the
    Taylor run of the Lagrangian twin (the same ODE, the driver on another program)."""
    tree_model, lagrange_model = tree_pair(name)
    q0, qd0 = STATES[name]
    run = dict(q0=q0, qd0=qd0, params=PARAMS[name], rtol=1e-13, atol=1e-13, t_eval=np.linspace(0, 5, 11))
    taylor = tree_model.simulate((0.0, 5.0), method="taylor", **run)
    dop853 = tree_model.simulate((0.0, 5.0), method="dop853", **run)
    twin = lagrange_model.simulate((0.0, 5.0), method="taylor", **run)
    assert taylor.status == dop853.status == twin.status == 0
    scale = np.max(np.abs(dop853.y))
    assert np.max(np.abs(taylor.y - dop853.y)) <= 5e-11 * scale      # (measured 8e-12, 1.1e-13)
    assert np.max(np.abs(taylor.y - twin.y)) <= 5e-13 * scale        # (measured 3.4e-14, 1.8e-16)


def test_a_top_on_a_ball_joint_keeps_its_invariants_over_many_shadow_switches(top):
    """An asymmetric heavy top (fixed point, gravity −z), 20 s at 60 rad/s of spin: the Taylor driver applies the
    ball joint's shadow switches (σ ↦ −σ/|σ|², events with resets) about 190 times; |σ| ≤ 1 throughout, E = T + V
    and the angular momentum about the vertical through the fixed point (gravity's moment is horizontal) stay
    constant: both within 2e-12 relative at rtol = atol = 3e-14 (measured: 2.7e-13 each)."""
    y0 = _top_state(60.0)
    sol = top.simulate((0.0, 20.0), q0=y0[:3], qd0=y0[3:], method="taylor", rtol=3e-14, atol=3e-14)
    assert sol.status == 0
    switches = sol.events["top_shadow"].t
    assert len(switches) > 150
    assert np.max(np.sum(sol.q**2, axis=1)) <= 1 + 1e-12
    assert sol.energy_drift() <= 2e-12
    sigma, rate = sol.q.T, sol.qd.T
    R, omega = np.array(rotation(sigma)), np.array(angular_velocity(sigma, rate))    # (3, 3, m), (3, m)
    m, l = 2.0, 0.3
    inertia = np.array([0.03 + m * l**2, 0.04 + m * l**2, 0.05])[:, None]     # about the fixed point (Steiner)
    Lz = np.einsum("jm,jm->m", R[2], inertia * omega)     # e_z · R I ω
    assert np.max(np.abs(Lz - Lz[0])) <= 2e-12 * np.max(np.abs(inertia * omega))


def test_sensitivities_by_taylor_agree_with_dop853(tree_pair):
    """simulate(..., sensitivities=...) with method="taylor" on a tree: the variational series of the tree's program
    (`lagcomp.codegen.taylor_variational`), against dop853's forward sensitivities (the tree's Jacobians)."""
    tree_model, _ = tree_pair("rigid_double_pendulum")
    q0, qd0 = STATES["rigid_double_pendulum"]
    run = dict(q0=q0, qd0=qd0, params=PARAMS["rigid_double_pendulum"], rtol=1e-13, atol=1e-13,
               sensitivities=["g", "th0"], t_eval=np.linspace(0, 1, 5))
    taylor = tree_model.simulate((0.0, 1.0), method="taylor", **run)
    dop853 = tree_model.simulate((0.0, 1.0), method="dop853", **run)
    assert taylor.sensitivity_names == dop853.sensitivity_names == ("q0:th0", "p:g")
    want = np.asarray(dop853.sensitivities)
    assert np.max(np.abs(np.asarray(taylor.sensitivities) - want)) <= 1e-11 * np.max(np.abs(want))   # (measured 7e-13)


# -- refusals --------------------------------------------------------------------------------------------------------


def _two_rods(**extra) -> lc.Tree:
    m, l = sp.symbols("m l")
    rod = {"mass": m, "com": (l / 2, 0, 0), "inertia": (0, m * l**2 / 12, m * l**2 / 12)}
    return lc.Tree([lc.Link("left", lc.Revolute("q1"), **rod),
                    lc.Link("right", lc.Revolute("q2", origin=(1, 0, 0)), **rod)],
                   name="taylor_rods", defaults={"m": 1.0, "l": 1.0}, **extra)


def test_a_closed_loop_is_refused(cache_dir):
    """A tree with a cut joint (lc.Loop) moves by an augmented solve with multipliers: method="taylor" is refused
    naming the constraint, and its Taylor program says why it has none."""
    l = sp.Symbol("l")
    tree = _two_rods(loops=[lc.Loop("pin", ("left", (l, 0, 0)), ("right", (l, 0, 0)), directions="x")])
    refusal = tree_taylor_decomposition(tree, tree_locals(tree))
    assert isinstance(refusal, Unsupported) and "closed loops (pin_x" in str(refusal)
    with pytest.raises(OptionError, match=r"`taylor` does not handle constraints yet; 'taylor_rods' has \['pin_x'\]"):
        lc.compile(tree, cache_dir=cache_dir).simulate((0, 1), q0=[0.5, np.pi - 0.5], qd0=[0.0, 0.0], method="taylor")


def test_functions_without_a_recurrence_are_refused():
    """A joint torque with sign (Coulomb friction): no Taylor program, saying why (``TAYLOR_REFUSED``, which
    `simulate` raises as taylor-not-applicable).  Contacts have programs (tests/test_multibody_taylor_contacts.py)."""
    q = lc.coordinates("q")[0]
    rubbing = lc.Tree([lc.Link("rod", lc.Revolute(q, torque=-sp.sign(q.diff(lc.t))), mass=1, com=(1, 0, 0))],
                      name="taylor_rubbing")
    refusal = tree_taylor_decomposition(rubbing, tree_locals(rubbing))
    assert isinstance(refusal, Unsupported) and "sign" in str(refusal)


@pytest.mark.slow     # (numba compiles the lane kernels: 162 s wall with the pair's compile, on the loaded machine)
def test_a_batched_taylor_sweep_agrees_with_dop853(tree_pair):
    """sweep(..., method="taylor", batched=True) on a tree: the lane kernels written from the tree's program
    (`lagcomp.codegen.taylor_lanes`), final states against a dop853 sweep at the same tolerance."""
    tree_model, _ = tree_pair("rigid_double_pendulum")
    q0, qd0 = STATES["rigid_double_pendulum"]
    run = dict(params=PARAMS["rigid_double_pendulum"], q0=q0, qd0=qd0, rtol=1e-12, atol=1e-12)
    grid = {"g": [9.0, 9.81], "m1": [0.5, 0.7]}
    taylor = tree_model.sweep((0.0, 1.0), grid, method="taylor", batched=True, **run)
    dop853 = tree_model.sweep((0.0, 1.0), grid, method="dop853", **run)
    assert np.all(taylor.status == 0)
    want = np.asarray(dop853.final)
    assert np.max(np.abs(np.asarray(taylor.final) - want)) <= 1e-10 * np.max(np.abs(want))
