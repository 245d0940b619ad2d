"""Events: located on the dense output of DOPRI5/DOP853, against scipy, closed forms and the energy identity."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import lagcomp as lc
from lagcomp import examples
from lagcomp.errors import ModelError, OptionError, UndeclaredSymbolError

E_REGULAR = 1 / 12


def _henon_heiles_energy(q, qd, lam=1.0):
    x, y = q[:, 0], q[:, 1]
    return 0.5 * (qd**2).sum(axis=1) + 0.5 * (x**2 + y**2) + lam * (x**2 * y - y**3 / 3)


@pytest.fixture(scope="module")
def henon_heiles(compiled):
    return compiled("henon_heiles")


@pytest.fixture(scope="module")
def section_run(henon_heiles):
    return henon_heiles.simulate((0, 2000), rtol=1e-12, atol=1e-12)


def test_poincare_section_lies_on_the_energy_surface(section_run):
    """Each crossing of x = 0 upwards: x vanishes there, ẋ > 0, and H = 1/12 to 1e-10."""
    section = section_run.events["section"]
    assert section_run.status == 0 and len(section) > 300
    assert np.max(np.abs(section.q[:, 0])) < 1e-12
    assert np.all(section.qd[:, 0] > 0)
    assert np.max(np.abs(_henon_heiles_energy(section.q, section.qd) - E_REGULAR)) < 1e-10
    assert np.all(np.diff(section.t) > 0)


def test_regular_orbit_section_is_a_smooth_closed_curve(section_run):
    """A regular orbit's section points trace one invariant curve: seen from its centre, the radius is a
    smooth function of the angle (a chaotic orbit's points scatter over an area and make it jump)."""
    points = np.column_stack([section_run.events["section"].q[:, 1], section_run.events["section"].qd[:, 1]])
    centre = points.mean(axis=0)
    offset = points - centre
    angle = np.arctan2(offset[:, 1], offset[:, 0])
    radius = np.hypot(offset[:, 0], offset[:, 1])
    order = np.argsort(angle)
    jumps = np.abs(np.diff(radius[order]))
    assert np.max(np.diff(np.sort(angle))) < 0.2          # the points go all the way round
    assert np.max(jumps) < 0.02 * np.max(radius)          # and never jump across to another curve


@pytest.mark.parametrize("method", ["dop853", "dopri5"])
def test_event_times_match_scipy(henon_heiles, method):
    """Same steps as scipy's solver with the same tolerances (see test_drivers), so the same dense output:
    the located times agree to 1e-12 although scipy's brentq and ours are separate codes."""
    tol = 1e-10
    sol = henon_heiles.simulate((0, 200), method=method, rtol=tol, atol=tol)
    y0 = henon_heiles.initial_state()

    def section(t, y):
        return y[0]
    section.direction = 1

    def y_turn(t, y):
        return y[3]
    y_turn.direction = -1

    ref = solve_ivp(lambda t, y: henon_heiles.rhs(t, y), (0, 200), y0, method={"dop853": "DOP853"}.get(method, "RK45"),
                    rtol=tol, atol=tol, events=[section, y_turn])
    assert sol.nsteps == ref.t.size - 1
    # The start lies on both surfaces (x = 0, ẏ = 0): scipy counts that as an event, lagcomp does not.
    later = [ref.t_events[i] > 0 for i in range(2)]
    np.testing.assert_allclose(sol.events["section"].t, ref.t_events[0][later[0]], rtol=0, atol=1e-12)
    np.testing.assert_allclose(sol.events["y_turn"].t, ref.t_events[1][later[1]], rtol=0, atol=1e-12)
    np.testing.assert_allclose(sol.events["section"].qd, ref.y_events[0][later[0]][:, 2:], rtol=0, atol=1e-12)


def test_uncoupled_limit_closed_form(henon_heiles):
    """λ = 0: two unit oscillators, x = a sin t from the section, so crossings at t = 2πk exactly."""
    sol = henon_heiles.simulate((0, 100), params={"lam": 0.0}, rtol=1e-13, atol=1e-13)
    k = np.arange(1, len(sol.events["section"]) + 1)
    assert len(k) == 15
    np.testing.assert_allclose(sol.events["section"].t, 2 * np.pi * k, rtol=0, atol=1e-11)
    # y = 0.1 cos t: the maxima of y (ẏ = 0 downwards) are at 2πk too, the start excluded
    np.testing.assert_allclose(sol.events["y_turn"].t, 2 * np.pi * k, rtol=0, atol=1e-11)
    np.testing.assert_allclose(sol.events["y_turn"].q[:, 1], 0.1, rtol=0, atol=1e-12)


def test_terminal_event_stops_the_run_at_the_event(cache_dir):
    """Direction and terminal flags are run-time settings: the same module (no recompilation) serves a
    System whose y_turn event is terminal.  λ = 0: y = 0.1 cos t + 0.05 sin t peaks at t = atan(1/2)."""
    system = examples.get("henon_heiles")
    section, y_turn = system.events
    terminal = dataclasses.replace(system, events=(section, dataclasses.replace(y_turn, terminal=True)))
    model = lc.compile(terminal, cache_dir=cache_dir)
    assert model.source_path == lc.compile(system, cache_dir=cache_dir).source_path
    sol = model.simulate((0, 50), qd0=[0.3, 0.05], params={"lam": 0.0}, rtol=1e-12, atol=1e-12)
    t_peak = np.arctan(0.5)
    assert sol.status == 1 and sol.success and "y_turn" in sol.message
    assert sol.t[-1] == sol.events["y_turn"].t[0]
    assert abs(sol.t[-1] - t_peak) < 1e-12
    np.testing.assert_allclose(sol.q[-1], [0.3 * np.sin(t_peak), np.hypot(0.1, 0.05)], atol=1e-12)
    assert len(sol.events["section"]) == 0


def test_events_with_t_eval_and_long_runs_across_buffers(henon_heiles, section_run):
    """Dense output for t_eval and events at once; many driver calls give the same events as one."""
    t_eval = np.linspace(0, 2000, 50_001)
    sol = henon_heiles.simulate((0, 2000), rtol=1e-12, atol=1e-12, t_eval=t_eval)
    np.testing.assert_array_equal(sol.events["section"].t, section_run.events["section"].t)
    np.testing.assert_array_equal(sol.t, t_eval)


def test_event_selection_and_errors(henon_heiles):
    only = henon_heiles.simulate((0, 50), events=["y_turn"])
    assert len(only.events["section"]) == 0 and len(only.events["y_turn"]) > 0
    off = henon_heiles.simulate((0, 50), events=False)
    assert all(len(record) == 0 for record in off.events.values())
    fixed = henon_heiles.simulate((0, 1), method="verlet", dt=0.01)  # events skipped by default
    assert all(len(record) == 0 for record in fixed.events.values())
    with pytest.raises(OptionError, match="dense output"):
        henon_heiles.simulate((0, 1), method="verlet", dt=0.01, events=True)
    with pytest.raises(OptionError, match="Unknown event"):
        henon_heiles.simulate((0, 1), events=["apex"])


def test_bad_event_declarations():
    x, y = lc.coordinates("x y")
    with pytest.raises(ModelError, match="direction"):
        lc.Event("e", x, direction=2)
    with pytest.raises(ModelError, match="identifier"):
        lc.Event("not a name", x)
    z = lc.coordinates("z")[0]
    with pytest.raises(UndeclaredSymbolError, match="event e"):
        lc.System([x, y], T=x.diff(lc.t) ** 2 / 2, events=[lc.Event("e", z)])
    with pytest.raises(ModelError, match="unique"):
        lc.System([x], T=x.diff(lc.t) ** 2 / 2, events=[lc.Event("e", x), lc.Event("e", -x)])
