"""The Gauss methods record their chart switches (a ball joint's MRPs σ to their shadow −σ/|σ|²) as events, as dop853
records the same shadow events: `Solution.events` and a sweep's ``output="events"``.

dop853 locates each switch at the crossing |σ| = 1 (its event function g = |σ|² − 1, direction +1); a Gauss method
switches, without locating, at the end of the first step whose state has left the chart (g > 0:
`lagcomp.integrate.drivers.collocation`), so it records that step's end t_g, the state there (g > 0) and the state in
the new chart.  The bound the times are tested against, derived: if the Gauss run followed the exact motion, its
switch would come at the first step end at or after the crossing t*, t* ≤ t_g < t* + h.  It follows the motion with a
global error e in σ, which moves its own crossing by |Δt| ≤ |∇g| |e| / |ġ| to first order (∇g = 2σ, |σ| = 1 there;
ġ = 2 σ·σ̇ from dop853's state at its crossing); e is measured at t_g, in the new chart, against dop853's state at
t_g (rtol 1e-13), and doubled for the second-order terms and its change over one step:
t* − δ ≤ t_g < t* + h + δ, δ = 2 · 2 |e| / |ġ| (δ ≤ 1e-6 s here, against h = 1e-2 s).
"""

from __future__ import annotations

import numpy as np
import pytest

import lagcomp as lc
from lagcomp.examples.trees import spherical_chain

#: A rigid body on a ball joint, unequal principal moments, spun about the vertical: a shadow switch every ~0.7 s.
BALL_PARAMETERS = {"m0": 1.3, "c0": 0.7, "A0": 0.4, "B0": 0.3, "C0": 0.2, "g": 9.81}
TUMBLING = ([0.3, 0.1, 0.0], [1.0, -0.5, 2.0])
SHADOW = "link0_shadow"


@pytest.fixture(scope="module")
def ball(cache_dir):
    return lc.compile(spherical_chain(1), cache_dir=cache_dir)


def _shadow(sigma, rate):
    """The shadow chart's (σ', σ̇') of (σ, σ̇): σ' = −σ/|σ|², its derivative along σ̇."""
    s = sigma @ sigma
    return -sigma / s, -rate / s + 2 * sigma * (sigma @ rate) / s ** 2


@pytest.mark.parametrize(("method", "dt"), [("gauss2", 0.01), ("gauss3", 0.02)])
def test_gauss_lists_the_switches_dop853_locates_within_one_step(ball, method, dt):
    """Over 5 s (seven switches): the same event, as many occurrences, each Gauss time a step end within the derived
    bound after dop853's crossing (module docstring); the state before has left the chart (|σ| > 1), the state after
    is its shadow (to rounding) and is the run's own state at t_g (its saved row, bit for bit)."""
    reference = ball.simulate((0, 5), *TUMBLING, BALL_PARAMETERS, method="dop853", rtol=1e-13, atol=1e-13)
    run = ball.simulate((0, 5), *TUMBLING, BALL_PARAMETERS, method=method, dt=dt)
    assert run.status == 0 and list(run.events) == list(reference.events) == [SHADOW]
    theirs, ours = reference.events[SHADOW], run.events[SHADOW]
    assert ours.t.size == theirs.t.size == 7
    at = ball.simulate((0, 5), *TUMBLING, BALL_PARAMETERS, method="dop853", rtol=1e-13, atol=1e-13, t_eval=ours.t)
    for i, t_g in enumerate(ours.t):
        row = np.flatnonzero(run.t == t_g)
        assert row.size == 1 and t_g == pytest.approx(round(t_g / dt) * dt, abs=1e-12)   # a step end
        error = np.linalg.norm(ours.q_after[i] - at.q[i])     # both in the new chart at t_g
        rate = abs(2 * theirs.q[i] @ theirs.qd[i])
        delta = 2 * 2 * error / rate
        assert 0.0 < delta < 1e-4    # (an error measured, not zero; and far below the step)
        assert theirs.t[i] - delta <= t_g < theirs.t[i] + dt + delta
        assert np.linalg.norm(ours.q[i]) > 1.0 > np.linalg.norm(ours.q_after[i])
        sigma, rate_after = _shadow(ours.q[i], ours.qd[i])
        np.testing.assert_allclose(ours.q_after[i], sigma, rtol=4e-16, atol=0)
        np.testing.assert_allclose(ours.qd_after[i], rate_after, rtol=1e-14, atol=1e-14 * np.abs(rate_after).max())
        assert np.array_equal(run.q[row[0]], ours.q_after[i]) and np.array_equal(run.qd[row[0]], ours.qd_after[i])


def test_more_switches_than_an_event_buffer_holds(ball):
    """30 s hold about 42 switches, more than the 16 rows of a driver call's event buffer: the driver stops for a
    fresh one between steps (the carry keeps the run bitwise what one call gives), and every switch is listed once,
    in time order, one at each step end where the chart changed (σ flips sign between saved rows)."""
    run = ball.simulate((0, 30), *TUMBLING, BALL_PARAMETERS, method="gauss2", dt=0.01)
    assert run.status == 0
    times = run.events[SHADOW].t
    flips = run.t[1:][np.einsum("ij,ij->i", run.q[1:], run.q[:-1]) < 0]     # σ' = −σ/|σ|²: the sign flips
    assert times.size > 32 and np.array_equal(times, flips)


def test_a_gauss_sweep_records_the_switches_a_run_does(ball):
    """``output="events"`` on a gauss2 sweep: per trajectory the count, times and states before and after of its
    own run's switches, bit for bit; an event cap below the count keeps the first ones and counts them all."""
    masses = (1.3, 1.0)
    sweep = ball.sweep((0, 20), {"m0": list(masses)}, q0=TUMBLING[0], qd0=TUMBLING[1], params=BALL_PARAMETERS,
                       method="gauss2", dt=0.01, output="events", event_cap=8, workers=1, progress=False)
    record = sweep.events[SHADOW]
    for k, mass in enumerate(masses):
        ours = ball.simulate((0, 20), *TUMBLING, {**BALL_PARAMETERS, "m0": mass}, method="gauss2", dt=0.01)
        expected = ours.events[SHADOW]
        assert record["count"][k] == expected.t.size > 8
        assert np.array_equal(record["t"][k], expected.t[:8])
        assert np.array_equal(record["y"][k], np.hstack([expected.q, expected.qd])[:8])
        assert np.array_equal(record["y_after"][k], np.hstack([expected.q_after, expected.qd_after])[:8])
        assert np.array_equal(sweep.final[k], ours.y[-1])


def test_a_gauss_run_without_ball_joints_records_no_events(cache_dir):
    """A model without chart switches (the double pendulum) has no events to record, and a sweep asking for them
    is refused as before (events need an adaptive method there)."""
    from lagcomp.examples import get

    model = lc.compile(get("double_pendulum"), cache_dir=cache_dir)
    assert model.simulate((0, 1), [1.2, -0.4], [0.3, 0.8], method="gauss2", dt=0.01).events == {}
    with pytest.raises(lc.OptionError, match="asks for events but none are active"):
        model.sweep((0, 1), {"theta1": [0.5, 1.0]}, method="gauss2", dt=0.01, output="events", progress=False)
