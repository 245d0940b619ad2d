"""A summary's energies by lane kernels (`lagcomp.codegen.energy_lanes`, `lagcomp.integrate.recording`).

``energy_lanes`` and ``energy_function_lanes`` evaluate T + V and h over a chunk's rows at once; each row must be
bitwise the scalar kernel's value (the rows whose sin and cos arguments leave the polynomials' range evaluated
again by the scalar kernel), so that ``record="summary"`` gives the values the pointwise fold gave before.
"""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp
from compile_probe import run_probe
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

import lagcomp as lc
from lagcomp.integrate import recording
from lagcomp.integrate.recording import (
    _by_lanes,
    _extreme,
    _largest_deviation,
    fold_rows,
    lane_kernels,
)
from lagcomp.kernel_support.trig import _TRIG_POLY_MAX
from lagcomp.model.system import t

#: Examples with lanes, one of each kind the summary distinguishes: h the energy (an alias), h its own kernel
#: reading t (T depends on time), h its own kernel (a rotating hoop), a cyclic coordinate, holonomic constraints.
EXAMPLES = ("double_pendulum", "driven_pendulum", "hoop_bead", "spherical_pendulum", "four_bar_linkage")


def _bits(values: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(values).view(np.int64)


def _scalar(kernel, ts, ys, p) -> np.ndarray:
    return np.array([kernel(ts[r], ys[r], p) for r in range(ys.shape[0])])


#: A coordinate or velocity: mostly moderate, sometimes far beyond the polynomials' range or not finite.
ENTRIES = st.one_of(st.floats(-10.0, 10.0), st.floats(-1e7, 1e7), st.sampled_from([np.nan, np.inf, -np.inf, 2e5]))


@pytest.mark.parametrize("example", EXAMPLES)
@settings(max_examples=40, deadline=None)
@given(data=st.data())
def test_lanes_are_bitwise_the_scalar_kernels(compiled, example, data):
    """On random rows: each lane whose reach is within range is bitwise the scalar kernel's value, and
    `_by_lanes` (the others again by the scalar kernel) is bitwise the scalar values on every row."""
    model = compiled(example)
    size = model.state_size
    rows = data.draw(st.integers(1, 40))
    ys = data.draw(arrays(np.float64, (rows, size), elements=ENTRIES))
    ts = data.draw(arrays(np.float64, rows, elements=st.floats(-50.0, 50.0)))
    p = model.parameter_vector()
    columns = np.ascontiguousarray(ys.T)
    for lanes, scalar in ((model.kernels.energy_lanes, model.kernels.energy),
                          (model.kernels.energy_function_lanes, model.kernels.energy_function)):
        expected = _scalar(scalar, ts, ys, p)
        values, reach = np.empty(rows), np.empty(rows)
        lanes(ts, columns, p, values, reach)
        near = reach <= _TRIG_POLY_MAX
        assert np.array_equal(_bits(values[near]), _bits(expected[near]))
        assert np.array_equal(_bits(_by_lanes(lanes, scalar, ts, ys, columns, p)), _bits(expected))


def test_reach_bounds_every_trigonometric_argument(compiled):
    """The double pendulum's reach is |θ1| + |θ2| + |θ1 − θ2| (its cosines' arguments); beyond the polynomials'
    range the lane value is not libm's, which the scalar kernel calls there: the fallback is needed."""
    model = compiled("double_pendulum")
    ys = np.array([[0.3, -0.2, 1.0, 2.0], [922352.0, 1.0, 0.0, 0.0], [np.nan, 0.0, 0.0, 0.0]])   # (found by search)
    ts, p = np.zeros(3), model.parameter_vector()
    values, reach = np.empty(3), np.empty(3)
    model.kernels.energy_lanes(ts, np.ascontiguousarray(ys.T), p, values, reach)
    assert reach[0] == 0.3 + 0.2 + 0.5 and reach[1] == 922352.0 + 1.0 + 922351.0 and np.isnan(reach[2])
    assert values[1] != model.kernels.energy(0.0, ys[1], p)


#: Column entries rich in ties (small integers), signed zeros, infinities and NaNs of either sign.
FOLDED = st.one_of(st.integers(-3, 3).map(float), st.sampled_from([0.0, -0.0, np.inf, -np.inf, np.nan, -np.nan]),
                   st.floats(-1e3, 1e3))
#: Columns whose smallest value is a zero of either sign, met in any order.
ZEROS = st.sampled_from([0.0, -0.0, 1.0, 2.0, np.inf])


@settings(max_examples=300, deadline=None)
@given(data=st.data())
def test_the_column_reductions_leave_fold_rows_bits(data):
    """`_extreme` and `_largest_deviation` (a column at a time, four running bounds) leave bitwise what `fold_rows`
    (row by row) leaves, chunk after chunk: the first NaN met, the first of +0 and −0, the same largest deviation."""
    rows, size = data.draw(st.integers(1, 20)), data.draw(st.integers(1, 3))
    ys = data.draw(arrays(np.float64, (rows, size), elements=data.draw(st.sampled_from([FOLDED, ZEROS]))))
    energies = data.draw(arrays(np.float64, (2, rows), elements=FOLDED))
    start = data.draw(arrays(np.float64, 2, elements=FOLDED))
    cuts = sorted(data.draw(st.lists(st.integers(1, rows - 1), max_size=3, unique=True))) if rows > 1 else []
    theirs = (np.array([np.full(size, np.inf), np.full(size, -np.inf)]), np.zeros(2))
    ours = (theirs[0].copy(), theirs[1].copy())
    for a, b in zip([0, *cuts], [*cuts, rows], strict=True):
        part = ys[a:b]
        fold_rows(part, energies[0, a:b], energies[1, a:b], np.empty((b - a, 1)), np.zeros(0, dtype=np.int64), start,
                  *theirs)
        columns = np.ascontiguousarray(part.T)
        for i in range(size):
            ours[0][0, i] = _extreme(columns[i], ours[0][0, i], True)
            ours[0][1, i] = _extreme(columns[i], ours[0][1, i], False)
        for k in range(2):
            ours[1][k] = _largest_deviation(np.ascontiguousarray(energies[k, a:b]), start[k], ours[1][k])
    assert _bits(ours[0]).tolist() == _bits(theirs[0]).tolist()
    assert _bits(ours[1]).tolist() == _bits(theirs[1]).tolist()


def _with_and_without_lanes(model, monkeypatch, *args, **options):
    """The same summary run with the lane kernels (built first, as ``lagcomp precompile`` does) and with the
    pointwise fold (the path before them)."""
    model.kernels.companion.entry("energy_lanes")
    assert lane_kernels(model.kernels) is not None
    lanes = model.simulate(*args, record="summary", **options)
    monkeypatch.setattr(recording, "lane_kernels", lambda kernels: None)
    pointwise = model.simulate(*args, record="summary", **options)
    monkeypatch.undo()
    return lanes, pointwise


def _assert_same_summary(a, b) -> None:
    for field in ("rows", "energy_error", "energy_function_error", "q_min", "q_max", "qd_min", "qd_max"):
        assert _bits(np.atleast_1d(np.asarray(getattr(a.summary, field), dtype=float))).tolist() == \
            _bits(np.atleast_1d(np.asarray(getattr(b.summary, field), dtype=float))).tolist(), field
    assert a.summary.momentum_errors.keys() == b.summary.momentum_errors.keys()
    for name, value in a.summary.momentum_errors.items():
        assert _bits(np.array([value])) == _bits(np.array([b.summary.momentum_errors[name]]))
    for name in ("t", "y", "energy", "energy_function", "momenta"):
        assert getattr(a, name).tobytes() == getattr(b, name).tobytes(), name


@pytest.mark.parametrize("example", EXAMPLES)
def test_a_summary_is_bitwise_the_pointwise_folds(compiled, monkeypatch, example):
    """Every value of a summary run (energy drifts, cyclic momenta's, extremes, the end rows' energies) is the
    pointwise fold's, over several chunks."""
    from lagcomp.integrate import simulate as simulate_module

    model = compiled(example)
    monkeypatch.setattr(simulate_module, "FIRST_CHUNK", 16)
    monkeypatch.setattr(simulate_module, "MAX_CHUNK", 64)
    lanes, pointwise = _with_and_without_lanes(model, monkeypatch, (0, 5), rtol=1e-10, atol=1e-12)
    assert lanes.summary.rows > 64
    _assert_same_summary(lanes, pointwise)


def test_a_summary_beyond_the_polynomials_range_is_the_pointwise_folds(compiled, monkeypatch):
    """A double pendulum started at θ1 = 2·10⁵ rad: every row's cosines go to libm in the scalar kernel, so to the
    scalar kernel in the lane fold too."""
    model = compiled("double_pendulum")
    lanes, pointwise = _with_and_without_lanes(model, monkeypatch, (0, 2), [2e5, 0.3], [0.0, 1.0], rtol=1e-9,
                                               atol=1e-9)
    _assert_same_summary(lanes, pointwise)


def test_a_contact_model_folds_by_lanes_to_the_same_values(cache_dir, monkeypatch):
    """A pendulum bouncing off a wall (restitution 0.8): the contacts' model has lane energies too."""
    theta, = lc.coordinates("theta")
    m, length, g = sp.symbols("m l g", positive=True)
    system = lc.System([theta], T=m * length**2 * theta.diff(t) ** 2 / 2, V=-m * g * length * sp.cos(theta),
                       events=[lc.Contact("wall", 0.4 - theta, restitution=0.8)], name="summary_lanes_wall",
                       parameters=(m, length, g), defaults={"m": 1.0, "l": 1.0, "g": 9.81})
    model = lc.compile(system, cache_dir=cache_dir)
    lanes, pointwise = _with_and_without_lanes(model, monkeypatch, (0, 6), [0.2], [2.0], rtol=1e-10, atol=1e-12)
    assert lanes.summary.rows > 50 and lanes.summary.energy_error > 0.1     # (impacts took energy)
    _assert_same_summary(lanes, pointwise)


def test_models_without_lanes_fold_pointwise(cache_dir, tree_pair):
    """A model with inputs has an empty kind (no lane kernels); a kinematic tree builds none (its energy is the
    multibody path's); both summaries still run."""
    x, = lc.coordinates("x")
    m, k = sp.symbols("m k", positive=True)
    driven = lc.compile(lc.System([x], T=m * x.diff(t) ** 2 / 2, V=k * x**2 / 2, forces=[lc.Input("f")],
                                  parameters=(m, k), defaults={"m": 1.0, "k": 2.0}, name="summary_lanes_input"),
                        cache_dir=cache_dir)
    assert lane_kernels(driven.kernels) is None
    times = np.linspace(0.0, 2.0, 21)
    run = driven.simulate((0, 2), [0.1], [0.0], inputs={"f": lc.Tabulated(times, np.sin(times))}, record="summary")
    assert run.summary.rows > 2
    tree, _ = tree_pair("rigid_double_pendulum")
    assert lane_kernels(tree.kernels) is None
    assert "energy_lanes" not in tree.kernels.companion._entries
    params = {name: 1.0 for name in tree.parameters}
    assert tree.simulate((0, 1), [0.1, 0.2], [0.0, 0.0], params=params, record="summary").summary.rows > 2


#: A fresh process: compile (or load) the double pendulum, one summary run; which kernels numba compiled, the
#: modules in the cache, whether sympy and the lowering were imported.
SCRIPT = """
    how, root, after = sys.argv[1:4]
    from lagcomp.integrate import recording
    recording.LANES_AFTER_ROWS = int(after)
    if how == "load":
        model = lc.load("double_pendulum", cache_dir=root)
    else:
        from lagcomp import examples
        model = lc.compile(examples.get("double_pendulum"), cache_dir=root)
    model.simulate((0, 0.5), progress=False, record="summary").summary
    modules = sorted(p.name for p in Path(root, "modules").glob("*.py"))
    print(json.dumps({"compiled": compiled, "modules": modules, "sympy": "sympy" in sys.modules,
                      "lowering": "lagcomp.codegen.lower" in sys.modules}))
"""


def test_a_summary_builds_the_lanes_kind_once_and_a_second_process_reuses_it(tmp_path):
    """A summary run builds no companion before its model's summaries have folded `LANES_AFTER_ROWS` rows; then
    it builds the energy_lanes companion (one module) and numba compiles its kernel, nothing else of a companion's;
    a second process, from `lagcomp.load`, uses it (whatever its count) and compiles nothing, imports no sympy."""
    early = run_probe(SCRIPT, "compile", tmp_path, 10**9)[0]
    assert not [m for m in early["modules"] if "_on_demand_" in m], early["modules"]
    first = run_probe(SCRIPT, "compile", tmp_path, 0)[0]
    companions = [m for m in first["modules"] if "_on_demand_" in m]
    assert len(companions) == 1 and "_on_demand_energy_lanes_" in companions[0], first["modules"]
    from_companions = {function for module, function in first["compiled"] if "_on_demand_" in module}
    assert from_companions == {"energy_lanes"}, first["compiled"]
    second = run_probe(SCRIPT, "load", tmp_path, 10**9)[0]
    assert second["modules"] == first["modules"]
    assert second["compiled"] == [] and not second["sympy"] and not second["lowering"]


def test_a_run_of_one_row_folds_its_held_row(compiled, monkeypatch):
    """The first row, held to fold with the next chunk (`Recorder._hold`), is folded by `result` when no chunk
    follows: the same values as the pointwise fold, and meanwhile the row's time and count are what a caller reads."""
    model = compiled("double_pendulum")
    p, t0, y0 = model.parameter_vector(), np.array([0.25]), np.array([[0.1, 0.2, -0.4, 0.3]])
    results = []
    for lanes in (True, False):
        if not lanes:
            monkeypatch.setattr(recording, "lane_kernels", lambda kernels: None)
        recorder = recording.Recorder(model, p, "summary")
        recorder.add(t0, y0)
        assert recorder.rows == 1 and recorder.last[0][0] == 0.25
        results.append(recorder.result())
    (ts, ys, observed), (ts_, ys_, observed_) = results
    assert ts.tobytes() == ts_.tobytes() and ys.tobytes() == ys_.tobytes()
    values, values_ = observed.values(), observed_.values()
    assert all(a.tobytes() == b.tobytes() for a, b in zip(values[:3], values_[:3], strict=True))
    assert values[0][0] == model.kernels.energy(0.25, y0[0], p) and values[3].rows == values_[3].rows == 1
    assert (values[3].energy_error, values[3].q_min.tobytes()) == (values_[3].energy_error, values_[3].q_min.tobytes())


def test_the_lanes_are_built_once_summaries_have_folded_enough_rows(tmp_path, monkeypatch):
    """Below `LANES_AFTER_ROWS` rows folded pointwise, summaries build nothing; the chunk after that builds the
    lane kernels, mid-run, and the run's values are the pointwise fold's."""
    from lagcomp import examples
    from lagcomp.integrate import simulate as simulate_module

    model = lc.compile(examples.get("simple_pendulum"), cache_dir=tmp_path)
    monkeypatch.setattr(recording, "LANES_AFTER_ROWS", 200)
    monkeypatch.setattr(simulate_module, "FIRST_CHUNK", 16)
    monkeypatch.setattr(simulate_module, "MAX_CHUNK", 64)
    short = model.simulate((0, 0.5), rtol=1e-10, atol=1e-12, record="summary")
    assert short.summary.rows < 200 and not model.kernels.companion.built("energy_lanes")
    long = model.simulate((0, 60), rtol=1e-10, atol=1e-12, record="summary")
    assert long.summary.rows > 400 and model.kernels.companion.built("energy_lanes")
    monkeypatch.setattr(recording, "lane_kernels", lambda kernels: None)
    _assert_same_summary(long, model.simulate((0, 60), rtol=1e-10, atol=1e-12, record="summary"))
