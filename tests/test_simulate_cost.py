"""What `simulate` no longer does per call (issue 38, item 3) gives what it gave: the Solution built without the
dataclass's ``__init__`` (`Solution.of_run`), the rows of a run's last driver call kept without a copy, the event
buffers allocated once per run.  Each is checked against the slower way it replaced, bit for bit."""

from __future__ import annotations

import dataclasses
import weakref

import numpy as np
import pytest
import sympy as sp
from hypothesis import given, settings
from hypothesis import strategies as st

import lagcomp as lc
from lagcomp import cache as cache_module
from lagcomp.companion import companion_key
from lagcomp.integrate import recording
from lagcomp.integrate import simulate as simulate_module
from lagcomp.integrate.recording import Observed
from lagcomp.integrate.solution import EventRecords, Solution

REQUIRED = [f.name for f in dataclasses.fields(Solution)
            if f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING]
OPTIONAL = [f.name for f in dataclasses.fields(Solution) if f.name not in REQUIRED]


def _required_values() -> dict:
    return dict(t=np.zeros(2), q=np.zeros((2, 1)), qd=np.ones((2, 1)), observed=Observed(values=(1,)), cyclic=(),
                status=0, message="", t_failure=None, nfev=3, nsteps=1, nrejected=0, method="dop853",
                coordinates=("x",))


@settings(max_examples=60, deadline=None)
@given(st.sets(st.sampled_from(OPTIONAL)))
def test_of_run_builds_the_object_init_builds(given_fields):
    """The same fields in the same order, each the object given or the field's default, a fresh dict per Solution
    where the default is a factory, and the events as `EventRecords`."""
    values = _required_values()
    values.update({name: object() for name in given_fields if name != "events"})
    if "events" in given_fields:
        values["events"] = {"hit": object()}
    built, fast = Solution(**values), Solution.of_run(**values)
    assert list(vars(fast)) == list(vars(built))
    for name, value in vars(built).items():
        if name == "events":
            assert type(fast.events) is EventRecords and dict(fast.events) == dict(value)
        elif isinstance(value, dict):       # a default made per Solution
            assert fast.__dict__[name] == value and fast.__dict__[name] is not Solution.of_run(**values).__dict__[name]
        else:
            assert fast.__dict__[name] is value, name
    assert repr(fast) == repr(built)


def test_of_run_refuses_what_init_refuses():
    with pytest.raises(TypeError, match="unknown field"):
        Solution.of_run(**_required_values(), velocity=1)
    values = _required_values()
    del values["nfev"]
    with pytest.raises(TypeError, match="nfev"):
        Solution.of_run(**values)


def _in_small_calls(monkeypatch, steps: int = 32):
    """Cut the next run into driver calls of `steps` steps into output buffers of 16 rows at first (reused from call
    to call until the run outgrows them), no step rate learned before."""
    monkeypatch.setattr(simulate_module, "_STEP_RATES", weakref.WeakKeyDictionary())
    monkeypatch.setattr(simulate_module, "FIRST_BUDGET", steps)
    monkeypatch.setattr(simulate_module, "FIRST_CHUNK", 16)


@pytest.mark.parametrize("options", [{}, {"save_every": 3}, {"t_eval": np.linspace(0.0, 20.0, 301)},
                                     {"record": "summary"}])
def test_rows_of_many_calls_are_those_of_one(compiled, monkeypatch, options):
    """A run cut into dozens of driver calls, whose buffers each next call fills again, keeps the rows a run of one
    call keeps, bit for bit; the arrays of the Solution own their memory (no view of a driver's buffer)."""
    model = compiled("double_pendulum")
    run = dict(rtol=1e-10, atol=1e-10, progress=False, specialize=False, **options)
    whole = model.simulate((0.0, 20.0), [2.0, 1.0], [0.0, 0.0], **run)
    _in_small_calls(monkeypatch)
    calls = _counting_calls(monkeypatch)
    cut = model.simulate((0.0, 20.0), [2.0, 1.0], [0.0, 0.0], **run)
    assert whole.nsteps > 500 and cut.nsteps == whole.nsteps and len(calls) >= 3
    for name in ("t", "q", "qd"):
        a, b = getattr(whole, name), getattr(cut, name)
        assert np.array_equal(a, b), name
        assert b.flags.c_contiguous and b.flags.owndata, name
    assert np.array_equal(whole.energy, cut.energy) and whole.summary.rows == cut.summary.rows


