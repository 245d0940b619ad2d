"""Events that change the state and continue (`lagcomp.Event(..., reset=...)`, issue 21's first increment).

References are closed forms (a ball bouncing on the floor with restitution e: the impacts' times and velocities)
and scipy's DOP853 restarted by hand at each event (a pendulum kicked at each upward passage of an angle).
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
import sympy as sp
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import solve_ivp

import lagcomp as lc
from lagcomp.errors import ModelError, OptionError, UndeclaredSymbolError
from lagcomp.integrate.status import Status

G, H0, E = 9.81, 1.0, 0.8


def _ball(**event) -> lc.System:
    """Height x above the floor, ẍ = −g; the impact x = 0 downwards reverses and scales the velocity by −e."""
    (x,) = lc.coordinates("x")
    g, e = sp.symbols("g e", positive=True)
    reset = event.pop("reset", {x.diff(lc.t): -e * x.diff(lc.t)})
    return lc.System(coordinates=(x,), T=x.diff(lc.t) ** 2 / 2, V=g * x, name=event.pop("name", "ball"),
                     defaults={"g": G, "e": E}, q0=(H0,), qd0=(0.0,),
                     events=[lc.Event("impact", x, direction=-1, reset=reset, **event)])


def _impacts(e: float, h0: float, t_end: float) -> tuple[np.ndarray, np.ndarray]:
    """The closed form: impact times t_1 = √(2 h0/g), t_{k+1} = t_k + 2 e^k v_1/g, and the speeds e^(k-1) v_1 at
    impact k, for the impacts before t_end (the accumulation point is t_1 + 2 v_1 e/(g (1 − e)))."""
    v1 = math.sqrt(2 * G * h0)
    times, speeds = [math.sqrt(2 * h0 / G)], [v1]
    while True:
        k = len(times)
        following = times[-1] + 2 * e**k * v1 / G
        if following >= t_end:
            return np.array(times), np.array(speeds)
        times.append(following)
        speeds.append(e**k * v1)


@pytest.fixture(scope="module")
def ball(cache_dir) -> lc.Model:
    return lc.compile(_ball(), cache_dir=cache_dir)


def _accumulation(e: float, h0: float) -> float:
    v1 = math.sqrt(2 * G * h0)
    return math.sqrt(2 * h0 / G) + 2 * v1 * e / (G * (1 - e))


@pytest.mark.parametrize("method, options", [("dop853", dict(rtol=1e-13, atol=1e-13)), ("taylor", {})])
def test_a_bouncing_ball_rebounds_with_ratio_e_at_the_closed_form_times(ball, method, options):
    t_end = 3.0  # the accumulation point is at 4.06: eight impacts before it, six before t_end
    assert t_end < _accumulation(E, H0) - 1
    sol = ball.simulate((0.0, t_end), method=method, **options)
    assert sol.status == Status.DONE, sol.message
    impact = sol.events["impact"]
    times, speeds = _impacts(E, H0, t_end)
    assert len(impact) == len(times) == 6
    np.testing.assert_allclose(impact.t, times, rtol=1e-12, atol=0)  # measured 3.0e-14 (dop853), 4.4e-16 (taylor)
    np.testing.assert_allclose(-impact.qd[:, 0], speeds, rtol=1e-12, atol=0)
    np.testing.assert_allclose(impact.qd_after[:, 0] / impact.qd[:, 0], -E, rtol=1e-12, atol=0)
    np.testing.assert_array_equal(impact.q_after, impact.q)  # the reset leaves the height as it was
    assert np.all(np.abs(impact.q[:, 0]) < 1e-12)
    # each impact is two saved rows at its time: the state before, then the state after
    for k, t_k in enumerate(impact.t):
        rows = np.flatnonzero(sol.t == t_k)
        assert rows.size == 2 and rows[1] == rows[0] + 1
        np.testing.assert_array_equal(sol.qd[rows, 0], [impact.qd[k, 0], impact.qd_after[k, 0]])
    assert np.all(np.diff(sol.t) >= 0)
    assert np.all(sol.q[:, 0] > -1e-12)  # no tunnelling through the floor


@pytest.mark.parametrize("method", ["dop853", "taylor"])
def test_a_flight_that_ends_exactly_with_a_step(ball, method):
    """With e = 1/2 the flight after the first impact lasts as long as the fall before it, which Taylor takes in one
    step: the step after the impact (at most that one) ends on the next impact, which the following step finds at
    its very start.  Taylor stopped there with STEP_TOO_SMALL before the step after a reset was kept ≥ the
    smallest step."""
    for h0 in (0.6818181818181819, 0.75, 0.9090909090909092):
        t_end = 0.9 * _accumulation(0.5, h0)
        sol = ball.simulate((0.0, t_end), q0=(h0,), params={"e": 0.5}, method=method)
        times, _ = _impacts(0.5, h0, t_end)
        assert sol.status == Status.DONE, sol.message
        np.testing.assert_allclose(sol.events["impact"].t, times, rtol=1e-12, atol=0)


def test_the_states_after_the_events_in_to_xarray_and_npz(ball, tmp_path):
    sol = ball.simulate((0.0, 1.0))
    impact = sol.events["impact"]
    assert len(impact) == 1 and impact.jumps
    sol.save_npz(tmp_path / "ball.npz")
    data = np.load(tmp_path / "ball.npz")
    np.testing.assert_array_equal(data["event_impact_qd_after"], impact.qd_after)
    xr = pytest.importorskip("xarray")
    ds = sol.to_xarray()
    assert isinstance(ds, xr.Dataset)
    np.testing.assert_array_equal(ds["event_impact_state_after"].values, np.hstack([impact.q_after, impact.qd_after]))


def test_a_run_chunked_into_many_calls_applies_the_same_resets(ball):
    """Small output buffers and step budgets cut the run into many driver calls (between an impact and the step
    after it too): the same impacts as one call."""
    whole = ball.simulate((0.0, 3.0), method="taylor")
    chunked = ball.simulate((0.0, 3.0), method="taylor", t_eval=np.linspace(0.0, 3.0, 20001))
    np.testing.assert_array_equal(chunked.events["impact"].t, whole.events["impact"].t)


def test_a_sweep_over_restitution_and_drop_height_matches_each_closed_form(ball):
    e_values, heights = np.linspace(0.7, 0.9, 5), np.linspace(0.5, 2.0, 4)
    t_end = 1.5
    assert t_end < min(_accumulation(e, h) for e in e_values for h in heights)
    result = ball.sweep((0.0, t_end), {"e": e_values, "x": heights}, output="events", rtol=1e-13, atol=1e-13,
                        workers=1, progress=False)
    assert np.all(result.status == Status.DONE)
    record = result.events["impact"]
    for i, e in enumerate(e_values):
        for j, h in enumerate(heights):
            times, speeds = _impacts(e, h, t_end)
            count = int(record["count"][i, j])
            assert count == len(times), (e, h)
            np.testing.assert_allclose(record["t"][i, j, :count], times, rtol=1e-12, atol=0)
            np.testing.assert_allclose(-record["y"][i, j, :count, 1], speeds, rtol=1e-12, atol=0)


@pytest.mark.parametrize("method", ["dop853", "taylor"])
def test_past_the_accumulation_point_the_run_stops_there_with_a_clear_status(ball, method):
    """Zeno: the impacts accumulate at t∞ = 4.0637; the flights shrink (each step after an impact at most the one
    before it) until an impact follows the last within the smallest step.  Handling accumulation (resting contact)
    is later work; until then the run stops there, promptly, with its own status."""
    sol = ball.simulate((0.0, 6.0), method=method)
    assert sol.status == Status.EVENTS_ACCUMULATED, sol.message
    assert sol.nsteps < 1000                                   # measured 171 (dop853), 157 (taylor)
    assert abs(sol.t[-1] - _accumulation(E, H0)) < 1e-9 * _accumulation(E, H0)
    assert len(sol.events["impact"]) > 100 and np.all(sol.q[:, 0] > -1e-12)


@pytest.mark.parametrize("method", ["dop853", "taylor"])
def test_a_reset_that_stops_the_fall_warns_when_the_ball_then_sinks_through_the_floor(ball, method):
    """A "plastic floor" written as a reset (e = 0: ẋ⁺ = 0 at x = 0): gravity then takes the ball below the floor,
    which leaves the event's zero rather than crossing it, so the event does not fire again.  The run warns and
    names lc.Contact; a bounce (e = 0.5) does not warn, nor does a kick that carries on (the kicked pendulum)."""
    with pytest.warns(lc.ResetWarning, match=r"event 'impact': its reset at t = 0\.4515.*lc\.Contact"):
        sol = ball.simulate((0.0, 1.0), params={"e": 0.0}, method=method)
    assert sol.status == Status.DONE and len(sol.events["impact"]) == 1
    assert sol.q[-1, 0] < -0.5 * G * (1.0 - math.sqrt(2 * H0 / G)) ** 2 * (1 - 1e-9)   # it did sink: −g τ²/2
    with warnings.catch_warnings():
        warnings.simplefilter("error", lc.ResetWarning)
        bounced = ball.simulate((0.0, 1.0), params={"e": 0.5}, method=method)
    assert len(bounced.events["impact"]) == 2 and bounced.q[-1, 0] > 0       # impacts at 0.4515 and 0.9030


# -- a reset coupling the state and time, against scipy restarted by hand ---------------------------------------

K, THETA_C = 0.3, 0.2


def _kicked_pendulum() -> lc.System:
    """θ̈ = −sin θ; each upward passage of θ = θ_c kicks θ̇ by k cos θ e^(−t/10) (a reset reading θ and t)."""
    (theta,) = lc.coordinates("theta")
    k = sp.Symbol("k", positive=True)
    return lc.System(coordinates=(theta,), T=theta.diff(lc.t) ** 2 / 2, V=-sp.cos(theta), name="kicked",
                     defaults={"k": K},
                     events=[lc.Event("kick", theta - THETA_C, direction=1,
                                      reset={theta.diff(lc.t): theta.diff(lc.t)
                                             + k * sp.cos(theta) * sp.exp(-lc.t / 10)})])


def _kicked_reference(t_end: float) -> tuple[np.ndarray, np.ndarray]:
    """scipy's DOP853 at rtol 1e-12 with a terminal event, restarted by hand after each kick (a first 1e-6 without
    the event, which scipy would otherwise find again at its start)."""
    def f(t, y):
        return [y[1], -math.sin(y[0])]

    def kick(t, y):
        return y[0] - THETA_C
    kick.terminal, kick.direction = True, 1
    t, y, times = 0.0, np.array([0.0, 1.0]), []
    while True:
        sol = solve_ivp(f, (t, t_end), y, method="DOP853", rtol=1e-13, atol=1e-13, events=kick)
        if sol.status == 0:
            return np.array(times), sol.y[:, -1]
        t, y = sol.t_events[0][0], sol.y_events[0][0].copy()
        times.append(t)
        y[1] += K * math.cos(y[0]) * math.exp(-t / 10)
        step = solve_ivp(f, (t, t + 1e-6), y, method="DOP853", rtol=1e-13, atol=1e-13)
        t, y = step.t[-1], step.y[:, -1]


@pytest.mark.parametrize("method", ["dop853", "taylor"])
def test_a_kicked_pendulum_matches_scipy_restarted_at_each_kick(cache_dir, method):
    model = lc.compile(_kicked_pendulum(), cache_dir=cache_dir)
    t_end = 20.0
    sol = model.simulate((0.0, t_end), q0=(0.0,), qd0=(1.0,), method=method,
                         **({"rtol": 1e-13, "atol": 1e-13} if method == "dop853" else {}))
    times, final = _kicked_reference(t_end)
    kick = sol.events["kick"]
    assert sol.status == Status.DONE and len(kick) == len(times) >= 3
    np.testing.assert_allclose(kick.t, times, rtol=0, atol=1e-10)
    jump = K * np.cos(kick.q[:, 0]) * np.exp(-kick.t / 10)
    np.testing.assert_allclose(kick.qd_after[:, 0] - kick.qd[:, 0], jump, rtol=1e-14, atol=0)
    np.testing.assert_allclose(np.concatenate([sol.q[-1], sol.qd[-1]]), final, rtol=0, atol=1e-9)


def test_a_kane_model_resets_its_speeds(cache_dir):
    """The same ball from sympy's KanesMethod: the reset sets the speed u(t)."""
    me = pytest.importorskip("sympy.physics.mechanics")
    x, u = me.dynamicsymbols("x u")
    g, e = sp.symbols("g e", positive=True)
    N = me.ReferenceFrame("N")
    origin = me.Point("O")
    origin.set_vel(N, 0)
    P = origin.locatenew("P", x * N.x)
    P.set_vel(N, u * N.x)
    ball = me.Particle("ball", P, 1)
    km = me.KanesMethod(N, q_ind=[x], u_ind=[u], kd_eqs=[x.diff(me.dynamicsymbols._t) - u])
    km.kanes_equations([ball], [(P, -g * N.x)])
    model = lc.compile(km, cache_dir=cache_dir, name="kane_ball", parameters=(g, e), defaults={"g": G, "e": E},
                       q0=(H0,), u0=(0.0,), events=[lc.Event("impact", x, direction=-1, reset={u: -e * u})])
    sol = model.simulate((0.0, 3.0), rtol=1e-13, atol=1e-13)
    times, _ = _impacts(E, H0, 3.0)
    np.testing.assert_allclose(sol.events["impact"].t, times, rtol=1e-12, atol=0)
    np.testing.assert_allclose(sol.events["impact"].qd_after[:, 0] / sol.events["impact"].qd[:, 0], -E, rtol=1e-12)


