"""Friction and contacts in one system (issue 21): a contact's event (an impact, a closing, a lift-off) decides the
friction modes again from the state after it, in the same ``event_reset``, so that no mode is stale; friction
pressed by a contact's normal force (``normal="floor"``).

References, closed forms (g = 9.81, a block of mass m on a floor contact, gap y, friction on ẋ pressed by it):

* pushed by F = c t from rest: it sticks (friction −c t) until c t_s = μs m g, then ẍ = (c t − μk m g)/m;
* launched at v0: it stops at x = v0²/(2 μk g), t = v0/(μk g), then stays (N = m g, friction 0);
* on a floor inclined at α (gap −x sin α + y cos α, friction on the velocity along it): it stays iff
  tan α ≤ μs (friction m g sin α up the slope), else slides with g (sin α − μk cos α);
* a point mass falling from h onto that floor (restitution e) at a tangential speed v_t: the impact leaves it
  v_n⁺ = e |v_n|, v_n = √(2 g h), and v_t⁺ = v_t − μk (1 + e) |v_n| sign v_t when |v_t| > μs (1 + e) |v_n|, else 0
  (the impulse that stops it is within μs P_n: stick);
* bouncing on (v0 along, dropped from h, e): every impact takes μk (1 + e) |v_n| off, the bounces' |v_n| sum to
  v1/(1 − e) (v1 = √(2 g h)), so the block lands for good at t∞ = v1/g + 2 e v1/(g (1 − e)) sliding at
  v_c = v0 − μk v1 (1 + e)/(1 − e), and stops v_c/(μk g) later, v_c²/(2 μk g) further;
* a block sliding toward a wall: a block (mass m) sliding on a table (friction on ẋ, N = m g, μs, μk) toward a wall at
x = L (a contact with gap L − x, restitution e), from x = 0 at v0: it decelerates by μk g and reaches the wall at
v_w = √(v0² − 2 μk g L), t_w = (v0 − v_w)/(μk g); it leaves at −e v_w (slipping the other way: the friction force
turns round with it) and stops at x = L − (e v_w)²/(2 μk g), t = t_w + e v_w/(μk g), where it stays (sticking,
with no force to hold).  A mode kept from before the impact would push the block away from the wall forever.
"""

import numpy as np
import pytest
import sympy as sp

import lagcomp as lc
from lagcomp.errors import OptionError
from lagcomp.integrate.status import Status

t = lc.t
G = 9.81


@pytest.fixture(scope="module")
def block_and_wall(tmp_path_factory):
    x, = lc.coordinates("x")
    m, g, L, e, mu_s, mu_k = sp.symbols("m g L e mu_s mu_k", positive=True)
    system = lc.System([x], T=m * x.diff(t) ** 2 / 2, V=0,
                       events=[lc.Friction("table", x.diff(t), normal=m * g, static=mu_s, kinetic=mu_k),
                               lc.Contact("wall", L - x, restitution=e)],
                       name="friction_wall", defaults={"m": 2.0, "g": G, "L": 1.0, "e": 0.5, "mu_s": 0.5,
                                                       "mu_k": 0.3})
    return lc.compile(system, cache_dir=tmp_path_factory.mktemp("cache"))


@pytest.fixture(scope="module")
def block_on_floor(tmp_path_factory):
    x, y = lc.coordinates("x y")
    m, g, c, e, mu_s, mu_k = sp.symbols("m g c e mu_s mu_k", positive=True)
    system = lc.System([x, y], T=m * (x.diff(t) ** 2 + y.diff(t) ** 2) / 2, V=m * g * y, forces=[c * t, 0],
                       events=[lc.Contact("floor", y, restitution=e),
                               lc.Friction("ground", x.diff(t), normal="floor", static=mu_s, kinetic=mu_k)],
                       name="friction_pressed_block", defaults={"m": 2.0, "g": G, "c": 3.0, "e": 0.0, "mu_s": 0.5,
                                                                "mu_k": 0.3})
    return lc.compile(system, cache_dir=tmp_path_factory.mktemp("cache"))


