"""The Taylor method through every mode of resting contacts and friction (issue 21): one ``taylor_coefficients``
branching on the mode slots of p to the program of the rows held (`lagcomp.codegen.taylor.ModePrograms`).

Closed forms (as in tests/test_resting_contacts.py and tests/test_friction.py):

* a ball dropped from h0 on a floor with restitution e: v1 = √(2 g h0), t1 = v1/g, at rest from
  t∞ = t1 + 2 e v1/(g (1 − e)), where the floor pushes with m g;
* a particle sliding from rest at θ0 from the top of a smooth circle leaves it at cos θ = (2/3) cos θ0;
* a mass on a spring (k) carried by a belt (v_b) with Coulomb friction (μs, μk, normal m g): breakaway at
  x_s = μs m g/k, then a slip arc of duration τ (design21.md §5), then stuck again until x_s.
"""

import numpy as np
import pytest
import sympy as sp

import lagcomp as lc
from lagcomp.integrate.status import Status

t = lc.t
G = 9.81


@pytest.fixture(scope="module")
def ball(tmp_path_factory):
    x, = lc.coordinates("x")
    m, g, e = sp.symbols("m g e", positive=True)
    system = lc.System([x], T=m * x.diff(t) ** 2 / 2, V=m * g * x, events=[lc.Contact("floor", x, restitution=e)],
                       name="taylor_modes_ball", defaults={"m": 2.0, "g": G, "e": 0.5})
    return lc.compile(system, cache_dir=tmp_path_factory.mktemp("cache"))


@pytest.fixture(scope="module")
def sphere(tmp_path_factory):
    x, y = lc.coordinates("x y")
    m, g, R = sp.symbols("m g R", positive=True)
    system = lc.System([x, y], T=m * (x.diff(t) ** 2 + y.diff(t) ** 2) / 2, V=m * g * y,
                       events=[lc.Contact("sphere", sp.sqrt(x**2 + y**2) - R, restitution=0.5)],
                       name="taylor_modes_sphere", defaults={"m": 1.5, "g": G, "R": 2.0})
    return lc.compile(system, cache_dir=tmp_path_factory.mktemp("cache"))


@pytest.fixture(scope="module")
def belt(tmp_path_factory):
    x, = lc.coordinates("x")
    m, k, g, v_b, mu_s, mu_k = sp.symbols("m k g v_b mu_s mu_k", positive=True)
    system = lc.System([x], T=m * x.diff(t) ** 2 / 2, V=k * x**2 / 2,
                       events=[lc.Friction("belt", x.diff(t) - v_b, normal=m * g, static=mu_s, kinetic=mu_k)],
                       name="taylor_modes_belt", defaults={"m": 1.0, "k": 4.0, "g": G, "v_b": 0.5, "mu_s": 0.6,
                                                          "mu_k": 0.4})
    return lc.compile(system, cache_dir=tmp_path_factory.mktemp("cache"))


def test_the_ball_comes_to_rest_at_the_accumulation_time_with_taylor(ball):
    m, e, h0 = 2.0, 0.5, 1.0
    v1 = np.sqrt(2 * G * h0)
    t_infinity = v1 / G + 2 * e * v1 / (G * (1 - e))
    sol = ball.simulate((0.0, 3 * t_infinity), [h0], [0.0], params={"e": e, "m": m}, method="taylor", rtol=1e-12,
                        atol=1e-12)
    assert sol.status == Status.DONE, sol.message
    assert [(s.contact, s.closed) for s in sol.contact_switches] == [("floor", True)]
    t_rest = sol.contact_switches[0].t
    assert t_rest == pytest.approx(t_infinity, abs=1e-9)
    rest = sol.t > t_rest
    assert np.abs(sol.q[rest, 0]).max() < 1e-15 * h0 and not sol.qd[rest, 0].any()
    np.testing.assert_allclose(sol.contact_forces[rest, 0], m * G, rtol=1e-12)
    assert not sol.contact_forces[sol.t < t_rest].any()


def test_the_ball_may_start_at_rest_with_taylor(ball):
    sol = ball.simulate((0.0, 100.0), [0.0], [0.0], method="taylor", rtol=1e-12, atol=1e-12)
    assert sol.status == Status.DONE and sol.contact_switches == ()
    assert not sol.q.any() and not sol.qd.any()


