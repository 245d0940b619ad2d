"""The bundled examples against closed-form solutions, conservation laws and a second derivation."""

from __future__ import annotations

import numpy as np
import pytest
from reference import lagranges_method_functions, lagranges_method_rhs
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from lagcomp import examples

TIGHT = dict(method="dop853", rtol=1e-12, atol=1e-14)


def test_sling_follows_cosh(compiled):
    model = compiled("sling")
    a, omega = 0.1, model.system.defaults["omega"]
    ts = np.linspace(0, 2, 41)
    sol = model.simulate((0, 2), q0=[a], qd0=[0.0], t_eval=ts, **TIGHT)
    assert sol.success
    np.testing.assert_allclose(sol.t, ts)
    np.testing.assert_allclose(sol.q[:, 0], a * np.cosh(omega * ts), rtol=1e-9, atol=0)


def test_rope_without_friction_follows_cosh(compiled):
    model = compiled("rope")
    L, g, x0 = model.system.defaults["L"], model.system.defaults["g"], 0.2
    ts = np.linspace(0, 0.6, 31)
    sol = model.simulate((0, 0.6), q0=[x0], qd0=[0.0], t_eval=ts, **TIGHT)
    np.testing.assert_allclose(sol.q[:, 0], x0 * np.cosh(ts * np.sqrt(g / L)), rtol=1e-9, atol=0)


def test_rope_with_friction_above_critical_length(compiled):
    model = compiled("rope_friction")
    d = model.system.defaults
    L, g, f, x0 = d["L"], d["g"], d["f"], 0.4
    l0 = f * L / (1 + f)
    assert x0 > l0
    ts = np.linspace(0, 0.55, 23)
    sol = model.simulate((0, 0.55), q0=[x0], qd0=[0.0], t_eval=ts, **TIGHT)
    expected = l0 + (x0 - l0) * np.cosh(ts * np.sqrt(g * (1 + f) / L))
    np.testing.assert_allclose(sol.q[:, 0], expected, rtol=1e-9, atol=0)


@pytest.mark.parametrize("amplitude", [0.1, 2.5])
def test_huygens_period_is_independent_of_amplitude(compiled, amplitude):
    model = compiled("huygens")
    R, g = model.system.defaults["R"], model.system.defaults["g"]
    period = 4 * np.pi * np.sqrt(R / g)

    def theta_at(time):  # θ crosses zero a quarter period after release from rest
        return model.simulate((0, time), q0=[amplitude], qd0=[0.0], **TIGHT).q[-1, 0]

    quarter = brentq(theta_at, 0.2 * period, 0.3 * period, xtol=1e-14, rtol=1e-15)
    assert 4 * quarter == pytest.approx(period, rel=1e-8)


def test_cylinder_on_tray_follows_the_tray_acceleration(compiled):
    model = compiled("tray_cylinder")
    d = model.system.defaults
    k = d["I"] / (d["I"] + d["M"] * d["R"] ** 2)
    A, W = d["A"], d["Omega"]
    ts = np.linspace(0, 10, 101)
    sol = model.simulate((0, 10), q0=[0.3], qd0=[0.1], t_eval=ts, **TIGHT)
    accel = np.array([model.rhs(t, y)[1] for t, y in zip(sol.t, sol.y)])
    np.testing.assert_allclose(accel, k * (-A * W**2 * np.sin(W * ts)), rtol=1e-12, atol=1e-12)
    # integrated twice: X = X0 + Ẋ0 t + k (a(t) − a(0) − ȧ(0) t)
    expected = 0.3 + 0.1 * ts + k * (A * np.sin(W * ts) - A * W * ts)
    np.testing.assert_allclose(sol.q[:, 0], expected, rtol=0, atol=1e-10)


def _random_states(rng, n, count=20):
    return rng.uniform(-np.pi, np.pi, (count, n)), rng.uniform(-3, 3, (count, n))


@pytest.mark.parametrize("name, kwargs", [("double_pendulum", {}), ("n_link_pendulum", {"n": 5})])
def test_mass_matrix_and_forcing_match_lagranges_method(compiled, rng, name, kwargs):
    model = compiled(name, **kwargs)
    ref_M, ref_F = lagranges_method_functions(model.system)
    params = {k: v for k, v in zip(model.parameters, rng.uniform(0.5, 2.0, len(model.parameters)))}
    pvec = model.parameter_vector(params)
    for q, qd in zip(*_random_states(rng, model.n)):
        np.testing.assert_allclose(model.mass_matrix(q, params=params), ref_M(q, qd, 0.0, pvec), rtol=1e-12, atol=1e-12)
        expected_F = np.asarray(ref_F(q, qd, 0.0, pvec), dtype=float).ravel()
        np.testing.assert_allclose(model.forcing(q, qd, params=params), expected_F, rtol=1e-12, atol=1e-11)