@pytest.fixture(scope="module")
def block_on_incline(tmp_path_factory):
    x, y = lc.coordinates("x y")
    m, g, alpha, mu_s, mu_k = sp.symbols("m g alpha mu_s mu_k", positive=True)
    along = x.diff(t) * sp.cos(alpha) + y.diff(t) * sp.sin(alpha)
    system = lc.System([x, y], T=m * (x.diff(t) ** 2 + y.diff(t) ** 2) / 2, V=m * g * y,
                       events=[lc.Contact("slope", -x * sp.sin(alpha) + y * sp.cos(alpha), restitution=0.0),
                               lc.Friction("grip", along, normal="slope", static=mu_s, kinetic=mu_k)],
                       name="friction_pressed_incline", defaults={"m": 2.0, "g": G, "alpha": 0.4, "mu_s": 0.5,
                                                                  "mu_k": 0.3})
    return lc.compile(system, cache_dir=tmp_path_factory.mktemp("cache"))


def breakaway_slide(t, m, c, mu_s, mu_k):
    """(t_s, t > t_s, x(t)) of a block of mass m at rest under a normal force m G, pushed by c t: it breaks away at
    c t_s = μs m G and slides with m ẍ = c t − μk m G, x = (c (t³ − t_s³)/6 − c t_s² (t − t_s)/2 − μk m G (t − t_s)²/2) / m
    after t_s."""
    t_s = mu_s * m * G / c
    tau = t - t_s
    return t_s, tau > 0, (c * (t**3 - t_s**3) / 6 - c * t_s**2 * tau / 2 - mu_k * m * G * tau**2 / 2) / m


def check_breakaway(sol, m, c, mu_s, mu_k):
    """A block of mass m resting on a floor (normal force m G), pushed along x by c t against friction (the element
    "ground", μs, μk): it sticks, the friction force −c t, until c t_s = μs m G, then slides with
    m ẍ = c t − μk m G from rest, x = (c (t³ − t_s³)/6 − c t_s² (t − t_s)/2 − μk m G (t − t_s)²/2) / m."""
    t_s, after, x = breakaway_slide(sol.t, m, c, mu_s, mu_k)
    assert [(s.friction, s.mode) for s in sol.friction_switches] == [("ground", 1)]
    assert abs(sol.friction_switches[0].t - t_s) < 1e-10
    np.testing.assert_allclose(sol.q[after, 0], x[after], rtol=1e-9, atol=1e-12)
    assert np.abs(sol.q[~after, 0]).max() < 1e-12 and np.abs(sol.q[:, 1]).max() < 1e-12
    np.testing.assert_allclose(sol.contact_forces[:, 0], m * G, rtol=1e-12)
    holding = sol.t < t_s
    np.testing.assert_allclose(sol.friction_forces[holding, 0], -c * sol.t[holding], rtol=1e-10, atol=1e-12)


def test_a_block_pushed_harder_and_harder_breaks_away_at_the_static_limit(block_on_floor):
    m, c, mu_s, mu_k = 2.0, 3.0, 0.5, 0.3
    t_s = mu_s * m * G / c
    sol = block_on_floor.simulate((0.0, 5.0), [0.0, 0.0], [0.0, 0.0], rtol=1e-12, atol=1e-12)
    assert sol.status == Status.DONE, sol.message
    check_breakaway(sol, m, c, mu_s, mu_k)
    slid = sol.t > t_s + 1e-6
    np.testing.assert_allclose(sol.friction_forces[slid, 0], -mu_k * m * G, rtol=1e-12)


def test_a_block_launched_along_the_floor_stops_where_friction_says_and_stays(block_on_floor):
    m, mu_k, v0 = 2.0, 0.3, 3.0
    sol = block_on_floor.simulate((0.0, 3.0), [0.0, 0.0], [v0, 0.0], params={"c": 0.0}, rtol=1e-12, atol=1e-12)
    assert sol.status == Status.DONE, sol.message
    assert [(s.friction, s.mode) for s in sol.friction_switches] == [("ground", 0)]
    np.testing.assert_allclose(sol.friction_switches[0].t, v0 / (mu_k * G), rtol=1e-11)
    np.testing.assert_allclose(sol.q[-1, 0], v0**2 / (2 * mu_k * G), rtol=1e-11)
    assert abs(sol.qd[-1, 0]) < 1e-13
    np.testing.assert_allclose(sol.contact_forces[:, 0], m * G, rtol=1e-12)
    moving = sol.t < sol.friction_switches[0].t
    np.testing.assert_allclose(sol.friction_forces[moving, 0], -mu_k * m * G, rtol=1e-12)
    assert np.abs(sol.friction_forces[sol.t > sol.friction_switches[0].t, 0]).max() < 1e-12


