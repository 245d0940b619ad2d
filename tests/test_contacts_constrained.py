"""Contacts on a System with holonomic constraints (issue 39): impacts that keep the constraints' velocities, and
resting contact whose force joins the constraints' multipliers (`lagcomp.kernel_support.constrained_response`).

The reference is the same particle written twice: on a circle of radius L as (x, y) with the constraint
x² + y² − L² = 0 (a rod from the origin), and in the angle θ (x = L sin θ, y = −L cos θ), where contacts need no
constraint.  The contacts are the same functions of the position in both: a wall at x = −d (gap x + d) and an
inclined floor y = −h + s x (gap y + h − s x).  Derived closed forms:

* an impact conserves the constraint's velocity: after it x ẋ + y ẏ = 0 (Λ q̇⁺ = Λ q̇⁻ to rounding); with e = 1 the
  energy m (ẋ² + ẏ²)/2 + m g y is the same before and after;
* the same motion: the events at the same times, (x, y) = L (sin θ, −cos θ) and the same normal impulses (the
  same gap function: P is the impulse conjugate to g in both);
* at rest on the floor at (x0, y0) (circle ∩ line), with e = 0 (the first impact closes the contact): statics
  0 = (0, −m g) + N (−s, 1) + μ (2 x0, 2 y0) gives N = m g x0 / (x0 + s y0) and the rod's multiplier
  μ = s N / (2 x0) (`reactions`' convention M q̈ = F + Λᵀ μ).
"""

import numpy as np
import pytest
import sympy as sp
from hypothesis import example, given, settings
from hypothesis import strategies as st

import lagcomp as lc
from lagcomp.integrate.status import Status
from lagcomp.model.constraints import Holonomic

t = lc.t
G = 9.81
DEFAULTS = {"m": 1.3, "g": G, "L": 1.0, "d": 0.5, "h": 0.6, "s": 0.3, "ew": 1.0, "ef": 0.0}
FAR = 10.0          # a wall or floor put where the particle never goes


def _contacts(x, y, symbols):
    d, h, s, ew, ef = (symbols[k] for k in ("d", "h", "s", "ew", "ef"))
    return [lc.Contact("wall", x + d, restitution=ew), lc.Contact("floor", y + h - s * x, restitution=ef)]


@pytest.fixture(scope="module")
def models(tmp_path_factory):
    cache = tmp_path_factory.mktemp("cache")
    symbols = {name: sp.Symbol(name, positive=True) for name in DEFAULTS}
    m, g, L = symbols["m"], symbols["g"], symbols["L"]
    x, y = lc.coordinates("x y")
    cartesian = lc.System([x, y], T=m * (x.diff(t) ** 2 + y.diff(t) ** 2) / 2, V=m * g * y,
                          constraints=[Holonomic("rod", x**2 + y**2 - L**2)], events=_contacts(x, y, symbols),
                          name="rod_contacts", defaults=DEFAULTS)
    theta, = lc.coordinates("theta")
    angle = lc.System([theta], T=m * L**2 * theta.diff(t) ** 2 / 2, V=-m * g * L * sp.cos(theta),
                      events=_contacts(L * sp.sin(theta), -L * sp.cos(theta), symbols), name="angle_contacts",
                      defaults=DEFAULTS)
    return lc.compile(cartesian, cache_dir=cache), lc.compile(angle, cache_dir=cache)


def _both(models, theta0, span, params, rtol=1e-12, t_eval=None, accumulating=False):
    cartesian, angle = models
    L = DEFAULTS["L"]
    on_angle = angle.simulate(span, [theta0], [0.0], params, rtol=rtol, atol=rtol, t_eval=t_eval)
    on_rod = cartesian.simulate(span, [L * np.sin(theta0), -L * np.cos(theta0)], [0.0, 0.0], params, rtol=rtol,
                                atol=rtol, t_eval=t_eval, throw=not accumulating)
    allowed = (Status.DONE, Status.EVENTS_ACCUMULATED) if accumulating else (Status.DONE,)
    assert on_angle.status == Status.DONE and on_rod.status in allowed, (on_angle.message, on_rod.message)
    return on_rod, on_angle


