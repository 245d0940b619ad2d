"""Forward sensitivities through `simulate(..., sensitivities=...)` (`lagcomp.integrate.sensitivities`).

Oracles: the closed form of a linear oscillator, and central finite differences of high-precision runs of
the double pendulum with Richardson extrapolation (issue #22's target: 1e-8 relative at t = 10).
"""

from __future__ import annotations

import numba
import numpy as np
import pytest
import sympy as sp

import lagcomp as lc
from lagcomp.model import t

x = lc.coordinates("x")[0]
m, k = sp.symbols("m k", positive=True)
OMEGA = 2.0                     # sqrt(k / m) with k = 4, m = 1
#: A regular (not chaotic) motion of the double pendulum: finite differences converge there.
PENDULUM_STATE = np.array([0.5, 0.3, 0.0, 0.0])


@pytest.fixture(scope="module")
def oscillator(cache_dir):
    system = lc.System([x], T=m * x.diff(t) ** 2 / 2, V=k * x**2 / 2, name="sensitivity_oscillator",
                       defaults={"m": 1.0, "k": OMEGA**2}, q0=(1.0,), qd0=(0.5,))
    return lc.compile(system, cache_dir=cache_dir)


@pytest.fixture(scope="module")
def pendulum(compiled):
    return compiled("double_pendulum")


def _pendulum_run(model, y0, rtol, **options):
    return model.simulate((0.0, 10.0), y0[:2], y0[2:], rtol=rtol, atol=rtol, progress=False, **options)


def test_oscillator_matches_the_closed_form(oscillator):
    sol = oscillator.simulate((0.0, 10.0), rtol=1e-12, atol=1e-12, sensitivities=("q0", "qd0"), progress=False)
    assert sol.success and sol.sensitivity_names == ("q0:x", "qd0:x_dot")
    assert sol.sensitivities.shape == (sol.t.size, 2, 2) and sol.q.shape == (sol.t.size, 1)
    c, s = np.cos(OMEGA * sol.t), np.sin(OMEGA * sol.t)
    exact = np.stack([np.stack([c, s / OMEGA], axis=-1), np.stack([-OMEGA * s, c], axis=-1)], axis=1)
    assert np.abs(sol.sensitivities - exact).max() < 1e-10
    assert np.array_equal(sol.sensitivities[0], np.eye(2))


def test_double_pendulum_against_richardson_extrapolated_differences(pendulum):
    def end(y0):
        return _pendulum_run(pendulum, y0, 1e-13).y[-1]

    def differences(h):
        columns = []
        for j in range(4):
            e = np.zeros(4)
            e[j] = h
            columns.append((end(PENDULUM_STATE + e) - end(PENDULUM_STATE - e)) / (2 * h))
        return np.stack(columns, axis=1)

    reference = (4 * differences(5e-4) - differences(1e-3)) / 3
    sol = _pendulum_run(pendulum, PENDULUM_STATE, 1e-12, sensitivities=("q0", "qd0"))
    relative = np.abs(sol.sensitivities[-1] - reference).max() / np.abs(reference).max()
    assert relative < 1e-8, relative           # measured 1.0e-10 (1.2e-10 with sensitivity_control="state")


def test_state_control_takes_the_plain_runs_steps(pendulum):
    plain = _pendulum_run(pendulum, PENDULUM_STATE, 1e-10)
    sol = _pendulum_run(pendulum, PENDULUM_STATE, 1e-10, sensitivities="q0", sensitivity_control="state")
    assert sol.q.shape == plain.q.shape and sol.qd.shape == plain.qd.shape and sol.sensitivities.shape[1:] == (4, 2)
    assert (sol.nsteps, sol.nrejected) == (plain.nsteps, plain.nrejected)
    # the same steps up to the rounding of the tolerances' division (the step sizes differ at ~1e-7 relative)
    assert np.abs(sol.t - plain.t).max() < 1e-6 and np.abs(sol.y[-1] - plain.y[-1]).max() < 1e-12


def test_both_control_stays_within_the_tolerance_of_a_plain_run(pendulum):
    plain = _pendulum_run(pendulum, PENDULUM_STATE, 1e-10)
    both = _pendulum_run(pendulum, PENDULUM_STATE, 1e-10, sensitivities="q0", sensitivity_control="both")
    state = _pendulum_run(pendulum, PENDULUM_STATE, 1e-10, sensitivities="q0")
    # the step control covers the sensitivities too: more steps, the same trajectory to the tolerance
    assert both.nsteps > plain.nsteps
    assert np.abs(both.y[-1] - plain.y[-1]).max() < 1e-8
    assert np.abs(both.sensitivities[-1] - state.sensitivities[-1]).max() < 1e-7 * np.abs(state.sensitivities).max()