@pytest.mark.parametrize("alpha", [0.4, 0.5])      # tan α = 0.42, 0.55 against μs = 0.5
def test_a_block_on_an_inclined_floor_sticks_iff_the_slope_is_within_the_static_coefficient(block_on_incline,
                                                                                            alpha):
    m, mu_s, mu_k = 2.0, 0.5, 0.3
    sol = block_on_incline.simulate((0.0, 1.0), [0.0, 0.0], [0.0, 0.0], params={"alpha": alpha}, rtol=1e-12,
                                    atol=1e-12)
    assert sol.status == Status.DONE, sol.message
    assert sol.friction_switches == ()
    np.testing.assert_allclose(sol.contact_forces[:, 0], m * G * np.cos(alpha), rtol=1e-12)
    s = sol.q[:, 0] * np.cos(alpha) + sol.q[:, 1] * np.sin(alpha)      # along the slope, up
    if np.tan(alpha) <= mu_s:
        assert np.abs(sol.q).max() < 1e-12
        np.testing.assert_allclose(sol.friction_forces[:, 0], m * G * np.sin(alpha), rtol=1e-12)
    else:
        np.testing.assert_allclose(s, -G * (np.sin(alpha) - mu_k * np.cos(alpha)) * sol.t**2 / 2, rtol=1e-10,
                                   atol=1e-14)
        np.testing.assert_allclose(sol.friction_forces[1:, 0], mu_k * m * G * np.cos(alpha), rtol=1e-12)


@pytest.mark.parametrize("v_t", [5.0, -5.0, 1.0, 2.5, -2.5])   # 2.5: between μk and μs (1 + e) v_n (1.99, 3.32)
def test_a_point_mass_hitting_a_frictional_floor_obliquely_loses_tangential_speed_by_coulombs_law(block_on_floor, v_t):
    h, e, mu_s, mu_k = 1.0, 0.5, 0.5, 0.3
    v_n = np.sqrt(2 * G * h)
    sol = block_on_floor.simulate((0.0, 0.5), [0.0, h], [v_t, 0.0], params={"c": 0.0, "e": e}, rtol=1e-12,
                                  atol=1e-12)
    assert sol.status == Status.DONE, sol.message
    impact = sol.events["floor"]
    assert len(impact) == 1
    np.testing.assert_allclose(impact.qd[0], [v_t, -v_n], rtol=1e-12)
    slipping = abs(v_t) > mu_s * (1 + e) * v_n
    expected = v_t - mu_k * (1 + e) * v_n * np.sign(v_t) if slipping else 0.0
    assert not slipping or np.sign(expected) == np.sign(v_t)
    np.testing.assert_allclose(impact.qd_after[0], [expected, e * v_n], rtol=1e-12, atol=1e-15)
    # in the air again: no friction, ẋ constant
    after = sol.t > impact.t[0]
    np.testing.assert_allclose(sol.qd[after, 0], expected, rtol=1e-12, atol=1e-15)
    assert np.abs(sol.friction_forces[:, 0]).max() == 0.0


