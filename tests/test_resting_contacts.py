"""Resting contacts (issue 21): a closed `lagcomp.Contact` is a constraint whose multiplier is the normal force; it
lifts off when that force would turn negative, and an accumulation of impacts (Zeno) closes it.

References, all closed forms:

* a particle sliding from rest at angle θ0 from the top of a smooth circle of radius R (gap √(x² + y²) − R):
  energy gives v² = 2 g R (cos θ0 − cos θ), the radial equation m v²/R = m g cos θ − N, so
  N = m g (3 cos θ − 2 cos θ0), zero at cos θ = (2/3) cos θ0; then free flight, a parabola;
* a ball dropped from h0 on a floor with restitution e: v1 = √(2 g h0), t1 = v1/g, flights 2 eᵏ v1/g, at rest from
  t∞ = t1 + 2 e v1/(g (1 − e)), where the floor pushes with m g;
* a mass at rest on the floor pulled up by F0 sin(ω t) > m g at its peak: N = m g − F0 sin(ω t), lift-off at
  sin(ω t) = m g/F0.
"""

import numba
import numpy as np
import pytest
import sympy as sp
from hypothesis import given, settings
from hypothesis import strategies as st

import lagcomp as lc
from lagcomp.integrate.status import Status
from lagcomp.kernel_support.resting import BOUNCE_TIME

t = lc.t
G = 9.81


@pytest.fixture(scope="module")
def sphere(tmp_path_factory):
    x, y = lc.coordinates("x y")
    m, g, R = sp.symbols("m g R", positive=True)
    system = lc.System([x, y], T=m * (x.diff(t) ** 2 + y.diff(t) ** 2) / 2, V=m * g * y,
                       events=[lc.Contact("sphere", sp.sqrt(x**2 + y**2) - R, restitution=0.5)],
                       name="resting_sphere", defaults={"m": 1.5, "g": G, "R": 2.0})
    return lc.compile(system, cache_dir=tmp_path_factory.mktemp("cache"))


@pytest.fixture(scope="module")
def ball(tmp_path_factory):
    x, = lc.coordinates("x")
    m, g, e = sp.symbols("m g e", positive=True)
    system = lc.System([x], T=m * x.diff(t) ** 2 / 2, V=m * g * x, events=[lc.Contact("floor", x, restitution=e)],
                       name="resting_ball", defaults={"m": 2.0, "g": G, "e": 0.5})
    return lc.compile(system, cache_dir=tmp_path_factory.mktemp("cache"))


@pytest.fixture(scope="module")
def pulled(tmp_path_factory):
    y, = lc.coordinates("y")
    m, g, F0, w = sp.symbols("m g F0 omega", positive=True)
    system = lc.System([y], T=m * y.diff(t) ** 2 / 2, V=m * g * y - F0 * sp.sin(w * t) * y,
                       events=[lc.Contact("floor", y, restitution=0.5)],
                       name="resting_pulled", defaults={"m": 2.0, "g": G, "F0": 30.0, "omega": 3.0})
    return lc.compile(system, cache_dir=tmp_path_factory.mktemp("cache"))


