"""Friction and contacts in one system (issue 21): a contact's event (an impact, a closing, a lift-off) decides the
friction modes again from the state after it, in the same ``event_reset``, so that no mode is stale.

Reference, a closed form: a block (mass m) sliding on a table (friction on ẋ, N = m g, μs, μk) toward a wall at
x = L (a contact with gap L − x, restitution e), from x = 0 at v0: it decelerates by μk g and reaches the wall at
v_w = √(v0² − 2 μk g L), t_w = (v0 − v_w)/(μk g); it leaves at −e v_w (slipping the other way: the friction force
turns round with it) and stops at x = L − (e v_w)²/(2 μk g), t = t_w + e v_w/(μk g), where it stays (sticking,
with no force to hold).  A mode kept from before the impact would push the block away from the wall forever.
"""

import numpy as np
import pytest
import sympy as sp

import lagcomp as lc
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