# -- refusals -------------------------------------------------------------------------------------------------------

def test_a_terminal_event_cannot_reset():
    with pytest.raises(ModelError, match="terminal"):
        _ball(terminal=True)


def test_a_reset_of_something_that_is_not_a_coordinate_is_refused():
    (x, y) = lc.coordinates("x y")
    with pytest.raises(ModelError, match=r"y\(t\) is not a coordinate"):
        _ball(reset={y.diff(lc.t): 0})
    with pytest.raises(ModelError, match="neither a coordinate"):
        _ball(reset={sp.Symbol("v"): 0})
    with pytest.raises(ModelError, match="neither a coordinate"):
        _ball(reset={x.diff(lc.t, 2): 0})
    with pytest.raises(ModelError, match="string"):
        _ball(reset={x.diff(lc.t): "-e*x"})
    with pytest.raises(ModelError, match="must map"):
        _ball(reset=[x])
    with pytest.raises(ModelError, match="empty"):
        _ball(reset={})


_X = lc.coordinates("x")[0]
#: Keys a reset may not have: numbers, symbols, expressions of the state, accelerations, other functions of t.
BAD_KEYS = st.sampled_from([1, 2.5, sp.Symbol("x"), sp.Symbol("v"), _X**2, _X + 1, sp.sin(_X), 2 * _X.diff(lc.t),
                            _X.diff(lc.t, 2), sp.Function("w")(lc.t), sp.Function("w")(lc.t).diff(lc.t), lc.t,
                            sp.Function("x")(sp.Symbol("s"))])