def _position(theta):
    L = DEFAULTS["L"]
    return np.stack([L * np.sin(theta), -L * np.cos(theta)], axis=-1)


def _velocity(theta, theta_dot):
    L = DEFAULTS["L"]
    return np.stack([L * np.cos(theta) * theta_dot, L * np.sin(theta) * theta_dot], axis=-1)


def test_elastic_wall_impacts_keep_the_rod_and_the_energy_and_match_the_angle_model(models):
    grid = np.linspace(0.0, 3.0, 31)
    on_rod, on_angle = _both(models, 1.0, (0.0, 3.0), {"h": FAR}, t_eval=grid)
    hits, reference = on_rod.events["wall"], on_angle.events["wall"]
    assert len(hits) == len(reference) >= 2
    np.testing.assert_allclose(hits.t, reference.t, rtol=0, atol=1e-11)
    np.testing.assert_allclose(hits.q, _position(reference.q[:, 0]), rtol=0, atol=1e-11)
    np.testing.assert_allclose(hits.qd_after, _velocity(reference.q[:, 0], reference.qd_after[:, 0]), rtol=0,
                               atol=1e-10)
    # the impact keeps x ẋ + y ẏ (Λ q̇ / 2) to rounding: it changes by K Gᵀ P, and Λ K = 0
    before = np.einsum("ij,ij->i", hits.q, hits.qd)
    after = np.einsum("ij,ij->i", hits.q, hits.qd_after)
    scale = np.abs(hits.q).sum(axis=1) * np.abs(hits.qd_after).sum(axis=1)
    assert np.all(np.abs(after - before) <= 8 * np.finfo(float).eps * scale)
    # e = 1: the kinetic energy changes by ½ (q̇⁺ + q̇⁻)ᵀ (Gᵀ P + Λᵀ Λc) = ½ P (v⁺ + v⁻) + Λc Λ q̇⁻ = Λc Λ q̇⁻: by
    # the run's drift off the rod's velocity constraint alone (Λ q̇⁻ = 2 (x ẋ + y ẏ), ~1e-13 here), with Λc, the
    # rod's impulse, from the jump's y row: m Δẏ = 2 y Λc (the wall's gradient is (1, 0))
    m = DEFAULTS["m"]
    kinetic = lambda v: m * np.einsum("ij,ij->i", v, v) / 2
    rod_impulse = m * (hits.qd_after[:, 1] - hits.qd[:, 1]) / (2 * hits.q[:, 1])
    change = kinetic(hits.qd_after) - kinetic(hits.qd)
    assert np.all(np.abs(change - rod_impulse * 2 * before) <= 8 * np.finfo(float).eps * kinetic(hits.qd))
    # the normal impulse is the same physical one: P conjugate to the same gap in both models
    np.testing.assert_allclose(hits.impulses[:, 0], reference.impulses[:, 0], rtol=1e-10)
    assert not hits.impulses[:, 1].any()
    # between impacts the two runs are one motion
    rows, reference_rows = np.isin(on_rod.t, grid), np.isin(on_angle.t, grid)
    assert rows.sum() == reference_rows.sum() == grid.size
    np.testing.assert_allclose(on_rod.q[rows], _position(on_angle.q[reference_rows, 0]), rtol=0, atol=1e-10)


def _floor_contact_point(h, s, L):
    """(x0, y0) on the circle x² + y² = L² and the line y = −h + s x, the left one (x0 < 0)."""
    # x² + (s x − h)² = L²: (1 + s²) x² − 2 s h x + h² − L² = 0
    x0 = (s * h - np.sqrt((s * h) ** 2 - (1 + s * s) * (h * h - L * L))) / (1 + s * s)
    return x0, -h + s * x0