@pytest.mark.parametrize("theta0", [0.1, 0.5])
def test_a_particle_leaves_the_sphere_at_two_thirds_of_cos_theta0_then_flies_free(sphere, theta0):
    R, m = 2.0, 1.5
    sol = sphere.simulate((0.0, 2.5), [R * np.sin(theta0), R * np.cos(theta0)], [0.0, 0.0], method="dop853",
                          rtol=1e-12, atol=1e-12)
    assert sol.status == Status.DONE, sol.message
    assert [(s.contact, s.closed) for s in sol.contact_switches] == [("sphere", False)]   # closed at the start
    t_off = sol.contact_switches[0].t
    leaving = sol.events["sphere"]
    assert len(leaving) == 1 and leaving.t[0] == t_off
    q, qd = leaving.q[0], leaving.qd[0]
    assert q[1] / np.hypot(*q) == pytest.approx(2 / 3 * np.cos(theta0), abs=1e-10)
    assert abs(np.hypot(*q) - R) < 1e-11                                 # still on the sphere (drift)
    np.testing.assert_array_equal(leaving.qd_after[0], qd)               # no jump at a lift-off
    # while closed, the normal force of the closed form; 0 once open
    on = sol.t < t_off
    cos = sol.q[on, 1] / np.hypot(sol.q[on, 0], sol.q[on, 1])
    np.testing.assert_allclose(sol.contact_forces[on, 0], m * G * (3 * cos - 2 * np.cos(theta0)), rtol=1e-9, atol=1e-9)
    after = sol.t > t_off
    assert not sol.contact_forces[after].any()
    # free flight: the parabola from the lift-off state
    s = sol.t[after] - t_off
    np.testing.assert_allclose(sol.q[after, 0], q[0] + qd[0] * s, rtol=1e-10, atol=1e-10)
    np.testing.assert_allclose(sol.q[after, 1], q[1] + qd[1] * s - G * s**2 / 2, rtol=1e-10, atol=1e-10)


@pytest.mark.parametrize("method", ["dop853", "dopri5"])
@pytest.mark.parametrize(("e", "h0"), [(0.5, 1.0), (0.8, 2.0), (0.3, 0.2)])
def test_a_bouncing_ball_comes_to_rest_at_the_accumulation_time(ball, method, e, h0):
    m = 2.0
    v1 = np.sqrt(2 * G * h0)
    t1 = v1 / G
    t_infinity = t1 + 2 * e * v1 / (G * (1 - e))
    t_end = 3 * t_infinity
    sol = ball.simulate((0.0, t_end), [h0], [0.0], params={"e": e, "m": m}, method=method, rtol=1e-12, atol=1e-12)
    assert sol.status == Status.DONE, sol.message
    assert [(s.contact, s.closed) for s in sol.contact_switches] == [("floor", True)]
    t_rest = sol.contact_switches[0].t
    assert t_rest == pytest.approx(t_infinity, abs=1e-9)
    impacts = sol.events["floor"]
    assert impacts.t[-1] == t_rest
    k = np.arange(len(impacts) - 1)
    closed_form = t1 + np.concatenate([[0.0], np.cumsum(2 * e ** (k + 1) * v1 / G)])
    np.testing.assert_allclose(impacts.t, closed_form, rtol=0, atol=1e-11)
    np.testing.assert_allclose(impacts.qd_after[:-1, 0] / impacts.qd[:-1, 0], -e, rtol=1e-9)
    assert impacts.qd_after[-1, 0] == 0.0                               # the closing impact is plastic
    # at rest on the floor to t_end: the height within rounding, no tunnelling, the floor pushing with m g
    rest = sol.t > t_rest
    assert sol.t[-1] == t_end
    assert np.abs(sol.q[rest, 0]).max() < 1e-15 * h0
    assert not sol.qd[rest, 0].any()
    assert sol.q[:, 0].min() > -1e-15 * h0
    np.testing.assert_allclose(sol.contact_forces[rest, 0], m * G, rtol=1e-12)
    assert not sol.contact_forces[sol.t < t_rest].any()


def test_a_long_rest_does_not_drift(ball):
    # g̈ = 0 exactly at rest (q̈ = q̈_free + M⁻¹ Gᵀ λ cancels to the last bit): no stabilisation needed.
    sol = ball.simulate((0.0, 1e4), [0.0], [0.0], method="dop853", rtol=1e-12, atol=1e-12)
    assert sol.status == Status.DONE and sol.contact_switches == ()
    assert not sol.q.any() and not sol.qd.any()
    np.testing.assert_array_equal(sol.contact_forces[:, 0], 2.0 * G)


