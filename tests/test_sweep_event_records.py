"""A sweep keeps, per trajectory, what a single run's `EventRecord` keeps (issue 21: "in sweeps, each trajectory its
own mode history"): the states after a reset (``y_after``) and a contact's impulses (``impulses``).

Reference: `Model.simulate` of the same grid point, whose records the sweep's must equal bitwise (the same driver,
the same kernels; the impulses from the same jump by the same arithmetic, compiled for the sweep in
`lagcomp.integrate.drivers.sweep_impulses`: bitwise equal so far, to rounding at worst).
"""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

import lagcomp as lc
from lagcomp.cli import main
from lagcomp.integrate.sweep import Sweep

t = lc.t


@pytest.fixture(scope="module")
def reset_ball(cache_dir):
    (x,) = lc.coordinates("x")
    g, e = sp.symbols("g e", positive=True)
    impact = lc.Event("impact", x, direction=-1, reset={x.diff(t): -e * x.diff(t)})
    return lc.compile(lc.System([x], T=x.diff(t) ** 2 / 2, V=g * x, events=[impact], name="sweep_record_ball",
                                defaults={"g": 9.81, "e": 0.8}, q0=(1.0,), qd0=(0.0,)), cache_dir=cache_dir)


@pytest.fixture(scope="module")
def cradle(cache_dir):
    """Newton's cradle of three balls on a line, the middle one of mass m2: two contacts."""
    x1, x2, x3 = lc.coordinates("x1 x2 x3")
    d, m2 = sp.symbols("d m2", positive=True)
    T = (x1.diff(t) ** 2 + m2 * x2.diff(t) ** 2 + x3.diff(t) ** 2) / 2
    return lc.compile(lc.System([x1, x2, x3], T=T, events=[lc.Contact("c12", x2 - x1 - d),
                                                            lc.Contact("c23", x3 - x2 - d)],
                                name="sweep_record_cradle", defaults={"d": 1.0, "m2": 1.0}), cache_dir=cache_dir)


def _assert_same_records(model, sweep, point, run_sol):
    """The sweep's record of grid index `point` equals the single run `run_sol`'s, event by event, bitwise."""
    n = model.n
    for name, single in run_sol.events.items():
        swept = sweep.events[name]
        assert swept["count"][point] == len(single), name
        kept = min(len(single), swept["t"].shape[-1])     # the first `event_cap` occurrences
        np.testing.assert_array_equal(swept["t"][point][:kept], single.t[:kept])
        np.testing.assert_array_equal(swept["y"][point][:kept], np.hstack([single.q, single.qd])[:kept])
        np.testing.assert_array_equal(swept["y_after"][point][:kept],
                                      np.hstack([single.q_after, single.qd_after])[:kept])
        assert np.isnan(swept["y_after"][point][kept:]).all()
        if single.impulses is not None:
            np.testing.assert_array_equal(swept["impulses"][point][:kept], single.impulses[:kept])
            assert np.isnan(swept["impulses"][point][kept:]).all()
        else:
            assert "impulses" not in swept
        assert swept["y_after"].shape[-1] == 2 * n


@pytest.mark.parametrize("method, options", [("dop853", dict(rtol=1e-12, atol=1e-12)), ("taylor", {})])
def test_a_reset_events_sweep_keeps_the_states_after_as_single_runs_do(reset_ball, method, options):
    # e = 0.5 accumulates its impacts before t = 2.5 (at t∞ = 1.35 for h₀ = 1): more than the 16 kept
    es, heights = np.array([0.5, 0.8]), np.array([1.0, 2.0])
    sweep = reset_ball.sweep((0.0, 2.5), {"e": es, "x": heights}, output="events", method=method, progress=False,
                             **options)
    record = sweep.events["impact"]
    assert set(record) == {"count", "t", "y", "y_after"}
    assert record["y_after"].shape == (2, 2, 16, 2)
    for i, e in enumerate(es):
        for j, h in enumerate(heights):
            sol = reset_ball.simulate((0.0, 2.5), [h], [0.0], params={"e": e}, method=method, **options)
            assert sweep.status[i, j] == sol.status and sweep.t_final[i, j] == sol.t[-1]
            _assert_same_records(reset_ball, sweep, (i, j), sol)
            kept = min(int(record["count"][i, j]), 16)
            np.testing.assert_allclose(record["y_after"][i, j, :kept, 1] / record["y"][i, j, :kept, 1], -e,
                                       rtol=1e-12)


def test_a_contacts_sweep_keeps_each_trajectorys_impulses_as_single_runs_do(cradle):
    speeds, masses = np.array([1.0, 2.0]), np.array([1.0, 3.0])
    q0 = [-0.5, 1.0, 2.0]           # balls 2 and 3 touching at rest; ball 1 arrives at t = 0.5 / speed
    sweep = cradle.sweep((0.0, 2.0), {"x1_dot": speeds, "m2": masses}, q0=q0, output="events", rtol=1e-12,
                         atol=1e-12, progress=False)
    impacts = sweep.events["c12"]
    assert set(impacts) == {"count", "t", "y", "y_after", "impulses"}
    assert impacts["impulses"].shape == (2, 2, 16, 2)
    for i, v in enumerate(speeds):
        for j, m2 in enumerate(masses):
            sol = cradle.simulate((0.0, 2.0), q0, [v, 0.0, 0.0], params={"m2": m2}, rtol=1e-12, atol=1e-12)
            _assert_same_records(cradle, sweep, (i, j), sol)
            first = impacts["impulses"][i, j, 0]
            assert (first > 0).all()                       # both contacts push at the simultaneous impact
            momentum_after = impacts["y_after"][i, j, 0, 3:] @ [1.0, m2, 1.0]
            assert momentum_after == pytest.approx(v, rel=1e-13, abs=0)
            assert first[0] == pytest.approx(v - impacts["y_after"][i, j, 0, 3], rel=1e-13, abs=0)  # P = m1 (v⁻ − v⁺)


def test_the_records_survive_save_and_load(cradle, tmp_path):
    sweep = cradle.sweep((0.0, 1.0), {"x1_dot": [1.0, 2.0]}, q0=[-0.5, 1.0, 2.0], output="events", progress=False)
    sweep.save_npz(tmp_path / "cradle.npz")
    loaded = Sweep.load_npz(tmp_path / "cradle.npz")
    assert set(loaded.events) == set(sweep.events)
    for name, record in sweep.events.items():
        assert set(loaded.events[name]) == set(record)
        for part, values in record.items():
            np.testing.assert_array_equal(loaded.events[name][part], values)


def test_lagcomp_sweep_prints_the_impacts_and_impulses(cradle, cache_dir, capsys):
    code = main(["--cache-dir", str(cache_dir), "sweep", "sweep_record_cradle", "--grid", "x1_dot=1:2:3",
                 "--q0", "-0.5", "1.0", "2.0", "--qd0", "0", "0", "0", "--t-end", "1", "--output", "events",
                 "--quiet", "--workers", "1"])
    out = capsys.readouterr().out
    assert code == 0, out
    line = next(line for line in out.splitlines() if line.startswith("event       c12"))
    assert "3 occurrence(s) in all" in line
    assert "impulse" in out and "c23" in out