def _counting_calls(monkeypatch) -> list:
    """Count the driver calls of the next run (`simulate._run`'s calls of its ``advance``); returns the list."""
    calls, real = [], simulate_module._run

    def counted(advance, *args, **kwargs):
        def call(*a):
            calls.append(1)
            return advance(*a)
        return real(call, *args, **kwargs)
    monkeypatch.setattr(simulate_module, "_run", counted)
    return calls


def _ball() -> lc.System:
    """Height x above the floor, ẍ = −g; the impact x = 0 downwards reverses and scales the velocity by −e."""
    (x,) = lc.coordinates("x")
    g, e = sp.symbols("g e", positive=True)
    return lc.System(coordinates=(x,), T=x.diff(lc.t) ** 2 / 2, V=g * x, name="cost_ball",
                     defaults={"g": 9.81, "e": 0.8}, q0=(1.0,), qd0=(0.0,),
                     events=[lc.Event("impact", x, direction=-1, reset={x.diff(lc.t): -e * x.diff(lc.t)})])


@pytest.fixture(scope="module")
def ball(cache_dir) -> lc.Model:
    return lc.compile(_ball(), cache_dir=cache_dir)


def test_event_rows_of_many_calls_are_those_of_one(ball, monkeypatch):
    """Impacts met in many driver calls, with the event buffers of the first call serving them all, are recorded as
    in a run of one call: times, states before and after, bit for bit."""
    run = dict(rtol=1e-10, atol=1e-10, progress=False)
    whole = ball.simulate((0.0, 3.0), **run)
    _in_small_calls(monkeypatch, steps=1)
    calls = _counting_calls(monkeypatch)
    cut = ball.simulate((0.0, 3.0), **run)
    a, b = whole.events["impact"], cut.events["impact"]
    assert len(a) >= 3 and len(calls) >= 3
    for part in ("t", "q", "qd", "q_after", "qd_after"):
        assert np.array_equal(getattr(a, part), getattr(b, part)), part
    assert np.array_equal(whole.t, cut.t) and np.array_equal(whole.qd, cut.qd)


def test_summaries_look_for_lane_kernels_on_disk_once(ball, monkeypatch):
    """A model whose lane kernels are not built: its first summary in the process looks for them in the cache on
    disk, the next ones do not; built in this process afterwards, they fold the next summary, to the same values."""
    kernels = ball.kernels
    wanted = companion_key(kernels.companion.key, "energy_lanes")
    if kernels.companion.built("energy_lanes"):
        pytest.skip("the ball's lane kernels were built earlier in this session")
    recording._LOOKED_UP.discard(kernels)
    recording._LANES.pop(kernels, None)
    lookups, real = [], cache_module.Cache.lookup

    def counted(self, key):
        lookups.append(key)
        return real(self, key)
    monkeypatch.setattr(cache_module.Cache, "lookup", counted)
    run = dict(record="summary", rtol=1e-10, atol=1e-10, progress=False)
    pointwise = [ball.simulate((0.0, 3.0), **run) for _ in range(3)]
    assert lookups.count(wanted) == 1 and recording.lane_kernels(kernels) is None
    kernels.companion.entry("energy_lanes")
    by_lanes = ball.simulate((0.0, 3.0), **run)
    assert recording.lane_kernels(kernels) is not None
    assert _same_summary(by_lanes.summary, pointwise[0].summary)


def _same_summary(a, b) -> bool:
    """Two `RunSummary`s equal bit for bit (arrays compared by value)."""
    return all(np.array_equal(getattr(a, f.name), getattr(b, f.name)) if isinstance(getattr(a, f.name), np.ndarray)
               else getattr(a, f.name) == getattr(b, f.name) for f in dataclasses.fields(a))