@settings(max_examples=40, deadline=None)
@given(key=BAD_KEYS, value=st.sampled_from([0, 1.5, sp.Symbol("e", positive=True), -_X.diff(lc.t)]))
def test_any_reset_of_something_that_is_not_a_coordinate_or_velocity_is_refused(key, value):
    with pytest.raises(ModelError):
        _ball(reset={key: value})


def test_a_reset_with_an_undeclared_symbol_is_refused_at_build_time():
    (x,) = lc.coordinates("x")
    g, e, w = sp.symbols("g e w", positive=True)
    with pytest.raises(UndeclaredSymbolError, match=r"w .*event impact reset"):
        lc.System(coordinates=(x,), T=x.diff(lc.t) ** 2 / 2, V=g * x, parameters=(g, e),
                  events=[lc.Event("impact", x, direction=-1, reset={x.diff(lc.t): -w * x.diff(lc.t)})])


def test_a_reset_reading_an_input_is_refused():
    (x,) = lc.coordinates("x")
    s = lc.Input("s")
    with pytest.raises(ModelError, match="reads the input"):
        _ball(reset={x.diff(lc.t): -s * x.diff(lc.t)})


@pytest.mark.parametrize("method, options", [("rk4", dict(dt=1e-3)), ("radau", {}), ("gauss2", dict(dt=1e-3))])
def test_methods_that_cannot_reset_are_refused_unless_the_events_are_left_out(ball, method, options):
    with pytest.raises(OptionError, match=r"reset the state.*events=False"):
        ball.simulate((0.0, 1.0), method=method, **options)
    sol = ball.simulate((0.0, 0.2), method=method, events=False, **options)
    assert sol.status == Status.DONE


