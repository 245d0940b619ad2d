"""method="radau" on Kane models (state (q, u)), through the public API.

Radau IIA integrates any y' = f(t, y) with its exact Jacobian, and a Kane module emits both (``rhs`` and
``rhs_jacobian`` of (q̇, u̇)).  Checked:

* a stiff Kane model, a pendulum held at the bottom by a PD controller of high gain
  (eigenvalues about −12,000 s⁻¹ and −1 s⁻¹): dop853 finds it stiff and advises radau, which takes a
  small fraction of dop853's steps and agrees with a tight dop853 reference;
* the Chaplygin sleigh (q̇ ≠ u, a knife-edge constraint, M with the constraint row: not symmetric)
  against its closed form, with the dependent speed held at 0 and events located on radau's dense output
  (the Kane pendulum's bottom and turning point against its elliptic period);
* the same steps as scipy's ``solve_ivp(method="Radau")`` given ``Model.rhs`` and ``Model.jacobian``
  on the sleigh (as tests/test_radau.py does on the stiff spring pendulum);
* sympy's Whipple bicycle (n_q = 4 ≠ n_u = 6, configuration and velocity constraints) against dop853 at
  rtol 1e-12, with bounds about ten times the measured errors;
* a sweep of the sleigh equal, bitwise, to the runs it sweeps; `projection=True` refused (radau does not
  project) and the constraint residual reported over the saved rows.
"""

from __future__ import annotations

import math

import kane_models
import numpy as np
import pytest
import sympy as sp
import sympy.physics.mechanics as me
from scipy.integrate import solve_ivp
from scipy.special import ellipk
from test_kane_interop import PENDULUM, SLEIGH, _on_constraints, chaplygin_sleigh, kane_pendulum, sleigh_closed_form
from test_stiffness_detection import STIFF_TOL, stiffness_warnings

import lagcomp as lc
from lagcomp import OptionError
from lagcomp.model import t

SLEIGH_START = dict(q0=[0.0, 0.0, 0.2], u0=[-0.5, 1.5, 0.0])


@pytest.fixture(scope="module")
def sleigh(cache_dir):
    """The Chaplygin sleigh of test_kane_interop (the same cache key as there)."""
    return lc.compile(chaplygin_sleigh(), cache_dir=cache_dir, name="chaplygin_sleigh", defaults=SLEIGH)


def controlled_pendulum():
    """A pendulum (u = q̇) held at q = 0 by a PD torque −kp q − kd u at its pivot: with I = m l², the motion
    I q̈ = −m g l sin q − kp q − kd q̇ has, linearized, the eigenvalues −kd/I and about −(kp + m g l)/kd."""
    q, u = me.dynamicsymbols("q u")
    m, length, g, kp, kd = sp.symbols("m l g kp kd", positive=True)
    N = me.ReferenceFrame("N")
    pivot = me.Point("O")
    pivot.set_vel(N, 0)
    A = N.orientnew("A", "Axis", [q, N.z])
    A.set_ang_vel(N, u * N.z)
    P = pivot.locatenew("P", -length * A.y)
    P.v2pt_theory(pivot, N, A)
    km = me.KanesMethod(N, [q], [u], kd_eqs=[q.diff(t) - u])
    km.kanes_equations([me.Particle("bob", P, m)], [(P, -m * g * N.y), (A, (-kp * q - kd * u) * N.z)])
    return km


#: I = m l² = 0.832: eigenvalues −kd/I ≈ −12,000 s⁻¹ and −(kp + m g l)/kd ≈ −1.0 s⁻¹.
CONTROLLED = dict(m=1.3, l=0.8, g=9.81, kp=1e4, kd=1e4)


def test_a_stiff_kane_model_is_advised_to_radau_which_integrates_it(cache_dir):
    model = lc.compile(controlled_pendulum(), cache_dir=cache_dir, name="kane_controlled_pendulum",
                       defaults=CONTROLLED)
    start = dict(q0=[1.0], u0=[0.0])
    messages, explicit = stiffness_warnings(lambda: model.simulate((0, 5), method="dop853", progress=False,
                                                                  **start, **STIFF_TOL))
    assert explicit.success and len(messages) == 1 and 'Use method="radau"' in messages[0], messages
    _, reference = stiffness_warnings(lambda: model.simulate((0, 5), method="dop853", rtol=1e-12, atol=1e-12,
                                                             progress=False, **start))
    s = model.simulate((0, 5), method="radau", progress=False, **start, **STIFF_TOL)
    assert s.success and s.njev > 0 and s.nlu > 0
    assert s.nsteps * 50 < explicit.nsteps, (s.nsteps, explicit.nsteps)    # measured 67 against 9,405
    assert np.max(np.abs(s.y[-1] - reference.y[-1])) < 2e-8   # measured 2.0e-9


