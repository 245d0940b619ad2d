"""The same answer in any units (issue 36, part 1).

A change of units multiplies every quantity by L^a M^b T^c for its dimension (a, b, c) (length, mass, time): a
run in the new units, mapped back, is the run in the old ones, up to the tolerance.  Each bundled example below
declares the dimension of its coordinates and parameters, derived from its Lagrangian:

* angles are dimensionless, so their rates are T⁻¹; lengths L, masses M, g (an acceleration) L T⁻²;
* a spring's stiffness k (k x²/2 is an energy, M L² T⁻²) is M T⁻², a damper's c (c ẋ²/2 a power, M L² T⁻³) M T⁻¹.

The rescaled run gets the parameters, the initial state, ``t_span`` (and ``dt``) in the new units, the same rtol
and an atol per state component in that component's units (positions × their unit, velocities × their unit over
the unit of time: `simulate(..., atol=array)`), so that every error test of the drivers compares the same
ratios; the runs are compared to the tolerance (the factors' roundings can still move a step).  Every method each
example accepts is covered (`test_the_cases_are_every_method_each_example_accepts` keeps the table whole).

Two faults of this kind are reproduced first (both failed before the fix): radau on a millimetre and a large
four-bar linkage ended at t = 0 with ITERATION_MATRIX_SINGULAR or NEWTON_FAILED (its singularity test and its
norms compared quantities of different units), and a ball dropped on a floor at height H ≠ 0 stopped with
EVENTS_ACCUMULATED before coming to rest (the closing rule looked at time alone, while the bounces it must
resolve are limited by the gap's rounding, ε H).  Then (each failed before its fix): an equilibrium judged against
max|K| max(1, |q|), a constraint residual against max(1, …) (a spring or a rod in millimetres passed 1e-8 and 1e-6
off), a periodic orbit's unscaled shooting residual (no convergence in units of time ×100), events located to
2 ε |t| + 2 ε (a ball on a floor at H = 0 in milliseconds: EVENTS_ACCUMULATED), a portrait's energy spread against
max(1, |E|), and a fit stopped by scipy's unscaled gtol.
"""

import math

import numpy as np
import pytest
import sympy as sp
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

import lagcomp as lc
from lagcomp.analysis import normal_modes, periodic_orbit, two_trajectory_lyapunov
from lagcomp.analysis.statics import RESIDUAL_TOLERANCE
from lagcomp.errors import LinearizationError
from lagcomp.examples.constrained import four_bar_closure
from lagcomp.integrate.methods import METHODS
from lagcomp.integrate.options import check_method
from lagcomp.integrate.status import Status
from lagcomp.kernel_support.resting import BOUNCE_HEIGHT, BOUNCE_TIME, ZENO_TIME

t = lc.t
EPS = np.finfo(float).eps
LENGTH, MASS, ACCELERATION = (1, 0, 0), (0, 1, 0), (1, 0, -2)
ANGLE = (0, 0, 0)

#: example: (dimensions of the coordinates, of the parameters, the methods it accepts, a span of a few of its
#: characteristic times, rk4's dt).
ADAPTIVE = ("dopri5", "dop853", "tsit5", "bs3", "radau")
EXPLICIT_FIXED = ("rk4",)
GAUSS = ("gauss1", "gauss2", "gauss3")
SEPARABLE = ("verlet", "yoshida4", "yoshida6")
EXAMPLES = {
    "simple_pendulum": ((ANGLE,), {"m": MASS, "l": LENGTH, "g": ACCELERATION},
                        ADAPTIVE + ("taylor",) + EXPLICIT_FIXED + SEPARABLE + GAUSS, 2.0, 1e-3),
    "double_pendulum": ((ANGLE, ANGLE), {"m1": MASS, "m2": MASS, "l1": LENGTH, "l2": LENGTH, "g": ACCELERATION},
                        ADAPTIVE + ("taylor",) + EXPLICIT_FIXED + GAUSS, 2.0, 1e-3),
    "stiff_spring_pendulum": ((LENGTH, ANGLE), {"m": MASS, "k": (0, 1, -2), "c": (0, 1, -1), "l0": LENGTH,
                                                "g": ACCELERATION},
                              ADAPTIVE + ("taylor",) + EXPLICIT_FIXED + GAUSS, 0.05, 2e-5),
    "four_bar_linkage": ((ANGLE, ANGLE, ANGLE), {"a": LENGTH, "b": LENGTH, "c": LENGTH, "d": LENGTH, "m1": MASS,
                                                  "m2": MASS, "m3": MASS, "g": ACCELERATION},
                         ADAPTIVE + EXPLICIT_FIXED, 0.5, 1e-4),
    "spherical_pendulum_cartesian": ((LENGTH, LENGTH, LENGTH), {"m": MASS, "l": LENGTH, "g": ACCELERATION},
                                     ADAPTIVE + EXPLICIT_FIXED + ("rattle",), 1.0, 1e-3),
    "n_link_pendulum": ((ANGLE, ANGLE, ANGLE), {"m1": MASS, "m2": MASS, "m3": MASS, "l1": LENGTH, "l2": LENGTH,
                                                 "l3": LENGTH, "g": ACCELERATION},
                        ADAPTIVE + ("taylor",) + EXPLICIT_FIXED + GAUSS, 1.0, 1e-3),
    "huygens": ((ANGLE,), {"m": MASS, "R": LENGTH, "g": ACCELERATION},
                ADAPTIVE + ("taylor",) + EXPLICIT_FIXED + GAUSS, 2.0, 1e-3),
    "driven_pendulum": ((ANGLE,), {"m": MASS, "l": LENGTH, "g": ACCELERATION, "A": LENGTH, "Omega": (0, 0, -1)},
                        ADAPTIVE + ("taylor",) + EXPLICIT_FIXED + SEPARABLE + GAUSS, 0.2, 1e-4),
    "sling": ((LENGTH,), {"m": MASS, "omega": (0, 0, -1)},
              ADAPTIVE + ("taylor",) + EXPLICIT_FIXED + SEPARABLE + GAUSS, 1.0, 1e-3),
}
CASES = [(name, method) for name, (*_, methods, _, _) in EXAMPLES.items() for method in methods]
RTOL = 1e-9


