"""Fuzz the public entry points with wrong types, shapes, values and names (issue 24, acceptance).

Every input is either accepted or refused with a `LagcompError` whose message
is not empty: never a raw TypeError, AttributeError, OSError... from inside
lagcomp.  The command line answers with a non-zero code and a message, never a
traceback, and never fails after it computed something (a bad output path is
refused before the run).  One small model is compiled once; `System` is
fuzzed without compiling.  Seeds are derandomized, so runs repeat.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
import sympy as sp
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import lagcomp as lc
from lagcomp.cli import main
from lagcomp.model import t

x, y = lc.coordinates("x y")
m, k = sp.symbols("m k", positive=True)
NAME = "fuzz_plane"

FUZZ = settings(max_examples=40, deadline=None, derandomize=True, database=None,
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])

#: Wrong (and some right) values of each kind, drawn from by the strategies below.
NUMBERS = [0, 1, -1, 0.5, 2.5, math.nan, math.inf, -math.inf, 1e300, True, None, "1", "x", [], [1.0], {}, 1j,
           np.float64(0.1), np.array([1.0, 2.0])]
NAMES = ["x", "y", "x_dot", "m", "k", "zz", "", "a b", 3, None, m, x, "θ", "a" * 300]


def _planar_system(**overrides) -> lc.System:
    """A unit mass on springs in the plane, with an event: x'' = −(k/m) x, y'' = −(k/m) y."""
    spec = dict(coordinates=[x, y], T=m * (x.diff(t) ** 2 + y.diff(t) ** 2) / 2, V=k * (x**2 + y**2) / 2,
                name=NAME, defaults={"m": 1.0, "k": 1.0}, q0=(1.0, 0.0), events=[lc.Event("cross", x)])
    spec.update(overrides)
    return lc.System(**spec)


@pytest.fixture(scope="module")
def fuzz_cache(tmp_path_factory):
    return tmp_path_factory.mktemp("fuzz-cache")


@pytest.fixture(scope="module")
def model(fuzz_cache):
    """The one compiled model, its dop853 and rk4 drivers and sweep loops compiled once here."""
    model = lc.compile(_planar_system(), cache_dir=fuzz_cache)
    for method, options in (("dop853", {}), ("rk4", {"dt": 0.1})):
        model.simulate((0, 0.2), method=method, progress=False, **options)
        model.sweep((0, 0.2), {"x": [0.0, 1.0]}, method=method, workers=1, progress=False, **options)
    return model


def _answered(call):
    """Run `call`; return its result, or the LagcompError it raised (checked to carry a message)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", lc.CacheWarning)
        try:
            return call()
        except lc.LagcompError as err:
            assert str(err).strip(), f"{type(err).__name__} without a message"
            return err


# -- System and compile --------------------------------------------------------------------

EXPRESSIONS = [m * x.diff(t) ** 2 / 2, k * x**2, "m*x**2", None, 3, [m], sp.I * x, sp.zoo * x, {x: 1},
               x.diff(t, 2), sp.Function("phi")(t), sp.Symbol("t") * x, object()]


@given(st.fixed_dictionaries({}, optional={
    "coordinates": st.sampled_from([[x], x, [x, y], "x", 3, None, [sp.Symbol("q")], [x, x], [], [x.diff(t)]]),
    "T": st.sampled_from(EXPRESSIONS),
    "V": st.sampled_from(EXPRESSIONS),
    "forces": st.sampled_from([None, [], [k * x], "k*x", 5, {x: k}, {y: 1}, [1, 2, 3], ["k"], k * x]),
    "dissipation": st.sampled_from(EXPRESSIONS),
    "constraints": st.sampled_from([(), lc.Holonomic("c", x - 1), [5], "c", [lc.Holonomic("c", x)] * 2]),
    "events": st.sampled_from([(), lc.Event("e", x), [lc.Event("e", x)], ["e"], 7]),
    "parameters": st.sampled_from([None, [m, k], [m], [3], "m", m, [k, m, sp.Symbol("zz")]]),
    "name": st.sampled_from(NAMES),
    "description": st.sampled_from(["", "ok", 5, None]),
    "defaults": st.sampled_from([{}, {"m": 1}, {m: 1}, [1], {"m": "x"}, {"zz": 1}, None, {"m": math.nan}, {3: 1}]),
    "q0": st.sampled_from(NUMBERS + [[1.0, 2.0], [[1.0]]]),
    "qd0": st.sampled_from(NUMBERS),
    "t_end": st.sampled_from(NUMBERS),
    "bodies": st.sampled_from([(), 5, ["body"]]),
    "loads": st.sampled_from([(), 5, ["load"]]),
    "frame": st.sampled_from([None, 5, "N"]),
}))
@FUZZ
def test_system_accepts_or_refuses_with_a_message(overrides):
    spec = dict(coordinates=[x], T=m * x.diff(t) ** 2 / 2, name="fuzz_system")
    spec.update(overrides)
    _answered(lambda: lc.System(**spec))