def test_names_choose_columns_and_t_eval_interpolates_them(pendulum):
    full = _pendulum_run(pendulum, PENDULUM_STATE, 1e-12, sensitivities=("q0", "qd0"), t_eval=[2.5, 10.0])
    one = _pendulum_run(pendulum, PENDULUM_STATE, 1e-12, sensitivities=["theta2_dot", "q0:theta1"],
                        t_eval=[2.5, 10.0])
    assert one.sensitivity_names == ("q0:theta1", "qd0:theta2_dot") and np.array_equal(one.t, [2.5, 10.0])
    scale = np.abs(full.sensitivities).max()
    assert np.abs(one.sensitivities - full.sensitivities[:, :, [0, 3]]).max() < 1e-9 * scale


def test_summary_runs_keep_the_first_and_last_rows(pendulum):
    full = _pendulum_run(pendulum, PENDULUM_STATE, 1e-10, sensitivities="qd0")
    summary = _pendulum_run(pendulum, PENDULUM_STATE, 1e-10, sensitivities="qd0", record="summary")
    assert summary.sensitivities.shape == (2, 4, 2)
    assert np.array_equal(summary.sensitivities, full.sensitivities[[0, -1]])


def test_xarray_names_the_axes(pendulum):
    pytest.importorskip("xarray")
    sol = _pendulum_run(pendulum, PENDULUM_STATE, 1e-8, sensitivities="q0")
    data = sol.to_xarray()["sensitivities"]
    assert data.dims == ("t", "state", "wrt")
    assert list(data["wrt"].values) == ["q0:theta1", "q0:theta2"]
    assert list(data["state"].values) == list(sol.state_names) == ["theta1", "theta2", "theta1_dot", "theta2_dot"]
    assert np.array_equal(data.values, sol.sensitivities)


@pytest.mark.parametrize(("options", "culprit"), [
    (dict(method="rk4", dt=0.01), "`rk4`"),
    (dict(method="radau"), "`radau`"),
    (dict(sensitivities="nonsense"), "'nonsense'"),
    (dict(sensitivities=()), "names no column"),
    (dict(sensitivity_control="all"), "'all'"),
])
def test_refusals(pendulum, options, culprit):
    options = {"sensitivities": "q0", **options}
    with pytest.raises(lc.OptionError) as info:
        pendulum.simulate((0.0, 1.0), progress=False, **options)
    assert culprit in str(info.value)


def test_refusals_of_models_and_runs(compiled, oscillator, cache_dir):
    with pytest.raises(lc.OptionError, match="sweep does not"):
        oscillator.sweep((0.0, 1.0), {"x": [0.0, 1.0]}, sensitivities="q0", progress=False)
    pushed = lc.compile(lc.System([x], T=m * x.diff(t) ** 2 / 2, V=k * x**2 / 2, forces=[lc.Input("f")],
                                  name="sensitivity_pushed", defaults={"m": 1.0, "k": 1.0}, q0=(1.0,),
                                  events=[lc.Event("follows", x - lc.Input("f"))]),
                        cache_dir=cache_dir)
    with pytest.raises(lc.OptionError, match="numba functions"):
        pushed.simulate((0.0, 1.0), inputs={"f": numba.njit(lambda t, y, p: 0.0)}, sensitivities="q0",
                        events=False, progress=False)
    table = {"f": ([0.0, 1.0], [0.0, 0.5])}     # (a linear table: the event reads no derivative of f)
    with pytest.raises(lc.OptionError, match="events that read inputs"):
        pushed.simulate((0.0, 1.0), inputs=table, sensitivities="q0", progress=False)
    assert pushed.simulate((0.0, 1.0), inputs=table, progress=False).success


def test_parameter_columns_match_the_closed_form(oscillator):
    sol = oscillator.simulate((0.0, 10.0), rtol=1e-12, atol=1e-12, sensitivities=("params", "q0"), progress=False)
    assert oscillator.parameters == ("k", "m") and sol.sensitivity_names == ("q0:x", "p:k", "p:m")
    # x = x0 cos ωt + v0/ω sin ωt, ω = sqrt(k/m): ∂x/∂k = ∂x/∂ω / (2 m ω), ∂x/∂m = -(k/m) ∂x/∂k
    x0, v0, tt = 1.0, 0.5, sol.t
    c, s = np.cos(OMEGA * tt), np.sin(OMEGA * tt)
    dx_domega = -x0 * tt * s + v0 * (tt * c / OMEGA - s / OMEGA**2)
    dx_dk = dx_domega / (2 * OMEGA)
    assert np.abs(sol.sensitivities[:, 0, 1] - dx_dk).max() < 1e-9
    assert np.abs(sol.sensitivities[:, 0, 2] + OMEGA**2 * dx_dk).max() < 1e-9