def test_double_pendulum_conserves_energy_and_matches_scipy(compiled):
    model = compiled("double_pendulum")
    sol = model.simulate((0, 100), q0=[2.0, 1.0], qd0=[0.0, 0.0], method="dop853", rtol=1e-12, atol=1e-12)
    assert sol.success
    assert sol.energy_drift() < 1e-9

    p = model.parameter_vector()
    rhs = lambda t, y: model.rhs(t, y)  # noqa: E731
    ts = np.linspace(0, 5, 51)
    ours = model.simulate((0, 5), q0=[2.0, 1.0], qd0=[0.0, 0.0], t_eval=ts, method="dop853", rtol=1e-12, atol=1e-12)
    theirs = solve_ivp(rhs, (0, 5), [2.0, 1.0, 0.0, 0.0], method="DOP853", t_eval=ts, rtol=1e-12, atol=1e-12)
    assert p.size == 5 and theirs.success
    np.testing.assert_allclose(ours.y, theirs.y.T, rtol=0, atol=1e-8)


def test_rk4_converges_with_order_four(compiled):
    model = compiled("sling")
    a, omega = 0.1, model.system.defaults["omega"]
    errors = []
    for dt in (0.04, 0.02, 0.01):
        sol = model.simulate((0, 2), q0=[a], qd0=[0.0], method="rk4", dt=dt)
        assert sol.t[-1] == 2.0
        errors.append(abs(sol.q[-1, 0] - a * np.cosh(omega * 2)))
    ratios = np.array(errors[:-1]) / np.array(errors[1:])
    assert np.all((15.0 <= ratios) & (ratios <= 17.0)), ratios


#: Examples whose energy function h is a first integral (no explicit t, no non-conservative force):
#: (bound on its max relative drift over [0, t_end] at rtol = atol = 1e-10, measured drift).
CONSERVED_H = {
    "chaplygin_sleigh": (6e-10, 1.5e-10), "double_pendulum": (5e-8, 1.2e-8), "four_bar_linkage": (6e-8, 1.4e-8),
    "free_axle": (2e-9, 4.2e-10), "henon_heiles": (3e-8, 6.6e-9), "huygens": (1e-9, 2.7e-10),
    "n_link_pendulum": (5e-11, 1.3e-11), "rolling_disc": (5e-12, 1.1e-12), "rope": (1e-10, 2.3e-11),
    "simple_pendulum": (4e-10, 9.0e-11),
    "sling": (3e-10, 6.1e-11), "spherical_pendulum": (4e-9, 8.5e-10), "spherical_pendulum_cartesian": (4e-8, 9.0e-9),
    "symmetric_top": (1.5e-11, 3.1e-12), "unbalanced_cylinder": (2e-10, 3.9e-11),
    "unbalanced_cylinder_reactions": (3e-10, 5.9e-11),
}
#: Largest constraint residual of the constrained examples over the same run: (bound, measured).
RESIDUALS = {
    "chaplygin_sleigh": (3e-10, 7.1e-11), "four_bar_linkage": (2e-7, 4.2e-8), "free_axle": (2e-10, 3.8e-11),
    "hoop_bead_reaction": (4e-13, 8.2e-14), "rolling_disc": (1.5e-11, 3.3e-12),
    "spherical_pendulum_cartesian": (3e-8, 5.7e-9),
    "unbalanced_cylinder_reactions": (2e-13, 4.0e-14),
}


@pytest.mark.parametrize("name", sorted(examples.EXAMPLES))
def test_every_example_runs_with_its_defaults(compiled, name):
    model = compiled(name)
    sol = model.simulate((0, model.system.t_end), method="dop853", rtol=1e-10, atol=1e-10)
    assert sol.success, sol.message
    assert np.all(np.isfinite(sol.y))
    if name in CONSERVED_H:
        bound, _ = CONSERVED_H[name]
        assert sol.energy_drift("energy_function") < bound
    if name in RESIDUALS:
        bound, _ = RESIDUALS[name]
        assert sol.constraint_residual < bound
    if name == "hoop_bead_reaction":  # the released drive angle follows the imposed φ(t) = Ωt + ε sin 2t
        d = model.system.defaults
        np.testing.assert_allclose(sol.q[:, 1], d["Omega"] * sol.t + d["epsilon"] * np.sin(2 * sol.t), rtol=0,
                                   atol=4e-13)  # measured 7.8e-14


