"""Statics, small oscillations, conserved quantities and phase portraits against closed forms.

Every reference here is derived by hand (in the docstrings) from the
example's Lagrangian, independently of the kernels: the wheel jack's balance
by virtual work, the spun hoop's relative equilibria and their frequency,
the double pendulum's 2×2 frequency equation, the unbalanced cylinder's
energy integral.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import sympy as sp

import lagcomp as lc
from lagcomp import analysis as an
from lagcomp import examples
from lagcomp.mechanics.lagrange import derive, rest_partials

t = lc.t


# -- the rest-partials kernel ---------------------------------------------------------------


def _gyroscopic_system() -> lc.System:
    """A particle in a trap turning at a time-dependent rate, damped, with a circulatory force.

    T = ½ m ((ẋ − w y)² + (ẏ + w x)²), w = Ω (1 + ε sin t): an offset b(q, t) (gyroscopic terms),
    M constant; plus a mass varying in time along x, a damper and a force −κ y on x.
    """
    x, y = lc.coordinates("x y")
    m, Omega, eps, k1, k2, c, kappa, mu = sp.symbols("m Omega epsilon k1 k2 c kappa mu", positive=True)
    w = Omega * (1 + eps * sp.sin(t))
    xd, yd = x.diff(t), y.diff(t)
    T = m * ((xd - w * y) ** 2 + (yd + w * x) ** 2) / 2 + mu * sp.cos(t) ** 2 * xd**2 / 2
    return lc.System([x, y], T=T, V=(k1 * x**2 + k2 * y**2) / 2 + x**2 * y, dissipation=c * (xd**2 + xd * yd),
                     forces=[-kappa * y * (1 + yd**2), 0], name="gyro_trap")


@pytest.mark.parametrize("factory", [_gyroscopic_system, lambda: examples.get("turn_indicator"),
                                     lambda: examples.get("hoop_bead"), lambda: examples.get("symmetric_top")])
def test_rest_partials_equal_the_jacobian_of_F_at_rest(factory):
    eom = derive(factory())
    F_q, F_v = rest_partials(eom)
    at_rest = {v: 0 for v in eom.qd}
    direct_q = eom.F.jacobian(eom.q).xreplace(at_rest)
    direct_v = eom.F.jacobian(eom.qd).xreplace(at_rest)
    assert sp.simplify(F_q - direct_q) == sp.zeros(eom.n)
    assert sp.simplify(F_v - direct_v) == sp.zeros(eom.n)


def test_rest_partials_kernel_ignores_the_velocities(compiled, rng):
    model = compiled("double_pendulum")
    p = model.parameter_vector()
    y = rng.normal(size=4)
    out = np.empty((2, 2, 2))
    model.kernels.rest_partials(0.0, y, p, out)
    still = y.copy()
    still[2:] = 0.0
    again = np.empty((2, 2, 2))
    model.kernels.rest_partials(0.0, still, p, again)
    np.testing.assert_array_equal(out, again)
    # ∂F/∂q at rest by central differences of the compiled forcing
    h = 1e-6
    for j in range(2):
        plus, minus = still.copy(), still.copy()
        plus[j] += h
        minus[j] -= h
        column = (model.forcing(plus[:2], [0, 0]) - model.forcing(minus[:2], [0, 0])) / (2 * h)
        np.testing.assert_allclose(out[0][:, j], column, rtol=1e-7, atol=1e-7)


# -- statics: the wheel jack ----------------------------------------------------------------


def test_wheel_jack_balance_by_virtual_work():
    """δW = F a δα − P δy_A with α = −4π l cos θ / h, y_A = 2 l sin θ: Q_θ = 2 l (2π a F sin θ / h − P cos θ)."""
    system = examples.get("wheel_jack")
    P, F, a, h, l = (next(s for s in system.parameters if s.name == k) for k in ("P", "F", "a", "h", "l"))
    theta = sp.Symbol("theta", real=True)
    Q = an.generalized_forces(system)
    assert sp.simplify(Q[0] - 2 * l * (2 * sp.pi * a * F * sp.sin(theta) / h - P * sp.cos(theta))) == 0
    [solution] = an.balance(system, "P")
    # the exact relation: P / F = 2π a tan θ / h
    assert sp.simplify(solution[P] / F - 2 * sp.pi * a * sp.tan(theta) / h) == 0


def test_wheel_jack_ratio_from_the_compiled_residual(compiled):
    """For several efforts F the root θ* of F(θ, 0) = 0 satisfies P/F = 2π a tan θ* / h to rounding."""
    model = compiled("wheel_jack")
    d = model.system.defaults
    thetas = []
    for effort in (2.0, 5.0, 11.0, 20.0, 60.0, 400.0):
        eq = an.find_equilibrium(model, [0.7], dict(F=effort))
        assert eq.success and eq.steady
        ratio = 2 * math.pi * d["a"] * math.tan(eq.q[0]) / d["h"]
        assert d["P"] / effort == pytest.approx(ratio, rel=1e-12, abs=0)
        thetas.append(eq.q[0])
    assert np.all(np.diff(thetas) < 0) and thetas[0] > 1.2 and thetas[-1] < 0.1  # several θ, from steep to flat
    # the textbook's numbers: a = 20 cm, h = 2 mm, θ = 30°
    effort = dict(F=4000.0 / (2 * math.pi * 0.2 * math.tan(math.pi / 6) / 0.002))
    eq = an.find_equilibrium(model, [0.5], effort)
    assert eq.q[0] == pytest.approx(math.pi / 6, rel=1e-12, abs=0)
    assert an.normal_modes(model, eq.q, effort).stability == "unstable"  # a frictionless jack never holds still


# -- relative equilibria: the bead on the spun hoop -----------------------------------------


def test_hoop_bead_relative_equilibria_and_frequency(compiled):
    """θ from the upward vertical, ε = 0: θ̈ = sin θ (g/R + Ω² cos θ).

    Off-axis equilibria: cos θ* = −g/(R Ω²), i.e. cos(π − θ*) = g/(Ω² R) from the downward
    vertical, which exist exactly when Ω² > g/R.  Linearizing, δθ̈ = −Ω² sin² θ* δθ:
    ω² = Ω² sin² θ* = Ω² − g²/(R² Ω²).  The bottom has ω² = g/R − Ω² (stable below the
    threshold only), the top −(g/R + Ω²) (always unstable).
    """
    model = compiled("hoop_bead")
    R, g = model.system.defaults["R"], model.system.defaults["g"]
    threshold = math.sqrt(g / R)
    for Omega in (1.05 * threshold, 6.0, 20.0):
        params = dict(Omega=Omega, epsilon=0.0)
        found = an.find_equilibria(model, (-1.0, 2 * math.pi - 1.0), params)
        angles = np.array([e.q[0] for e in found])
        star = math.acos(-g / (R * Omega**2))
        np.testing.assert_allclose(angles, [0.0, star, math.pi, 2 * math.pi - star], rtol=0, atol=1e-13)
        assert all(e.steady for e in found)
        assert math.cos(math.pi - angles[1]) == pytest.approx(g / (Omega**2 * R), rel=1e-13, abs=0)
        modes = an.normal_modes(model, found[1].q, params)
        assert modes.stability == "stable"
        assert modes.frequencies[0] == pytest.approx(math.sqrt(Omega**2 - g**2 / (R**2 * Omega**2)), rel=1e-12, abs=0)
        assert an.normal_modes(model, [math.pi], params).stability == "unstable"
    for Omega in (0.95 * threshold, 1.0):
        params = dict(Omega=Omega, epsilon=0.0)
        found = an.find_equilibria(model, (-1.0, 2 * math.pi - 1.0), params)
        np.testing.assert_allclose([e.q[0] for e in found], [0.0, math.pi], atol=1e-13)
        bottom = an.normal_modes(model, [math.pi], params)
        assert bottom.stability == "stable"
        assert bottom.frequencies[0] == pytest.approx(math.sqrt(g / R - Omega**2), rel=1e-12, abs=0)
        assert an.normal_modes(model, [0.0], params).omega2[0] == pytest.approx(-(g / R + Omega**2), rel=1e-12, abs=0)


def test_hoop_bead_symbolic_frequency():
    R, g, Omega = sp.symbols("R g Omega", positive=True)
    result = an.linearize_symbolic(examples.get("hoop_bead"), [sp.acos(-g / (R * Omega**2))], subs={"epsilon": 0})
    [omega2] = result["omega2_roots"]
    assert sp.simplify(omega2 - (Omega**2 - g**2 / (R**2 * Omega**2))) == 0
    assert result["G"] == sp.zeros(1, 1) and result["D"] == sp.zeros(1, 1)


def test_wobbling_hoop_balances_only_for_an_instant(compiled):
    model = compiled("hoop_bead")
    eq = an.find_equilibrium(model, [2.0], dict(epsilon=0.2), t=0.4)
    assert eq.success and not eq.steady


def test_turn_indicator_steady_tilt(compiled):
    """k θ* = I ω Ω cos(θ* + α) + ½ (I − I_X) ω² sin 2(θ* + α) (the gimbal's balance), damped oscillation."""
    model = compiled("turn_indicator")
    d = model.system.defaults
    eq = an.find_equilibrium(model, [0.0])
    assert eq.success and eq.steady
    b = eq.q[0] + d["alpha"]
    rhs = d["I"] * d["omega"] * d["Omega"] * math.cos(b) + 0.5 * (d["I"] - d["I_X"]) * d["omega"] ** 2 * math.sin(2 * b)
    assert d["k"] * eq.q[0] == pytest.approx(rhs, rel=1e-13, abs=0)
    modes = an.normal_modes(model, eq.q)
    assert modes.stability == "asymptotically stable"
    lin = modes.linearization
    assert lin.D[0, 0] == pytest.approx(d["c"], rel=1e-13, abs=0)
    # K = k − I ω Ω sin β·(−1)... checked as the growth rate of the damped oscillator: Re λ = −c/(2 I_X)
    assert modes.growth_rate == pytest.approx(-d["c"] / (2 * d["I_X"]), rel=1e-10)


# -- normal modes: the double pendulum ------------------------------------------------------


def test_double_pendulum_normal_modes_closed_form(compiled):
    """About θ1 = θ2 = 0: M = [[(m1+m2) l1², m2 l1 l2], [m2 l1 l2, m2 l2²]], K = g diag((m1+m2) l1, m2 l2).

    det(K − ω² M) = a ω⁴ − b ω² + c with a = m1 m2 l1² l2², b = (m1+m2) m2 g l1 l2 (l1 + l2),
    c = (m1+m2) m2 g² l1 l2; ω² = (b ∓ √(b² − 4ac)) / 2a, the smaller one as 2c / (b + √·).
    """
    model = compiled("double_pendulum")
    m1, m2, l1, l2, g = 1.3, 0.7, 1.1, 0.8, 9.81
    params = dict(m1=m1, m2=m2, l1=l1, l2=l2, g=g)
    eq = an.find_equilibrium(model, [0.2, -0.3], params)
    assert eq.success and np.max(np.abs(eq.q)) < 1e-14
    modes = an.normal_modes(model, eq.q, params)
    a = m1 * m2 * l1**2 * l2**2
    b = (m1 + m2) * m2 * g * l1 * l2 * (l1 + l2)
    c = (m1 + m2) * m2 * g**2 * l1 * l2
    root = math.sqrt(b * b - 4 * a * c)
    expected = np.sqrt([2 * c / (b + root), (b + root) / (2 * a)])
    np.testing.assert_allclose(modes.frequencies, expected, rtol=1e-12)
    assert modes.stability == "stable"
    lin = modes.linearization
    V = modes.shapes
    np.testing.assert_allclose(V.T @ lin.M @ V, np.eye(2), atol=1e-12)  # M-orthonormal shapes
    np.testing.assert_allclose(lin.K @ V, lin.M @ V @ np.diag(expected**2), atol=1e-11)
    # in-phase then anti-phase
    assert V[0, 0] * V[1, 0] > 0 > V[0, 1] * V[1, 1]


def test_gyroscopic_stabilization_is_marginal(cache_dir):
    """A particle on a hill, U = −k (x² + y²)/2, in a frame turning at Ω (centrifugal term cancelled in V).

    T = ½ ((ẋ − Ω y)² + (ẏ + Ω x)²): b = Ω (−y, x), so G = [[0, −2Ω], [2Ω, 0]], K = −k I and
    ẍ − 2Ω ẏ − k x = 0, ÿ + 2Ω ẋ − k y = 0: λ⁴ + (4Ω² − 2k) λ² + k² = 0.  For Ω² > k both
    λ² are negative: ω² = ((4Ω² − 2k) ∓ √((4Ω² − 2k)² − 4k²))/2, stable only linearly ("marginal").
    """
    x, y = lc.coordinates("x y")
    k, Omega = sp.symbols("k Omega", positive=True)
    xd, yd = x.diff(t), y.diff(t)
    T = ((xd - Omega * y) ** 2 + (yd + Omega * x) ** 2) / 2
    system = lc.System([x, y], T=T, V=(Omega**2 - k) * (x**2 + y**2) / 2, name="spun_hill",
                       defaults={"k": 1.0, "Omega": 3.0})
    model = lc.compile(system, cache_dir=cache_dir)
    lin = an.linearize(model, [0.0, 0.0])
    np.testing.assert_allclose(lin.G, [[0, -6.0], [6.0, 0]], atol=1e-15)
    np.testing.assert_allclose(lin.K, -np.eye(2), atol=1e-15)
    modes = an.normal_modes(lin)
    assert modes.stability == "marginal" and not lin.conservative
    s, kk = 4 * 9.0 - 2 * 1.0, 1.0
    root = math.sqrt(s * s - 4 * kk * kk)
    np.testing.assert_allclose(modes.frequencies, np.sqrt([2 * kk * kk / (s + root), (s + root) / 2]), rtol=1e-12)
    slow = an.normal_modes(model, [0.0, 0.0], dict(Omega=0.9))  # Ω² < k: the hill wins
    assert slow.stability == "unstable" and slow.growth_rate > 0


# -- conserved quantities -------------------------------------------------------------------


def test_conserved_quantities_report(compiled):
    top = {c.name for c in an.conserved_quantities(compiled("symmetric_top"))}
    assert top == {"h", "p_psi", "p_phi"}
    assert [c.name for c in an.conserved_quantities(compiled("double_pendulum"))] == ["h"]
    assert an.conserved_quantities(compiled("hoop_bead")) == []  # T has the imposed φ(t)


# -- phase portraits: the badly balanced cylinder -------------------------------------------


def test_unbalanced_cylinder_portrait(compiled):
    """E = ½ J(θ) θ̇² + M g (R − a cos θ), J = M (R² + a² − 2 a R cos θ) + I, so
    θ̇(θ, E) = √(2 (E − M g (R − a cos θ)) / J(θ)); the top θ = π is the unstable
    equilibrium, separatrix energy E_s = M g (R + a); turning points cos θ_t = (M g R − E)/(M g a)."""
    model = compiled("unbalanced_cylinder")
    d = model.system.defaults
    M, R, a, I, g = d["M"], d["R"], d["a"], d["I"], d["g"]
    E_min, E_s = M * g * (R - a), M * g * (R + a)
    energies = [0.9 * E_min, E_min + 0.3 * (E_s - E_min), E_s, 1.4 * E_s]
    portrait = an.phase_portrait(model, energies, (-math.pi, math.pi), periodic=True)
    assert portrait.separatrices == pytest.approx([E_s], rel=1e-13, abs=0)
    assert portrait.regimes == ("no motion", "oscillation", "separatrix", "revolution")
    theta = portrait.q
    J = M * (R**2 + a**2 - 2 * a * R * np.cos(theta)) + I
    for E, qd in zip(energies, portrait.qd):
        with np.errstate(invalid="ignore"):
            expected = np.sqrt(2 * (E - M * g * (R - a * np.cos(theta))) / J)
        np.testing.assert_allclose(qd, expected, rtol=1e-12, atol=1e-12, equal_nan=True)
    turning = portrait.turning_points[1]
    cos_t = (M * g * R - energies[1]) / (M * g * a)
    np.testing.assert_allclose(turning, [-math.acos(cos_t), math.acos(cos_t)], rtol=1e-12)
    assert [e.q[0] for e in portrait.equilibria] == pytest.approx([-math.pi, 0.0], abs=1e-13)
    assert portrait.stable == (False, True)
