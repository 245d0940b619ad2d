"""lagcomp.compile(KanesMethod): Kane's equations as KanesMethod forms them, over the state (q, u).

References nobody here wrote: closed forms derived below (a pendulum with u = l q̇
and its rod tension, the Chaplygin sleigh), sympy's own equations of the Whipple
bicycle integrated by scipy at tight tolerance, and the benchmark bicycle's
published eigenvalues (Meijaard, Papadopoulos, Ruina & Schwab 2007).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import sympy as sp
import sympy.physics.mechanics as me
from scipy.integrate import solve_ivp
from scipy.special import ellipk

import lagcomp as lc
from lagcomp import InitialConditionError, ModelError, OptionError
from lagcomp.analysis import conserved_quantities, linearize
from lagcomp.integrate.sweep import Sweep

import kane_models

t = me.dynamicsymbols._t


def kane_pendulum(auxiliary: bool = False):
    """A pendulum of length l with the speed u = l q̇ (the bob's speed), optionally with an auxiliary
    speed along the rod and the rod force R(t) (positive pulling the bob towards the pivot)."""
    q, u, ua, R = me.dynamicsymbols("q u ua R")
    m, l, g = sp.symbols("m l g", positive=True)
    N = me.ReferenceFrame("N")
    O = me.Point("O")
    O.set_vel(N, 0)
    A = N.orientnew("A", "Axis", [q, N.z])
    P = O.locatenew("P", -l * A.y)
    P.set_vel(N, u * A.x + (ua * A.y if auxiliary else 0))
    loads = [(P, -m * g * N.y)] + ([(P, R * A.y)] if auxiliary else [])
    km = me.KanesMethod(N, [q], [u], kd_eqs=[q.diff(t) - u / l], u_auxiliary=[ua] if auxiliary else [])
    km.kanes_equations([me.Particle("bob", P, m)], loads)
    return km


PENDULUM = dict(m=1.3, l=0.8, g=9.81)


def test_pendulum_with_u_equal_l_qdot_returns_after_its_elliptic_period(cache_dir):
    model = lc.compile(kane_pendulum(), cache_dir=cache_dir, name="kane_pendulum_u_lqd", defaults=PENDULUM)
    assert model.coordinates == ("q",) and model.speeds == ("u",)
    m, l, g = PENDULUM["m"], PENDULUM["l"], PENDULUM["g"]
    q0 = 2.0  # a large swing: the period is 4 sqrt(l/g) K(sin²(q0/2)), 1.35 times the small-swing one
    period = 4 * math.sqrt(l / g) * ellipk(math.sin(q0 / 2) ** 2)
    sol = model.simulate((0, period), q0=[q0], u0=[0.0], rtol=1e-12, atol=1e-12)
    assert sol.status == 0
    assert abs(sol.q[-1, 0] - q0) < 5e-12  # measured 3.5e-13
    assert abs(sol.u[-1, 0]) < 1e-11  # measured 1.3e-12
    np.testing.assert_allclose(sol.qd[:, 0], sol.u[:, 0] / l, rtol=1e-15)  # q̇ from the kinematic equation
    np.testing.assert_allclose(sol.y, np.hstack([sol.q, sol.u]))
    saved = sol.to_dict()
    assert saved["u"] is sol.u and list(saved["speeds"]) == ["u"]
    energy = 0.5 * m * sol.u[:, 0] ** 2 - m * g * l * np.cos(sol.q[:, 0])
    np.testing.assert_allclose(sol.energy, energy, rtol=1e-14)  # measured 8e-16
    assert np.ptp(sol.energy) < 1e-11 * abs(sol.energy[0])  # measured 1.4e-12


def test_auxiliary_speed_gives_the_rod_tension_as_a_reaction(cache_dir):
    model = lc.compile(kane_pendulum(auxiliary=True), cache_dir=cache_dir, name="kane_pendulum_tension",
                       defaults=PENDULUM)
    assert model.reaction_names == ("R",)
    m, l, g = PENDULUM["m"], PENDULUM["l"], PENDULUM["g"]
    sol = model.simulate((0, 2.0), q0=[1.0], u0=[0.5], rtol=1e-11, atol=1e-11)
    q, u = sol.q[:, 0], sol.u[:, 0]
    tension = m * g * np.cos(q) + m * u**2 / l  # radial Newton's law: R − m g cos q = m v²/l
    np.testing.assert_allclose(sol.reactions["R"], tension, rtol=1e-14)  # measured 2.6e-16
    assert model.reactions(0.0, [0.3, 1.1])["R"] == pytest.approx(m * g * math.cos(0.3) + m * 1.1**2 / l, rel=1e-14, abs=0)


def test_energy_is_nan_where_a_load_has_no_potential(cache_dir):
    """A damped pendulum (a load −c u along the path): no T + V to form, so the energy kernel says NaN."""
    q, u = me.dynamicsymbols("q u")
    m, l, g, c = sp.symbols("m l g c", positive=True)
    N = me.ReferenceFrame("N")
    A = N.orientnew("A", "Axis", [q, N.z])
    O = me.Point("O")
    O.set_vel(N, 0)
    P = O.locatenew("P", -l * A.y)
    P.set_vel(N, u * A.x)
    km = me.KanesMethod(N, [q], [u], kd_eqs=[q.diff(t) - u / l])
    km.kanes_equations([me.Particle("bob", P, m)], [(P, -m * g * N.y), (P, -c * u * A.x)])
    model = lc.compile(km, cache_dir=cache_dir, name="kane_damped_pendulum", defaults=dict(PENDULUM, c=0.7))
    assert not model.energy_available
    sol = model.simulate((0, 1), q0=[1.0], u0=[0.0], record="summary")
    assert np.all(np.isnan(sol.energy)) and math.isnan(model.energy([1.0], [0.0]))
    assert sol.summary.qd_min[0] < -1.0  # the summary's velocity ranges are those of u (q̇ = u / l) here


def chaplygin_sleigh():
    """A rigid body on a knife edge at P, its mass centre G a distance a ahead of P along the blade.

    q = (x, y, θ) of P; speeds u1 (along the blade), u2 (across it), u3 = θ̇: q̇ ≠ u.
    The knife edge: u2 = 0, a velocity constraint with u2 dependent.
    """
    x, y, th = me.dynamicsymbols("x y theta")
    u1, u2, u3 = me.dynamicsymbols("u1 u2 u3")
    m, I, a = sp.symbols("m I a", positive=True)
    N = me.ReferenceFrame("N")
    B = N.orientnew("B", "Axis", [th, N.z])
    B.set_ang_vel(N, u3 * N.z)
    P = me.Point("P")
    P.set_vel(N, u1 * B.x + u2 * B.y)
    G = P.locatenew("G", a * B.x)
    G.v2pt_theory(P, N, B)
    body = me.RigidBody("sleigh", G, B, m, (me.inertia(B, 0, 0, I), G))
    kd = [x.diff(t) - (u1 * sp.cos(th) - u2 * sp.sin(th)), y.diff(t) - (u1 * sp.sin(th) + u2 * sp.cos(th)),
          th.diff(t) - u3]
    km = me.KanesMethod(N, [x, y, th], [u1, u3], kd_eqs=kd, u_dependent=[u2], velocity_constraints=[u2])
    km.kanes_equations([body], [])
    return km


SLEIGH = dict(m=2.0, I=0.3, a=0.4)


def sleigh_closed_form(times, v0, w0, theta0):
    """v̇ = a ω², ω̇ = −m a v ω / J (J = I + m a²) conserve E = ½ m v² + ½ J ω², so with V = √(2E/m)
    and λ = m a V / J: v = V tanh(λ t + c), ω = ω0 cosh c / cosh(λ t + c), and
    θ = θ0 + (ω0 cosh c / λ)(gd(λ t + c) − gd(c)), gd(s) = 2 atan(tanh(s/2))."""
    m, I, a = SLEIGH["m"], SLEIGH["I"], SLEIGH["a"]
    J = I + m * a**2
    V = math.sqrt((m * v0**2 + J * w0**2) / m)
    lam, c = m * a * V / J, math.atanh(v0 / V)
    s = lam * times + c
    gd = lambda z: 2 * np.arctan(np.tanh(z / 2))  # noqa: E731
    return V * np.tanh(s), w0 * math.cosh(c) / np.cosh(s), theta0 + w0 * math.cosh(c) / lam * (gd(s) - gd(c))


def test_chaplygin_sleigh_follows_its_closed_form_and_keeps_the_knife_edge(cache_dir):
    model = lc.compile(chaplygin_sleigh(), cache_dir=cache_dir, name="chaplygin_sleigh", defaults=SLEIGH)
    assert model.speeds == ("u1", "u3", "u2")  # independent, then dependent
    times = np.linspace(0, 6, 61)
    sol = model.simulate((0, 6), q0=[0.0, 0.0, 0.2], u0=[-0.5, 1.5, 0.0], t_eval=times, rtol=1e-12, atol=1e-12)
    v, w, theta = sleigh_closed_form(times, -0.5, 1.5, 0.2)
    assert np.max(np.abs(sol.u[:, 0] - v)) < 1e-11  # measured 1.3e-12
    assert np.max(np.abs(sol.u[:, 1] - w)) < 2e-11  # measured 4.4e-12
    assert np.max(np.abs(sol.q[:, 2] - theta)) < 2e-11  # measured 3.4e-12
    assert np.max(np.abs(sol.u[:, 2])) == 0.0 and sol.constraint_residual < 1e-12
    # the contact point moves along the blade: ẋ = v cos θ, ẏ = v sin θ
    np.testing.assert_allclose(sol.qd[:, :2], np.column_stack([v * np.cos(theta), v * np.sin(theta)]), atol=2e-11)
    assert np.ptp(sol.energy) < 2e-11 * sol.energy[0]  # measured 3.6e-12
    dopri5 = model.simulate((0, 6), q0=[0.0, 0.0, 0.2], u0=[-0.5, 1.5, 0.0], t_eval=times, method="dopri5",
                            rtol=1e-10, atol=1e-12)
    assert np.max(np.abs(dopri5.u[:, :2] - np.column_stack([v, w]))) < 5e-10  # measured 8.8e-11
    fixed = model.simulate((0, 6), q0=[0.0, 0.0, 0.2], u0=[-0.5, 1.5, 0.0], method="rk4", dt=1e-3)
    v, w, theta = sleigh_closed_form(fixed.t, -0.5, 1.5, 0.2)
    assert np.max(np.abs(fixed.u[:, :2] - np.column_stack([v, w]))) < 5e-13  # rk4 with projection; measured 4.9e-14
    assert np.max(np.abs(fixed.q[:, 2] - theta)) < 5e-13  # measured 4.1e-14


def test_kane_model_refuses_what_needs_q_qdot_and_inconsistent_starts(cache_dir):
    model = lc.compile(chaplygin_sleigh(), cache_dir=cache_dir, name="chaplygin_sleigh", defaults=SLEIGH)
    for method in ("gauss2", "taylor", "verlet", "yoshida4"):
        with pytest.raises(OptionError, match="rk4, dopri5, dop853, tsit5, bs3 or radau"):
            model.simulate((0, 1), q0=[0, 0, 0], u0=[1, 0, 0], method=method, dt=0.01)
    with pytest.raises(InitialConditionError, match="velocity_0"):
        model.simulate((0, 1), q0=[0, 0, 0], u0=[1, 0, 0.1])
    sol = model.simulate((0, 1), q0=[0, 0, 0], u0=[1, 0, 0.1], project_initial=True)
    assert sol.u[0, 2] == 0.0 and sol.projected_initial_state is not None
    with pytest.raises(InitialConditionError, match="u0"):
        model.simulate((0, 1), q0=[0, 0, 0], qd0=[1, 0, 0])
    with pytest.raises(OptionError, match="baumgarte"):
        model.simulate((0, 1), q0=[0, 0, 0], u0=[1, 0, 0], baumgarte=(1.0, 1.0))
    with pytest.raises(OptionError, match="Kane model .* drop `batched`"):
        model.sweep((0, 1), {"m": [1.0, 2.0]}, q0=[0, 0, 0], u0=[1, 0, 0], batched=True)
    with pytest.raises(InitialConditionError, match="u0"):
        model.sweep((0, 1), {"m": [1.0, 2.0]}, q0=[0, 0, 0], qd0=[1, 0, 0])
    with pytest.raises(OptionError, match="speeds or parameters: .*'u1', 'u3', 'u2'"):
        model.sweep((0, 1), {"u1_dot": [1.0]}, q0=[0, 0, 0])
    with pytest.raises(ModelError, match="Kane model .* linearize_steady .* lagcomp.System or sympy LagrangesMethod"):
        conserved_quantities(model)
    with pytest.raises(ModelError, match="Kane model"):
        model.momenta([0, 0, 0], [1, 0, 0])
    with pytest.raises(ModelError, match="Kane model .* no `rest_partials`"):  # analysis written for (q, q̇)
        linearize(model, [0, 0, 0])
    with pytest.raises(ModelError, match="kanes_equations"):
        lc.compile(me.KanesMethod(me.ReferenceFrame("N"), [me.dynamicsymbols("z")], [me.dynamicsymbols("w")],
                                  kd_eqs=[me.dynamicsymbols("z", 1) - me.dynamicsymbols("w")]))


def test_sweeps_of_a_kane_model_equal_separate_runs_and_the_closed_form(cache_dir, tmp_path):
    """A grid over a parameter and an initial speed (dop853), and over a speed (rk4, projecting): each
    trajectory's final (q, u) equals a separate `simulate` bitwise; dop853's follow the sleigh's closed form."""
    model = lc.compile(chaplygin_sleigh(), cache_dir=cache_dir, name="chaplygin_sleigh", defaults=SLEIGH)
    start = dict(q0=[0.0, 0.0, 0.2], u0=[-0.5, 1.5, 0.0])
    a_values, u1_values = [0.3, 0.4], [-0.5, 0.25, 1.0]
    sweep = model.sweep((0, 3), {"a": a_values, "u1": u1_values}, rtol=1e-12, atol=1e-12, workers=2,
                        output="energy", progress=False, **start)
    assert sweep.shape == (2, 3) and sweep.final.shape == (2, 3, 6) and sweep.speeds == ("u1", "u3", "u2")
    assert np.all(sweep.status == 0)
    for i, a in enumerate(a_values):
        for j, u1 in enumerate(u1_values):
            sol = model.simulate((0, 3), q0=start["q0"], u0=[u1, 1.5, 0.0], params={"a": a}, rtol=1e-12, atol=1e-12)
            np.testing.assert_array_equal(sweep.final[i, j], sol.y[-1])
            assert sweep.energy_error[i, j] == pytest.approx(sol.energy_drift(), rel=1e-12, abs=1e-16)
    v, w, theta = sleigh_closed_form(np.array([3.0]), 1.0, 1.5, 0.2)  # a = 0.4 (SLEIGH), u1 = 1.0
    assert np.max(np.abs(sweep.final[1, 2, [3, 4, 2]] - [v[0], w[0], theta[0]])) < 2e-11  # measured 3.6e-13
    fixed = model.sweep((0, 1), {"u3": [1.0, 2.0]}, method="rk4", dt=1e-3, progress=False, **start)
    sol = model.simulate((0, 1), q0=start["q0"], u0=[-0.5, 2.0, 0.0], method="rk4", dt=1e-3)
    np.testing.assert_array_equal(fixed.final[1], sol.y[-1])
    assert fixed.final[1, 5] == 0.0  # projected onto the knife edge after every step, as simulate does
    fixed.save_npz(tmp_path / "sweep.npz")
    again = Sweep.load_npz(tmp_path / "sweep.npz")
    assert again.speeds == ("u1", "u3", "u2") and np.array_equal(again.final, fixed.final)


def test_events_of_a_kane_model_fall_at_the_pendulums_closed_form_times(cache_dir):
    """g = q (the bob passing the bottom, downwards) and g = u (a turning point, terminal) on the pendulum with
    u = l q̇ from rest at q0: at T/4 and T/2 of the elliptic period, with speed −√(2 g l (1 − cos q0)) at the
    bottom (energy); in a sweep too, per amplitude. An event holding a symbol the equations lack is refused."""
    km = kane_pendulum()
    q, u = km.q[0], km.u[0]
    events = [lc.Event("bottom", q, direction=-1), lc.Event("turn", u, direction=1, terminal=True)]
    model = lc.compile(km, cache_dir=cache_dir, name="kane_pendulum_events", defaults=PENDULUM, events=events)
    assert model.event_names == ("bottom", "turn")
    l, g = PENDULUM["l"], PENDULUM["g"]
    period = lambda q0: 4 * math.sqrt(l / g) * ellipk(math.sin(q0 / 2) ** 2)  # noqa: E731
    sol = model.simulate((0, 10), q0=[2.0], u0=[0.0], rtol=1e-12, atol=1e-12)
    assert sol.status == 1 and "Event 'turn'" in sol.message
    assert abs(sol.events["bottom"].t[0] - period(2.0) / 4) < 2e-13  # measured 2.3e-14
    assert abs(sol.events["turn"].t[0] - period(2.0) / 2) < 5e-13  # measured 1.2e-13
    assert sol.t[-1] == sol.events["turn"].t[0]
    speed = math.sqrt(2 * g * l * (1 - math.cos(2.0)))
    assert abs(sol.events["bottom"].qd[0, 0] + speed) < 5e-11  # `qd` holds u; measured 6.7e-12
    amplitudes = [0.5, 1.0, 2.0]
    sweep = model.sweep((0, 10), {"q": amplitudes}, q0=[0.0], u0=[0.0], rtol=1e-12, atol=1e-12, output="events",
                        progress=False)
    assert np.all(sweep.status == 1) and np.all(sweep.events["turn"]["count"] == 1)
    expected = np.array([period(a) / 4 for a in amplitudes])
    assert np.max(np.abs(sweep.events["bottom"]["t"][:, 0] - expected)) < 3e-13  # measured 6.4e-14
    np.testing.assert_allclose(sweep.t_final, 2 * expected, rtol=0, atol=5e-13)  # the terminal turning point
    with pytest.raises(ModelError, match=r"Event `far` holds \['L'\]"):
        lc.compile(km, cache_dir=cache_dir, name="kane_pendulum_stray", events=[lc.Event("far", q - sp.Symbol("L"))])


def test_a_failed_kane_run_names_its_speeds(cache_dir):
    """The failure message lists the last good state (q, u) by the coordinates' and speeds' names."""
    model = lc.compile(chaplygin_sleigh(), cache_dir=cache_dir, name="chaplygin_sleigh", defaults=SLEIGH)
    sol = model.simulate((0, 2), q0=[0.0, 0.0, 0.2], u0=[-0.5, 1.5, 0.0], max_steps=3)
    assert sol.status == -4
    state = sol.message.split("last good state ")[1]
    assert [part.split("=")[0] for part in state.rstrip(".").split(", ")] == ["x", "y", "theta", "u1", "u3", "u2"]
    assert f"u3={sol.u[-1, 1]:.6g}" in state and "_dot" not in sol.message


def test_a_kane_model_is_loaded_by_name_without_sympy(cache_dir):
    again = lc.compile(chaplygin_sleigh(), cache_dir=cache_dir, name="chaplygin_sleigh", defaults=SLEIGH)
    reordered = lc.compile(chaplygin_sleigh(), cache_dir=cache_dir, name="sleigh_reordered", parameters=["a", "m", "I"],
                           defaults=SLEIGH)
    assert reordered.parameters == ("a", "m", "I") and reordered.cache_key != again.cache_key
    assert lc.compile(chaplygin_sleigh(), cache_dir=cache_dir, name="chaplygin_sleigh", defaults=SLEIGH).from_cache
    lc.compile(chaplygin_sleigh(), cache_dir=cache_dir, name="chaplygin_sleigh", defaults=SLEIGH, q0=[0, 0, 0.2],
               u0=[-0.5, 1.5, 0])  # the run defaults `load` finds
    loaded = lc.load("chaplygin_sleigh", cache_dir=cache_dir)
    assert type(loaded).__name__ == "KaneModel" and loaded.first_order_form is None
    v, w, _ = sleigh_closed_form(np.array([1.0]), -0.5, 1.5, 0.2)
    sol = loaded.simulate((0, 1), rtol=1e-12, atol=1e-12)
    assert abs(sol.u[-1, 0] - v[0]) < 1e-9 and abs(sol.u[-1, 1] - w[0]) < 1e-9


# -- the Whipple bicycle of sympy's test_kane3 ------------------------------------------------------------

#: Lean/steer eigenvalues of the benchmark bicycle at v = 5 m/s (Meijaard et al. 2007, table 2).
PUBLISHED_5 = np.array([-14.07838969, -0.32286642, -0.77534188 - 4.46486771j, -0.77534188 + 4.46486771j])


@pytest.fixture(scope="module")
def bicycle(whipple_bicycle):
    km, model = whipple_bicycle
    return km, dict(kane_models.BENCHMARK), (kane_models.RAD_REAR, kane_models.RAD_FRONT), model


def _on_constraints(model, q_ind, u_ind):
    """The full state (q1 q2 q5 q4, u2 u3 u5 u1 u4 u6) from the independent ones: q4 by Newton on the
    configuration constraint, the dependent speeds from the velocity constraints (linear in u)."""
    y = np.zeros(10)
    y[:3], y[4:7] = q_ind, u_ind
    residual = lambda z: np.array(list(model.constraint_residuals(0.0, z).values()))  # noqa: E731
    for _ in range(50):
        bumped = y.copy()
        bumped[3] += 1e-7
        r = residual(y)[0]
        y[3] -= r / ((residual(bumped)[0] - r) / 1e-7)
        if abs(r) < 1e-15:
            break
    base = y.copy()
    base[7:] = 0.0
    b = residual(base)[1:]
    A = np.column_stack([residual(np.where(np.arange(10) == 7 + j, 1.0, base))[1:] - b for j in range(3)])
    y[7:] = np.linalg.solve(A, -b)
    return y


def test_bicycle_of_test_kane3_compiles_with_its_state_q_u(bicycle):
    km, _, _, model = bicycle
    assert model.coordinates == ("q1", "q2", "q5", "q4")
    assert model.speeds == ("u2", "u3", "u5", "u1", "u4", "u6")
    assert model.residual_labels[0] == ("configuration_0", "position")
    assert model.first_order_form.M.shape == (6, 6) and model.first_order_form.Psi.shape == (3, 1)


def test_bicycle_eigenvalues_at_5_m_s_match_the_benchmark(bicycle):
    """A finite-difference Jacobian of the compiled rhs, reduced to the independent lean, steer and their
    rates as sympy's test_kane3 reduces its linearization, against the published eigenvalues."""
    _, _, (rr, rf), model = bicycle
    x0 = np.array([0.0, 0.0, 0.0, 0.0, 5.0 / rr, 0.0])

    def f(x):
        d = model.rhs(0.0, _on_constraints(model, x[:3], x[3:]))
        return np.concatenate([d[:3], d[4:7]])

    h, J = 1e-5, np.empty((6, 6))
    for j in range(6):
        e = np.zeros(6)
        e[j] = h
        J[:, j] = (f(x0 + e) - f(x0 - e)) / (2 * h)
    lean_steer = [1, 2, 3, 5]  # q2, q5, u2, u5
    eigenvalues = np.sort_complex(np.linalg.eigvals(J[np.ix_(lean_steer, lean_steer)]))
    # measured 8.8e-9: the published values have 8 decimals
    np.testing.assert_allclose(eigenvalues, np.sort_complex(PUBLISHED_5), atol=3e-8)


def test_bicycle_run_agrees_with_scipy_on_sympys_own_equations(bicycle):
    km, values, (rr, rf), model = bicycle
    y0 = _on_constraints(model, [0.0, 0.0, 0.0], [0.5, 5.0 / rr, 0.0])  # 5 m/s, a lean-rate kick
    assert y0[9] == pytest.approx(5.0 / rf, rel=1e-3)
    sol = model.simulate((0, 2.0), q0=y0[:4], u0=y0[4:], rtol=1e-11, atol=1e-11, t_eval=[1.0, 2.0])
    assert sol.status == 0 and sol.constraint_residual < 5e-12  # measured 5.7e-13
    numbers = {s: values[s.name] for s in km.mass_matrix_full.free_symbols | km.forcing_full.free_symbols
               if isinstance(s, sp.Symbol) and s.name in values}
    full = sp.lambdify([list(km.q) + list(km.u)], [km.mass_matrix_full.xreplace(numbers),
                                                  km.forcing_full.xreplace(numbers)], cse=True)

    def reference(_, y):
        M, F = full(y)
        return np.linalg.solve(np.asarray(M, dtype=float), np.asarray(F, dtype=float).ravel())

    ref = solve_ivp(reference, (0, 2.0), y0, method="DOP853", rtol=1e-12, atol=1e-12, t_eval=[1.0, 2.0])
    np.testing.assert_allclose(sol.y, ref.y.T, rtol=0, atol=5e-10)  # measured 6.5e-11
    assert abs(sol.q[-1, 1]) > 1e-2  # the kick did lean it (the comparison is not of a bicycle at rest)
    assert np.ptp(sol.energy) < 1e-12 * abs(sol.energy[0])  # no-slip rolling does no work; measured 1.0e-13


def test_bicycle_with_wheel_angles_is_refused_by_lagrange_paths_and_compiled_right_by_kane(bicycle, cache_dir):
    """Issue 18's variant: the wheel angles q3, q6 as coordinates (u = q̇), velocities still set by hand.
    Re-deriving Lagrange's equations from its T is refused; compile(km) gives the original bicycle's u̇."""
    variant, values, (rr, rf) = kane_models.bicycle(wheel_angles=True)
    with pytest.raises(ModelError, match=r"point \w+: its velocity in N was set by hand .* Compile the KanesMethod"):
        lc.from_kanes_method(variant)
    model = lc.compile(variant, cache_dir=cache_dir, name="whipple_bicycle_wheel_angles", defaults=values)
    assert model.coordinates == ("q1", "q2", "q5", "q3", "q6", "q4")
    original = bicycle[3]
    y = _on_constraints(original, [0.1, 0.05, -0.02], [0.3, 5.0 / rr, -0.1])
    wheels = [1.0, 2.0]  # the wheel angles do not enter the dynamics
    ours = model.rhs(0.0, np.concatenate([y[:3], wheels, y[3:]]))
    np.testing.assert_allclose(ours[6:], original.rhs(0.0, y)[4:], rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(ours[3:5], [y[5], y[9]])  # q̇3 = u3, q̇6 = u6


def test_lagranges_method_with_a_rolling_contact_in_its_velocities_is_refused():
    """A disc rolling upright along a line, the rolling written into the velocities: v_G from the contact
    point (velocity set to zero) by v2pt_theory with the spinning disc frame, L from those velocities."""
    x, phi = me.dynamicsymbols("x phi")
    m, r = sp.symbols("m r", positive=True)
    N = me.ReferenceFrame("N")
    D = N.orientnew("D", "Axis", [-phi, N.z])
    C = me.Point("C")
    C.set_vel(N, 0)
    G = C.locatenew("G", r * N.y)
    G.v2pt_theory(C, N, D)
    disc = me.RigidBody("disc", G, D, m, (me.inertia(D, m * r**2 / 4, m * r**2 / 4, m * r**2 / 2), G))
    lm = me.LagrangesMethod(me.Lagrangian(N, disc), [x, phi], bodies=[disc], frame=N)
    with pytest.raises(ModelError, match="point G: its velocity in N was set by hand"):
        lc.from_lagranges_method(lm)
    with pytest.raises(ModelError, match="point G"):
        lc.System([x, phi], bodies=[disc], frame=N, name="disc")
