"""`simulate` and `sweep` check their shared options in one place (`lagcomp.integrate.options.run_options`).

The property: for any option values, both refuse with the same `OptionError` message, or both
build the same `RunOptions`.  No run starts: each call stops right after `run_options`, so the
drivers are not compiled.  Then the disagreements this replaced, one test each, and the
`implicit_solver` a sweep now takes like a run.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import sympy as sp
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import lagcomp as lc
from lagcomp.integrate import options as options_module
from lagcomp.integrate import simulate as simulate_module
from lagcomp.integrate import sweep as sweep_module
from lagcomp.integrate.options import RunOptions, run_options
from lagcomp.model import t

x, y = lc.coordinates("x y")
m, k = sp.symbols("m k", positive=True)

PROPERTY = settings(max_examples=500, deadline=None, derandomize=True, database=None,
                    suppress_health_check=[HealthCheck.function_scoped_fixture])

#: Values of every option simulate and sweep share, good and bad (and good ones that are refused
#: in combination: dt with an adaptive method, t_eval or events with a fixed-step one...).
SHARED = {
    "method": st.sampled_from(["dop853", "DOPRI5", "rk45", "rk4", "verlet", "gauss2", "taylor", "bs3", "euler", 5]),
    "dt": st.sampled_from([None, 0.05, 0.3, -1.0, "a", math.nan, 0.0, [0.1], "0.1"]),
    "rtol": st.sampled_from([None, 1e-8, -1.0, "a", 2.0, 1e-20, 1e-15, math.nan, "1e-6"]),
    "atol": st.sampled_from([None, 1e-10, 0.0, math.inf, "x"]),
    "t_eval": st.sampled_from([None, [0.25], [0.0, 0.5], [0.4, 0.1], "a", np.linspace(0, 0.5, 5), [[0.1]], [],
                               [math.nan], [0.6]]),
    "save_every": st.sampled_from([1, 0, 2.5, "a", 3, None, True, np.int64(2)]),
    "max_step": st.sampled_from([math.inf, 0.1, 0.0, "a", -math.inf, "inf", None]),
    "max_steps": st.sampled_from([100_000, 0, "a", 3, 2.5, np.int32(50)]),
    "implicit_solver": st.sampled_from([None, "newton", "fixed_point", "broyden", 3]),
    "events": st.sampled_from([None, True, False, ["nope"], "cross", 5, ["cross"]]),
    "projection": st.sampled_from([None, True, False]),
    "memory_limit": st.sampled_from([2**30] * 8 + [-1, "x", math.nan, True]),  # mostly good: checked first
}


class _Built(Exception):
    """Raised in place of running: carries the `RunOptions` a call built."""

    def __init__(self, options: RunOptions):
        super().__init__("built")
        self.options = options


def _planar_system() -> lc.System:
    """A unit mass on springs in the plane, with an event: x'' = −(k/m) x, y'' = −(k/m) y."""
    return lc.System(coordinates=[x, y], T=m * (x.diff(t) ** 2 + y.diff(t) ** 2) / 2, V=k * (x**2 + y**2) / 2,
                     name="options_plane", defaults={"m": 1.0, "k": 1.0}, q0=(1.0, 0.0),
                     events=[lc.Event("cross", x)])


@pytest.fixture(scope="module")
def model(tmp_path_factory):
    return lc.compile(_planar_system(), cache_dir=tmp_path_factory.mktemp("options-cache"))


@pytest.fixture
def stop_after_options(monkeypatch):
    """simulate and sweep stop with `_Built` once their options are built (nothing runs or compiles)."""
    def build_then_stop(*args, **kwargs):
        raise _Built(run_options(*args, **kwargs))

    monkeypatch.setattr(simulate_module, "run_options", build_then_stop)
    monkeypatch.setattr(sweep_module, "run_options", build_then_stop)


def _outcome(call):
    """("refused", message) or ("built", RunOptions) of a call stopped after its options."""
    try:
        call()
    except lc.OptionError as err:
        return "refused", str(err)
    except _Built as built:
        return "built", built.options
    raise AssertionError("the call neither refused its options nor built them")


def _fields(options: RunOptions) -> dict:
    """The fields of `options`, arrays as lists (comparable with ==)."""
    return {name: value.tolist() if isinstance(value, np.ndarray) else value
            for name, value in vars(options).items()}


@given(st.fixed_dictionaries({}, optional=SHARED))
@PROPERTY
def test_simulate_and_sweep_refuse_or_build_the_same_options(model, stop_after_options, arguments):
    span = (0.0, 0.5)
    ran = _outcome(lambda: model.simulate(span, progress=False, **arguments))
    swept = _outcome(lambda: model.sweep(span, {"x": [0.5, 1.0]}, progress=False, workers=1, **arguments))
    assert ran[0] == swept[0], (arguments, ran, swept)
    if ran[0] == "refused":
        assert ran[1] == swept[1] and ran[1]
    else:
        assert _fields(ran[1]) == _fields(swept[1])


@given(st.fixed_dictionaries({}, optional=SHARED))
@PROPERTY
def test_the_options_built_are_normalised(model, arguments):
    """What `run_options` accepts is in the form the drivers take: floats, positive ints, checked arrays."""
    try:
        built = run_options(model, (0.0, 0.5), memory_limit=arguments.pop("memory_limit", 2**30), **arguments)
    except lc.OptionError:
        return
    assert isinstance(built.save_every, int) and built.save_every >= 1
    assert isinstance(built.max_steps, int) and built.max_steps >= 1
    assert built.projecting == 0 and built.directions.dtype == built.actions.dtype == np.int64
    if built.adaptive:
        assert built.dt is None and built.n_steps is None
        assert 0 < built.rtol < 1 and 0 < built.atol < math.inf and 0 < built.max_step
        if built.t_eval is not None:
            assert np.all(np.diff(built.t_eval) > 0) and 0.0 <= built.t_eval[0] and built.t_eval[-1] <= 0.5
    else:
        assert built.rtol is None and built.t_eval is None and not built.actions.any()
        assert 0 < built.dt and 1 <= built.n_steps <= built.max_steps
        times = built.fixed_step_times()
        assert times[0] == 0.0 and times[-1] == 0.5 and np.all(np.diff(times) > 0)


# -- where simulate and sweep disagreed before --------------------------------------------------

def test_dt_with_an_adaptive_method_has_one_message(model, stop_after_options):
    ran = _outcome(lambda: model.simulate((0, 1), dt=0.1))
    swept = _outcome(lambda: model.sweep((0, 1), {"x": [1.0]}, dt=0.1))
    assert ran == swept == ("refused", "`dt` sets the step of fixed-step methods; dop853 chooses its own "
                                       "(bound it with `max_step`).")


def test_t_eval_with_a_fixed_step_method_is_refused_before_its_points_are_read(model, stop_after_options):
    """simulate checked a malformed t_eval first (and named its range), sweep refused t_eval itself."""
    for t_eval in ([0.2], [0.5, 0.1], "a"):
        ran = _outcome(lambda: model.simulate((0, 1), method="rk4", dt=0.1, t_eval=t_eval))  # noqa: B023
        swept = _outcome(lambda: model.sweep((0, 1), {"x": [1.0]}, method="rk4", dt=0.1, t_eval=t_eval))  # noqa: B023
        assert ran == swept and ran[0] == "refused" and "`t_eval` needs dense output, which rk4 lacks" in ran[1]


def test_a_bad_memory_limit_is_refused_whatever_is_recorded(model, stop_after_options):
    """simulate checked `memory_limit` only when it kept the trajectory."""
    for record in ("trajectory", "summary"):
        ran = _outcome(lambda: model.simulate((0, 1), memory_limit="lots", record=record))  # noqa: B023
        assert ran == ("refused", "`memory_limit` must be a positive number of bytes, got 'lots'.")


def test_sweep_checks_the_options_before_it_projects_the_initial_states(compiled, monkeypatch):
    """A bad option is refused before the (Python, per-trajectory) check of the initial states."""
    rod = compiled("spherical_pendulum_cartesian")
    monkeypatch.setattr(sweep_module, "_consistent_initial_states",
                        lambda *args: pytest.fail("the initial states were checked before the options"))
    with pytest.raises(lc.OptionError, match="`save_every`"):
        rod.sweep((0, 1), {"g": [9.0, 10.0]}, method="rk4", dt=0.1, save_every=0)


def test_the_fixed_step_grid_is_computed_once(model):
    built = run_options(model, (0.0, 1.0), method="rk4", dt=0.3, save_every=2, memory_limit=2**30)
    assert built.n_steps == options_module.fixed_step_count(0.0, 1.0, 0.3) == 4
    np.testing.assert_array_equal(built.fixed_step_times(), [0.0, 0.6, 1.0])


def test_the_memory_check_sees_the_rows_before_t_eval_is_copied(model):
    seen = []
    times = np.broadcast_to(np.float64(0.5), (10**9,))  # 8 GB if it were copied
    with pytest.raises(lc.OptionError, match="too many"):
        run_options(model, (0, 1), t_eval=times, memory_limit=2**30,
                    check_rows=lambda rows, where: seen.append((rows, where)) or _refuse("too many"))
    assert seen == [(10**9, "1,000,000,000 `t_eval` times")]


def _refuse(message):
    raise lc.OptionError(message)


# -- implicit_solver: a sweep takes it as a run does ---------------------------------------------

def test_a_sweep_solves_the_stage_equations_as_asked(model):
    q0s = [0.5, 1.0]
    for solver in ("fixed_point", "newton"):
        swept = model.sweep((0, 1), {"x": q0s}, method="gauss2", dt=0.05, implicit_solver=solver, workers=1,
                            progress=False)
        for i, q0 in enumerate(q0s):
            run = model.simulate((0, 1), q0=[q0, 0.0], method="gauss2", dt=0.05, implicit_solver=solver,
                                 progress=False)
            np.testing.assert_array_equal(swept.final[i], np.r_[run.q[-1], run.qd[-1]])
            assert swept.nfev[i] == run.nfev
    with pytest.raises(lc.OptionError, match="broyden"):
        model.sweep((0, 1), {"x": q0s}, method="gauss2", dt=0.05, implicit_solver="broyden")