def factor(units, dimension):
    """The factor L^a M^b T^c of a quantity of ``dimension`` (a, b, c) for the units' factors (L, M, T)."""
    return math.prod(u ** d for u, d in zip(units, dimension, strict=True))


def state_atol(position, time, size=1e-3 * RTOL):
    """atol per state component in the new units: `size` times each coordinate's unit (`position`, one per
    coordinate), and that over the unit of time for its velocity."""
    return np.concatenate([size * position, size * position / time])


def run_in_units(model, name, method, units):
    """A short run of the bundled ``name`` in units scaled by ``units`` = (L, M, T), mapped back: (status, y)."""
    coordinates, dimensions, _, span, dt = EXAMPLES[name]
    position = np.array([factor(units, d) for d in coordinates])
    time = units[2]
    params = {k: v * factor(units, dimensions[k]) for k, v in model.defaults.items()}
    q0, qd0 = np.asarray(model.q0, float), np.asarray(model.qd0, float)
    options = ({"rtol": RTOL, "atol": state_atol(position, time)} if METHODS[method].adaptive
               else {"dt": dt * time})
    sol = model.simulate((0.0, span * time), q0 * position, qd0 * position / time, params=params, method=method,
                         throw=False, progress=False, **options)
    return sol.status, np.concatenate([sol.q[-1] / position, sol.qd[-1] * time / position]), sol.t[-1] / time


unit_factors = st.floats(-3.0, 3.0).map(lambda x: 10.0 ** x)