@given(st.sampled_from([None, 5, "double_pendulum", [x], {"T": 1}, object(), lc.Holonomic("c", x)]),
       st.sampled_from([{}, {"name": "x"}, {"cache_dir": 5}]))
@FUZZ
def test_compile_refuses_what_is_not_a_system(thing, options):
    result = _answered(lambda: lc.compile(thing, **options))
    assert isinstance(result, lc.LagcompError)


@given(st.sampled_from([5, 2.5, b"bytes", object(), ["a"], ""]))
@FUZZ
def test_compile_and_load_refuse_a_bad_cache_dir(cache_dir):
    _answered(lambda: lc.compile(_planar_system(name="fuzz_cache_dir"), cache_dir=cache_dir))
    _answered(lambda: lc.load(NAME, cache_dir=cache_dir))


@given(st.sampled_from(NAMES + [b"x", "../x", "x/y", ".", "names", "a" * 5000]))
@FUZZ
def test_load_of_any_name_answers(fuzz_cache, name):
    result = _answered(lambda: lc.load(name, cache_dir=fuzz_cache))
    assert isinstance(result, (lc.Model, lc.LagcompError))


# -- simulate and sweep on the one compiled model -------------------------------------------

SPANS = [(0, 0.5), (0.5, 0), (0, math.nan), "ab", None, 5, (0, 0.5, 1), (0, math.inf), [0, 0.3], (1j, 2)]
STATES = [None, [1.0, 0.0], [1.0], [[1.0, 0.0]], "ab", [math.nan, 0.0], {}, 5, [1.0, "a"], np.zeros(2), [1j, 0]]
PARAMS = [None, {}, {"m": 2.0}, {"zz": 1.0}, [1.0], {"m": "a"}, {m: 2.0}, {"m": math.nan}, 5, {3: 1.0},
          {"m": [1.0, 2.0]}, {"m": 0.0}, {"m": 1j}, {m: 1.0, "m": 2.0}]


@given(st.fixed_dictionaries({
    "t_span": st.sampled_from(SPANS), "q0": st.sampled_from(STATES), "qd0": st.sampled_from(STATES),
    "params": st.sampled_from(PARAMS),
}, optional={
    "method": st.sampled_from(["dop853", "rk4", "euler", 5, None, "verlet", "gauss2", "taylor"]),
    "dt": st.sampled_from([None, 0.05, -1.0, "a", math.nan, 0.0, 1e-9, [0.1]]),
    "rtol": st.sampled_from([None, 1e-8, -1.0, "a", 2.0, 1e-20]),
    "atol": st.sampled_from([None, 1e-10, 0.0, math.inf]),
    "t_eval": st.sampled_from([None, [0.25], [0.4, 0.1], "a", np.linspace(0, 0.5, 5), [[0.1]], [], [math.nan]]),
    "save_every": st.sampled_from([1, 0, 2.5, "a", 10, None, True]),
    "record": st.sampled_from(["trajectory", "summary", 5, None]),
    "events": st.sampled_from([None, True, False, ["nope"], "cross", 5, ["cross"]]),
    "max_steps": st.sampled_from([100_000, 0, "a", 3, 2.5]),
    "memory_limit": st.sampled_from([2**30, -1, "x", 100, math.nan]),
    "first_step": st.sampled_from([None, 0.01, -1.0, "a"]),
    "max_step": st.sampled_from([math.inf, 0.1, 0.0, "a"]),
    "projection": st.sampled_from([None, True, "yes"]),
    "baumgarte": st.sampled_from([(0.0, 0.0), 5, (1.0,), ("a", "b")]),
    "throw": st.sampled_from([False, True]),
    "bogus_option": st.sampled_from([1]),
}))
@FUZZ
def test_simulate_accepts_or_refuses_and_keeps_what_it_computed(model, arguments):
    arguments.setdefault("method", "dop853")
    if arguments["method"] == "rk4" and arguments.get("dt") in (None, 1e-9):
        arguments["dt"] = 0.05  # a valid step for some of the runs, and no run of 10⁸ steps
    result = _answered(lambda: model.simulate(progress=False, **arguments))
    if isinstance(result, lc.IntegrationError):
        result = result.solution  # throw=True: the partial solution rides on the error
    if isinstance(result, lc.Solution):
        assert result.t.size >= 1 and np.all(np.diff(result.t) > 0) and result.q.shape == (result.t.size, 2)
        assert np.all(np.isfinite(result.q[: -1 if result.status < 0 else None]))


