"""Friction pressed by a contact on a System with constraints (issue 39): the sticking element's row, the contact's
and the constraints' held together (`lagcomp.kernel_support.resting.constrained_pressed_frictional_accelerations`),
the frictional impact through the constrained response K (`lagcomp.kernel_support.impacts
.constrained_frictional_impact`).

The model: a block of mass m at (x, y) carries a second mass m2 at (u, w) on a rigid rod, the holonomic
constraints u − x − d = 0 and w − y = 0 (Λ rows (−1, 0, 1, 0), (0, −1, 0, 1)); the block sits on a floor inclined at
α (gap −x sin α + y cos α, the distance from it, so the contact's force is the physical normal force N) with
Coulomb friction on its velocity along the floor, v = ẋ cos α + ẏ sin α, pressed by that contact.  The reference is
the same block of mass M = m + m2 with no constraint (the rod-carried mass moves with it), and closed forms:

* at rest on the floor: it stays iff tan α ≤ μs, with N = M g cos α, friction M g sin α up the slope and the rod's
  multipliers (`reactions`' convention M q̈ = F + Λᵀ μ: m2 ü = μ_x, m2 ẅ = −m2 g + μ_y) μ_x = 0, μ_y = m2 g;
* else it slides with s̈ = −g (sin α − μk cos α) along the slope (s up it), friction μk N, and the rod pulls the
  carried mass along: μ_x = m2 s̈ cos α, μ_y = m2 (s̈ sin α + g);
* dropped from h onto a level floor (α = 0) at a tangential speed v_t, restitution e: v_n = √(2 g h), and the
  impact leaves v_t⁺ = v_t − μk (1 + e) v_n sign v_t when |v_t| > μs (1 + e) v_n, else 0 (the impulses scale with M,
  the velocities do not), the carried mass with the block's velocity (Λ q̇⁺ = 0).
"""

import numpy as np
import pytest
import sympy as sp

import lagcomp as lc
from lagcomp.integrate.status import Status

t = lc.t
G = 9.81
DEFAULTS = {"m": 1.5, "m2": 0.5, "g": G, "d": 0.3, "alpha": 0.4, "mu_s": 0.5, "mu_k": 0.3, "e": 0.0}
M = DEFAULTS["m"] + DEFAULTS["m2"]


def _events(x, y, symbols):
    alpha, mu_s, mu_k, e = (symbols[k] for k in ("alpha", "mu_s", "mu_k", "e"))
    along = x.diff(t) * sp.cos(alpha) + y.diff(t) * sp.sin(alpha)
    return [lc.Contact("slope", -x * sp.sin(alpha) + y * sp.cos(alpha), restitution=e),
            lc.Friction("grip", along, normal="slope", static=mu_s, kinetic=mu_k)]


@pytest.fixture(scope="module")
def models(tmp_path_factory):
    cache = tmp_path_factory.mktemp("cache")
    symbols = {name: sp.Symbol(name, positive=True) for name in DEFAULTS}
    m, m2, g, d = (symbols[k] for k in ("m", "m2", "g", "d"))
    x, y, u, w = lc.coordinates("x y u w")
    carried = lc.System([x, y, u, w], T=m * (x.diff(t) ** 2 + y.diff(t) ** 2) / 2
                        + m2 * (u.diff(t) ** 2 + w.diff(t) ** 2) / 2, V=m * g * y + m2 * g * w,
                        constraints=[lc.Holonomic("rod_x", u - x - d), lc.Holonomic("rod_y", w - y)],
                        events=_events(x, y, symbols), name="friction_rod_block", defaults=DEFAULTS)
    block = lc.System([x, y], T=(m + m2) * (x.diff(t) ** 2 + y.diff(t) ** 2) / 2, V=(m + m2) * g * y,
                      events=_events(x, y, symbols), name="friction_heavy_block",
                      defaults={k: v for k, v in DEFAULTS.items() if k != "d"})
    return lc.compile(carried, cache_dir=cache), lc.compile(block, cache_dir=cache)


def _both(models, span, q0, qd0, params):
    carried, block = models
    d = DEFAULTS["d"]
    on_rod = carried.simulate(span, [q0[0], q0[1], q0[0] + d, q0[1]], [qd0[0], qd0[1], qd0[0], qd0[1]], params,
                              rtol=1e-12, atol=1e-12)
    alone = block.simulate(span, q0, qd0, params, rtol=1e-12, atol=1e-12)
    assert on_rod.status == alone.status == Status.DONE, (on_rod.message, alone.message)
    return on_rod, alone