@pytest.mark.parametrize("method", ["dop853", "dopri5"])
def test_a_pulled_mass_lifts_off_when_the_force_exceeds_its_weight(pulled, method):
    m, F0, omega = 2.0, 30.0, 3.0
    t_off = np.arcsin(m * G / F0) / omega
    # The body at rest has no motion to limit the steps (they grow tenfold each): the first long step spans the whole
    # time the pull exceeds the weight, whose ends both show the floor pushing; its stages there see the body free
    # (rhs holds λ ≥ 0), so its error estimate rejects it, and shorter steps find λ's zero.
    sol = pulled.simulate((0.0, 1.0), [0.0], [0.0], method=method, rtol=1e-12, atol=1e-12)
    assert sol.status == Status.DONE, sol.message
    assert (sol.contact_switches[0].contact, sol.contact_switches[0].closed) == ("floor", False)
    assert sol.contact_switches[0].t == pytest.approx(t_off, abs=1e-10)
    on = sol.t < t_off
    np.testing.assert_allclose(sol.contact_forces[on, 0], m * G - F0 * np.sin(omega * sol.t[on]), rtol=1e-12,
                               atol=1e-12)
    # at rest to the last bit until the lift-off's row (that row, located within rounding of t_off, is the dense
    # output of the step that lifts off: 0 to the tolerance, e.g. −2e-18)
    held = sol.t < sol.contact_switches[0].t
    assert not sol.q[held].any()
    assert np.all(np.abs(sol.q[on]) <= 1e-12)
    assert sol.q[sol.t > t_off + 0.01, 0].min() > 0.0                    # lifted


def test_a_sweep_gives_each_trajectory_its_own_modes(ball):
    # h0 = 0 starts closed (at rest on the floor), the others bounce and close at their own t∞; all end at rest.
    h0 = np.array([0.0, 0.5, 1.0, 2.0])
    e = 0.5
    sweep = ball.sweep((0.0, 5.0), grid={"x": h0}, q0=[1.0], qd0=[0.0], params={"e": e}, rtol=1e-12, atol=1e-12,
                       output="events", event_cap=256, progress=False)
    assert (sweep.status == Status.DONE).all()
    assert np.abs(sweep.final[:, 0]).max() < 1e-15 and not sweep.final[:, 1].any()
    counts = sweep.events["floor"]["count"]
    assert counts[0] == 0 and (counts[1:] > 10).all()
    for i in range(1, h0.size):
        v1 = np.sqrt(2 * G * h0[i])
        last = sweep.events["floor"]["t"][i, counts[i] - 1]
        assert last == pytest.approx(v1 / G + 2 * e * v1 / (G * (1 - e)), abs=1e-9)


def test_the_switches_and_forces_are_saved(ball, tmp_path):
    sol = ball.simulate((0.0, 3.0), [1.0], [0.0], params={"e": 0.5}, rtol=1e-12, atol=1e-12)
    sol.save_npz(tmp_path / "rest.npz")
    saved = np.load(tmp_path / "rest.npz")
    np.testing.assert_array_equal(saved["contact_forces"], sol.contact_forces)
    assert saved["contact_switch_t"].tolist() == [sol.contact_switches[0].t]
    assert saved["contact_switch_contact"].tolist() == ["floor"] and saved["contact_switch_closed"].tolist() == [True]


@pytest.fixture(scope="module")
def corner(tmp_path_factory):
    x, y = lc.coordinates("x y")
    m, g = sp.symbols("m g", positive=True)
    system = lc.System([x, y], T=m * (x.diff(t) ** 2 + y.diff(t) ** 2) / 2, V=m * g * (0.6 * x + y),
                       events=[lc.Contact("wall", x, restitution=0.5), lc.Contact("floor", y, restitution=0.7)],
                       name="resting_corner", defaults={"m": 1.0, "g": G})
    return lc.compile(system, cache_dir=tmp_path_factory.mktemp("cache"))