@pytest.mark.parametrize("theta0", [-1.2, -1.25, -1.5])
def test_a_plastic_impact_on_the_floor_rests_with_the_static_forces(models, theta0):
    # θ0 = −1.5, −1.25: fast, the free normal acceleration before the impact does not press (the centripetal b of
    # the curved gap); after the plastic impact the particle is at rest and its weight presses: both models close
    # there (the forces checked at the state after the impact, lagcomp.kernel_support.resting)
    cartesian, _ = models
    on_rod, on_angle = _both(models, theta0, (0.0, 2.0), {"d": FAR, "ef": 0.0})
    assert [(s.contact, s.closed) for s in on_rod.contact_switches] == [("floor", True)]
    assert [(s.contact, s.closed) for s in on_angle.contact_switches] == [("floor", True)]
    assert on_rod.contact_switches[0].t == on_rod.events["floor"].t[0]
    assert on_rod.contact_switches[0].t == pytest.approx(on_angle.contact_switches[0].t, abs=1e-11)
    m, h, s, L = DEFAULTS["m"], DEFAULTS["h"], DEFAULTS["s"], DEFAULTS["L"]
    x0, y0 = _floor_contact_point(h, s, L)
    resting = on_rod.t > on_rod.contact_switches[0].t
    np.testing.assert_allclose(on_rod.q[resting], np.tile([x0, y0], (resting.sum(), 1)), rtol=0, atol=1e-11)
    normal = m * G * x0 / (x0 + s * y0)
    np.testing.assert_allclose(on_rod.contact_forces[resting, 1], normal, rtol=1e-11)
    np.testing.assert_allclose(on_rod.reactions["rod"][resting], s * normal / (2 * x0), rtol=1e-10)
    assert not on_rod.contact_forces[:, 0].any()
    # the angle model rests at the same point (θ0 = atan2(x0, −y0)) with the same force (the same gap function)
    at_rest = on_angle.t > on_angle.contact_switches[0].t
    np.testing.assert_allclose(on_angle.q[at_rest, 0], np.arctan2(x0, -y0), rtol=0, atol=1e-11)
    np.testing.assert_allclose(on_angle.contact_forces[at_rest, 1], normal, rtol=1e-11)
    # before the impact the rod's tension is the free pendulum's, m (g cos θ... ) from the free solve: Λᵀ μ alone
    free = on_rod.t < on_rod.contact_switches[0].t
    lam = np.empty(1)
    p = cartesian.parameter_vector({"d": FAR, "ef": 0.0})
    for row in np.flatnonzero(free)[::7]:
        assert cartesian.kernels.reactions_free(on_rod.t[row], on_rod.y[row], p, lam) == 0
        assert on_rod.reactions["rod"][row] == lam[0]


@settings(max_examples=12, deadline=None)
@example(theta0=-1.0, restitution=0.7421875)
@example(theta0=-1.28125, restitution=0.625)   # (found by CI: the rest point 1.006e-11 off, the drift's 1.050e-11)
@given(theta0=st.floats(-1.3, -0.9), restitution=st.floats(0.05, 0.9))   # (e = 0: the test above)
def test_bounces_to_rest_on_the_floor_as_the_angle_model(models, theta0, restitution):
    # A known limit: the last bounces of the Zeno series (~4e-7 m/s, rising ~1e-14 m) may end the Cartesian run with
    # EVENTS_ACCUMULATED just before the rule closes the contact (θ0 = −1, e = 0.742: at t = 2.2405, the angle
    # model closing at the same time to 2e-7; with projection=True too, at other starts): the rule's rounding scale
    # ε Σ |∂g/∂q_j| |q_j| does not cover the gap's noise from the drift off the rod.  Then it must have stopped
    # there, at the angle model's rest within the rule's bound.
    on_rod, on_angle = _both(models, theta0, (0.0, 3.0), {"d": FAR, "ef": restitution}, accumulating=True)
    hits, reference = on_rod.events["floor"], on_angle.events["floor"]
    assert len(hits) >= 1 and len(reference) >= 1
    # the bounces the runs resolve well (more than 1 ms apart) at the same times; the last ones, near the rest
    # where the Zeno rule closes the contact (lagcomp.kernel_support.resting), depend on the coordinates'
    # rounding scale (ε Σ |∂g/∂q_j| |q_j|) and may differ in number
    resolved = np.flatnonzero(np.diff(reference.t) < 1e-3)
    k = resolved[0] if resolved.size else len(reference)
    np.testing.assert_allclose(hits.t[:k], reference.t[:k], rtol=0, atol=1e-9)     # (after ~15 bounces at rtol 1e-12)
    bound = (1e-11 * 3.0 + 2 * np.sqrt(2 * 64 * np.finfo(float).eps * 2 / (G / 4))) / (1 - restitution)
    if on_rod.status == Status.EVENTS_ACCUMULATED:
        assert [(s.contact, s.closed) for s in on_angle.contact_switches] == [("floor", True)]
        assert abs(on_rod.t_failure - on_angle.contact_switches[0].t) <= bound
        return
    switches = [(s.contact, s.closed) for s in on_rod.contact_switches]
    assert switches == [(s.contact, s.closed) for s in on_angle.contact_switches]
    if switches:        # at rest by t = 3: at the same time within the Zeno rule's bound (resting's docstring:
        # the bounces left out, 1/(1 − e) times the largest of BOUNCE_TIME t and 2 √(2 BOUNCE_HEIGHT ε H/|a|), with
        # H ≤ 2 the gap's rounding scale Σ |∂g/∂q_j| |q_j| in either coordinates and |a| ≥ g/4 the normal pull)
        assert switches == [("floor", True)]
        assert abs(on_rod.contact_switches[0].t - on_angle.contact_switches[0].t) <= bound
        # both rest where the floor meets the rod's circle, the Cartesian run off the circle by its drift δr (it
        # does not project: ~1e-11 by t = 3), i.e. along the floor (direction u) by δr / (u·r̂) from the angle model's
        L, s = DEFAULTS["L"], DEFAULTS["s"]
        rest = on_rod.q[-1]
        drift = (rest @ rest - L * L) / (2 * L)
        u = np.array([1.0, s]) / np.hypot(1.0, s)
        expected = _position(on_angle.q[-1, 0]) + drift / (u @ rest / L) * u
        np.testing.assert_allclose(rest, expected, rtol=0, atol=1e-12)
    # each impact keeps Λ q̇ to rounding
    scale = np.abs(hits.q).sum(axis=1) * (np.abs(hits.qd) + np.abs(hits.qd_after)).sum(axis=1)
    change = np.einsum("ij,ij->i", hits.q, hits.qd_after - hits.qd)
    assert np.all(np.abs(change) <= 8 * np.finfo(float).eps * scale)