def test_double_pendulum_parameter_columns_against_richardson_extrapolated_differences(pendulum):
    """∂y(10)/∂p through the emitted ``rhs_parameter_jacobian``, against relative central differences in each
    parameter of rtol 1e-13 runs, extrapolated (the issue's 1e-8 relative)."""
    base = {name: float(value) for name, value in pendulum.defaults.items()}

    def end(values):
        return pendulum.simulate((0.0, 10.0), PENDULUM_STATE[:2], PENDULUM_STATE[2:], params=values,
                                 rtol=1e-13, atol=1e-13, progress=False).y[-1]

    def differences(h):
        return np.stack([(end({**base, name: base[name] * (1 + h)}) - end({**base, name: base[name] * (1 - h)}))
                         / (2 * h * base[name]) for name in pendulum.parameters], axis=1)

    reference = (4 * differences(5e-4) - differences(1e-3)) / 3
    sol = _pendulum_run(pendulum, PENDULUM_STATE, 1e-12, sensitivities="params")
    assert sol.sensitivity_names == tuple(f"p:{name}" for name in pendulum.parameters)
    relative = np.abs(sol.sensitivities[-1] - reference).max() / np.abs(reference).max()
    assert relative < 1e-8, relative           # measured 5.5e-10 (5.6e-10 with sensitivity_control="state")


def test_kane_model_state_is_q_and_u(cache_dir):
    import sympy.physics.mechanics as me

    w = me.dynamicsymbols("w")
    frame, point = me.ReferenceFrame("N"), me.Point("P")
    point.set_vel(frame, w * frame.x)
    km = me.KanesMethod(frame, [x], [w], kd_eqs=[x.diff(t) - w])
    km.kanes_equations([me.Particle("p", point, m)], [(point, -k * x * frame.x)])
    model = lc.compile(km, name="sensitivity_kane_oscillator", cache_dir=cache_dir,
                       defaults={"m": 1.0, "k": OMEGA**2}, events=[lc.Event("zero", x)])
    sol = model.simulate((0.0, 5.0), [1.0], [0.5], rtol=1e-12, atol=1e-12, sensitivities=("q0", "u0"),
                         progress=False)
    assert sol.sensitivity_names == ("q0:x", "qd0:w") and sol.state_names == ("x", "w")
    c, s = np.cos(OMEGA * sol.t), np.sin(OMEGA * sol.t)
    exact = np.stack([np.stack([c, s / OMEGA], axis=-1), np.stack([-OMEGA * s, c], axis=-1)], axis=1)
    assert np.abs(sol.sensitivities - exact).max() < 1e-10
    b = 0.5 / OMEGA                                   # the crossings' times as in the closed-form test below
    a2 = 1.0 + b**2
    crossings = sol.event_sensitivities["zero"].t
    assert crossings.shape == (3, 2) and np.abs(crossings - [-b / (a2 * OMEGA), 1.0 / (a2 * OMEGA**2)]).max() < 1e-10


@pytest.fixture(scope="module")
def crossing_oscillator(cache_dir):
    """The oscillator with two events: ``zero``, x = 0 either way (closed form), and ``line``, terminal, x crossing
    the moving line k t / 40 downwards (its partials ∂g/∂t and ∂g/∂k nonzero)."""
    system = lc.System([x], T=m * x.diff(t) ** 2 / 2, V=k * x**2 / 2, name="sensitivity_crossings",
                       defaults={"m": 1.0, "k": OMEGA**2}, q0=(1.0,), qd0=(0.5,),
                       events=[lc.Event("zero", x), lc.Event("line", x - k * t / 40, direction=-1, terminal=True)])
    return lc.compile(system, cache_dir=cache_dir)


def _richardson(crossings, w0, scales):
    """∂crossings/∂w at w0 by central differences of steps h scales_j (h = 1e-3, 5e-4), extrapolated: (…, len(w0))."""
    def differences(h):
        result = []
        for j, scale in enumerate(scales):
            step = np.zeros(w0.size)
            step[j] = h * scale
            result.append((crossings(w0 + step) - crossings(w0 - step)) / (2 * step[j]))
        return np.stack(result, axis=-1)
    return (4 * differences(5e-4) - differences(1e-3)) / 3