@pytest.mark.parametrize(("q0", "closings"), [([1.0, 2.0], ["wall", "floor"]), ([1.0, 0.0], ["wall"])])
def test_a_particle_comes_to_rest_in_a_corner(corner, q0, closings):
    # Pulled into the corner (0.6 g towards the wall, g towards the floor): bounces on both, or slides along the
    # closed floor into the wall (an impact with another contact closed), then rests pushed by (0.6 m g, m g).
    sol = corner.simulate((0.0, 8.0), q0, [0.0, 0.0], rtol=1e-12, atol=1e-12)
    assert sol.status == Status.DONE, sol.message
    assert [(s.contact, s.closed) for s in sol.contact_switches] == [(c, True) for c in closings]
    np.testing.assert_allclose(sol.contact_forces[-1], [0.6 * G, G], rtol=1e-12)
    assert np.abs(sol.q[-1]).max() < 1e-15 and not sol.qd[-1].any()
    if q0[1] == 0.0:                        # sliding on the closed floor: x = 1 − 0.3 g t², at the wall at √(1/(0.3 g))
        assert sol.events["wall"].t[0] == pytest.approx(np.sqrt(1 / (0.3 * G)), rel=1e-12, abs=0)
        assert not sol.q[:, 1].any()


def test_the_modes_sit_before_the_inputs_headers(tmp_path):
    # The pull as an input (a numba function of t): p holds the parameters, the modes, then the input's header.
    y, = lc.coordinates("y")
    m, g = sp.symbols("m g", positive=True)
    system = lc.System([y], T=m * y.diff(t) ** 2 / 2, V=m * g * y, forces=[lc.Input("f")],
                       events=[lc.Contact("floor", y, restitution=0.5)], name="resting_input",
                       defaults={"m": 2.0, "g": G})
    model = lc.compile(system, cache_dir=tmp_path)

    @numba.njit
    def pull(time, state, p):
        return 30.0 * np.sin(3.0 * time)

    sol = model.simulate((0.0, 0.5), [0.0], [0.0], inputs={"f": pull}, rtol=1e-12, atol=1e-12)
    assert sol.contact_switches[0].t == pytest.approx(np.arcsin(2.0 * G / 30.0) / 3.0, abs=1e-10)


@pytest.mark.parametrize("method", ["dop853", "bs3"])
def test_a_lively_ball_comes_to_rest_too(ball, method):
    # e = 0.95: 436 bounces; the next-bounce criterion closes the floor first (BOUNCE_TIME/(1 − e) > ZENO_TIME), and
    # the time of rest is off by the bounces left out, at most BOUNCE_TIME max(1, t)/(1 − e).
    e, h0 = 0.95, 1.0
    v1 = np.sqrt(2 * G * h0)
    t_infinity = v1 / G + 2 * e * v1 / (G * (1 - e))
    sol = ball.simulate((0.0, 1.2 * t_infinity), [h0], [0.0], params={"e": e}, method=method, rtol=1e-10, atol=1e-10)
    assert sol.status == Status.DONE, sol.message
    assert abs(sol.contact_switches[0].t - t_infinity) < BOUNCE_TIME * t_infinity / (1 - e)
    assert sol.q[:, 0].min() > -1e-14 and sol.qd[-1, 0] == 0.0


def test_each_run_starts_from_its_own_modes(ball):
    # The drivers' resets write the modes into the run's copy of p: a run that closed the floor leaves the next
    # run's start as it was (open, the ball dropped), and the parameters reported are the run's start.
    first = ball.simulate((0.0, 3.0), [1.0], [0.0], params={"e": 0.5}, rtol=1e-12, atol=1e-12)
    second = ball.simulate((0.0, 3.0), [1.0], [0.0], params={"e": 0.5}, rtol=1e-12, atol=1e-12)
    assert first.contact_switches == second.contact_switches and len(first.contact_switches) == 1
    np.testing.assert_array_equal(first.q, second.q)
    assert first.params == {"e": 0.5, "g": G, "m": 2.0}


@pytest.fixture(scope="module")
def stack(tmp_path_factory):
    x1, x2 = lc.coordinates("x1 x2")
    g, e = sp.symbols("g e", positive=True)
    system = lc.System([x1, x2], T=(x1.diff(t) ** 2 + x2.diff(t) ** 2) / 2, V=g * (x1 + x2),
                       events=[lc.Contact("floor", x1, restitution=e), lc.Contact("balls", x2 - x1, restitution=e)],
                       name="resting_stack", defaults={"g": G, "e": 0.5})
    return lc.compile(system, cache_dir=tmp_path_factory.mktemp("cache"))