@pytest.mark.parametrize("method", ["dopri5", "tsit5", "bs3"])
def test_the_other_event_methods_bounce_to_rest_as_dop853(models, method):
    cartesian, _ = models
    start, params = (_position(-1.2), [0.0, 0.0]), {"d": FAR, "ef": 0.3}
    reference = cartesian.simulate((0.0, 2.0), *start, params, rtol=1e-12, atol=1e-12)
    run = cartesian.simulate((0.0, 2.0), *start, params, method=method, rtol=1e-10, atol=1e-10)
    assert run.status == Status.DONE, run.message
    np.testing.assert_allclose(run.events["floor"].t[:3], reference.events["floor"].t[:3], rtol=0, atol=1e-8)
    assert [(s.contact, s.closed) for s in run.contact_switches] == [("floor", True)]
    bound = 1e-8 + 2 * np.sqrt(2 * 64 * np.finfo(float).eps * 2 / (G / 4)) / (1 - 0.3)   # (the Zeno rule's, above)
    assert abs(run.contact_switches[0].t - reference.contact_switches[0].t) <= bound


def test_methods_without_contacts_or_constraints_are_refused_naming_the_capable_ones(models):
    cartesian, _ = models
    start = (_position(-1.2), [0.0, 0.0])
    with pytest.raises(lc.OptionError, match="constraints") as refused:
        cartesian.simulate((0.0, 1.0), *start, method="taylor")
    assert "['rod']" in str(refused.value)
    with pytest.raises(lc.OptionError, match="switch and jump") as refused:
        cartesian.simulate((0.0, 1.0), *start, method="radau")
    assert "taylor" not in str(refused.value) and "dop853" in str(refused.value)


def test_a_sweep_over_the_restitution_matches_its_single_runs(models):
    cartesian, _ = models
    restitutions = np.array([0.0, 0.3, 0.6])
    start = {"q0": _position(-1.2), "qd0": [0.0, 0.0]}
    sweep = cartesian.sweep((0.0, 2.0), grid={"ef": restitutions}, params={"d": FAR}, rtol=1e-12, atol=1e-12,
                            output="events", event_cap=256, progress=False, **start)
    assert (sweep.status == Status.DONE).all()
    for i, restitution in enumerate(restitutions):
        single = cartesian.simulate((0.0, 2.0), params={"d": FAR, "ef": restitution}, rtol=1e-12, atol=1e-12,
                                    **start)
        count = sweep.events["floor"]["count"][i]
        assert count == len(single.events["floor"])
        np.testing.assert_array_equal(sweep.events["floor"]["t"][i, :count], single.events["floor"].t)
        np.testing.assert_array_equal(sweep.final[i], single.y[-1])