@pytest.mark.parametrize("alpha", [0.4, 0.5])      # tan α = 0.42, 0.55 against μs = 0.5
def test_a_block_carrying_a_mass_on_a_rod_sticks_on_an_incline_iff_tan_alpha_is_within_mu_s(models, alpha):
    mu_s, mu_k, m2 = DEFAULTS["mu_s"], DEFAULTS["mu_k"], DEFAULTS["m2"]
    on_rod, alone = _both(models, (0.0, 1.0), [0.0, 0.0], [0.0, 0.0], {"alpha": alpha})
    assert on_rod.friction_switches == alone.friction_switches == ()
    assert on_rod.contact_switches == alone.contact_switches == ()
    normal = M * G * np.cos(alpha)
    np.testing.assert_allclose(on_rod.contact_forces[:, 0], normal, rtol=1e-12)
    s = on_rod.q[:, 0] * np.cos(alpha) + on_rod.q[:, 1] * np.sin(alpha)      # along the slope, up
    if np.tan(alpha) <= mu_s:
        assert np.abs(on_rod.q[:, :2]).max() < 1e-12
        np.testing.assert_allclose(on_rod.friction_forces[:, 0], M * G * np.sin(alpha), rtol=1e-12)
        assert np.abs(on_rod.reactions["rod_x"]).max() < 1e-12 * m2 * G
        np.testing.assert_allclose(on_rod.reactions["rod_y"], m2 * G, rtol=1e-12)
    else:
        acceleration = -G * (np.sin(alpha) - mu_k * np.cos(alpha))
        np.testing.assert_allclose(s, acceleration * on_rod.t**2 / 2, rtol=1e-10, atol=1e-14)
        np.testing.assert_allclose(on_rod.friction_forces[1:, 0], mu_k * normal, rtol=1e-12)
        np.testing.assert_allclose(on_rod.reactions["rod_x"], m2 * acceleration * np.cos(alpha), rtol=1e-11)
        np.testing.assert_allclose(on_rod.reactions["rod_y"], m2 * (acceleration * np.sin(alpha) + G), rtol=1e-12)
    # the carried mass stays on its rod, and the block moves as the heavy block alone
    np.testing.assert_allclose(on_rod.q[:, 2:], on_rod.q[:, :2] + [DEFAULTS["d"], 0.0], rtol=0, atol=1e-13)
    end = alone.q[-1]
    np.testing.assert_allclose(on_rod.q[-1, :2], end, rtol=0, atol=1e-12)
    np.testing.assert_allclose(on_rod.contact_forces[-1], alone.contact_forces[-1], rtol=1e-12)
    np.testing.assert_allclose(on_rod.friction_forces[-1], alone.friction_forces[-1], rtol=1e-12)