#: Unconstrained examples against scipy's DOP853 (rtol 1e-12) on the equations sympy.physics.mechanics'
#: LagrangesMethod derives from the same T, V, Q and D: (horizon, bound on max |Δy| / (1 + max |y|), measured).
#: Chaotic or fast-driven examples are compared over a shorter horizon (double pendulum: 1.8e-7 over 20 s).
LAGRANGES_METHOD = {
    "compton_disc": (None, 1e-14, 7.8e-16), "double_pendulum": (5.0, 1e-14, 1.2e-15),
    "driven_pendulum": (2.5, 2e-10, 3.3e-11), "driven_pendulum_support": (2.5, 1e-11, 1.4e-12),
    "henon_heiles": (None, 1e-13, 2.1e-14), "hoop_bead": (None, 1.5e-13, 3.0e-14), "huygens": (None, 4e-14, 7.2e-15),
    "n_link_pendulum": (None, 1.5e-14, 2.5e-15), "rope": (None, 1e-14, 3.7e-16),
    "rope_friction": (None, 1e-14, 1.8e-16), "simple_pendulum": (None, 1e-14, 2.1e-15),
    "sling": (None, 1e-14, 8.3e-16), "spherical_pendulum": (None, 1e-14, 8.9e-16),
    "symmetric_top": (None, 1e-14, 1.2e-15), "tray_cylinder": (None, 1.5e-14, 2.4e-15),
    "turn_indicator": (None, 5e-11, 8.3e-12), "unbalanced_cylinder": (None, 5e-14, 1.1e-14),
    "wheel_jack": (None, 1e-14, 8.3e-16),
    # stiff (eigenvalues -1000 s⁻¹): both DOP853 runs sit at their stability limit, where each one's error is
    # at the tolerance and their step sequences differ, so the two agree to the tolerance, not to rounding
    "stiff_spring_pendulum": (0.5, 5e-12, 8.9e-13),
}


def test_every_example_has_an_independent_reference():
    """Each example meets at least one check that does not compare lagcomp with itself (here or in
    test_reactions: hoop_bead_reaction's drive angle; the constrained examples' conserved h and residuals;
    test_accuracy: the gravitational examples' kernels against Newton's law and Hairer's hand-written
    restricted problem, and the Pythagorean run against scipy on a hand-written rhs)."""
    covered = set(CONSERVED_H) | set(LAGRANGES_METHOD) | {"hoop_bead_reaction"}
    covered |= {"pythagorean_three_body", "restricted_three_body"}
    assert covered == set(examples.EXAMPLES)
    assert not any(examples.get(name).constraints for name in LAGRANGES_METHOD)


@pytest.mark.parametrize("name", sorted(LAGRANGES_METHOD))
def test_unconstrained_examples_match_lagranges_method_and_scipy(compiled, name):
    model = compiled(name)
    horizon, bound, _ = LAGRANGES_METHOD[name]
    horizon = model.system.t_end if horizon is None else horizon
    ts = np.linspace(0, horizon, 21)
    ours = model.simulate((0, horizon), t_eval=ts, method="dop853", rtol=1e-12, atol=1e-12)
    theirs = solve_ivp(lagranges_method_rhs(model.system), (0, horizon), model.initial_state(), method="DOP853",
                       t_eval=ts, rtol=1e-12, atol=1e-12)
    assert ours.success and theirs.success
    error = np.max(np.abs(ours.y - theirs.y.T)) / (1 + np.max(np.abs(theirs.y)))
    assert error < bound, error


def test_pendulum_of_imposed_length_matches_the_hand_derived_equation(cache_dir):
    """A mass matrix that depends on t: the pendulum whose length is imposed, l(t) = l0 + a sin Ωt.

    T = m (l̇² + l² θ̇²)/2, V = −m g l cos θ; by hand, d/dt(m l² θ̇) = −m g l sin θ, i.e.
    l θ̈ + 2 l̇ θ̇ + g sin θ = 0 — the −(∂M/∂t) θ̇ term is the 2 l̇ θ̇ (dropping it fails by 1.3).  Against
    scipy's DOP853 at rtol 1e-12 on that equation (measured: 2.1e-14 over 10 s).
    """
    import sympy as sp

    import lagcomp as lc

    (theta,) = lc.coordinates("theta")
    m, g, l0, a, W = sp.symbols("m g l0 a Omega", positive=True)
    length = l0 + a * sp.sin(W * lc.t)
    system = lc.System([theta], T=m * (length.diff(lc.t) ** 2 + length**2 * theta.diff(lc.t) ** 2) / 2,
                       V=-m * g * length * sp.cos(theta), name="pumped_pendulum",
                       defaults={"m": 1.3, "g": 9.81, "l0": 1.0, "a": 0.2, "Omega": 3.0}, q0=[0.8], qd0=[0.0])
    model = lc.compile(system, cache_dir=cache_dir)
    assert model.mass_matrix([0.8], t=0.0)[0, 0] != model.mass_matrix([0.8], t=0.5)[0, 0]  # M = m l(t)²
    G, L0, A, Om = 9.81, 1.0, 0.2, 3.0

    def by_hand(time, y):
        ell, ell_dot = L0 + A * np.sin(Om * time), A * Om * np.cos(Om * time)
        return [y[1], -(2 * ell_dot * y[1] + G * np.sin(y[0])) / ell]

    ts = np.linspace(0, 10, 101)
    ours = model.simulate((0, 10), t_eval=ts, method="dop853", rtol=1e-12, atol=1e-12)
    theirs = solve_ivp(by_hand, (0, 10), [0.8, 0.0], method="DOP853", t_eval=ts, rtol=1e-12, atol=1e-12)
    assert ours.success and theirs.success
    np.testing.assert_allclose(ours.y, theirs.y.T, rtol=0, atol=1e-13)