@pytest.mark.parametrize("theta0", [0.1, 0.5])
def test_the_particle_leaves_the_sphere_at_two_thirds_of_cos_theta0_with_taylor(sphere, theta0):
    # The held program's λ has either sign; the lift-off is its event, located on the series' dense output.
    R, m = 2.0, 1.5
    sol = sphere.simulate((0.0, 2.5), [R * np.sin(theta0), R * np.cos(theta0)], [0.0, 0.0], method="taylor",
                          rtol=1e-12, atol=1e-12)
    assert sol.status == Status.DONE, sol.message
    assert [(s.contact, s.closed) for s in sol.contact_switches] == [("sphere", False)]
    leaving = sol.events["sphere"]
    q = leaving.q[0]
    assert q[1] / np.hypot(*q) == pytest.approx(2 / 3 * np.cos(theta0), abs=1e-10)
    assert abs(np.hypot(*q) - R) < 1e-11
    on = sol.t < sol.contact_switches[0].t
    cos = sol.q[on, 1] / np.hypot(sol.q[on, 0], sol.q[on, 1])
    np.testing.assert_allclose(sol.contact_forces[on, 0], m * G * (3 * cos - 2 * np.cos(theta0)), rtol=1e-9, atol=1e-9)


def test_a_pulled_mass_lifts_off_when_the_force_exceeds_its_weight_with_taylor(tmp_path):
    # At rest the held program is exact (q̈ = 0) and the steps grow long: λ = m g − F0 sin ω t turns negative within
    # one, and its event locates the zero on the step's series.
    y, = lc.coordinates("y")
    m, g, F0, w = sp.symbols("m g F0 omega", positive=True)
    system = lc.System([y], T=m * y.diff(t) ** 2 / 2, V=m * g * y - F0 * sp.sin(w * t) * y,
                       events=[lc.Contact("floor", y, restitution=0.5)],
                       name="taylor_modes_pulled", defaults={"m": 2.0, "g": G, "F0": 30.0, "omega": 3.0})
    pulled = lc.compile(system, cache_dir=tmp_path)
    t_off = np.arcsin(2.0 * G / 30.0) / 3.0
    sol = pulled.simulate((0.0, 1.0), [0.0], [0.0], method="taylor", rtol=1e-12, atol=1e-12)
    assert sol.status == Status.DONE, sol.message
    assert (sol.contact_switches[0].contact, sol.contact_switches[0].closed) == ("floor", False)
    assert sol.contact_switches[0].t == pytest.approx(t_off, abs=1e-10)
    assert not sol.q[sol.t < t_off].any()
    assert sol.q[sol.t > t_off + 0.01, 0].min() > 0.0


def _belt_switches(mu_s, mu_k, periods, m=1.0, k=4.0, v_b=0.5):
    """The closed form's switching times (stick → slip, slip → stick, ...) over `periods` periods from x = 0 stuck
    (tests/test_friction.py)."""
    omega = np.sqrt(k / m)
    x_s, x_star = mu_s * m * G / k, mu_k * m * G / k
    t_s = x_s / v_b
    tau = (2 * np.pi - 2 * np.arctan2(omega * (x_s - x_star), v_b)) / omega
    period = tau + 2 * (x_s - x_star) / v_b
    return np.array([t_s + i * period + offset for i in range(periods) for offset in (0.0, tau)]), period


@pytest.mark.parametrize("mu_s, mu_k", [(0.6, 0.4), (0.3, 0.1)])
def test_the_belt_oscillator_switches_at_the_closed_form_times_with_taylor(belt, mu_s, mu_k):
    expected, period = _belt_switches(mu_s, mu_k, periods=4)
    sol = belt.simulate((0.0, expected[-1] + period / 4), [0.0], [0.5], params={"mu_s": mu_s, "mu_k": mu_k},
                        method="taylor", rtol=1e-12, atol=1e-12)
    assert sol.status == Status.DONE, sol.message
    assert [s.mode for s in sol.friction_switches] == [-1, 0] * 4
    np.testing.assert_allclose([s.t for s in sol.friction_switches], expected, rtol=0, atol=1e-10)
    stuck = np.zeros(sol.t.size, dtype=bool)
    for start, end in zip(expected[1::2], np.append(expected[2::2], np.inf), strict=True):
        stuck |= (sol.t > start + 1e-9) & (sol.t < end - 1e-9)
    np.testing.assert_allclose(sol.qd[stuck, 0], 0.5, rtol=1e-12)


def test_more_mode_sets_than_the_bound_keep_todays_refusal(tmp_path):
    # Four contacts: 16 mode sets > MODE_PROGRAMS_MAX, so the Taylor program is the motion without contacts.
    from lagcomp.codegen.taylor import MODE_PROGRAMS_MAX
    from lagcomp.errors import OptionError

    xs = lc.coordinates("x0 x1 x2 x3")
    system = lc.System(list(xs), T=sum(x.diff(t) ** 2 for x in xs) / 2, V=G * sum(xs),
                       events=[lc.Contact(f"floor{i}", x, restitution=0.5) for i, x in enumerate(xs)],
                       name="taylor_modes_four")
    assert 2 ** 4 > MODE_PROGRAMS_MAX
    model = lc.compile(system, cache_dir=tmp_path)
    assert not hasattr(model.kernels, "TAYLOR_MODE_PROGRAMS")
    with pytest.raises(OptionError, match="start closed"):
        model.simulate((0.0, 1.0), [0.0, 1.0, 1.0, 1.0], [0.0] * 4, method="taylor")
