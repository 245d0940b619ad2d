"""Coulomb friction with stick–slip (issue 21, `lagcomp.Friction`): an element sticks (v = 0 held, its force the
multiplier) until the force it needs reaches μs N, slips (−μk N sign v) until v reaches 0.

References, all closed forms (the lead's design notes for #21, §5):

* the seed's rope on a table (mass M, length L, μ = M/L, x the hanging length, friction f on the table part,
  N = μ g (L − x)): it stays at rest iff x ≤ l0 = f L/(1 + f); above, from rest, x = l0 + (x0 − l0) cosh(ω t),
  ω² = g (1 + f)/L;
* a block on an incline at angle α: sticks iff tan α ≤ μs; else s̈ = g (sin α − μk cos α);
* a mass m on a spring k dragged by a belt at speed v_b (v = ẋ − v_b, N = m g), from x = 0 stuck: stick until
  x_s = μs m g/k (t_s = x_s/v_b), slip x = x* + (x_s − x*) cos ωτ + (v_b/ω) sin ωτ (x* = μk m g/k, ω² = k/m)
  for ωτ = 2π − 2φ, φ = atan2(ω (x_s − x*), v_b), then stick again for 2 (x_s − x*)/v_b: periodic from t_s.
"""

import numpy as np
import pytest
import sympy as sp

import lagcomp as lc
from lagcomp.integrate.status import Status

t = lc.t
G = 9.81


@pytest.fixture(scope="module")
def rope(tmp_path_factory):
    x, = lc.coordinates("x")
    M, L, g, f = sp.symbols("M L g f", positive=True)
    mu = M / L
    system = lc.System([x], T=M * x.diff(t) ** 2 / 2, V=-mu * g * x**2 / 2,
                       events=[lc.Friction("table", x.diff(t), normal=mu * g * (L - x), static=f, kinetic=f)],
                       name="friction_rope", defaults={"M": 1.0, "L": 1.0, "g": G, "f": 0.3})
    return lc.compile(system, cache_dir=tmp_path_factory.mktemp("cache"))


@pytest.fixture(scope="module")
def incline(tmp_path_factory):
    s, = lc.coordinates("s")
    m, g, alpha, mu_s, mu_k = sp.symbols("m g alpha mu_s mu_k", positive=True)
    system = lc.System([s], T=m * s.diff(t) ** 2 / 2, V=-m * g * sp.sin(alpha) * s,
                       events=[lc.Friction("slope", s.diff(t), normal=m * g * sp.cos(alpha), static=mu_s,
                                           kinetic=mu_k)],
                       name="friction_incline", defaults={"m": 2.0, "g": G, "alpha": 0.5, "mu_s": 0.6, "mu_k": 0.4})
    return lc.compile(system, cache_dir=tmp_path_factory.mktemp("cache"))


@pytest.fixture(scope="module")
def belt(tmp_path_factory):
    x, = lc.coordinates("x")
    m, k, g, v_b, mu_s, mu_k = sp.symbols("m k g v_b mu_s mu_k", positive=True)
    system = lc.System([x], T=m * x.diff(t) ** 2 / 2, V=k * x**2 / 2,
                       events=[lc.Friction("belt", x.diff(t) - v_b, normal=m * g, static=mu_s, kinetic=mu_k)],
                       name="friction_belt", defaults={"m": 1.0, "k": 4.0, "g": G, "v_b": 0.5, "mu_s": 0.6,
                                                       "mu_k": 0.4})
    return lc.compile(system, cache_dir=tmp_path_factory.mktemp("cache"))


# -- the rope on a table ------------------------------------------------------------------------------------------

def test_a_rope_below_the_threshold_length_does_not_move(rope):
    l0 = 0.3 / 1.3
    x0 = 0.99 * l0
    sol = rope.simulate((0.0, 1000.0), [x0], [0.0], rtol=1e-12, atol=1e-12)
    assert sol.status == Status.DONE, sol.message
    assert sol.friction_switches == () and len(sol.events["table"]) == 0
    assert np.abs(sol.q[:, 0] - x0).max() < 1e-12 and np.abs(sol.qd[:, 0]).max() < 1e-14
    # the table holds the hanging weight μ g x: λ = −μ g x along ẋ
    np.testing.assert_allclose(sol.friction_forces[:, 0], -G * x0, rtol=1e-12)
    assert sol.nsteps < 50                                              # nothing happens: long steps