def test_resets_with_sensitivities_or_batched_sweeps_are_refused(ball):
    with pytest.raises(OptionError, match="saltation"):
        ball.simulate((0.0, 1.0), sensitivities=("q0",))
    with pytest.raises(OptionError, match="batched"):
        ball.sweep((0.0, 1.0), {"e": [0.5, 0.6]}, batched=True, progress=False)


@pytest.mark.parametrize("method", ["dop853", "taylor"])
def test_a_reset_to_a_non_finite_state_stops_the_run_at_the_event(cache_dir, method):
    (x,) = lc.coordinates("x")
    g = sp.Symbol("g", positive=True)
    e = sp.Symbol("e", positive=True)
    model = lc.compile(_ball(name="ball_nonfinite", reset={x.diff(lc.t): x.diff(lc.t) * sp.exp(1000 * g * e)}),
                       cache_dir=cache_dir)
    sol = model.simulate((0.0, 1.0), method=method)
    assert sol.status == Status.RESET_FAILED, sol.message
    assert "reset" in sol.message
    assert sol.t[-1] == pytest.approx(math.sqrt(2 * H0 / G), rel=1e-12, abs=0)
    assert np.all(np.isfinite(sol.qd))


@pytest.mark.parametrize("method", ["dop853", "dopri5", "taylor"])
@pytest.mark.parametrize("rtol", [1e-12, 1e-8, 1e-6])
@pytest.mark.parametrize("e, h0", [(0.45, 0.5), (0.8, 1.0), (0.3, 2.0)])
def test_the_ball_never_passes_through_the_floor(ball, method, rtol, e, h0):
    # Near t∞ a flight is shorter than the first sample after its impact (h/2048) or than the resolution of
    # t: the first sample is already below the floor.  g left its zero upwards, so that is a return (bracketed,
    # or at t: accumulated), never a ball falling through (before the fix: status 0 and x = -600 at t = 12).
    sol = ball.simulate((0.0, 12.0), [h0], [0.0], params={"e": e}, method=method, rtol=rtol, atol=rtol)
    assert sol.status == Status.EVENTS_ACCUMULATED
    assert sol.t[-1] == pytest.approx(_accumulation(e, h0), rel=1e-9)
    assert sol.q[:, 0].min() > -1e-14