def test_an_impact_on_a_resting_body_pushes_through_its_closed_contact(stack):
    """Ball 2 (unit masses, point-like) dropped from h on ball 1 resting on the floor: with G = [[1, 0], [−1, 1]]
    (floor, balls) both contacts push, W P = −(1 + e) v⁻ gives P = ((1 + e) v, (1 + e) v), v = √(2 g h): ball 1
    stays, ball 2 leaves at e v.  The floor's impulse counts only if its closed contact is taken as touching
    (its event value is then its force, not its gap): in a single run and in a sweep alike."""
    h, e = 1.0, 0.5
    v = np.sqrt(2 * G * h)
    sol = stack.simulate((0, 0.5), q0=[0.0, h], qd0=[0.0, 0.0], method="dop853", rtol=1e-12, atol=1e-12)
    hit = sol.events["balls"]
    assert hit.t[0] == pytest.approx(np.sqrt(2 * h / G), rel=1e-12, abs=0)
    np.testing.assert_allclose(hit.impulses[0], [(1 + e) * v, (1 + e) * v], rtol=1e-11)
    np.testing.assert_allclose(hit.qd_after[0], [0.0, e * v], atol=1e-11)
    sweep = stack.sweep((0, 0.5), {"e": [e, 0.8]}, q0=[0.0, h], qd0=[0.0, 0.0], method="dop853", rtol=1e-12,
                        atol=1e-12, output="events")
    impulses = sweep.events["balls"]["impulses"]
    np.testing.assert_array_equal(impulses[0, 0], hit.impulses[0])
    np.testing.assert_allclose(impulses[1, 0], [1.8 * v, 1.8 * v], rtol=1e-11)


@pytest.fixture(scope="module")
def ladder(tmp_path_factory):
    X, Y, th = lc.coordinates("X Y theta")
    m, g, L = sp.symbols("m g L", positive=True)
    T = m * (X.diff(t) ** 2 + Y.diff(t) ** 2) / 2 + m * L**2 / 12 * th.diff(t) ** 2 / 2
    system = lc.System([X, Y, th], T=T, V=m * g * Y, name="resting_ladder", defaults={"m": 3.0, "g": G, "L": 2.0},
                       events=[lc.Contact("wall", X - L / 2 * sp.sin(th), restitution=0.0),
                               lc.Contact("floor", Y - L / 2 * sp.cos(th), restitution=0.0)])
    return lc.compile(system, cache_dir=tmp_path_factory.mktemp("cache"))


def check_ladder_leaves_the_wall(sol, m, theta0):
    """A ladder of mass m released at rest at angle θ0 from the wall (coordinates X, Y, θ; contacts "wall" and
    "floor"): its first switch opens the wall at cos θ = (2/3) cos θ0, the floor still pushing, and the initial
    contact forces are ((3/4) m G sin θ0 cos θ0, m G (1 − (3/4) sin² θ0)) (the closed form below)."""
    first = sol.contact_switches[0]
    assert (first.contact, first.closed) == ("wall", False)
    row = np.searchsorted(sol.t, first.t)
    assert np.cos(sol.q[row, 2]) == pytest.approx(2 / 3 * np.cos(theta0), abs=1e-10)
    np.testing.assert_allclose(sol.contact_forces[0], [0.75 * m * G * np.sin(theta0) * np.cos(theta0),
                                                        m * G * (1 - 0.75 * np.sin(theta0) ** 2)], rtol=1e-12)
    assert sol.contact_forces[row, 1] > 0.0