def test_a_rope_above_the_threshold_length_slides_with_cosh(rope):
    f, L = 0.3, 1.0
    l0, omega = f * L / (1 + f), np.sqrt(G * (1 + f) / L)
    x0 = 0.4
    sol = rope.simulate((0.0, 0.5), [x0], [0.0], rtol=1e-12, atol=1e-12)
    assert sol.status == Status.DONE, sol.message
    assert sol.friction_switches == () and len(sol.events["table"]) == 0      # slipping from the start
    np.testing.assert_allclose(sol.q[:, 0], l0 + (x0 - l0) * np.cosh(omega * sol.t), rtol=1e-10)
    # sliding (ẋ > 0 after t0): the table brakes with f μ g (L − x); at t0, v = 0 slipping forward, the same
    np.testing.assert_allclose(sol.friction_forces[:, 0], -f * G * (L - sol.q[:, 0]), rtol=1e-12)


# -- a block on an incline ----------------------------------------------------------------------------------------

@pytest.mark.parametrize("tan_alpha", [0.3, 0.6 * (1 - 1e-6), 0.6 * (1 + 1e-6), 0.9])
def test_a_block_on_an_incline_sticks_iff_tan_alpha_is_at_most_mu_s(incline, tan_alpha):
    alpha, mu_s, mu_k, m = np.arctan(tan_alpha), 0.6, 0.4, 2.0
    sol = incline.simulate((0.0, 3.0), [0.0], [0.0], params={"alpha": alpha}, rtol=1e-12, atol=1e-12)
    assert sol.status == Status.DONE, sol.message
    assert sol.friction_switches == ()
    if tan_alpha <= mu_s:
        assert np.abs(sol.q[:, 0]).max() < 1e-14
        np.testing.assert_allclose(sol.friction_forces[:, 0], -m * G * np.sin(alpha), rtol=1e-12)
    else:
        acceleration = G * (np.sin(alpha) - mu_k * np.cos(alpha))
        np.testing.assert_allclose(sol.q[:, 0], acceleration * sol.t**2 / 2, rtol=1e-10, atol=1e-15)
        np.testing.assert_allclose(sol.friction_forces[:, 0], -mu_k * m * G * np.cos(alpha), rtol=1e-12)


@pytest.mark.parametrize("static, kinetic", [(0, None), (0.0, 0.0), (0.5, 0)])
def test_a_coefficient_of_zero_is_accepted(static, kinetic):
    """μ ≥ 0, as the docstring says: μ = 0 is a frictionless element (μk = 0: slides freely once it slips)."""
    s, = lc.coordinates("s")
    element = lc.Friction("slope", s.diff(t), normal=G, static=static, kinetic=kinetic)
    assert float(element.static) == static and float(element.kinetic) == 0.0


def test_a_block_on_a_frictionless_incline_slides_as_without_the_element(cache_dir):
    """μs = μk = 0 given as numbers: s = g sin α t²/2 down the slope, the friction force 0."""
    s, = lc.coordinates("s")
    m, alpha = 2.0, 0.1
    system = lc.System([s], T=m * s.diff(t) ** 2 / 2, V=-m * G * np.sin(alpha) * s, name="friction_none",
                       events=[lc.Friction("slope", s.diff(t), normal=m * G * np.cos(alpha), static=0, kinetic=0)])
    sol = lc.compile(system, cache_dir=cache_dir).simulate((0.0, 1.0), [0.0], [0.0], rtol=1e-12, atol=1e-12)
    assert sol.status == Status.DONE, sol.message
    np.testing.assert_allclose(sol.q[:, 0], G * np.sin(alpha) * sol.t**2 / 2, rtol=1e-10, atol=0)
    assert np.abs(sol.friction_forces[:, 0]).max() == 0.0