@given(st.fixed_dictionaries({
    "t_span": st.sampled_from(SPANS[:4]),
    "grid": st.sampled_from([{"x": [0.0, 1.0]}, {"zz": [1.0]}, {"x": []}, {"x": "ab"}, {3: [1.0]}, [[1.0, 2.0]],
                             {"x": [math.nan]}, {"m": [1.0, 2.0]}, {"x_dot": [0.1]}, None, 5, {m: [1.0]},
                             {"x": [[0.0, 1.0]]}, {"x": [0.0, 1.0], "y": [0.0]}, {"x": 0.5}]),
}, optional={
    "combine": st.sampled_from(["product", "zip", "bad", 5]),
    "names": st.sampled_from([None, ["x"], "x", [3], ["x", "y"]]),
    "output": st.sampled_from([(), "dense", "energy", "events", "bad", 5, ["energy", "energy"]]),
    "method": st.sampled_from(["dop853", "rk4", "nope"]),
    "dt": st.sampled_from([None, 0.1, -1.0]),
    "t_eval": st.sampled_from([None, [0.25], "a"]),
    "workers": st.sampled_from([None, 1, 0, "a", 2.5]),
    "memory_limit": st.sampled_from([2**30, 10, -1]),
    "params": st.sampled_from(PARAMS[:6]),
    "q0": st.sampled_from(STATES[:4]),
    "batched": st.sampled_from([False, "yes"]),
    "event_cap": st.sampled_from([16, 0, "a"]),
}))
@FUZZ
def test_sweep_accepts_or_refuses_with_a_message(model, arguments):
    arguments.setdefault("method", "dop853")
    if arguments["method"] == "rk4" and arguments.get("dt") is None:
        arguments["dt"] = 0.1
    result = _answered(lambda: model.sweep(progress=False, **{"workers": 1, **arguments}))
    if isinstance(result, lc.Sweep):
        assert result.done.all() and result.final.shape == (*result.shape, 4)


# -- the command line ----------------------------------------------------------------------

@given(st.sampled_from(["run", "sweep", "show", "bench"]),
       st.sampled_from([NAME, "no_such_model", "", "n_link_pendulum", "a" * 300, "../etc"]),
       st.lists(st.sampled_from([
           ["--t-end", "0.3"], ["--t-end", "-1"], ["--t-end", "nan"], ["--method", "rk4"], ["--dt", "0.1"],
           ["--dt", "0"], ["--param", "k=2"], ["--param", "zz=1"], ["--param", "k"], ["--param", "k=x"],
           ["--q0", "1", "0"], ["--q0", "1"], ["--qd0", "nan", "0"], ["--out", "/nonexistent/dir/x.npz"],
           ["--arg", "m=3"], ["--arg", "n=abc"], ["--grid", "x=0:1:2"], ["--grid", "x=1:0:0"],
           ["--grid", "zz=0:1:2"], ["--output", "bad"], ["--save-every", "0"], ["--rtol", "-1"],
           ["--workers", "0"], ["--summary"],
       ]), max_size=4))
@FUZZ
def test_cli_answers_with_a_code_and_a_line_never_a_traceback(model, fuzz_cache, capsys, command, name, options):
    argv = ["--cache-dir", str(fuzz_cache), command, name, *[part for option in options for part in option]]
    if command == "bench":
        argv += ["--no-cold", "--methods", "rk4", "--repeats", "1", "--steps", "100"]
    elif command in ("run", "sweep"):
        argv += ["--quiet"]
    if command == "sweep" and not any(option[0] == "--grid" for option in options):
        argv += ["--grid", "y=0:1:2"]
    try:
        code = main(argv)
    except SystemExit as exit_:  # argparse's own refusal of a malformed option: usage and one error line
        code = exit_.code
    out, err = capsys.readouterr()
    assert "Traceback" not in err and "Traceback" not in out
    if code not in (0, 1):  # 1: a run that failed part-way, its summary printed
        assert code in (2, 130) and err.strip(), (argv, code, err)
        assert "final " not in out, f"{argv}: failed after the run printed its result\n{out}\n{err}"