def test_sleigh_follows_its_closed_form_and_keeps_the_knife_edge(sleigh):
    times = np.linspace(0, 6, 61)
    v, w, theta = sleigh_closed_form(times, -0.5, 1.5, 0.2)
    for tol, bound in ((1e-8, 3e-8), (1e-10, 3e-10)):    # measured 3.4e-9 and 2.8e-11
        s = sleigh.simulate((0, 6), method="radau", rtol=tol, atol=tol, t_eval=times, progress=False,
                            **SLEIGH_START)
        assert s.success and s.njev > 0 and s.nlu > 0 and s.method == "radau"
        error = max(np.max(np.abs(s.u[:, 0] - v)), np.max(np.abs(s.u[:, 1] - w)), np.max(np.abs(s.q[:, 2] - theta)))
        assert error < bound, (tol, error)
        assert np.max(np.abs(s.u[:, 2])) == 0.0 and s.constraint_residual < 1e-12    # the knife edge: u2 = 0
        np.testing.assert_allclose(s.qd[:, :2], np.column_stack([s.u[:, 0] * np.cos(s.q[:, 2]),
                                                                 s.u[:, 0] * np.sin(s.q[:, 2])]), atol=1e-14)


def test_radau_takes_scipys_steps_on_the_sleigh(sleigh):
    s = sleigh.simulate((0, 10), method="radau", rtol=1e-6, atol=1e-6, progress=False, **SLEIGH_START)
    r = solve_ivp(sleigh.rhs, (0, 10), sleigh.initial_state(**SLEIGH_START), method="Radau", jac=sleigh.jacobian,
                  rtol=1e-6, atol=1e-6)
    assert (s.nsteps, s.nfev, s.njev, s.nlu) == (r.t.size - 1, r.nfev, r.njev, r.nlu)
    np.testing.assert_allclose(s.y[-1], r.y[:, -1], rtol=0, atol=1e-12)


def test_events_of_a_kane_model_on_radaus_dense_output(cache_dir):
    """The Kane pendulum (u = l q̇) of test_kane_interop from q = 2 at rest: the bottom after a quarter of
    the elliptic period, the terminal turning point after half."""
    km = kane_pendulum()
    q, u = km.q[0], km.u[0]
    events = [lc.Event("bottom", q, direction=-1), lc.Event("turn", u, direction=1, terminal=True)]
    model = lc.compile(km, cache_dir=cache_dir, name="kane_pendulum_events", defaults=PENDULUM, events=events)
    period = 4 * math.sqrt(PENDULUM["l"] / PENDULUM["g"]) * ellipk(math.sin(1.0) ** 2)
    s = model.simulate((0, 10), q0=[2.0], u0=[0.0], method="radau", rtol=1e-10, atol=1e-10, progress=False)
    assert s.status == 1 and "Event 'turn'" in s.message and s.t[-1] == s.events["turn"].t[0]
    assert abs(s.events["bottom"].t[0] - period / 4) < 2e-13     # measured 1.7e-14
    assert abs(s.events["turn"].t[0] - period / 2) < 2e-12     # measured 1.8e-13
    speed = math.sqrt(2 * PENDULUM["g"] * PENDULUM["l"] * (1 - math.cos(2.0)))
    assert abs(s.events["bottom"].qd[0, 0] + speed) < 1.5e-9     # `qd` holds u; measured 1.3e-10