@pytest.mark.parametrize(("name", "method"), CASES)
@settings(max_examples=4, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(length=unit_factors, mass=unit_factors, time=unit_factors)
def test_a_run_is_the_same_in_any_units(compiled, name, method, length, mass, time):
    model = compiled(name)
    status, y, t_end = run_in_units(model, name, method, (1.0, 1.0, 1.0))
    assert status == Status.DONE
    scaled_status, scaled_y, scaled_t_end = run_in_units(model, name, method, (length, mass, time))
    assert scaled_status == status and scaled_t_end == pytest.approx(t_end, rel=4 * EPS)
    # to the tolerance: a few hundred rtol of the state's size over a few characteristic times (rk4: the same
    # steps, so rounding only)
    bound = (300 * RTOL if METHODS[method].adaptive else 1e-10) * np.max(np.abs(y))
    np.testing.assert_allclose(scaled_y, y, rtol=0, atol=bound)


@pytest.mark.parametrize("name", list(EXAMPLES))
def test_the_cases_are_every_method_each_example_accepts(compiled, name):
    """The table above names every method the example accepts (a new method or example must join it)."""
    model = compiled(name)
    accepted = []
    for method in METHODS.values():
        try:
            check_method(model, method)
        except lc.OptionError:
            continue
        accepted.append(method.name)
    assert sorted(EXAMPLES[name][2]) == sorted(accepted)


# --- radau on a closed loop in millimetres and in a large size (the reproduction) ---------------------------

@pytest.mark.parametrize(("length", "mass"), [(1e-2, 1e-3), (1e-3, 1e-3), (1e3, 1e3)])
def test_radau_runs_a_small_and_a_large_four_bar_linkage_as_dop853_does(compiled, length, mass):
    """Lengths and masses scaled, g kept (a different mechanism, not a change of units): before the fix radau
    ended at t = 0 with status −10 or −9 at rtol 1e-8 while dop853 ran."""
    model = compiled("four_bar_linkage")
    params = dict(model.defaults)
    for k in "abcd":
        params[k] *= length
    for k in ("m1", "m2", "m3"):
        params[k] *= mass
    q0, qd0 = four_bar_closure(params, 0.0, 10.0)
    start = {"q0": q0, "qd0": qd0, "params": params, "throw": False, "progress": False}
    reference = model.simulate((0.0, 1.0), method="dop853", rtol=1e-12, atol=1e-12, **start)
    sol = model.simulate((0.0, 1.0), method="radau", rtol=1e-8, atol=1e-8, **start)
    assert reference.status == sol.status == Status.DONE, sol.message
    np.testing.assert_allclose(sol.q[-1], reference.q[-1], rtol=0, atol=1e-6 * np.max(np.abs(reference.q[-1])))


# --- contacts: a floor at any height, in any units --------------------------------------------------------------------

@pytest.fixture(scope="module")
def ball(cache_dir):
    x, = lc.coordinates("x")
    m, g, e, H = sp.symbols("m g e H", positive=True)
    system = lc.System([x], T=m * x.diff(t) ** 2 / 2, V=m * g * x, events=[lc.Contact("floor", x - H, restitution=e)],
                       name="units_ball", defaults={"m": 2.0, "g": 9.81, "e": 0.5, "H": 0.0})
    return lc.compile(system, cache_dir=cache_dir)


@pytest.fixture(scope="module")
def incline(cache_dir):
    x, y = lc.coordinates("x y")
    m, g, e, H, s = sp.symbols("m g e H s", positive=True)
    system = lc.System([x, y], T=m * (x.diff(t) ** 2 + y.diff(t) ** 2) / 2, V=m * g * y,
                       events=[lc.Contact("incline", y - s * x - H, restitution=e)],
                       name="units_incline", defaults={"m": 1.0, "g": 9.81, "e": 0.5, "H": 0.0, "s": 0.25})
    return lc.compile(system, cache_dir=cache_dir)


def rest_time_bound(e, g, height_scale, t_infinity):
    """How far the time of rest may be from t∞, from the closing rule (`lagcomp.kernel_support.resting`): the
    bounces it leaves out, in all 1/(1 − e) times the first left out, which lasts less than the largest of
    BOUNCE_TIME t (time's rounding), the bounce rising BOUNCE_HEIGHT ε × (the gap's scale) (2 √(2 h/g)), and
    ZENO_TIME t (1 − e) (all left); plus the impacts' location, a few roundings of t."""
    bounce = max(BOUNCE_TIME * t_infinity, 2 * np.sqrt(2 * BOUNCE_HEIGHT * EPS * height_scale / g),
                 ZENO_TIME * t_infinity * (1 - e))
    return bounce / (1 - e) + 64 * EPS * t_infinity


@pytest.mark.parametrize("method", ["dop853", "dopri5"])
@pytest.mark.parametrize("H", [0.0, 1.0, 10.0, 1000.0, 1e6])
def test_a_ball_comes_to_rest_on_a_floor_at_any_height(ball, method, H):
    """Dropped from h0 above the floor, with restitution e: it falls for t1 = √(2 h0/g), then bounces of
    2 eᵏ v1/g (v1 = g t1) follow, a geometric series: at rest from t∞ = t1 (1 + e)/(1 − e).  Before the fix every
    H ≠ 0 stopped with EVENTS_ACCUMULATED ~1e-7 s before t∞."""
    e, g, h0 = 0.5, 9.81, 1.0
    t_infinity = np.sqrt(2 * h0 / g) * (1 + e) / (1 - e)
    sol = ball.simulate((0.0, 2 * t_infinity), [H + h0], [0.0], params={"e": e, "H": H}, method=method,
                        rtol=1e-12, atol=1e-12 * max(1.0, H), progress=False, throw=False)
    assert sol.status == Status.DONE, sol.message
    assert [(s.contact, s.closed) for s in sol.contact_switches] == [("floor", True)]
    assert abs(sol.contact_switches[0].t - t_infinity) <= rest_time_bound(e, g, H + h0, t_infinity)
    rest = sol.t > sol.contact_switches[0].t
    assert np.all(np.abs(sol.q[rest, 0] - H) <= 4 * EPS * max(H, h0)) and not sol.qd[rest].any()


@pytest.mark.parametrize("height", [0.0, 1000.0])
def test_a_ball_bouncing_on_an_incline_in_cartesian_coordinates_comes_to_rest_on_it(incline, height):
    """The gap g = y − s x − H of a frictionless incline: in free flight g̈ = −g whatever the tangential motion, and
    an impact reverses ġ times e, so g bounces as the ball on a floor does: ġ = 0 from t∞ = √(2 g0/g) (1 + e)/(1 − e)
    (dropped from rest at gap g0), after which the ball slides along the incline.  Far from the origin (x = 1000)
    its gap rounds at ε (s |x| + |y|)."""
    e, g, g0, s = 0.5, 9.81, 1.0, 0.25
    x0 = 1000.0
    y0 = s * x0 + height + g0
    t_infinity = np.sqrt(2 * g0 / g) * (1 + e) / (1 - e)
    sol = incline.simulate((0.0, 1.5 * t_infinity), [x0, y0], [0.0, 0.0], params={"e": e, "H": height, "s": s},
                           rtol=1e-12, atol=1e-9, progress=False, throw=False)
    assert sol.status == Status.DONE, sol.message
    assert [(c.contact, c.closed) for c in sol.contact_switches] == [("incline", True)]
    assert abs(sol.contact_switches[0].t - t_infinity) <= rest_time_bound(e, g, s * x0 + y0, t_infinity)


@settings(max_examples=6, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(length=unit_factors, mass=unit_factors, time=unit_factors, height=st.floats(-3.0, 3.0))
def test_the_bounces_and_the_rest_are_the_same_in_any_units(ball, length, mass, time, height):
    """The floor at H = 10^height, the ball dropped from 1 above it, in units (L, M, T): the impacts' times over T
    and the time of rest are those of the run in the base units, to their rounding and the closing rule's bound."""
    e, g, h0 = 0.5, 9.81, 1.0
    H = 10.0 ** height
    t_infinity = np.sqrt(2 * h0 / g) * (1 + e) / (1 - e)

    def run(L, M, T):
        sol = ball.simulate((0.0, 2 * t_infinity * T), [(H + h0) * L], [0.0],
                            params={"e": e, "H": H * L, "m": 2.0 * M, "g": g * L / T**2}, rtol=1e-12,
                            atol=1e-12 * (H + h0) * L, progress=False, throw=False)
        return sol, sol.events["floor"].t / T

    base, base_impacts = run(1.0, 1.0, 1.0)
    sol, impacts = run(length, mass, time)
    assert sol.status == base.status == Status.DONE, sol.message
    bound = rest_time_bound(e, g, H + h0, t_infinity)
    assert abs(sol.contact_switches[0].t / time - t_infinity) <= bound
    first = min(len(impacts), len(base_impacts)) - 2          # (the last bounces kept depend on the rounding)
    np.testing.assert_allclose(impacts[:first], base_impacts[:first], rtol=0, atol=1e-9 * t_infinity)
    np.testing.assert_allclose(sol.contact_forces[-1, 0], 2.0 * mass * g * length / time**2, rtol=1e-12)


@pytest.mark.parametrize("method", ["dop853", "taylor"])
@pytest.mark.parametrize("units", [(1.0, 1.0, 1e-3), (1e3, 1.0, 1e-3), (1e-3, 1e3, 1e-3), (1.0, 1.0, 1e3)])
def test_a_ball_comes_to_rest_on_a_floor_at_zero_in_any_units(ball, method, units):
    """The floor at H = 0, where the gap's rounding vanishes with the height and only the closing rule's times
    (relative to |t|) end the bounces: the time of rest t∞ in any units.  Before the fix, in units of time ×1e-3
    every run stopped with EVENTS_ACCUMULATED after 31–33 impacts: the impacts were located to 2 ε |t| + 2 ε in
    time, an absolute 4.4e-16 that in milliseconds is 1600 times coarser than 2 ε |t| at t∞ = 0.6 ms."""
    length, mass, time = units
    e, g, h0 = 0.5, 9.81, 0.2
    t_infinity = np.sqrt(2 * h0 / g) * (1 + e) / (1 - e)
    sol = ball.simulate((0.0, 3 * t_infinity * time), [h0 * length], [0.0], method=method,
                        params={"e": e, "H": 0.0, "m": 2.0 * mass, "g": g * length / time**2}, rtol=1e-12,
                        atol=1e-12 * h0 * length, progress=False, throw=False)
    assert sol.status == Status.DONE, sol.message
    assert abs(sol.contact_switches[0].t / time - t_infinity) <= rest_time_bound(e, g, 0.0, t_infinity)


# --- user events: located at the same times, with the same resets, in any units ------------------------------------

@pytest.fixture(scope="module")
def watched(cache_dir):
    """A pendulum with four events of each kind: a reset at the bottom (θ̇ → r θ̇ when θ passes 0 downwards, r
    dimensionless), a height l (1 − cos θ) − h crossed upwards (a length), the turning points θ̇ = 0 (a rate:
    its zeros are the same in any units), and a terminal one at t = τ (a time)."""
    theta, = lc.coordinates("theta")
    m, l, g, r, h, tau = sp.symbols("m l g r h tau", positive=True)
    events = [lc.Event("bottom", theta, direction=-1, reset={theta.diff(t): r * theta.diff(t)}),
              lc.Event("height", l * (1 - sp.cos(theta)) - h, direction=1),
              lc.Event("turn", theta.diff(t)),
              lc.Event("late", t - tau, direction=1, terminal=True)]
    system = lc.System([theta], T=m * l**2 * theta.diff(t) ** 2 / 2, V=-m * g * l * sp.cos(theta), events=events,
                       name="units_watched", defaults={"m": 1.0, "l": 1.0, "g": 9.81, "r": 0.9, "h": 0.2, "tau": 4.5})
    return lc.compile(system, cache_dir=cache_dir)


@pytest.mark.parametrize("method", ["dop853", "dopri5", "taylor"])
@settings(max_examples=4, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(length=unit_factors, mass=unit_factors, time=unit_factors)
def test_user_events_are_the_same_in_any_units(watched, method, length, mass, time):
    """Each event's times over T, the states at them mapped back, and the terminal stop, as in the base units, to
    the tolerance (a few hundred rtol of the motion's period)."""

    def run(L, M, T):
        params = {"m": M, "l": L, "g": 9.81 * L / T**2, "r": 0.9, "h": 0.2 * L, "tau": 4.5 * T}
        sol = watched.simulate((0.0, 10.0 * T), [1.0], [0.0], params=params, method=method, rtol=RTOL,
                               atol=1e-3 * RTOL, progress=False, throw=False)
        return sol, {name: (sol.events[name].t / T, sol.events[name].qd[:, 0] * T if len(sol.events[name].t) else
                            np.zeros(0)) for name in ("bottom", "height", "turn", "late")}

    base, base_events = run(1.0, 1.0, 1.0)
    sol, events = run(length, mass, time)
    assert sol.status == base.status and sol.t[-1] / time == pytest.approx(4.5, rel=4 * EPS)
    for name, (times, rates) in base_events.items():
        assert len(times) == len(events[name][0]) > 0, name
        np.testing.assert_allclose(events[name][0], times, rtol=0, atol=300 * RTOL * 4.5, err_msg=name)
        np.testing.assert_allclose(events[name][1], rates, rtol=0, atol=300 * RTOL * 5.0, err_msg=name)


# --- linearization: eigenvalues in 1/time ------------------------------------------------------------------------------

@pytest.mark.parametrize(("name", "changed"), [("double_pendulum", {}), ("stiff_spring_pendulum", {}),
                                               ("stiff_spring_pendulum", {"c": 1e-3})])
@settings(max_examples=5, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(length=unit_factors, mass=unit_factors, time=unit_factors)
def test_normal_modes_scale_with_one_over_time(compiled, name, changed, length, mass, time):
    """At the hanging equilibrium (the spring stretched by m g/k): the eigenvalues in units (L, M, T) are those of
    the base units over T, and the verdict (stable / asymptotically stable) the same.  To √ε of the largest: the
    spring pendulum's damper is critical (c = 2 √(m k)), a double eigenvalue, which rounding splits by ~√ε.
    With a light damper (c = 1e-3, Re λ = −c/(2m)) the verdict used to depend on the units: the damping matrix
    was judged against max(|K|, |M|), whose entries are in different units (in milliseconds it was "stable")."""
    model = compiled(name)
    coordinates, dimensions, *_ = EXAMPLES[name]
    units = (length, mass, time)

    def modes(u):
        params = {k: v * factor(u, dimensions[k]) for k, v in {**model.defaults, **changed}.items()}
        if name == "stiff_spring_pendulum":
            q = [params["l0"] + params["m"] * params["g"] / params["k"], 0.0]
        else:
            q = [0.0] * len(coordinates)
        return normal_modes(model, q, params)

    base, scaled = modes((1.0, 1.0, 1.0)), modes(units)
    assert scaled.stability == base.stability
    def by_frequency(values):
        return np.array(sorted(values, key=lambda z: (z.imag, z.real)))

    np.testing.assert_allclose(by_frequency(scaled.eigenvalues * time), by_frequency(base.eigenvalues),
                               rtol=0, atol=4 * np.sqrt(EPS) * np.max(np.abs(base.eigenvalues)))


# --- friction pressed by a contact, in any units ---------------------------------------------------------------------

@pytest.fixture(scope="module")
def skidding(cache_dir):
    x, y = lc.coordinates("x y")
    m, g, e, H, mu_s, mu_k = sp.symbols("m g e H mu_s mu_k", positive=True)
    system = lc.System([x, y], T=m * (x.diff(t) ** 2 + y.diff(t) ** 2) / 2, V=m * g * y,
                       events=[lc.Contact("floor", y - H, restitution=e),
                               lc.Friction("ground", x.diff(t), normal="floor", static=mu_s, kinetic=mu_k)],
                       name="units_skidding", defaults={"m": 2.0, "g": 9.81, "e": 0.5, "H": 0.0, "mu_s": 0.5,
                                                        "mu_k": 0.3})
    return lc.compile(system, cache_dir=cache_dir)


def skid_closed_form(v0, h, e, g, mu_k):
    """A block dropped from h above the floor moving at v0 along it: it falls for t1 = v1/g (v1 = √(2 g h)); impact
    k ≥ 1 (normal speed v1 e^(k−1)) takes μk (1 + e) v1 e^(k−1) off the tangential speed (sliding: the impulse
    at the friction limit) and a flight of 2 v1 eᵏ/g follows; it lands for good at t∞ = t1 (1 + e)/(1 − e) at
    v_c = v0 − μk v1 (1 + e)/(1 − e), and slides to rest v_c/(μk g) later, v_c²/(2 μk g) further.  Returns (the time
    it stops, the distance it has gone)."""
    v1 = np.sqrt(2 * g * h)
    t1 = v1 / g
    k = np.arange(1, 80)
    speeds = v0 - mu_k * (1 + e) * v1 * (1 - e**k) / (1 - e)        # after impact k
    distance = v0 * t1 + np.sum(speeds * 2 * v1 * e**k / g)
    t_landed = t1 * (1 + e) / (1 - e)
    v_c = v0 - mu_k * v1 * (1 + e) / (1 - e)
    return t_landed + v_c / (mu_k * g), distance + v_c**2 / (2 * mu_k * g), t_landed


@settings(max_examples=5, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(length=unit_factors, mass=unit_factors, time=unit_factors, height=st.floats(-3.0, 3.0))
def test_a_skidding_block_stops_at_the_same_place_in_any_units(skidding, length, mass, time, height):
    """Friction pressed by a bouncing contact (a floor at H = 10^height): the block stops where and when the closed
    form says, in units (L, M, T) as in the base units; the statuses equal."""
    e, g, h0, v0, mu_k = 0.5, 9.81, 0.2, 5.0, 0.3
    H = 10.0 ** height
    t_stop, distance, t_landed = skid_closed_form(v0, h0, e, g, mu_k)

    def run(L, M, T):
        sol = skidding.simulate((0.0, 1.2 * t_stop * T), [0.0, (H + h0) * L], [v0 * L / T, 0.0],
                                params={"e": e, "H": H * L, "m": 2.0 * M, "g": g * L / T**2}, rtol=1e-12,
                                atol=1e-12 * (H + h0) * L, progress=False, throw=False)
        return sol, sol.q[-1, 0] / L, sol.qd[-1, 0] * T / L

    base, base_x, base_v = run(1.0, 1.0, 1.0)
    sol, x, v = run(length, mass, time)
    assert sol.status == base.status == Status.DONE, sol.message
    assert abs(v) <= 64 * EPS * v0 and abs(base_v) <= 64 * EPS * v0       # (stuck: v at its zero, rounded)
    # the bounces left out when the floor closes (rest_time_bound) change the landing speed by μk g per time left
    # out, the distance by v_c times that
    slack = rest_time_bound(e, g, H + h0, t_landed) * (v0 + mu_k * g * t_stop)
    assert abs(x - distance) <= slack + 1e-9 * distance
    assert abs(base_x - distance) <= slack + 1e-9 * distance
    assert abs(x - base_x) <= 2 * slack + 1e-9 * distance


# --- Lyapunov exponents: in 1/time, the shadow's distance in each component's units ---------------------------------

@pytest.mark.parametrize("units", [(1e-3, 1e-6, 1.0), (1e3, 1e3, 1e-3), (1.0, 1.0, 1e3), (2.0, 0.5, 0.25)])
def test_a_two_trajectory_lyapunov_exponent_scales_with_one_over_time(compiled, units):
    """The double pendulum from (2, 1) at rest, over 20 of its time units (before rounding differences grow past
    1e-5 on this chaotic orbit): the exponent times T is the base units' to 1e-4, with the shadow's distance d0 = 1e-8
    relative to each component of x = (q, p) (`scale`: 1 for the angles, M L²/T for the momenta).  With the default
    scale (d0 absolute, 1e-8 in every unit) momenta of 1e-12 ended in NaN and time × 1e3 gave 1.57 for 1.41."""
    model = compiled("double_pendulum")
    _, dimensions, *_ = EXAMPLES["double_pendulum"]

    def exponent(units):
        params = {k: v * factor(units, dimensions[k]) for k, v in model.defaults.items()}
        momentum = units[1] * units[0] ** 2 / units[2]
        scale = np.array([1.0, 1.0, momentum, momentum])
        return units[2] * two_trajectory_lyapunov(model, (0.0, 20.0 * units[2]), [2.0, 1.0], [0.0, 0.0],
                                                  params=params, dt=0.01 * units[2], scale=scale,
                                                  progress=False).exponents[0]

    base = exponent((1.0, 1.0, 1.0))
    assert exponent(units) == pytest.approx(base, rel=1e-4)


# --- periodic orbits: the period in units of time, the multipliers unchanged ------------------------------------------

#: The orbit in the base units (periodic_orbit's result, not modified by the tests), shared by the examples.
_BASE_ORBIT: dict = {}


@settings(max_examples=3, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(length=unit_factors, mass=unit_factors, time=unit_factors)
@example(length=1.0, mass=1.0, time=100.0)      # (no convergence before the residual was scaled)
@example(length=1.0, mass=1.0, time=1000.0)     # (another period)
def test_a_periodic_orbit_is_the_same_in_any_units(compiled, length, mass, time):
    """The double pendulum's nonlinear in-phase normal mode at amplitude 0.3 (angles: only the rates and the period
    carry units): period/T, the state mapped back and the Floquet multipliers (dimensionless) agree with the base
    units' to the orbit's accuracy (its residual 1e-10 in the state's units: 1e-10 T in the rates mapped back)."""
    model = compiled("double_pendulum")
    _, dimensions, *_ = EXAMPLES["double_pendulum"]

    def orbit(units):
        params = {k: v * factor(units, dimensions[k]) for k, v in model.defaults.items()}
        modes = normal_modes(model, [0.0, 0.0], params)
        shape = modes.shapes[:, 0] / modes.shapes[0, 0]
        guess = np.concatenate([0.3 * shape, [0.0, 0.0]])
        # atol per component in its units: the angles', and their rates' (per unit of time)
        return periodic_orbit(model, guess, 2 * np.pi / modes.frequencies[0], params=params,
                              atol=state_atol(np.ones(2), units[2], 1e-12))

    if "base" not in _BASE_ORBIT:      # the same for every example: computed by the first
        _BASE_ORBIT["base"] = orbit((1.0, 1.0, 1.0))
    base, scaled = _BASE_ORBIT["base"], orbit((length, mass, time))
    assert scaled.stable == base.stable
    assert scaled.period / time == pytest.approx(base.period, rel=1e-9)
    back = np.concatenate([scaled.y0[:2], scaled.y0[2:] * time])
    np.testing.assert_allclose(back, base.y0, rtol=0, atol=1e-9 * max(1.0, time))
    np.testing.assert_allclose(np.sort_complex(scaled.multipliers), np.sort_complex(base.multipliers), rtol=0,
                               atol=1e-6)


# --- equilibria: "F = 0" judged in the problem's own scale -------------------------------------------------------------

def spring_pendulum_params(model, units, changed=None):
    _, dimensions, *_ = EXAMPLES["stiff_spring_pendulum"]
    return {k: v * factor(units, dimensions[k]) for k, v in {**model.defaults, **(changed or {})}.items()}


@pytest.mark.parametrize("offset", [1e-8, 1e-11])
@pytest.mark.parametrize("units", [(1e-3, 1.0, 1.0), (1e3, 1.0, 1.0), (1e-3, 1e3, 1e-3), (1e3, 1e-3, 1e3)])
def test_a_point_off_equilibrium_is_refused_or_accepted_alike_in_any_units(compiled, units, offset):
    """The spring stretched to r* (1 + δ) instead of the hanging equilibrium r* = l0 + m g/k: a force k r* δ that
    does not vanish, relative δ to the force the spring carries (k r*).  δ = 1e-8 is no equilibrium and δ = 1e-11 is
    one (below `RESIDUAL_TOLERANCE` = 1e-10), in any units: normal_modes refuses the first and takes the second.
    Before the fix the force scale was max |K| max(1, |q|),
    a metre where lengths are below one, so in millimetres (×1e-3) δ = 1e-8 passed."""
    model = compiled("stiff_spring_pendulum")

    def verdict(u):
        params = spring_pendulum_params(model, u)
        q = [(params["l0"] + params["m"] * params["g"] / params["k"]) * (1 + offset), 0.0]
        try:
            normal_modes(model, q, params)
        except LinearizationError:
            return False
        return True

    assert offset > RESIDUAL_TOLERANCE or offset < RESIDUAL_TOLERANCE / 4
    assert verdict((1.0, 1.0, 1.0)) == (offset < RESIDUAL_TOLERANCE)
    assert verdict(units) == (offset < RESIDUAL_TOLERANCE)


@pytest.mark.parametrize("offset", [1e-6, 1e-10])
@pytest.mark.parametrize("length", [1e-3, 1e3])
def test_a_point_off_the_constraints_is_refused_or_accepted_alike_in_any_units(compiled, length, offset):
    """The Cartesian spherical pendulum hanging at z = −l (1 + δ): the rod's constraint x² + y² + z² − l² is off by
    2 δ l², relative 2 δ to the terms it balances (Σ_j |∂Φ/∂q_j| |q_j| = 2 l²).  δ = 1e-6 is off the constraint
    manifold (above `CONSISTENT` = 1e-8) and δ = 1e-10 on it, for a rod of any length: linearize_steady refuses
    the first and takes the second.  Before the fix the scale was max(1, max|Φ_q| max|q|), one square metre for a
    rod in millimetres, where δ = 1e-6 passed."""
    from lagcomp.analysis import linearize_steady
    from lagcomp.analysis._steady_setup import CONSISTENT
    from lagcomp.errors import InitialConditionError

    model = compiled("spherical_pendulum_cartesian")

    def verdict(scale):
        params = {**model.defaults, "l": model.defaults["l"] * scale, "g": model.defaults["g"] * scale}
        try:
            linearize_steady(model, [0.0, 0.0, -params["l"] * (1 + offset)], params=params)
        except InitialConditionError:
            return False
        return True

    assert offset > CONSISTENT or offset < CONSISTENT / 4
    assert verdict(1.0) == verdict(length) == (offset < CONSISTENT)


@pytest.fixture(scope="module")
def preloaded(cache_dir):
    """A mass hanging on a spring, x measured from the spring's end at rest: F = −k x + k δ − m g, δ = m g/k a
    parameter, so that x = 0 balances the weight with the spring's pre-load k δ, terms that do not grow with x."""
    x, = lc.coordinates("x")
    m, g, k, delta = sp.symbols("m g k delta", positive=True)
    system = lc.System([x], T=m * x.diff(t) ** 2 / 2, V=k * (x - delta) ** 2 / 2 + m * g * x, name="units_preloaded",
                       defaults={"m": 0.3, "g": 9.81, "k": 7.0, "delta": 0.3 * 9.81 / 7.0})
    return lc.compile(system, cache_dir=cache_dir)


@settings(max_examples=6, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(length=unit_factors, mass=unit_factors, time=unit_factors)
def test_a_preloaded_spring_balances_at_zero_in_any_units(preloaded, length, mass, time):
    """With δ = (m g/k)(1 + 1e-13) the force at x = 0 is k δ − m g = 1e-13 m g, zero to 1e-13 of the terms it
    balances: an equilibrium to `RESIDUAL_TOLERANCE`, whose scale is the parameters' terms (the stiffness term
    k |x| is 0 there; without them it was refused); ω² = k/m in 1/time²."""
    from lagcomp.analysis import find_equilibrium

    units = (length, mass, time)
    stiffness = 7.0 * factor(units, (0, 1, -2))
    params = {"m": 0.3 * mass, "g": 9.81 * factor(units, ACCELERATION), "k": stiffness}
    params["delta"] = params["m"] * params["g"] / stiffness * (1 + 1e-13)
    assert preloaded.rhs(0.0, [0.0, 0.0], params)[1] != 0.0
    modes = normal_modes(preloaded, [0.0], params)
    assert modes.frequencies[0] * time == pytest.approx(np.sqrt(7.0 / 0.3), rel=1e-12)
    assert find_equilibrium(preloaded, [0.1 * length], params).success


@pytest.mark.parametrize("scale", [1.0, 1e-3, 1e3])
def test_a_portrait_refuses_an_unsteady_energy_in_any_units(compiled, scale):
    """The bead on a hoop wobbling by ε = 1e-7 (φ̇ = Ω + 2 ε cos 2t): its energy function varies in time by ~4 ε/Ω
    of itself, no energy integral, whatever the units of mass and length (both × scale, energies × scale³; the
    wobble's 2 rad/s is written into the model, so time is not rescaled).  Before the fix the spread was compared
    with 1e-12 max(1, |E|), an absolute unit of energy, and in small units (E ~ 1e-9) the portrait was drawn."""
    from lagcomp.analysis import phase_portrait
    from lagcomp.errors import ModelError

    model = compiled("hoop_bead")
    params = {**model.defaults, "epsilon": 1e-7, **{k: model.defaults[k] * scale for k in ("m", "R", "g")}}
    energy = model.defaults["m"] * model.defaults["g"] * model.defaults["R"] * scale**3
    with pytest.raises(ModelError, match="depends on t"):
        phase_portrait(model, [0.5 * energy], (-np.pi, np.pi), params, periodic=True)


# --- fitting: the same estimate in any units ----------------------------------------------------------------------

@pytest.fixture(scope="module")
def spring(cache_dir):
    x, = lc.coordinates("x")
    m, k = sp.symbols("m k", positive=True)
    return lc.compile(lc.System([x], T=m * x.diff(t) ** 2 / 2, V=k * x**2 / 2, name="units_spring",
                                defaults={"m": 1.5, "k": 6.0}), cache_dir=cache_dir)


@pytest.mark.parametrize("units", [(1.0, 1.0, 1.0), (1e-3, 1.0, 1.0), (1e-3, 1e-3, 1e3), (1e3, 1e3, 1e-3)])
def test_a_fit_is_as_accurate_in_any_units(spring, units):
    """x(t) = A cos(√(k/m) t), sampled exactly, fitted for k from 0.9 k: the estimate is k to 1e-8 at the default
    rtol (1e-10) in any units.  Before the fix atol defaulted to rtol in the state's units: in millimetres the
    runs were 1e-7 accurate, and k came out ~1e-7 off."""
    length, mass, time = units
    k, m, amplitude = 6.0 * mass / time**2, 1.5 * mass, 0.8 * length
    times = np.linspace(0.1, 3.0, 30) * time
    observed = amplitude * np.cos(np.sqrt(k / m) * times)
    result = spring.fit(times, observed, {"k": 0.9 * k}, q0=[amplitude], qd0=[0.0], fixed={"m": m})
    assert result.success
    assert result.estimates["k"] == pytest.approx(k, rel=1e-8, abs=0)