def test_a_sliding_block_stops_where_the_kinetic_friction_brakes_it(incline):
    # tan α < μk: launched down the slope it decelerates by g (μk cos α − sin α), then sticks for good
    alpha, mu_k, v0 = 0.2, 0.4, 1.5
    braking = G * (mu_k * np.cos(alpha) - np.sin(alpha))
    sol = incline.simulate((0.0, 2.0), [0.0], [v0], params={"alpha": alpha}, rtol=1e-12, atol=1e-12)
    assert sol.status == Status.DONE, sol.message
    assert [(s.friction, s.mode) for s in sol.friction_switches] == [("slope", 0)]
    assert sol.friction_switches[0].t == pytest.approx(v0 / braking, abs=1e-12)
    assert sol.q[-1, 0] == pytest.approx(v0**2 / (2 * braking), abs=1e-12)
    assert abs(sol.qd[-1, 0]) < 1e-12


def test_a_block_launched_up_a_steep_incline_stops_and_slides_back(incline):
    # tan α > μs: up the slope (v < 0) it decelerates by g (sin α + μk cos α); at v = 0 the force that would hold
    # it, m g sin α, exceeds μs m g cos α: it slips the other way at once, accelerating by g (sin α − μk cos α)
    alpha, mu_k, v0 = 0.7, 0.4, -2.0
    up, down = G * (np.sin(alpha) + mu_k * np.cos(alpha)), G * (np.sin(alpha) - mu_k * np.cos(alpha))
    t_top = -v0 / up
    sol = incline.simulate((0.0, 2 * t_top), [0.0], [v0], params={"alpha": alpha}, rtol=1e-12, atol=1e-12)
    assert sol.status == Status.DONE, sol.message
    assert [(s.friction, s.mode) for s in sol.friction_switches] == [("slope", 1)]
    assert sol.friction_switches[0].t == pytest.approx(t_top, abs=1e-12)
    tau = sol.t - t_top
    expected = np.where(tau < 0, v0 * sol.t + up * sol.t**2 / 2, v0 * t_top / 2 + down * tau**2 / 2)
    np.testing.assert_allclose(sol.q[:, 0], expected, rtol=0, atol=1e-12)


# -- the stick–slip oscillator on a belt ----------------------------------------------------------------------------

def _belt_switches(mu_s, mu_k, periods, m=1.0, k=4.0, v_b=0.5):
    """The closed form's switching times (stick → slip, slip → stick, ...) over `periods` periods from x = 0 stuck."""
    omega = np.sqrt(k / m)
    x_s, x_star = mu_s * m * G / k, mu_k * m * G / k
    t_s = x_s / v_b
    tau = (2 * np.pi - 2 * np.arctan2(omega * (x_s - x_star), v_b)) / omega
    period = tau + 2 * (x_s - x_star) / v_b
    return np.array([t_s + i * period + offset for i in range(periods) for offset in (0.0, tau)]), period


