"""Contacts (`lagcomp.Contact`): the impact branch of ``event_reset`` and the refusals.

References: Newton's restitution on one contact (v⁺ = −e v⁻), the three-ball chain's closed form
(`tests/test_impacts.py` derives it), and the kinetic energy and momentum an elastic impact keeps.
"""

import numpy as np
import pytest
import sympy as sp

import lagcomp as lc
from lagcomp.errors import InitialConditionError, ModelError, OptionError, ParameterError
from lagcomp.integrate.status import Status

t = lc.t


@pytest.fixture(scope="module")
def ball(tmp_path_factory):
    x, = lc.coordinates("x")
    m, g, e = sp.symbols("m g e", positive=True)
    system = lc.System([x], T=m * x.diff(t) ** 2 / 2, V=m * g * x, events=[lc.Contact("floor", x, restitution=e)],
                       name="contact_ball", defaults={"m": 2.0, "g": 9.81, "e": 0.9})
    return lc.compile(system, cache_dir=tmp_path_factory.mktemp("cache"))


@pytest.fixture(scope="module")
def chain(tmp_path_factory):
    x1, x2, x3 = lc.coordinates("x1 x2 x3")
    d, m2 = sp.symbols("d m2", positive=True)
    T = (x1.diff(t) ** 2 + m2 * x2.diff(t) ** 2 + x3.diff(t) ** 2) / 2
    system = lc.System([x1, x2, x3], T=T, events=[lc.Contact("c12", x2 - x1 - d), lc.Contact("c23", x3 - x2 - d)],
                       name="contact_chain", defaults={"d": 1.0, "m2": 1.0})
    return lc.compile(system, cache_dir=tmp_path_factory.mktemp("cache"))


def _reset(model, y, params, event):
    out = np.empty(len(y))
    p = model.parameter_vector(params)
    status = model.kernels.event_reset(0.0, np.asarray(y, float), p, event, out)
    return status, out


@pytest.mark.parametrize("e", [0.0, 0.5, 0.9, 1.0])
def test_the_floor_reverses_the_velocity_by_e(ball, e):
    status, out = _reset(ball, [0.0, -3.25], {"e": e}, 0)
    assert status == 0
    assert out[0] == 0.0
    assert out[1] == pytest.approx(3.25 * e, rel=1e-15, abs=0.0)


@pytest.mark.parametrize("m2", [1.0, 3.0])
def test_three_balls_at_once(chain, m2):
    # Ball 1 arrives at speed 1 on balls 2 and 3 touching at rest: both contacts take part.
    y = [0.0, 1.0, 2.0, 1.0, 0.0, 0.0]
    for event in (0, 1):            # whichever contact's event fires, the impact is the same
        status, out = _reset(chain, y, {"m2": m2}, event)
        assert status == 0
        np.testing.assert_array_equal(out[:3], y[:3])
        v = out[3:]
        masses = np.array([1.0, m2, 1.0])
        assert masses @ v == pytest.approx(1.0, rel=1e-15, abs=0)                        # momentum
        assert 0.5 * masses @ v**2 == pytest.approx(0.5, rel=1e-14, abs=0)               # e = 1: energy
        assert v[1] - v[0] >= 0 and v[2] - v[1] >= -1e-15                         # no approach left
    if m2 == 1.0:
        np.testing.assert_allclose(out[3:], [-1 / 3, 2 / 3, 2 / 3], rtol=1e-15)


def test_an_open_contact_is_left_out(chain):
    # Ball 3 is far away: only c12 acts, an exchange of velocities for equal masses.
    status, out = _reset(chain, [0.0, 1.0, 5.0, 1.0, 0.0, 0.0], {"m2": 1.0}, 0)
    assert status == 0
    np.testing.assert_allclose(out[3:], [0.0, 1.0, 0.0], atol=1e-16)


def test_contacts_constant(ball, chain):
    assert ball.kernels.CONTACTS == (("floor", 0, "e"),)
    assert chain.kernels.CONTACTS == (("c12", 0, 1.0), ("c23", 1, 1.0))


@pytest.mark.parametrize("restitution", [-0.1, 1.5, "e", sp.Symbol("e") + 1, True, float("nan")])
def test_bad_restitution_refused(restitution):
    x, = lc.coordinates("x")
    with pytest.raises(ModelError, match="restitution"):
        lc.Contact("floor", x, restitution=restitution)


