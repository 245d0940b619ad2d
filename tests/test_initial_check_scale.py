"""The check of a constrained start is unit-free: |Φ_i| against the rounding scale A(Φ_i) of its terms.

A start is refused (`InitialConditionError`, docs/errors.md ``inconsistent-initial-conditions``) when some
residual row exceeds `lagcomp.integrate.constraints.INITIAL_TOLERANCE` times the size of the terms it sums
(`lagcomp.codegen.rounding_scale`), at position and at velocity level.  Before, the bound was 1e-9 in Φ's units:
a rod of 1 nm started 0.1 % off its circle ran (|Φ| ~ 1e-22), and the rounding of an exact start of a rod of
1000 km (|Φ| ~ ε L² ~ 1e-4) was refused.  Here the same models are scaled over fifteen decades: a rounded exact
start is accepted at every scale, a start 1e-3 off (relatively) refused at every scale.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import sympy as sp
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import lagcomp as lc
from lagcomp.codegen.rounding_scale import program_scales, rounding_scale
from lagcomp.examples.constrained import four_bar_closure, four_bar_linkage
from lagcomp.model import t
from lagcomp.multibody.program import Program

x, y = lc.coordinates("x y")
m, g, L = sp.symbols("m g L", positive=True)

#: The scales of the property tests: log10 of the rod's length (and of the four-bar's links).
DECADES = st.floats(min_value=-9.0, max_value=6.0, allow_nan=False)
ANGLES = st.floats(min_value=-3.1, max_value=3.1, allow_nan=False)
SETTINGS = settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])


@pytest.fixture(scope="module")
def rod(cache_dir):
    """A particle on a massless rod of length L about the origin, in gravity: x² + y² − L² = 0."""
    system = lc.System(coordinates=[x, y], T=m * (x.diff(t) ** 2 + y.diff(t) ** 2) / 2, V=m * g * y,
                       constraints=[lc.Holonomic("rod", x**2 + y**2 - L**2)], name="initcheck_rod",
                       defaults={"m": 1.0, "g": 9.81, "L": 1.0})
    return lc.compile(system, cache_dir=cache_dir)


def _start(length: float, angle: float, rate: float, off: float = 0.0, slip: float = 0.0):
    """q0, qd0 of the rod at `angle` from the downward vertical turning at `rate` (rad/s): positions scaled by
    1 + `off` (off the circle), the velocity given a radial part `slip` times its size (off the tangent)."""
    q0 = [length * math.sin(angle) * (1 + off), -length * math.cos(angle) * (1 + off)]
    speed = length * rate
    qd0 = [speed * (math.cos(angle) + slip * math.sin(angle)), speed * (math.sin(angle) - slip * math.cos(angle))]
    return q0, qd0


def _params(length: float) -> dict:
    return {"L": length, "m": 1.0, "g": 9.81}


def test_the_reported_nanometre_rod_started_off_its_circle_is_refused(rod):
    q0 = [1e-9 * math.sin(0.3) * (1 + 1e-3), -1e-9 * math.cos(0.3)]
    with pytest.raises(lc.InitialConditionError, match="constraint `rod` at position level"):
        rod.simulate((0, 1e-3), q0=q0, qd0=[0, 0], params=_params(1e-9))


def test_an_exact_start_of_a_thousand_kilometre_rod_is_accepted(rod):
    q0, qd0 = _start(1e6, 0.3, 0.0)
    assert rod.simulate((0, 1e-3), q0=q0, qd0=qd0, params=_params(1e6)).success


@SETTINGS
@given(decade=DECADES, angle=ANGLES, rate=st.floats(min_value=-5.0, max_value=5.0))
def test_a_rounded_exact_start_is_accepted_at_every_scale(rod, decade, angle, rate):
    length = 10.0**decade
    q0, qd0 = _start(length, angle, rate)
    sol = rod.simulate((0, 1e-6), q0=q0, qd0=qd0, params=_params(length))
    assert sol.success and sol.projected_initial_state is None


@SETTINGS
@given(decade=DECADES, angle=ANGLES, rate=st.floats(min_value=0.1, max_value=5.0), sign=st.sampled_from((-1, 1)))
def test_a_start_a_thousandth_off_is_refused_at_every_scale(rod, decade, angle, rate, sign):
    length = 10.0**decade
    q0, qd0 = _start(length, angle, rate, off=sign * 1e-3)
    with pytest.raises(lc.InitialConditionError, match="constraint `rod` at position level"):
        rod.simulate((0, 1e-6), q0=q0, qd0=qd0, params=_params(length))
    q0, qd0 = _start(length, angle, rate, slip=sign * 1e-3)
    with pytest.raises(lc.InitialConditionError, match="constraint `rod` at velocity level"):
        rod.simulate((0, 1e-6), q0=q0, qd0=qd0, params=_params(length))
    sol = rod.simulate((0, 1e-6), q0=q0, qd0=qd0, params=_params(length), project_initial=True)
    assert sol.success and sol.projected_initial_state is not None


@pytest.fixture(scope="module")
def four_bar(compiled):
    return compiled("four_bar_linkage")


@pytest.mark.parametrize("theta1", [0.0, math.pi])
@pytest.mark.parametrize("scale", [1e-9, 1.0, 1e6])
def test_a_four_bar_at_crank_angle_zero_and_pi_is_accepted_exact_and_refused_off(four_bar, theta1, scale):
    """Lengths scaled together (masses kept): the angles do not change, Φ scales with the lengths.  At θ1 = 0
    and π the crank's terms a sin θ1 vanish (or round to a sin π ~ 1e-17 a): the scale is that of the
    terms the other links add, and of cos θ1's slope carrying θ1's rounding."""
    defaults = four_bar_linkage().defaults
    params = {**defaults, **{k: scale * defaults[k] for k in "abcd"}}
    q0, qd0 = four_bar_closure(params, theta1, 10.0)
    assert four_bar.simulate((0, 1e-9), q0=list(q0), qd0=list(qd0), params=params).success
    off = [q0[0], q0[1] * (1 + 1e-3), q0[2]]   # at rest: Λ q̇ = 0 exactly, only the position is off
    with pytest.raises(lc.InitialConditionError, match="at position level"):
        four_bar.simulate((0, 1e-9), q0=off, qd0=[0.0, 0.0, 0.0], params=params)
    slipping = [qd0[0], qd0[1] * (1 + 1e-3), qd0[2]]
    with pytest.raises(lc.InitialConditionError, match="at velocity level"):
        four_bar.simulate((0, 1e-9), q0=list(q0), qd0=slipping, params=params)


def test_rounding_scale_takes_terms_and_factors_in_absolute_value():
    a, b, th = sp.symbols("a b theta", real=True)
    assert rounding_scale(a**2 + b**2 - L**2) == a**2 + b**2 + L**2
    assert rounding_scale(-3 * a * b) == 3 * sp.Abs(a) * sp.Abs(b)
    # a function: its value, and its argument's scale through its slope
    assert rounding_scale(a * sp.sin(th)) == sp.Abs(a) * (sp.Abs(sp.sin(th)) + sp.Abs(sp.cos(th)) * sp.Abs(th))
    assert rounding_scale(1 / a) == 1 / sp.Abs(a) + sp.Abs(a) / a**2
    # the four-bar's loop_y at θ = π: a sin π rounds to 1.2e-16 a, but sin's argument π rounds too
    value = float(rounding_scale(a * sp.sin(th)).subs({a: 1.0, th: math.pi}))
    assert value == pytest.approx(math.pi, rel=1e-15)


def test_a_moving_constraints_scale_grows_with_the_rounding_of_its_time_argument():
    """x − a sin(ω t): sin's argument ω t rounds by ε |ω| |t|, which its slope carries into the row."""
    a, w = sp.symbols("a omega", positive=True)
    xs = sp.Symbol("x", real=True)
    expected = sp.Abs(xs) + a * (sp.Abs(sp.sin(w * t)) + sp.Abs(sp.cos(w * t)) * w * sp.Abs(t))
    assert sp.simplify(rounding_scale(xs - a * sp.sin(w * t)) - expected) == 0