def test_event_time_sensitivities_match_the_closed_form(crossing_oscillator):
    """x = A cos(ω t − φ), A² = x0² + (v0/ω)², φ = atan2(v0/ω, x0): crossings t_j = (π/2 + φ + j π)/ω, whose
    derivatives wrt x0, v0 are those of φ/ω, wrt ω −t_j/ω + ∂φ/∂ω / ω (k = ω² m, m = 1); there x stays 0 and
    v = −(−1)^j ω A."""
    options = dict(rtol=1e-12, atol=1e-12, events="zero", progress=False)
    sol = crossing_oscillator.simulate((0.0, 10.0), sensitivities=("q0", "qd0", "params"),
                                       sensitivity_control="state", **options)   # the plain run's steps
    plain = crossing_oscillator.simulate((0.0, 10.0), **options)
    assert sol.sensitivity_names == ("q0:x", "qd0:x_dot", "p:k", "p:m")
    assert set(sol.event_sensitivities) == {"zero", "line"} and len(sol.event_sensitivities["line"]) == 0
    times, found = sol.events["zero"].t, sol.event_sensitivities["zero"]
    assert times.size == 6 == len(found) and np.abs(times - plain.events["zero"].t).max() < 1e-14
    assert found.t.shape == (6, 4) and found.y.shape == (6, 2, 4)
    x0, v0, b = 1.0, 0.5, 0.5 / OMEGA
    a2, sign = x0**2 + b**2, (-1.0) ** np.arange(6)
    d_omega = -times / OMEGA - x0 * v0 / (a2 * OMEGA**3)
    exact_t = np.stack([np.full(6, -b / (a2 * OMEGA)), np.full(6, x0 / (a2 * OMEGA**2)),
                        d_omega / (2 * OMEGA), -OMEGA / 2 * d_omega], axis=1)   # dω/dk = 1/(2ω), dω/dm = −ω/2
    assert np.abs(found.t - exact_t).max() < 1e-10                   # measured 4.9e-12
    assert np.abs(found.y[:, 0]).max() < 1e-12                       # the crossing stays on x = 0
    amplitude = np.sqrt(a2)
    assert np.abs(found.y[:, 1, 0] + sign * OMEGA * x0 / amplitude).max() < 1e-10
    assert np.abs(found.y[:, 1, 1] + sign * v0 / (OMEGA * amplitude)).max() < 1e-10


def test_terminal_event_with_time_and_parameter_against_differences(crossing_oscillator):
    """The terminal ``line`` event (g = x − k t / 40: ∂g/∂t and ∂g/∂k count) against extrapolated differences of
    rtol 1e-13 runs in x0, v0, k, m."""
    def crossing(w):
        sol = crossing_oscillator.simulate((0.0, 10.0), [w[0]], [w[1]], params={"k": w[2], "m": w[3]}, rtol=1e-13,
                                           atol=1e-13, events="line", progress=False)
        record = sol.events["line"]
        return np.concatenate([record.t, record.q[0], record.qd[0]])

    w0 = np.array([1.0, 0.5, OMEGA**2, 1.0])
    reference = _richardson(crossing, w0, np.abs(w0))
    sol = crossing_oscillator.simulate((0.0, 10.0), rtol=1e-12, atol=1e-12, events="line", progress=False,
                                       sensitivities=("q0", "qd0", "params"))
    assert sol.status == 1 and sol.t[-1] == sol.events["line"].t[0]
    found = sol.event_sensitivities["line"]
    got = np.concatenate([found.t, found.y[0]])
    relative = np.abs(got - reference).max() / np.abs(reference).max()
    assert relative < 1e-8, relative                   # measured 3.1e-12


def test_poincare_section_of_henon_heiles_against_richardson_extrapolated_differences(compiled):
    """The times and the states of four crossings of the Poincaré section x = 0 (upwards) of Hénon–Heiles over
    t ∈ [0, 20], from off the section, against extrapolated differences of rtol 1e-13 runs: every column (x0, y0,
    ẋ0, ẏ0, λ) to the issue's 1e-8 relative, and the crossings' times those of a plain run."""
    model = compiled("henon_heiles")
    w0 = np.array([-0.1, 0.1, 0.35, 0.0, 1.0])

    def run(w, rtol, **options):
        return model.simulate((0.0, 20.0), w[:2], w[2:4], params={"lam": w[4]}, rtol=rtol, atol=rtol,
                              progress=False, **options)

    def crossings(w):
        record = run(w, 1e-13).events["section"]
        return np.concatenate([record.t[:, None], record.q, record.qd], axis=1)

    reference = _richardson(crossings, w0, (0.1, 0.1, 0.35, 0.1, 1.0))   # (ẏ0 = 0 has no scale of its own)
    sol = run(w0, 1e-12, sensitivities=("q0", "qd0", "params"), sensitivity_control="state")  # the plain steps
    assert sol.sensitivity_names == ("q0:x", "q0:y", "qd0:x_dot", "qd0:y_dot", "p:lam")
    found = sol.event_sensitivities["section"]
    got = np.concatenate([found.t[:, None, :], found.y], axis=1)
    assert got.shape == reference.shape == (4, 5, 5)
    assert np.abs(sol.events["section"].t - run(w0, 1e-12).events["section"].t).max() < 1e-13
    relative = np.abs(got - reference).max() / np.abs(reference).max()
    assert relative < 1e-8, relative                   # measured 2.4e-11