def test_bad_contacts_refused():
    x, = lc.coordinates("x")
    with pytest.raises(ModelError, match="velocities"):
        lc.Contact("floor", x.diff(t) + x)
    with pytest.raises(ModelError, match="direction"):
        lc.Contact("floor", x, direction=1)
    y, = lc.coordinates("y")
    with pytest.raises(ModelError, match="not a coordinate"):
        lc.System([x], T=x.diff(t) ** 2 / 2, events=[lc.Contact("floor", y)], name="stray")


def test_run_refuses_penetration_and_restitution_out_of_range(ball):
    with pytest.raises(InitialConditionError, match="gap is -0.01"):
        ball.simulate((0.0, 1.0), [-0.01], [0.0])
    with pytest.raises(ParameterError, match="outside"):
        ball.simulate((0.0, 1.0), [1.0], [0.0], params={"e": 1.2})
    with pytest.raises(ParameterError, match="trajectory 1"):
        ball.sweep((0.0, 1.0), grid={"e": [0.5, 1.5]}, q0=[1.0], qd0=[0.0])


def test_the_impact_under_the_names_of_its_own_code(tmp_path):
    # The branch's locals, its solver and the kernel's arguments as the user's names (tests/test_names.py
    # collects every emitted identifier; these are the ones the impact branch adds).
    e_, out, mass, firing = sp.symbols("e out _mass _firing", positive=True)
    c, = lc.coordinates("contact_impacts")
    system = lc.System([c], T=mass * c.diff(t) ** 2 / 2, V=firing * c,
                       events=[lc.Contact("np", c - out, restitution=e_)], name="contact_names")
    model = lc.compile(system, cache_dir=tmp_path)
    status, after = _reset(model, [0.5, -2.0], {"e": 0.25, "out": 0.5, "_mass": 3.0, "_firing": 1.0}, 0)
    assert status == 0
    np.testing.assert_array_equal(after, [0.5, 0.5])


# -- runs ---------------------------------------------------------------------------------------------


def _impact_times(h0, g, e, count):
    """The closed form of a ball dropped from rest at h0: t_1 = √(2 h0/g), then flights of 2 eᵏ v_1/g."""
    v1 = np.sqrt(2 * g * h0)
    times = [np.sqrt(2 * h0 / g)]
    for k in range(1, count):
        times.append(times[-1] + 2 * e**k * v1 / g)
    return np.array(times), v1


@pytest.mark.parametrize("method", ["dop853", "taylor"])
def test_bouncing_ball_rebounds_by_e_at_the_closed_form_times(ball, method):
    h0, g, e, count = 1.25, 9.81, 0.8, 12
    times, v1 = _impact_times(h0, g, e, count)
    t_end = times[-1] + 0.5 * (times[-1] - times[-2])
    sol = ball.simulate((0.0, t_end), [h0], [0.0], params={"e": e, "g": g}, method=method, rtol=1e-13, atol=1e-13)
    assert sol.status >= 0
    floor = sol.events["floor"]
    assert len(floor) == count
    np.testing.assert_allclose(floor.t, times, rtol=1e-12)
    np.testing.assert_allclose(floor.qd[:, 0], -v1 * e ** np.arange(count), rtol=1e-12)
    np.testing.assert_allclose(floor.qd_after[:, 0] / floor.qd[:, 0], -e, rtol=1e-12)
    assert np.abs(floor.q[:, 0]).max() < 1e-14                       # at the floor, not through it
    assert sol.q[:, 0].min() > -1e-14


def test_newtons_cradle_keeps_momentum_and_energy(chain):
    # Ball 1 arrives at speed 1 on balls 2 and 3 at rest, touching: one simultaneous impact, then free flight.
    sol = chain.simulate((0.0, 2.0), [-0.5, 1.0, 2.0], [1.0, 0.0, 0.0], params={"m2": 1.0}, rtol=1e-12, atol=1e-12)
    impacts = sol.events["c12"]
    assert len(impacts) == 1
    assert impacts.t[0] == pytest.approx(0.5, rel=1e-14, abs=0)
    np.testing.assert_allclose(impacts.qd_after[0], [-1 / 3, 2 / 3, 2 / 3], rtol=1e-13)
    momentum = sol.qd.sum(axis=1)
    np.testing.assert_allclose(momentum, 1.0, rtol=1e-13)
    np.testing.assert_allclose(sol.energy, 0.5, rtol=1e-13)
    np.testing.assert_allclose(sol.q[-1], [-1.5 / 3, 1.0 + 1.5 * 2 / 3, 2.0 + 1.5 * 2 / 3], rtol=1e-12)