@pytest.mark.parametrize("theta0", [0.2, 0.6])
def test_a_ladder_leaves_the_wall_at_two_thirds_of_its_height(ladder, theta0):
    """A uniform ladder (length L, mass m, angle θ from the wall) released at rest against a smooth wall on a
    smooth floor: both contacts start closed; while they hold, its centre moves on the circle of radius L/2,
    energy gives θ̇² = (3 g/L)(cos θ0 − cos θ), and the wall pushes with m Ẍ = (3/4) m g sin θ (3 cos θ − 2 cos θ0),
    zero at cos θ = (2/3) cos θ0: the top leaves the wall at 2/3 of its height, the floor still pushing."""
    m, L = 3.0, 2.0
    q0 = [L / 2 * np.sin(theta0), L / 2 * np.cos(theta0), theta0]
    sol = ladder.simulate((0, 3.0), q0=q0, qd0=[0.0, 0.0, 0.0], method="dop853", rtol=1e-12, atol=1e-12)
    check_ladder_leaves_the_wall(sol, m, theta0)


# -- the kernel helpers, called directly -----------------------------------------------------------------------------


@settings(max_examples=100, deadline=None)
@given(st.floats(-0.95, -0.05), st.floats(0.1, 10.0), st.floats(0.05, 0.95), st.floats(0.5, 5.0))
def test_of_two_pulling_contacts_the_most_negative_is_released_and_the_other_pushes(c, a, fraction, m):
    """Two closed contacts of a point mass m in the plane, gap gradients g1 = (1, 0) and g2 = (c, √(1 − c²)) (unit,
    at an obtuse angle: c < 0), with G q̈_free + b = (a, f) at q̈_free = 0, a > 0 and c a < f < 0.  Holding both,
    W = (1/m) [[1, c], [c, 1]] and λ = −m W̃⁻¹ (a, f) = −m/(1 − c²) (a − c f, f − c a): both pull, λ1 < λ2 (as a > f).
    Releasing contact 1 (the most negative) leaves contact 2 alone with λ2 = −m f > 0: it pushes and stays, and
    q̈ = −f g2.  Releasing contact 2 first would leave contact 1 alone with λ1 = −m a < 0: both released."""
    from lagcomp.kernel_support.resting import held_row_accelerations

    f = fraction * c * a
    g2 = np.array([c, np.sqrt(1.0 - c * c)])
    both = -m / (1.0 - c * c) * np.array([a - c * f, f - c * a])
    assert both[0] < both[1] < 0.0                                  # the premise: both pull, contact 1 the more
    qdd, forces = np.zeros(2), np.empty(2)
    status = held_row_accelerations(m * np.eye(2), np.array([[1.0, 0.0], g2]), np.array([a, f]),
                                    np.array([True, True]), 2, qdd, forces, 1.0)
    assert status == 0
    assert forces[0] == 0.0
    assert forces[1] == pytest.approx(-m * f, rel=1e-13, abs=0)
    np.testing.assert_allclose(qdd, -f * g2, rtol=1e-13, atol=1e-15 * abs(f))
    assert qdd[0] + a > 0.0                                          # contact 1, released, opens


@pytest.mark.parametrize("mode", [1.0, -1.0])
@pytest.mark.parametrize("force", [0.0, 1e-300, -2.5])
def test_a_slipping_element_with_no_normal_force_never_sticks(mode, force):
    """With limit μs |N| = 0 (an open contact presses with no force) a slipping element stays slipping, even when
    the force needed to hold it is 0: it slips against that force (+1 for a force of 0 or less)."""
    from lagcomp.kernel_support.resting import friction_mode_after

    assert friction_mode_after(mode, force, 0.0) == (-1.0 if force > 0.0 else 1.0)


@pytest.mark.parametrize("mode, force, limit, after", [
    (1.0, 0.3, 0.5, 0.0), (-1.0, -0.5, 0.5, 0.0),       # from slip, held within μs |N|: sticks
    (1.0, 0.7, 0.5, -1.0), (-1.0, -0.7, 0.5, 1.0),      # from slip, beyond it: slips against the force
    (0.0, 0.5, 0.5, -1.0), (0.0, -0.5, 0.5, 1.0),       # from stick (its force reached the limit): slips against it
])
def test_the_mode_after_a_friction_event_follows_coulombs_law(mode, force, limit, after):
    from lagcomp.kernel_support.resting import friction_mode_after

    assert friction_mode_after(mode, force, limit) == after