def test_event_records_hold_every_speed_when_n_u_exceeds_n_q(cache_dir):
    """A particle pushed along x by a constant force F, q = (x,), u = (u1, u2) with u2 (across) held at 0 by a
    velocity constraint: x = 1 is reached at t = √(2m/F) with u1 = √(2F/m); the record's `qd` holds (u1, u2)."""
    x, u1, u2 = me.dynamicsymbols("x u1 u2")
    m, F = sp.symbols("m F", positive=True)
    N = me.ReferenceFrame("N")
    P = me.Point("P")
    P.set_vel(N, u1 * N.x + u2 * N.y)
    km = me.KanesMethod(N, [x], [u1], kd_eqs=[x.diff(t) - u1], u_dependent=[u2], velocity_constraints=[u2])
    km.kanes_equations([me.Particle("p", P, m)], [(P, F * N.x)])
    model = lc.compile(km, cache_dir=cache_dir, name="kane_pushed_particle", defaults=dict(m=2.0, F=3.0),
                       events=[lc.Event("x_one", x - 1, direction=1)])
    s = model.simulate((0, 2), q0=[0.0], u0=[0.0, 0.0], method="radau", rtol=1e-10, atol=1e-10, progress=False)
    record = s.events["x_one"]
    assert record.q.shape == (1, 1) and record.qd.shape == (1, 2)
    assert abs(record.t[0] - math.sqrt(2 * 2.0 / 3.0)) < 1e-12 and record.qd[0, 1] == 0.0
    assert abs(record.qd[0, 0] - math.sqrt(2 * 3.0 / 2.0)) < 1e-12


@pytest.fixture(scope="module")
def bicycle(whipple_bicycle):
    """The bicycle at 5 m/s with a lean-rate kick (test_kane_interop's run), on its constraints."""
    _, model = whipple_bicycle
    return model, _on_constraints(model, [0.0, 0.0, 0.0], [0.5, 5.0 / kane_models.RAD_REAR, 0.0])


@pytest.mark.slow  # numba compiles the bicycle's rhs_jacobian for it: ~23 s on 2 cores, a tenth of the suite's growth
def test_whipple_bicycle_agrees_with_dop853(bicycle):
    model, y0 = bicycle
    start = dict(q0=y0[:4], u0=y0[4:])
    reference = model.simulate((0, 3), method="dop853", rtol=1e-12, atol=1e-12, progress=False, **start)
    # bounds on the error at t = 3 s, the constraint residual (over the saved rows) and the relative energy
    # drift (no-slip rolling does no work), about ten times the measured ones
    for tol, bound, residual, drift in ((1e-8, 3e-9, 1.5e-9, 3e-10),        # measured 2.4e-10, 1.2e-10, 2.1e-11
                                        (1e-10, 1e-11, 2e-12, 5e-13)):      # measured 9.8e-13, 1.7e-13, 3.2e-14
        s = model.simulate((0, 3), method="radau", rtol=tol, atol=tol, progress=False, **start)
        assert s.success and s.njev > 0 and s.nlu > 0
        assert s.u.shape == (s.t.size, 6) and s.qd.shape == (s.t.size, 4)
        error = np.max(np.abs(s.y[-1] - reference.y[-1]))
        assert error < bound, (tol, error)
        assert 0 < s.constraint_residual < residual, (tol, s.constraint_residual)
        assert np.ptp(s.energy) < drift * abs(s.energy[0]), (tol, np.ptp(s.energy) / abs(s.energy[0]))
    assert abs(s.q[-1, 1]) > 1e-2      # the kick did lean it


def test_radau_does_not_project_a_kane_model(bicycle):
    model, y0 = bicycle
    with pytest.raises(OptionError, match="`radau` does not project .* rk4, dopri5, dop853, tsit5 or bs3"):
        model.simulate((0, 1), q0=y0[:4], u0=y0[4:], method="radau", projection=True)


def test_a_radau_sweep_of_the_sleigh_is_bitwise_the_runs_it_sweeps(sleigh):
    grid = {"a": [0.3, 0.4], "u1": [-0.5, 1.0]}
    swept = sleigh.sweep((0, 3), grid, method="radau", rtol=1e-8, atol=1e-8, workers=1, progress=False,
                         q0=SLEIGH_START["q0"], u0=SLEIGH_START["u0"])
    assert swept.shape == (2, 2) and np.all(swept.status == 0) and swept.speeds == ("u1", "u3", "u2")
    for i, a in enumerate(grid["a"]):
        for j, u1 in enumerate(grid["u1"]):
            s = sleigh.simulate((0, 3), q0=SLEIGH_START["q0"], u0=[u1, 1.5, 0.0], params={"a": a}, method="radau",
                                rtol=1e-8, atol=1e-8, progress=False)
            assert np.array_equal(swept.final[i, j], s.y[-1]), (a, u1)