def test_a_programs_scale_follows_its_assignments():
    """s = a − b, then s·s + c: A = (|a| + |b|)² + |c|, not |s|² + |c| (the cancellation in s rounds)."""
    a, b, c = sp.symbols("a b c", real=True)
    prog = Program()
    s = prog.let(a - b)
    (scale,) = program_scales(prog, [s * s + c])
    values = {a: 3.0, b: 2.0, c: -1.0}
    for local, expr in reversed(prog.assignments):   # (later locals read earlier ones)
        scale = scale.subs(local, expr)
    assert float(scale.subs(values)) == 26.0


@pytest.fixture(scope="module")
def four_bar_as_tree(cache_dir):
    from test_multibody_loops import four_bar_tree

    return lc.compile(four_bar_tree(), cache_dir=cache_dir)


@pytest.mark.parametrize("theta1", [0.0, math.pi])
@pytest.mark.parametrize("scale", [1e-9, 1.0, 1e6])
def test_a_tree_with_a_loop_is_checked_over_its_program_at_every_scale(four_bar_as_tree, theta1, scale):
    """The four-bar as a tree with a cut joint (tests/test_multibody_loops.py): its closure is a program of the
    forward kinematics, whose running bound is the scale."""
    from test_multibody_loops import TO_TREE

    defaults = four_bar_linkage().defaults
    params = {**defaults, **{k: scale * defaults[k] for k in "abcd"}}
    q0, qd0 = (TO_TREE @ np.array(v) for v in four_bar_closure(params, theta1, 10.0))
    assert four_bar_as_tree.simulate((0, 1e-9), q0=q0, qd0=qd0, params=params).success
    with pytest.raises(lc.InitialConditionError, match="at position level"):
        four_bar_as_tree.simulate((0, 1e-9), q0=q0 + [0.0, 1e-3, 0.0], qd0=[0.0, 0.0, 0.0], params=params)
    with pytest.raises(lc.InitialConditionError, match="at velocity level"):
        four_bar_as_tree.simulate((0, 1e-9), q0=q0, qd0=qd0 * [1.0, 1.0 + 1e-3, 1.0], params=params)