def test_a_block_bouncing_along_the_floor_lands_for_good_and_slides_to_a_stop(block_on_floor):
    h, e, mu_k, v0 = 1.0, 0.5, 0.3, 9.0
    v1 = np.sqrt(2 * G * h)
    t_land = v1 / G + 2 * e * v1 / (G * (1 - e))
    v_c = v0 - mu_k * v1 * (1 + e) / (1 - e)
    k = np.arange(1, 200)
    speeds = v0 - mu_k * (1 + e) * v1 * (1 - e**k) / (1 - e)               # along, after impact k
    x_land = v0 * v1 / G + np.sum(speeds * 2 * e**k * v1 / G)
    sol = block_on_floor.simulate((0.0, 5.0), [0.0, h], [v0, 0.0], params={"c": 0.0, "e": e}, rtol=1e-12,
                                  atol=1e-12)
    assert sol.status == Status.DONE, sol.message
    [closing] = sol.contact_switches
    assert (closing.contact, closing.closed) == ("floor", True)
    assert abs(closing.t - t_land) < 1e-9                                   # (the Zeno closing: ~1e-10)
    np.testing.assert_allclose(sol.events["floor"].qd_after[:5, 0], speeds[:5], rtol=1e-12)
    [stop] = sol.friction_switches[-1:]
    assert stop.mode == 0
    np.testing.assert_allclose(stop.t, t_land + v_c / (mu_k * G), rtol=1e-9)
    np.testing.assert_allclose(sol.q[-1], [x_land + v_c**2 / (2 * mu_k * G), 0.0], rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(sol.contact_forces[-1, 0], 2.0 * G, rtol=1e-12)


def test_a_block_bouncing_off_a_wall_slides_back_against_friction_and_stops(block_and_wall):
    L, e, mu_k, v0 = 1.0, 0.5, 0.3, 4.0
    v_w = np.sqrt(v0**2 - 2 * mu_k * G * L)
    t_w = (v0 - v_w) / (mu_k * G)
    t_stop, x_stop = t_w + e * v_w / (mu_k * G), L - (e * v_w) ** 2 / (2 * mu_k * G)
    sol = block_and_wall.simulate((0.0, 3.0), [0.0], [v0], rtol=1e-12, atol=1e-12)
    assert sol.status == Status.DONE, sol.message
    impact = sol.events["wall"]
    assert len(impact) == 1
    np.testing.assert_allclose(impact.t, [t_w], rtol=1e-12)
    np.testing.assert_allclose(impact.qd_after[:, 0], [-e * v_w], rtol=1e-12)
    assert [(s.friction, s.mode) for s in sol.friction_switches] == [("table", -1), ("table", 0)]
    assert sol.friction_switches[0].t == impact.t[0]
    np.testing.assert_allclose(sol.friction_switches[1].t, t_stop, rtol=1e-11)
    final = sol.q[-1, 0]
    np.testing.assert_allclose(final, x_stop, rtol=1e-11)
    assert sol.qd[-1, 0] == 0.0 or abs(sol.qd[-1, 0]) < 1e-13
    # along the way: −μk m g sign ẋ while it slides, 0 at rest
    slid = np.abs(sol.qd[:, 0]) > 1e-9
    np.testing.assert_allclose(sol.friction_forces[slid, 0], -mu_k * 2.0 * G * np.sign(sol.qd[slid, 0]), rtol=1e-12)


def test_taylor_refuses_friction_pressed_by_a_contact(block_on_floor):
    """The Taylor programs of the held rows have no column for the slip force −μk s λ_c ∂v/∂q̇ (it lives in the
    held-row system, not in rhs_free): refused, not integrated as if the floor had no friction."""
    with pytest.raises(OptionError, match="pressed by a contact"):
        block_on_floor.simulate((0.0, 1.0), [0.0, 1.0], [1.0, 0.0], params={"c": 0.0}, method="taylor")


@pytest.fixture(scope="module")
def leaning_wall(tmp_path_factory):
    x, y = lc.coordinates("x y")
    g, k = sp.symbols("g k", positive=True)
    system = lc.System([x, y], T=(x.diff(t) ** 2 + y.diff(t) ** 2) / 2, V=g * y,
                       events=[lc.Contact("floor", y, restitution=0.0),
                               lc.Contact("wall", 1 - x - k * y, restitution=0.5),
                               lc.Friction("ground", x.diff(t), normal="floor", static=0.2, kinetic=0.2)],
                       name="contact_friction_leaning_wall", defaults={"g": G, "k": 0.0})
    return lc.compile(system, cache_dir=tmp_path_factory.mktemp("cache"))


def test_an_impact_that_pushes_a_sliding_pressed_contact_stops_the_run(leaning_wall):
    """A point sliding on a frictional floor (μ = 0.2) into the wall 1 − x − k y ≥ 0.  Upright (k = 0) the wall's
    impulse is horizontal, the floor takes none, and the frictionless impact is exact: it leaves at −e times its
    arrival speed v_w = √(v0² − 2 μ g).  Leaning over the floor (k > 0) the wall pushes the point into the floor,
    which pushes back while the point slides: Coulomb's tangential impulse there is not solved, so the run stops
    at the impact (RESET_FAILED), with the state just before it, instead of leaving friction out."""
    v0 = 3.0
    v_w = np.sqrt(v0**2 - 2 * 0.2 * G)
    upright = leaning_wall.simulate((0.0, 0.5), [0.0, 0.0], [v0, 0.0], rtol=1e-12, atol=1e-12)
    assert upright.status == Status.DONE, upright.message
    np.testing.assert_allclose(upright.events["wall"].qd_after[0], [-0.5 * v_w, 0.0], rtol=1e-10, atol=1e-12)
    leaning = leaning_wall.simulate((0.0, 0.5), [0.0, 0.0], [v0, 0.0], params={"k": 0.5}, rtol=1e-12, atol=1e-12)
    assert leaning.status == Status.RESET_FAILED and "friction" in leaning.message
    assert leaning.qd[-1, 0] == pytest.approx(v_w, rel=1e-10)