def test_a_sweep_of_bouncing_balls_misses_no_impact(ball):
    # Each trajectory its own impacts; where they accumulate before t_end (t∞ = t_1 + 2 e v_1 / (g (1 − e)),
    # a Zeno point) the last impact closes the floor at t∞ to 1e-9 and the ball rests there to t_end.
    e = np.linspace(0.3, 0.9, 5)
    h0 = np.linspace(0.5, 2.0, 4)
    g, t_end, cap = 9.81, 3.0, 256
    sweep = ball.sweep((0.0, t_end), grid={"e": e, "x": h0}, q0=[1.0], qd0=[0.0], params={"g": g}, rtol=1e-12,
                       atol=1e-12, output="events", event_cap=cap, progress=False)
    floor = sweep.events["floor"]
    accumulated = 0
    for i, ei in enumerate(e):
        for j, hj in enumerate(h0):
            times, v1 = _impact_times(hj, g, ei, cap)
            t_infinity = times[0] + 2 * ei * v1 / (g * (1 - ei))
            count = min(int(floor["count"][i, j]), cap)
            if t_infinity < t_end:
                accumulated += 1
                assert sweep.status[i, j] == Status.DONE
                assert floor["t"][i, j, count - 1] == pytest.approx(t_infinity, rel=1e-9)
                assert abs(sweep.final[i, j, 0]) < 1e-15 and sweep.final[i, j, 1] == 0.0
            else:
                assert sweep.status[i, j] >= 0 and count == np.count_nonzero(times < t_end)
            np.testing.assert_allclose(floor["t"][i, j, :count], times[:count], rtol=1e-11)
    assert 0 < accumulated < e.size * h0.size


@pytest.mark.parametrize("method", ["dop853", "dopri5", "taylor"])
@pytest.mark.parametrize("rtol", [1e-12, 1e-8, 1e-6])
def test_no_tunnelling_up_to_the_accumulation(ball, method, rtol):
    # The bounces' flights shrink geometrically; once one is shorter than the step after its impact can
    # resolve, the gap's first sample after the impact is already below 0: that is a return (bracketed
    # below the sample, or, at the resolution of t, accumulated), never the ball passing through the floor.
    # Every method closes the floor at t∞ (resting contact) and goes on.
    h0, g, e = 0.5, 9.81, 0.45
    times, v1 = _impact_times(h0, g, e, 2)
    t_infinity = times[0] + 2 * e * v1 / (g * (1 - e))
    sol = ball.simulate((0.0, 3.0), [h0], [0.0], params={"e": e, "g": g}, method=method, rtol=rtol, atol=rtol)
    assert sol.status == Status.DONE and sol.t[-1] == 3.0
    assert [(s.t, s.closed) for s in sol.contact_switches] == [(pytest.approx(t_infinity, rel=1e-9), True)]
    assert abs(sol.q[-1, 0]) < 1e-15 and sol.qd[-1, 0] == 0.0
    assert sol.q[:, 0].min() > -1e-15


def test_impacts_record_their_impulses(ball, chain):
    # One contact: P = m (v⁺ − v⁻) = m (1 + e) v⁻ (in N s for m in kg); three balls: the LCP's (4/3, 2/3).
    sol = ball.simulate((0.0, 1.0), [1.25], [0.0], params={"e": 0.8, "g": 9.81, "m": 2.0}, rtol=1e-12, atol=1e-12)
    floor = sol.events["floor"]
    assert ball.contacts == ("floor",)
    np.testing.assert_allclose(floor.impulses[:, 0], 2.0 * 1.8 * -floor.qd[:, 0], rtol=1e-13)
    sol = chain.simulate((0.0, 1.0), [-0.5, 1.0, 2.0], [1.0, 0.0, 0.0], params={"m2": 1.0}, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(sol.events["c12"].impulses, [[4 / 3, 2 / 3]], rtol=1e-13)
    assert sol.events["c23"].impulses.shape == (0, 2)


def test_a_batched_sweep_of_contacts_does_not_advise_leaving_them_out(ball):
    """A contact is part of the motion (a run refuses ``events=False`` with one), so the batched sweep's refusal
    names it and says to drop `batched`, not to leave the events out."""
    with pytest.raises(OptionError, match="batched") as refused:
        ball.sweep((0.0, 1.0), {"e": [0.5, 0.6]}, q0=[1.0], qd0=[0.0], batched=True, progress=False)
    message = str(refused.value)
    assert "['floor'] are part of the motion" in message and "events=False" not in message
    with pytest.raises(OptionError, match="cannot leave out"):      # (what the old advice led to)
        ball.sweep((0.0, 1.0), {"e": [0.5, 0.6]}, q0=[1.0], qd0=[0.0], batched=True, events=False, progress=False)