def test_a_rolling_disc_bounces_off_a_wall_keeping_its_rolling_constraint(tmp_path):
    """A nonholonomic constraint: a disc (mass m, I = κ m R²) rolling without slipping, ẋ − R θ̇ = 0, pushed by F0
    toward a wall at x = −d.  The impact keeps the rolling: with W = J K Jᵀ = 1/(m + I/R²) (K of the module
    docstring of `lagcomp.kernel_support.constrained_response`), ẋ⁺ = −e ẋ⁻, θ̇⁺ = ẋ⁺/R and P = (1 + e) m_eff |ẋ⁻|,
    m_eff = m + I/R²; between impacts ẍ = −F0/m_eff, so from x0 at rest the first impact comes at
    t1 = √(2 (x0 + d) m_eff/F0), the bounces end at t∞ = t1 + 2 e v1 m_eff/(F0 (1 − e)), and at rest the wall
    pushes with F0 while the rolling constraint holds with 0 (statics: −F0 + μ + N = 0, −R μ = 0)."""
    x, theta = lc.coordinates("x theta")
    m, R, kappa, F0, d, e = sp.symbols("m R kappa F0 d e", positive=True)
    system = lc.System([x, theta], T=m * x.diff(t) ** 2 / 2 + kappa * m * R**2 * theta.diff(t) ** 2 / 2, V=F0 * x,
                       constraints=[lc.Nonholonomic("roll", x.diff(t) - R * theta.diff(t))],
                       events=[lc.Contact("wall", x + d, restitution=e)], name="rolling_disc",
                       defaults={"m": 2.0, "R": 0.3, "kappa": 0.5, "F0": 3.0, "d": 0.5, "e": 0.5})
    model = lc.compile(system, cache_dir=tmp_path)
    mass, inertia, force, restitution = 2.0, 0.5 * 2.0 * 0.3**2, 3.0, 0.5
    effective = mass + inertia / 0.3**2
    sol = model.simulate((0.0, 6.0), [1.0, 0.0], [0.0, 0.0], rtol=1e-12, atol=1e-12)
    assert sol.status == Status.DONE, sol.message
    hits = sol.events["wall"]
    t1 = np.sqrt(2 * 1.5 * effective / force)
    v1 = force / effective * t1
    assert hits.t[0] == pytest.approx(t1, abs=1e-11)
    assert hits.qd_after[0, 0] == pytest.approx(restitution * v1, rel=1e-10)
    residual = lambda qd: qd[:, 0] - 0.3 * qd[:, 1]  # (ẋ − R θ̇: kept by the impact, drift and all)
    assert np.all(np.abs(residual(hits.qd_after) - residual(hits.qd)) <= 8 * np.finfo(float).eps * np.abs(hits.qd).max())
    assert hits.impulses[0, 0] == pytest.approx((1 + restitution) * effective * v1, rel=1e-10)
    t_rest = t1 + 2 * restitution * v1 * effective / (force * (1 - restitution))
    assert [(s.contact, s.closed) for s in sol.contact_switches] == [("wall", True)]
    # within the Zeno rule's bound (resting's docstring): the bounces below 64 roundings of the gap (ε |x| = ε d)
    # left out, 2 √(2 · 64 ε d / |a|) / (1 − e), |a| = F0/m_eff
    bound = 2 * np.sqrt(2 * 64 * np.finfo(float).eps * 0.5 / (force / effective)) / (1 - restitution)
    assert abs(sol.contact_switches[0].t - t_rest) <= bound
    resting = sol.t > sol.contact_switches[0].t
    np.testing.assert_allclose(sol.contact_forces[resting, 0], force, rtol=1e-12)
    assert np.abs(sol.reactions["roll"][resting]).max() <= 1e-12 * force
    rolling = sol.t < hits.t[0]
    np.testing.assert_allclose(sol.reactions["roll"][rolling], force * inertia / 0.3**2 / effective, rtol=1e-10)