@pytest.mark.parametrize("mu_s, mu_k", [(0.6, 0.4), (0.3, 0.1), (0.9, 0.3)])
def test_the_belt_oscillator_switches_at_the_closed_form_times(belt, mu_s, mu_k):
    expected, period = _belt_switches(mu_s, mu_k, periods=5)
    sol = belt.simulate((0.0, expected[-1] + period / 4), [0.0], [0.5], params={"mu_s": mu_s, "mu_k": mu_k},
                        rtol=1e-12, atol=1e-12)
    assert sol.status == Status.DONE, sol.message
    switches = sol.friction_switches
    assert [s.mode for s in switches] == [-1, 0] * 5                 # slip backwards (v < 0), stick, ...
    np.testing.assert_allclose([s.t for s in switches], expected, rtol=0, atol=1e-10)
    x_s = mu_s * G / 4.0
    breakaway = np.searchsorted(sol.t, [s.t for s in switches[::2]])     # (the row before each switch)
    np.testing.assert_allclose(sol.q[breakaway, 0], x_s, rtol=1e-10)    # k x = μs m g there
    stuck = np.zeros(sol.t.size, dtype=bool)
    for start, end in zip(expected[1::2], np.append(expected[2::2], np.inf), strict=True):
        stuck |= (sol.t > start + 1e-9) & (sol.t < end - 1e-9)
    np.testing.assert_allclose(sol.qd[stuck, 0], 0.5, rtol=1e-12)          # carried by the belt
    np.testing.assert_allclose(sol.friction_forces[stuck, 0], 4.0 * sol.q[stuck, 0], rtol=1e-9, atol=1e-12)
    slipping = np.zeros(sol.t.size, dtype=bool)                          # slower than the belt: pushed along it
    for start, end in zip(expected[::2], expected[1::2], strict=True):
        slipping |= (sol.t > start + 1e-9) & (sol.t < end - 1e-9)
    np.testing.assert_allclose(sol.friction_forces[slipping, 0], mu_k * G, rtol=1e-14)


def test_the_belt_oscillator_takes_a_few_steps_per_switch_whatever_mu(belt):
    # Steps per period for three friction laws, against the slip arc alone (the same arc from the breakaway state,
    # stopped just short of its end: no switch): a stick phase is a straight line, so what remains is the cost of
    # locating the two switches.  Measured 1.2 to 2.4 extra steps per switch at rtol 1e-10.
    extra = []
    for mu_s, mu_k in [(0.6, 0.4), (0.3, 0.1), (0.9, 0.3)]:
        expected, _ = _belt_switches(mu_s, mu_k, periods=8)
        params = {"mu_s": mu_s, "mu_k": mu_k}
        sol = belt.simulate((0.0, expected[-2] + 1e-3), [0.0], [0.5], params=params, rtol=1e-10, atol=1e-10)
        assert sol.status == Status.DONE and len(sol.friction_switches) == 15, sol.message
        tau = expected[1] - expected[0]
        arc = belt.simulate((0.0, 0.999 * tau), [mu_s * G / 4.0], [0.5 - 1e-9], params=params, rtol=1e-10,
                            atol=1e-10)
        assert arc.friction_switches == ()
        extra.append((sol.nsteps / 7 - arc.nsteps) / 2)
    assert max(extra) <= 4 and max(extra) - min(extra) <= 2, extra


def test_a_sweep_gives_each_trajectory_its_own_friction_modes(belt):
    mu_s = np.array([0.4, 0.6, 0.8])
    sweep = belt.sweep((0.0, 6.0), grid={"mu_s": mu_s}, q0=[0.0], qd0=[0.5], params={"mu_k": 0.3},
                       rtol=1e-12, atol=1e-12, output="events", event_cap=64, progress=False)
    assert (sweep.status == Status.DONE).all()
    for i, mu in enumerate(mu_s):
        expected, _ = _belt_switches(mu, 0.3, periods=3)
        expected = expected[expected < 6.0]
        count = sweep.events["belt"]["count"][i]
        np.testing.assert_allclose(sweep.events["belt"]["t"][i, :count], expected, rtol=0, atol=1e-10)


def test_the_friction_switches_and_forces_are_saved(belt, tmp_path):
    sol = belt.simulate((0.0, 4.0), [0.0], [0.5], rtol=1e-12, atol=1e-12)
    sol.save_npz(tmp_path / "belt.npz")
    saved = np.load(tmp_path / "belt.npz")
    np.testing.assert_array_equal(saved["friction_forces"], sol.friction_forces)
    assert saved["friction_switch_t"].tolist() == [s.t for s in sol.friction_switches]
    assert saved["friction_switch_friction"].tolist() == ["belt"] * len(sol.friction_switches)
    assert saved["friction_switch_mode"].tolist() == [s.mode for s in sol.friction_switches]
    assert sol.contact_forces is None and sol.contact_switches == ()
    assert belt.frictions == ("belt",) and belt.contacts == ()