def kane_rod():
    """The rod as a KanesMethod: x independent, y dependent through x² + y² − L² = 0, u_y through x u_x + y u_y = 0."""
    import sympy.physics.mechanics as me

    qx, qy = me.dynamicsymbols("qx qy")
    ux, uy = me.dynamicsymbols("ux uy")
    N = me.ReferenceFrame("N")
    O = me.Point("O")
    O.set_vel(N, 0)
    P = O.locatenew("P", qx * N.x + qy * N.y)
    P.set_vel(N, ux * N.x + uy * N.y)
    km = me.KanesMethod(N, q_ind=[qx], u_ind=[ux], kd_eqs=[qx.diff(t) - ux, qy.diff(t) - uy], q_dependent=[qy],
                        configuration_constraints=[qx**2 + qy**2 - L**2], u_dependent=[uy],
                        velocity_constraints=[qx * ux + qy * uy])
    km.kanes_equations([me.Particle("bob", P, m)], [(P, -m * g * N.y)])
    return km


@pytest.fixture(scope="module")
def kane_model(cache_dir):
    return lc.compile(kane_rod(), cache_dir=cache_dir, name="initcheck_kane_rod", defaults=_params(1.0))


@SETTINGS
@given(decade=DECADES, angle=st.floats(min_value=0.2, max_value=1.3), rate=st.floats(min_value=0.1, max_value=5.0))
def test_a_kane_models_start_is_checked_at_every_scale(kane_model, decade, angle, rate):
    length = 10.0**decade
    q0, qd0 = _start(length, angle, rate)
    assert kane_model.simulate((0, 1e-6), q0=q0, u0=qd0, params=_params(length)).success
    q0, _ = _start(length, angle, rate, off=1e-3)
    with pytest.raises(lc.InitialConditionError, match="configuration_0"):
        kane_model.simulate((0, 1e-6), q0=q0, u0=[0.0, 0.0], params=_params(length))
    q0, qd0 = _start(length, angle, rate, slip=1e-3)
    with pytest.raises(lc.InitialConditionError, match="velocity_0"):
        kane_model.simulate((0, 1e-6), q0=q0, u0=qd0, params=_params(length))


@pytest.mark.parametrize("length", [1e-12, 1e-9, 1.0, 1e6])
def test_projection_reaches_rounding_level_at_every_scale(rod, length):
    """`project` stops its Gauss-Newton corrections at a step of 4 ulps of the coordinates' size (relative, not
    4e-16 (1 + size), which at L = 1e-12 stopped after one correction of a start 1e-4 off: |r − L| ~ 5e-8 L); the
    projected start then passes the check it failed."""
    for off in (1e-3, 3e-4, 1e-4, 1e-5, 1e-6):
        q0 = [length * math.sin(0.3) * (1 + off), -length * math.cos(0.3) * (1 + off)]
        start = rod.simulate((0, 1e-9), q0=q0, qd0=[0, 0], params=_params(length),
                             project_initial=True).projected_initial_state
        assert abs(math.hypot(start[0], start[1]) - length) <= 4 * np.finfo(float).eps * length
        assert rod.simulate((0, 1e-9), q0=start[:2], qd0=start[2:], params=_params(length)).success


@pytest.mark.parametrize("length", [1e-12, 1e-9, 1.0, 1e6])
def test_rattle_holds_the_rod_to_rounding_level_at_every_scale(rod, length):
    """RATTLE's Newton iteration on Φ stops at 4 ulps of the coordinates' size (relative: `ROUNDING`); with
    4 ulps of 1 + size it left |r − L| ~ 5e-8 L at L = 1e-12.  Gravity scaled with L: the same swing, period 2.3 s."""
    q0 = [length * math.sin(1.0), -length * math.cos(1.0)]
    sol = rod.simulate((0, 20), q0=q0, qd0=[0, 0], params={**_params(length), "g": 9.81 * length}, method="rattle",
                       dt=1e-2)
    assert sol.success
    assert np.max(np.abs(np.hypot(sol.q[:, 0], sol.q[:, 1]) - length)) <= 4 * np.finfo(float).eps * length