@pytest.mark.parametrize("v_t", [5.0, -5.0, 1.0])   # μs (1 + e) v_n = 3.32: 5 slips through the impact, 1 sticks
def test_a_frictional_impact_with_a_rod_keeps_it_and_takes_coulombs_tangential_impulse(models, v_t):
    h, e, mu_s, mu_k = 1.0, 0.5, DEFAULTS["mu_s"], DEFAULTS["mu_k"]
    v_n = np.sqrt(2 * G * h)
    on_rod, alone = _both(models, (0.0, 0.6), [0.0, h], [v_t, 0.0], {"alpha": 0.0, "e": e})
    impact, reference = on_rod.events["slope"], alone.events["slope"]
    assert len(impact) == len(reference) == 1
    np.testing.assert_allclose(impact.qd[0, :2], [v_t, -v_n], rtol=1e-12)
    slipping = abs(v_t) > mu_s * (1 + e) * v_n
    expected = v_t - mu_k * (1 + e) * v_n * np.sign(v_t) if slipping else 0.0
    np.testing.assert_allclose(impact.qd_after[0], [expected, e * v_n, expected, e * v_n], rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(impact.qd_after[0, :2], reference.qd_after[0], rtol=1e-13, atol=1e-15)
    np.testing.assert_allclose(on_rod.q[-1, :2], alone.q[-1], rtol=0, atol=1e-12)


@pytest.fixture(scope="module")
def looped(tmp_path_factory):
    """The carried block as a kinematic tree with a loop: each mass on a massless carriage (x, then y on it; u, then
    w), the loop pinning the point (d, 0) of the block to the carried mass in x and y: u − x − d = 0, w − y = 0, the
    System's constraints, in the same coordinates."""
    symbols = {name: sp.Symbol(name, positive=True) for name in DEFAULTS}
    m, m2, g, d = (symbols[k] for k in ("m", "m2", "g", "d"))
    x, y, u, w = lc.coordinates("x y u w")
    tree = lc.Tree([lc.Link("carriage", lc.Prismatic(x, axis="x")),
                    lc.Link("block", lc.Prismatic(y, axis="y"), parent="carriage", mass=m),
                    lc.Link("cart", lc.Prismatic(u, axis="x")),
                    lc.Link("carried", lc.Prismatic(w, axis="y"), parent="cart", mass=m2)],
                   gravity=(0, -g, 0), name="friction_loop_block", defaults=DEFAULTS,
                   loops=[lc.Loop("rod", ("block", (d, 0, 0)), ("carried", (0, 0, 0)), directions="xy")],
                   events=_events(x, y, symbols))
    return lc.compile(tree, cache_dir=tmp_path_factory.mktemp("cache"))


@pytest.mark.parametrize("alpha", [0.4, 0.5])
def test_friction_on_a_tree_with_a_loop_is_the_constrained_systems(models, looped, alpha):
    carried, _ = models
    mu_s, mu_k = DEFAULTS["mu_s"], DEFAULTS["mu_k"]
    q0, d = [0.0, 0.0, DEFAULTS["d"], 0.0], DEFAULTS["d"]
    on_tree = looped.simulate((0.0, 1.0), q0, [0.0] * 4, {"alpha": alpha}, rtol=1e-12, atol=1e-12)
    on_rod = carried.simulate((0.0, 1.0), q0, [0.0] * 4, {"alpha": alpha}, rtol=1e-12, atol=1e-12)
    assert on_tree.status == on_rod.status == Status.DONE, (on_tree.message, on_rod.message)
    assert on_tree.friction_switches == () and on_tree.contact_switches == ()
    normal = M * G * np.cos(alpha)
    np.testing.assert_allclose(on_tree.contact_forces[:, 0], normal, rtol=1e-12)
    s = on_tree.q[:, 0] * np.cos(alpha) + on_tree.q[:, 1] * np.sin(alpha)
    if np.tan(alpha) <= mu_s:
        assert np.abs(on_tree.q[:, :2]).max() < 1e-12
        np.testing.assert_allclose(on_tree.friction_forces[:, 0], M * G * np.sin(alpha), rtol=1e-12)
    else:
        np.testing.assert_allclose(s, -G * (np.sin(alpha) - mu_k * np.cos(alpha)) * on_tree.t**2 / 2, rtol=1e-10,
                                   atol=1e-14)
        np.testing.assert_allclose(on_tree.friction_forces[1:, 0], mu_k * normal, rtol=1e-12)
    np.testing.assert_allclose(on_tree.q[:, 2:], on_tree.q[:, :2] + [d, 0.0], rtol=0, atol=1e-13)
    np.testing.assert_allclose(on_tree.q[-1], on_rod.q[-1], rtol=0, atol=1e-12)


@pytest.fixture(scope="module")
def dragged(tmp_path_factory):
    """The tree with the loop of `looped`, no floor: a friction element on the block's ẋ pressed by the expression
    N = (m + m2) g (its mode in the slot after the Baumgarte gains and the closing flag)."""
    symbols = {name: sp.Symbol(name, positive=True) for name in DEFAULTS}
    m, m2, g, d, mu_s, mu_k = (symbols[k] for k in ("m", "m2", "g", "d", "mu_s", "mu_k"))
    x, y, u, w = lc.coordinates("x y u w")
    tree = lc.Tree([lc.Link("carriage", lc.Prismatic(x, axis="x")),
                    lc.Link("block", lc.Prismatic(y, axis="y"), parent="carriage", mass=m),
                    lc.Link("cart", lc.Prismatic(u, axis="x")),
                    lc.Link("carried", lc.Prismatic(w, axis="y"), parent="cart", mass=m2)],
                   gravity=(0, -g, 0), name="friction_loop_drag",
                   defaults={k: v for k, v in DEFAULTS.items() if k not in ("alpha", "e")},
                   loops=[lc.Loop("rod", ("block", (d, 0, 0)), ("carried", (0, 0, 0)), directions="xy")],
                   events=[lc.Friction("drag", x.diff(t), normal=(m + m2) * g, static=mu_s, kinetic=mu_k)])
    return lc.compile(tree, cache_dir=tmp_path_factory.mktemp("cache"))


def test_a_tree_with_a_loop_launched_against_friction_pressed_by_an_expression_stops_where_coulomb_says(dragged):
    """Launched at ẋ = v0 (the carried mass with it), falling freely in y: friction μk M g on the mechanism of mass M
    stops it at t_s = v0/(μk g), x = v0²/(2 μk g); it then sticks (no force along x to hold: 0 ≤ μs M g)."""
    v0, mu_k, d = 2.0, DEFAULTS["mu_k"], DEFAULTS["d"]
    sol = dragged.simulate((0.0, 1.0), [0.0, 0.0, d, 0.0], [v0, 0.0, v0, 0.0], rtol=1e-12, atol=1e-12)
    assert sol.status == Status.DONE, sol.message
    t_s = v0 / (mu_k * G)
    assert [(s.friction, s.mode) for s in sol.friction_switches] == [("drag", 0)]
    assert sol.friction_switches[0].t == pytest.approx(t_s, abs=1e-9)
    x = np.where(sol.t < t_s, v0 * sol.t - mu_k * G * sol.t**2 / 2, v0**2 / (2 * mu_k * G))
    np.testing.assert_allclose(sol.q[:, 0], x, rtol=0, atol=1e-9)
    np.testing.assert_allclose(sol.q[:, 1], -G * sol.t**2 / 2, rtol=1e-10, atol=1e-14)
    np.testing.assert_allclose(sol.q[:, 2:], sol.q[:, :2] + [d, 0.0], rtol=0, atol=1e-12)