@pytest.fixture(scope="module")
def inclines(tmp_path_factory):
    """A block on an incline of angle α with Coulomb friction (N = m g cos α, an expression): as (x, y) with the
    constraint y − x tan α = 0 and the element's velocity v = ẋ cos α + ẏ sin α, and as the distance s along the
    incline (no constraint)."""
    cache = tmp_path_factory.mktemp("cache")
    m, g, alpha, mu_s, mu_k = sp.symbols("m g alpha mu_s mu_k", positive=True)
    defaults = {"m": 1.5, "g": G, "alpha": 0.3, "mu_s": 0.4, "mu_k": 0.25}
    x, y = lc.coordinates("x y")
    planar = lc.System([x, y], T=m * (x.diff(t) ** 2 + y.diff(t) ** 2) / 2, V=m * g * y,
                       constraints=[Holonomic("incline", y - x * sp.tan(alpha))],
                       events=[lc.Friction("rub", x.diff(t) * sp.cos(alpha) + y.diff(t) * sp.sin(alpha),
                                           normal=m * g * sp.cos(alpha), static=mu_s, kinetic=mu_k)],
                       name="incline_planar", defaults=defaults)
    s, = lc.coordinates("s")
    along = lc.System([s], T=m * s.diff(t) ** 2 / 2, V=m * g * s * sp.sin(alpha),
                      events=[lc.Friction("rub", s.diff(t), normal=m * g * sp.cos(alpha), static=mu_s, kinetic=mu_k)],
                      name="incline_along", defaults=defaults)
    return lc.compile(planar, cache_dir=cache), lc.compile(along, cache_dir=cache)


def test_friction_with_a_constraint_stops_and_sticks_as_on_the_incline_coordinate(inclines):
    """Sent up the incline at v0: it slows at g (sin α + μk cos α), stops at t1 = v0 / that and sticks (tan α ≤ μs),
    held by the friction force m g sin α up the incline, while the incline's multiplier is then the statics' (the
    constraint's row (−tan α, 1) carries N: μ = m g cos² α)."""
    planar, along = inclines
    alpha, v0, m = 0.3, 2.0, 1.5
    on_line = along.simulate((0.0, 1.5), [0.0], [v0], rtol=1e-12, atol=1e-12)
    on_plane = planar.simulate((0.0, 1.5), [0.0, 0.0], [v0 * np.cos(alpha), v0 * np.sin(alpha)], rtol=1e-12,
                               atol=1e-12)
    assert on_line.status == on_plane.status == Status.DONE, (on_line.message, on_plane.message)
    t1 = v0 / (G * (np.sin(alpha) + 0.25 * np.cos(alpha)))
    switches = [(s.friction, s.mode) for s in on_plane.friction_switches]
    assert switches == [(s.friction, s.mode) for s in on_line.friction_switches] == [("rub", 0)]
    assert on_plane.friction_switches[0].t == pytest.approx(t1, abs=1e-11)
    assert on_line.friction_switches[0].t == pytest.approx(t1, abs=1e-11)
    stuck = on_plane.t > t1
    np.testing.assert_allclose(on_plane.friction_forces[stuck, 0], m * G * np.sin(alpha), rtol=1e-10)
    np.testing.assert_allclose(on_plane.reactions["incline"][stuck], m * G * np.cos(alpha) ** 2, rtol=1e-10)
    sliding = on_plane.t < on_plane.friction_switches[0].t
    np.testing.assert_allclose(on_plane.friction_forces[sliding, 0], -0.25 * m * G * np.cos(alpha), rtol=1e-12)
    # stuck where the incline coordinate's run is, at v0² / (2 g (sin α + μk cos α)) up the incline
    top = v0**2 / (2 * G * (np.sin(alpha) + 0.25 * np.cos(alpha)))
    np.testing.assert_allclose(on_plane.q[-1], top * np.array([np.cos(alpha), np.sin(alpha)]), rtol=1e-10)
    assert on_line.q[-1, 0] == pytest.approx(top, rel=1e-10)
